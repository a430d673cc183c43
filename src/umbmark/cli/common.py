"""What every command shares: error reporting, warnings, option checks."""

from __future__ import annotations

import contextlib
import functools
import math
import sys
from collections.abc import Callable, Iterator
from enum import Enum
from pathlib import Path
from typing import ParamSpec, TypeVar

import typer

from ..errors import InputError

__all__ = [
    "AngleUnit",
    "Estimator",
    "LengthUnit",
    "check_figure_path",
    "check_length_flag",
    "check_positive_flag",
    "progress_bar",
    "reports_input_errors",
    "warn",
]

P = ParamSpec("P")
R = TypeVar("R")

#: Exit status for bad input (as for a usage error).
EXIT_BAD_INPUT = 2


class LengthUnit(str, Enum):
    """Unit of lengths in an input table."""

    m = "m"
    cm = "cm"
    mm = "mm"


class Estimator(str, Enum):
    """Estimators a square path test can be evaluated with."""

    paper = "paper"
    exact = "exact"
    heading = "heading"
    trajectory = "trajectory"


class AngleUnit(str, Enum):
    """Unit of angles in an input table."""

    rad = "rad"
    deg = "deg"


def error_line(message: str) -> None:
    """Print one error line to stderr (plain text: no wrapping, no colour codes)."""
    sys.stderr.write(f"umbmark: error: {message}\n")


def warn(message: str) -> None:
    """Print one warning line to stderr."""
    sys.stderr.write(f"umbmark: warning: {message}\n")


def reports_input_errors(fn: Callable[P, R]) -> Callable[P, R]:
    """Turn :class:`InputError` into one line on stderr and exit status 2."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            return fn(*args, **kwargs)
        except InputError as exc:
            error_line(str(exc))
            raise typer.Exit(EXIT_BAD_INPUT) from None

    return wrapper


def check_positive_flag(name: str, value: float, unit: str = "") -> None:
    """Refuse a flag value that is not a positive finite number."""
    if not (math.isfinite(value) and value > 0):
        shown = f"{value:g} {unit}".strip()
        raise InputError(f"{name} must be > 0, got {shown}")


def check_figure_path(flag: str, path: Path | None) -> None:
    """Refuse a figure file name whose extension names no figure format."""
    from ..plotting import FIGURE_FORMATS

    if path is not None and path.suffix.lower() not in FIGURE_FORMATS:
        raise InputError(f"{flag} {path}: the file name should end in {', '.join(FIGURE_FORMATS)}")


def check_length_flag(name: str, value: float, largest: float) -> None:
    """Refuse a length flag [m] that is not positive or is implausibly large (unit slip)."""
    check_positive_flag(name, value, "m")
    if value > largest:
        raise InputError(
            f"{name} {value:g} m is implausibly large: lengths on the command line are in "
            f"metres (at most {largest:g} m here)"
        )


@contextlib.contextmanager
def progress_bar(description: str) -> Iterator[Callable[[float], None]]:
    """A progress bar on stderr; yields a callback taking the fraction done (0 to 1).

    Shown only on a terminal, so that pipes and ``--json`` output stay clean.
    """
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True)
    if not console.is_terminal:
        yield lambda fraction: None
        return
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    ) as bar:
        task = bar.add_task(description, total=1.0)
        yield lambda fraction: bar.update(task, completed=fraction)

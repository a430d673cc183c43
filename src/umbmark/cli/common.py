"""What every command shares: error and warning lines, progress bars, the console."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

__all__ = ["EXIT_BAD_INPUT", "console", "error_line", "progress_bar", "warn", "wrote"]

#: Exit status for bad input (as for a usage error).
EXIT_BAD_INPUT = 2
#: Width of output that goes to a file or a pipe: wide enough that no table wraps.
_PIPE_WIDTH = 200


def error_line(message: str) -> None:
    """Print one error line to stderr (plain text: no wrapping, no colour codes)."""
    sys.stderr.write(f"umbmark: error: {' '.join(message.split())}\n")


def warn(message: str) -> None:
    """Print one warning line to stderr."""
    sys.stderr.write(f"umbmark: warning: {' '.join(message.split())}\n")


def wrote(paths: Iterable[str | Path]) -> None:
    """Say on stderr which files were written (stdout stays for the result)."""
    for path in paths:
        sys.stderr.write(f"umbmark: wrote {path}\n")


def console() -> Console:
    """A console on stdout; not wrapped at 80 columns when piped."""
    from rich.console import Console

    out = Console(highlight=False)
    if not out.is_terminal:
        out = Console(highlight=False, width=_PIPE_WIDTH, soft_wrap=True)
    return out


@contextlib.contextmanager
def progress_bar(description: str) -> Iterator[Callable[[float], None]]:
    """A progress bar on stderr; yields a callback taking the fraction done (0 to 1).

    Shown only on a terminal, so that pipes and ``--json`` output stay clean.
    """
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    err = Console(stderr=True)
    if not err.is_terminal:
        yield lambda fraction: None
        return
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        console=err,
        transient=True,
    ) as bar:
        task = bar.add_task(description, total=1.0)
        yield lambda fraction: bar.update(task, completed=fraction)

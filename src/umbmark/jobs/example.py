"""The bundled example runs table: five cw and five ccw runs of a virtual LabMate, in mm."""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from ..errors import InputError

__all__ = ["EXAMPLE_RUNS", "example"]

#: The bundled example, in ``umbmark/data``.
EXAMPLE_RUNS = "labmate_runs_mm.csv"


def example(path: str | os.PathLike[str] | None = None, *, force: bool = False) -> str:
    """The bundled example runs table; written to ``path`` when given.

    Its header says where its numbers come from. Calibrate it with
    ``umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit="mm")``.

    Raises
    ------
    InputError
        If ``path`` exists and ``force`` is not set, or cannot be written.
    """
    from ..outputs.atomic import atomic_write_text

    text = resources.files("umbmark.data").joinpath(EXAMPLE_RUNS).read_text(encoding="utf-8")
    if path is not None:
        target = Path(path)
        if target.exists() and not force:
            raise InputError("exists already; pass --force to overwrite it", source=target)
        atomic_write_text(target, text)
    return text

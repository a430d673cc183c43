"""Writing runs tables (the format is described in :mod:`umbmark.sources.runs_table`)."""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path

from ..runs import Run
from ..sources.runs_table import REQUIRED_COLUMNS
from .atomic import atomic_write_text

__all__ = ["format_runs_table", "write_runs_table"]


def format_runs_table(runs: Sequence[Run]) -> str:
    """The runs as a runs table (metres, radians), headings included when all runs have them."""
    with_theta = all(
        run.true_end.theta is not None and run.odometry_end.theta is not None for run in runs
    )
    columns = (
        ["direction", "x_abs", "y_abs", "theta_abs", "x_odo", "y_odo", "theta_odo"]
        if with_theta
        else list(REQUIRED_COLUMNS)
    )
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(columns)
    for run in runs:
        t, o = run.true_end, run.odometry_end
        if with_theta:
            row = [
                run.direction.value,
                f"{t.x:.6f}",
                f"{t.y:.6f}",
                f"{t.theta:.8f}",
                f"{o.x:.6f}",
                f"{o.y:.6f}",
                f"{o.theta:.8f}",
            ]
        else:
            row = [run.direction.value, f"{t.x:.6f}", f"{t.y:.6f}", f"{o.x:.6f}", f"{o.y:.6f}"]
        writer.writerow(row)
    return out.getvalue()


def write_runs_table(path: str | Path, runs: Sequence[Run], comment: str = "") -> None:
    """Write ``runs`` as a runs table, atomically; ``comment`` lines are prefixed with ``#``."""
    prefix = "".join(f"# {line}\n" for line in comment.splitlines())
    atomic_write_text(path, prefix + format_runs_table(runs))

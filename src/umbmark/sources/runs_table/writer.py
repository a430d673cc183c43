"""Writing runs tables (the format is described in :mod:`umbmark.sources.runs_table.reader`)."""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path

from umbmark.core.atomic import atomic_write_text
from umbmark.model.active import ActiveParams
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run
from umbmark.sources.runs_table.reader import ACTIVE_TAG, REQUIRED_COLUMNS

__all__ = ["active_of", "format_active", "format_runs_table", "write_runs_table"]


def active_of(odometry: WheelParams, configured_wheelbase: float | None = None) -> ActiveParams:
    """The active parameters of an odometry: its ``c_L``, ``c_R``, and its wheelbase as the
    configured ``configured_wheelbase`` [m] times a ``wheel_separation_multiplier`` (1 when
    not given: the odometry's wheelbase is then the configured one)."""
    configured = odometry.wheelbase if configured_wheelbase is None else configured_wheelbase
    return ActiveParams(
        wheelbase=configured,
        c_left=odometry.c_left,
        c_right=odometry.c_right,
        separation_multiplier=odometry.wheelbase / configured,
        wheel_diameter=odometry.wheel_diameter,
    )


def format_active(active: ActiveParams) -> str:
    """The ``umbmark-active:`` comment (without ``#``) recording ``active`` (metres)."""
    parts = [f"wheelbase={active.wheelbase:.12g}"]
    if active.wheel_diameter is not None:
        parts.append(f"wheel_diameter={active.wheel_diameter:.12g}")
    parts += [
        f"c_L={active.c_left:.12g}",
        f"c_R={active.c_right:.12g}",
        f"wheel_separation_multiplier={active.separation_multiplier:.12g}",
    ]
    return f"{ACTIVE_TAG} {' '.join(parts)}"


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


def write_runs_table(
    path: str | Path,
    runs: Sequence[Run],
    comment: str = "",
    active: ActiveParams | None = None,
) -> None:
    """Write ``runs`` as a runs table, atomically; ``comment`` lines are prefixed with ``#``,
    and ``active``, the parameters active during the runs, is recorded in a
    ``# umbmark-active:`` line that :func:`umbmark.calibrate` reads back."""
    if active is not None:
        comment = f"{comment}\n{format_active(active)}" if comment else format_active(active)
    prefix = "".join(f"# {line}\n" for line in comment.splitlines())
    atomic_write_text(path, prefix + format_runs_table(runs))

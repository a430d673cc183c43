"""``umbmark history``: parse the options, call :func:`umbmark.history`, render."""

from __future__ import annotations

from typing import Any

import click

from .options import OTHER, OUTPUTS, Command, apply, option

__all__ = ["history"]


@click.command(cls=Command)
@click.argument("robot", required=False)
@apply(
    [
        option("--history", section=OTHER, type=click.Path(),
               help="The history file [default: $UMBMARK_HISTORY, else "
               "$XDG_DATA_HOME/umbmark/history.sqlite3 or ~/.local/share/umbmark/...]."),
        option("--applied", section=OTHER, type=click.IntRange(min=1),
               help="Mark this calibration (its id) of the robot as applied."),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print one JSON object (metres)."),
    ]
)  # fmt: skip
def history(robot: str | None, json_out: bool, **options: Any) -> None:
    """The robots' calibration history: without ROBOT, the robots; with it, its
    calibrations (calibrate --robot records them) and whether E_d or E_b drift.
    """
    from .. import history as run_history
    from .common import console, warn

    report = run_history(robot, **options)
    for note in report.notes:
        warn(note)
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    out = console()
    if report.robot is None:
        if not report.robots:
            out.print(f"No robots in {report.path} yet (umbmark calibrate --robot NAME).")
        for r in report.robots:
            diameter = "?" if r.wheel_diameter is None else f"{r.wheel_diameter:.4f}"
            out.print(
                f"{r.name}: wheelbase {r.wheelbase:.4f} m, wheel diameter {diameter} m, "
                f"{r.calibrations} calibration(s) since {r.created[:10]}",
                markup=False,
            )
        return
    out.print(
        f"{'id':>4}  {'time (UTC)':<20}  {'method':<16}  {'E_d':>9}  {'E_b':>9}  "
        f"{'E_max,syst [mm]':>15}  applied",
        markup=False,
    )
    for c in report.calibrations:
        e_max = "-" if c.e_max_syst is None else f"{c.e_max_syst * 1000:.1f}"
        out.print(
            f"{c.id:>4}  {c.time[:19]:<20}  {c.method:<16}  {c.E_d:9.6f}  {c.E_b:9.6f}  "
            f"{e_max:>15}  {'yes' if c.applied else 'no'}",
            markup=False,
        )
    if report.drift is not None:
        out.print(report.drift, markup=False)
    else:
        out.print("Drift: needs 3 calibrations or more.")

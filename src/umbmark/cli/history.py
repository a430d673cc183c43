"""``umbmark history``: parse the options, call :func:`umbmark.history`, render."""

from __future__ import annotations

from typing import Any

import click

from umbmark.cli.click_options import (
    OTHER,
    Command,
    apply,
    force_option,
    option,
    override_option,
    spec_option,
)
from umbmark.options.spec import HISTORY, OUTPUTS

__all__ = ["history"]


@click.command(cls=Command)
@click.argument("robot", required=False)
@apply(
    [
        spec_option(HISTORY, section=OTHER),
        option("--applied", section=OTHER, type=click.IntRange(min=1),
               help="Mark this calibration (its id) of the robot as applied; refused for "
               "a calibration whose verdict was do not apply."),
        override_option("With --applied: mark it even when its verdict was do not "
                        "apply.", section=OTHER),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print one JSON object (metres)."),
        option("--plot", section=OUTPUTS, type=click.Path(),
               help="Draw the robot's E_d, E_b (composed with the active parameters; 95 % "
               "error bars) and the passes' E_max,syst over time to a .png, .svg or .pdf "
               "file."),
        force_option(),
    ]
)  # fmt: skip
def history(robot: str | None, json_out: bool, **options: Any) -> None:
    """The robots' calibration history: without ROBOT, the robots; with it, its
    calibrations (calibrate --robot records them) and whether the robot's E_d or E_b
    drift; --plot draws their trend. A pass measures E_d, E_b relative to the parameters
    active during it; the robot's are those composed with the active parameters (what
    calibrate configures), and drift compares these.
    """
    from umbmark import history as run_history
    from umbmark.calibration.verdict import Verdict
    from umbmark.cli.common import console, note, wrote
    from umbmark.cli.render import row, table
    from umbmark.store.history import DEFINITIONS

    report = run_history(robot, **options)
    for line in report.notes:
        note(line)
    wrote([options["plot"]] if options["plot"] else [])
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    out = console()
    if report.robot is None:
        if not report.robots:
            if report.notes:  # no history file yet: the note said so, and how to record
                return
            out.print(
                f"No robots in {report.path} yet (umbmark calibrate --robot NAME).", markup=False
            )
            return
        _robots(report, out)
        return
    gyro = any(c.k_g is not None for c in report.calibrations)
    relative = any(c.relative_to_gyro for c in report.calibrations)
    grid = table(
        f"Calibrations of {report.robot}",
        [
            "id",
            "time (UTC)",
            "method",
            "pass E_d (measured)",
            "pass E_b (measured)",
            "robot E_d (composed)",
            "robot E_b (composed)",
            *(["gyro k_g"] if gyro else []),
            "E_max,syst [mm]",
            "verdict",
            "applied",
        ],
        left=("time (UTC)", "method", "verdict", "applied"),
    )
    for c in report.calibrations:
        e_max = "-" if c.e_max_syst is None else f"{c.e_max_syst * 1000:.1f}"
        mark = " (k_g)" if c.relative_to_gyro else ""
        row(
            grid,
            str(c.id),
            c.time[:19],
            c.method,
            f"{c.E_d:.6f}",
            f"{c.E_b:.6f}{mark}",
            f"{c.robot_E_d:.6f}",
            f"{c.robot_E_b:.6f}{mark}",
            *([("-" if c.k_g is None else f"{c.k_g:.5f}")] if gyro else []),
            e_max,
            "-" if not c.verdict else Verdict(c.verdict["level"]).words,  # a stretch: none
            "yes" if c.applied else "no",
        )
    out.print(grid)
    if relative:
        out.print(
            "(k_g): E_b relative to the gyro (E_b k_g: wheels and gyro alone), not the "
            "wheelbase itself; left out of robot E_b's drift.",
            markup=False,
        )
    if gyro:
        out.print(f"gyro k_g: {DEFINITIONS['k_g']}.", markup=False)
    for name in ("E_d", "E_b", "robot_E_d", "robot_E_b"):
        label = name.replace("_", " ", 1) if name.startswith("robot") else f"pass {name}"
        out.print(f"{label}: {DEFINITIONS[name]}.", markup=False)
    if report.drift is not None:
        out.print(report.drift, markup=False)
    else:
        out.print("Drift: needs 3 calibrations or more.")


def _robots(report: Any, out: Any) -> None:
    """The robots of the history, each dated by its calibrations (a fleet's: its
    recordings' days), not by the day the history learnt of it."""
    from umbmark.cli.render import row, table

    first, last = "first calibration (UTC)", "last calibration (UTC)"
    robots = table(
        f"Robots in {report.path}",
        ["robot", "wheelbase [m]", "wheel diameter [m]", "calibrations", first, last],
        left=("robot", first, last),
    )
    for r in report.robots:
        diameter = "?" if r.wheel_diameter is None else f"{r.wheel_diameter:.4f}"
        row(robots, r.name, f"{r.wheelbase:.4f}", diameter, str(r.calibrations),
            (r.first or "-")[:10], (r.last or "-")[:10])  # fmt: skip
    out.print(robots)

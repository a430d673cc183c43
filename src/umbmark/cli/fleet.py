"""``umbmark fleet``: parse the options, call :func:`umbmark.fleet`, render."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Any

import click

from umbmark.cli.click_options import (
    Command,
    apply,
    force_option,
    option,
    source_options,
    spec_option,
)
from umbmark.options.fleet import FLEET_OPTIONS
from umbmark.options.spec import HISTORY, OUTPUTS

if TYPE_CHECKING:
    from umbmark.fleets.summary import RobotSummary

__all__ = ["fleet"]


#: A robot's notes printed at most (the JSON holds them all).
NOTES_SHOWN = 3


@click.command(cls=Command, no_args_is_help=True)
@click.argument("sources", nargs=-1, required=True, type=click.Path())
@apply([spec_option(spec) for spec in FLEET_OPTIONS])
@source_options()
@apply(
    [
        spec_option(HISTORY),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print one JSON object (metres, radians, seconds)."),
        force_option(),
    ]
)  # fmt: skip
def fleet(sources: tuple[str, ...], json_out: bool, **options: Any) -> None:
    """Calibrate every new recording of a fleet by what it holds, and say which robots
    changed.

    SOURCES: recordings (ROS 1 and 2 bags, MCAP, run logs, OptiOdom sessions), folders
    to search, or globs, of many robots and days; paths, or URLs (https://, s3://, ...:
    the remote extra). Each recording is calibrated by what it holds, on a Dask cluster
    (local by default): scan matching where it has wheels and a laser, a trajectory fit
    where it has an independent reference, else left out with the reason. Every result
    goes into the history (--history), per robot with the recording's time and digest; a
    recording already there with the same options is not done again, so a nightly run
    does only the new ones. Prints every robot's latest figures with their 95 % intervals
    and flags a robot whose figures stepped (since which recording) or trend (per week)
    beyond its own intervals.
    """
    from umbmark import fleet as run_fleet
    from umbmark.cli.common import command_line, console, note, warn, wrote

    options["command"] = command_line(sys.argv)
    with _bar() as progress:
        report = run_fleet(*sources, progress=progress, **options)
    for message in report.warnings:
        warn(message)
    wrote(report.files)
    for outcome in report.failed:
        note(f"failed: {outcome.reason}")
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    _render(report, console())


def _bar() -> Any:
    import contextlib

    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    @contextlib.contextmanager
    def bar() -> Any:
        err = Console(stderr=True)
        if not err.is_terminal:
            yield None
            return
        with Progress(
            TextColumn("fleet"), BarColumn(), TextColumn("{task.description}"),
            TimeElapsedColumn(), console=err, transient=True,
        ) as shown:  # fmt: skip
            task = shown.add_task("looking at the recordings", total=None)

            def update(progress: Any) -> None:
                shown.update(
                    task, total=progress.total, completed=progress.done, description=progress.text()
                )

            yield update

    return bar()


def _render(report: Any, out: Any) -> None:
    from umbmark.cli.render import row, table
    from umbmark.fleets.outcome import FIGURES
    from umbmark.fleets.summary import FIGURE_UNITS

    summary = report.summary
    out.print(
        f"{report.found} recordings found: {len(report.done)} done now, {report.skipped} done "
        f"before (in {report.history}).",
        markup=False,
    )
    names = [n for n in FIGURES if any(n in r.tracks for r in summary.robots)]
    heads = [f"{FIGURE_UNITS[n][0]}{' [' + FIGURE_UNITS[n][2] + ']' if FIGURE_UNITS[n][2] else ''}"
             for n in names]  # fmt: skip
    grid = table("The fleet (latest, ± 95 %)", ["robot", "recordings", *heads, "changes"],
                 left=("robot", "changes"))  # fmt: skip
    for robot in summary.robots:
        if not robot.usable:
            continue
        cells = []
        for name in names:
            track = robot.tracks.get(name)
            if track is None:
                cells.append("-")
                continue
            cells.append(track.shown(unit=False))
        row(grid, robot.robot, str(robot.recordings), *cells, "; ".join(robot.flags) or "-")
    out.print(grid)
    for robot in summary.robots:
        if robot.changed:
            for line in _to_apply(robot):
                out.print(f"{robot.robot}: {line}", markup=False)
        for said in robot.notes[:NOTES_SHOWN]:
            out.print(f"{robot.robot}: {said}", markup=False)
        if len(robot.notes) > NOTES_SHOWN:
            more = len(robot.notes) - NOTES_SHOWN
            out.print(f"{robot.robot}: and {more} more such changes (--json)", markup=False)
        if not robot.usable:
            reasons = "; ".join(r if p in r else f"{p}: {r}" for p, r in robot.left_out[:3])
            out.print(f"{robot.robot}: no usable recording ({reasons})", markup=False)
    out.print(summary.line() + ".", markup=False)


def _to_apply(robot: RobotSummary) -> list[str]:
    """What to put into a changed robot's controller and to declare of its laser, from its
    latest calibration: the overlay's multipliers in one line, the laser's URDF origin."""
    latest = robot.latest
    if latest is None or latest.multipliers is None:
        return []
    lines = []
    if latest.verdict == "do-not-apply":
        lines.append("its latest calibration's verdict is do not apply: no overlay offered")
    else:
        sep, left, right = latest.multipliers
        lines.append(
            f"to apply: wheel_separation_multiplier {sep:.6f}, left_wheel_radius_multiplier "
            f"{left:.6f}, right_wheel_radius_multiplier {right:.6f} (the overlay: --report, "
            "--json)"
        )
    forms = robot.mounting
    if forms is not None:
        lines.append(f"laser {forms.fitted.frame}: {forms.urdf_origin()} ({forms.verdict()})")
    return lines

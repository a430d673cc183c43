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
    try:
        with _bar() as progress:
            report = run_fleet(*sources, progress=progress, **options)
    except KeyboardInterrupt as exc:
        _interrupted(exc)
        raise
    for message in report.warnings:
        warn(message)
    for outcome in report.failed:
        note(f"failed: {outcome.reason}")
    if json_out:
        click.echo(report.to_json(), nl=False)
    else:
        _render(report, console())
    wrote(report.files)  # after the summary: the last lines of a run say where it went


#: A plain progress line (stderr not a terminal: cron, a log) at most this often [s], at
#: each recording's end: a recording every second does not fill a log.
PROGRESS_EVERY = 10.0


def _bar() -> Any:
    import contextlib

    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from umbmark.cli.common import progress_lines

    @contextlib.contextmanager
    def bar() -> Any:
        err = Console(stderr=True)
        if not err.is_terminal:
            line = progress_lines(PROGRESS_EVERY)
            yield lambda progress: line(progress.done, progress.total, progress.text())
            return
        with Progress(
            TextColumn("fleet"), BarColumn(), TextColumn("{task.description}"),
            TimeElapsedColumn(), console=err, transient=True,
        ) as shown:  # fmt: skip
            task = shown.add_task("looking at the recordings (Ctrl-C stops)", total=None)

            def update(progress: Any) -> None:
                shown.update(task, total=progress.total, completed=progress.done,
                             description=f"{progress.counts()} (Ctrl-C stops)")  # fmt: skip

            yield update

    return bar()


def _interrupted(exc: BaseException) -> None:
    """After a Ctrl-C mid-run: one line saying what the history keeps and how to finish,
    exit status 130 (nothing where the run had not begun: the usual one line)."""
    from umbmark.cli.common import error_line
    from umbmark.cli.main import EXIT_INTERRUPTED
    from umbmark.jobs.fleet import fleet_stopped

    stop = fleet_stopped(exc)
    if stop is None:
        return
    sys.stderr.write("\n" if sys.stderr.isatty() else "")  # after the ^C the terminal echoed
    error_line(f"interrupted: {stop.text()}")
    raise click.exceptions.Exit(EXIT_INTERRUPTED) from None


def _render(report: Any, out: Any) -> None:
    summary = report.summary
    out.print(
        f"{report.found} recordings found: {len(report.done)} done now, {report.skipped} done "
        f"before (in {report.history}).",
        markup=False,
    )
    _table(summary, out)
    for robot in summary.robots:
        for flag in robot.flags:  # under the table, whole: a flag is a sentence
            _say(out, robot.robot, flag)
        if robot.changed:
            for line in _to_apply(robot):
                _say(out, robot.robot, line)
        for said in robot.notes[:NOTES_SHOWN]:
            _say(out, robot.robot, said)
        if len(robot.notes) > NOTES_SHOWN:
            more = len(robot.notes) - NOTES_SHOWN
            _say(out, robot.robot, f"and {more} more such changes (--json)")
        if not robot.usable:
            reasons = "; ".join(r if p in r else f"{p}: {r}" for p, r in robot.left_out[:3])
            _say(out, robot.robot, f"no usable recording ({reasons})")
    out.print(summary.line() + ".", markup=False)


#: The indent of a robot's line where it wraps (on a terminal narrower than the line).
WRAP_INDENT = "    "


def _say(out: Any, robot: str, text: str) -> None:
    """``ROBOT: TEXT`` on a line of its own, wrapped between words to the console's width
    with its further lines indented (a word wider than the console is folded, never cut);
    piped output is not wrapped (:func:`umbmark.cli.common.console`)."""
    import textwrap

    lines = textwrap.wrap(f"{robot}: {text}", width=out.width, subsequent_indent=WRAP_INDENT,
                          break_on_hyphens=False)  # fmt: skip
    for line in lines:
        out.print(line, markup=False, soft_wrap=True)


def _table(summary: Any, out: Any) -> None:
    """The usable robots' present E_max,syst and figures: as wide as the console lets it
    (split into parts, each repeating the robot, where the figures do not fit side by
    side)."""
    from umbmark.cli.render import print_table
    from umbmark.fleets.outcome import FIGURES
    from umbmark.fleets.summary import FIGURE_UNITS

    names = [n for n in FIGURES if any(n in r.tracks for r in summary.robots)]
    heads = [f"{FIGURE_UNITS[n][0]}{' [' + FIGURE_UNITS[n][2] + ']' if FIGURE_UNITS[n][2] else ''}"
             for n in names]  # fmt: skip
    rows = [
        [robot.robot, str(robot.recordings),
         "-" if robot.e_max_syst is None else f"{robot.e_max_syst * 1000:.1f}",
         *(robot.tracks[n].shown(unit=False) if n in robot.tracks else "-" for n in names)]
        for robot in summary.robots
        if robot.usable
    ]  # fmt: skip
    if rows:
        print_table(out, "The fleet (present state, ± 95 %)",
                    ["robot", "recordings", "E_max,syst 4 m [mm]", *heads], rows,
                    left=("robot",))  # fmt: skip


def _to_apply(robot: RobotSummary) -> list[str]:
    """What to put into a changed robot's controller and to declare of its laser, from its
    present state: the multipliers in one line, the laser's URDF origin."""
    lines = []
    if robot.apply is not None:
        lines.append(f"to apply: {robot.apply.line()} (the overlay: --report, --json)")
    forms = robot.mounting
    if forms is not None:
        lines.append(f"laser ({forms.fitted.frame}): {forms.urdf_origin()} ({forms.verdict()})")
    return lines

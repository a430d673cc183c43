"""``umbmark monitor``: parse the options, call the monitor's job, render.

``--sim`` runs the monitor's core on the simulated warehouse robot
(:func:`umbmark.monitor_sim`). The ROS nodes' switches (``--ros1``, ``--ros2``) are
added beside it, in :data:`BACKENDS` and the branch of :func:`monitor` marked for them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import click

from umbmark.cli.click_options import Command, apply, option, spec_option
from umbmark.options.monitor import MONITOR_OPTIONS, MONITOR_SECTION, MONITOR_SIM_OPTIONS
from umbmark.options.spec import HISTORY, OUTPUTS

if TYPE_CHECKING:
    from umbmark.jobs.monitor import MonitorSimReport
    from umbmark.monitor.status import MonitorStatus

__all__ = ["monitor"]

#: Where the monitor's inputs come from: ``--sim`` here; ``--ros1`` and ``--ros2`` join.
BACKENDS = ("sim",)


def _figures(status: MonitorStatus) -> str:
    """The figures on one line, with their units and 95 % half-widths."""
    parts = []
    for fig in status.figures:
        unit = f" {fig.unit}" if fig.unit else ""
        if fig.value is None or fig.half_width is None:
            parts.append(f"{fig.name} -")
        else:
            parts.append(f"{fig.name} {fig.value:.5g} +- {fig.half_width:.1g}{unit}")
    return ", ".join(parts)


def _said(status: MonitorStatus) -> None:
    click.echo(
        f"[{status.time:8.1f} s, {status.odometer:6.0f} m] {status.level:<5} {status.message}"
    )
    click.echo(f"    {_figures(status)}")


def _truth(report: MonitorSimReport) -> None:
    truth, last = report.truth, report.last
    click.echo(
        f"After {report.seconds / 60:.0f} min of robot time ({last.odometer:.0f} m driven, "
        f"{report.cpu:.1f} s of CPU in the monitor): {last.level}"
    )
    click.echo(
        f"The change: at {truth['changed_at']:.0f} s, {truth['changed_at_metres']:.0f} m "
        "driven. Each figure as the monitor says it (95 %), and the truth:"
    )
    for fig in last.figures:
        unit = f" {fig.unit}" if fig.unit else ""
        said = (
            f"not determined ({fig.note})"
            if fig.value is None or fig.half_width is None
            else f"{fig.value:.6g} +- {fig.half_width:.2g}{unit}"
        )
        click.echo(f"  {fig.name:<10} {said:<32} truth {truth[fig.name]:.6g}{unit}")


@click.command(cls=Command, no_args_is_help=True)
@apply(
    [
        option("--sim", is_flag=True, section=MONITOR_SECTION,
               help="Watch a simulated warehouse robot driving ordinary missions, its right "
               "wheel changed after --change-after (and its laser knocked: --knock), and "
               "print what the monitor says as it changes, the truth beside at the end."),
        # --- the ROS nodes' switches (--ros1, --ros2) go here ---
    ]
)  # fmt: skip
@apply([spec_option(spec) for spec in MONITOR_OPTIONS])
@apply([spec_option(spec) for spec in MONITOR_SIM_OPTIONS])
@apply(
    [
        spec_option(HISTORY, help="The history file each stretch of driving is recorded in "
                    "[default: none with --sim]."),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print one JSON object at the end (metres, radians, seconds)."),
    ]
)  # fmt: skip
def monitor(sim: bool, json_out: bool, **options: Any) -> None:
    """Watch the robot's odometry as it works: the wheels against the laser's own motion
    and the gyro, over a window of driving; E_d, E_b, E_s, the laser's mounting, the
    gyro's scale and bias, each with its 95 % interval; a change (a wheel changed, a laser
    knocked, a payload) flagged with its size and since when. Never commands the robot.
    """
    from umbmark import monitor_sim

    if sim:
        report = monitor_sim(on_status=None if json_out else _said, **options)
        if json_out:
            click.echo(report.to_json(), nl=False)
            return
        _truth(report)
        return
    # --- the ROS nodes (--ros1, --ros2) branch here ---
    raise click.UsageError("give --sim (the ROS nodes: --ros1, --ros2)")

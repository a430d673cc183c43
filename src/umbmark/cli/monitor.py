"""``umbmark monitor``: parse the options, call the monitor's job, render.

``--sim`` runs the monitor's core on the simulated warehouse robot
(:func:`umbmark.monitor_sim`); ``--ros1`` and ``--ros2`` start the node
(:func:`umbmark.monitor.ros1_node.run_ros1`, :func:`umbmark.monitor.ros2_node.run_ros2`)
with the core :func:`umbmark.monitor.core.make_monitor` makes. ROS's own arguments
(``--ros-args ...``, ROS 1's ``name:=value``) are passed through to the node
(:func:`umbmark.monitor.ros_node.split_ros_args`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import click

from umbmark.cli.click_options import Command, apply, option, spec_option
from umbmark.monitor.ros_node import NODE_OPTIONS, SHARED
from umbmark.options.monitor import (
    MONITOR,
    MONITOR_OPTIONS,
    MONITOR_SECTION,
    MONITOR_SIM,
    MONITOR_SIM_OPTIONS,
)
from umbmark.options.spec import HISTORY, OUTPUTS, READ

if TYPE_CHECKING:
    from umbmark.jobs.monitor import MonitorSimReport
    from umbmark.monitor.status import MonitorStatus

__all__ = ["monitor"]

#: Where the monitor's inputs come from.
BACKENDS = ("sim", "ros1", "ros2")


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
    metres = truth["changed_at_metres"]
    change = (
        f"The change: at {truth['changed_at']:.0f} s, {metres:.0f} m driven."
        if math.isfinite(metres)
        else f"The change at {truth['changed_at']:.0f} s did not come: the run ended first."
    )
    click.echo(f"{change} Each figure as the monitor says it (95 %), and the truth:")
    for fig in last.figures:
        unit = f" {fig.unit}" if fig.unit else ""
        said = (
            f"not determined ({fig.note})"
            if fig.value is None or fig.half_width is None
            else f"{fig.value:.6g} +- {fig.half_width:.2g}{unit}"
        )
        click.echo(f"  {fig.name:<10} {said:<32} truth {truth[fig.name]:.6g}{unit}")


#: The node's options that are not the core's (those it shares are the core's own).
_NODE = [spec for spec in NODE_OPTIONS if spec.name not in MONITOR]


@click.command(
    cls=Command,
    no_args_is_help=True,
    context_settings={"ignore_unknown_options": True, "allow_extra_args": True},
)
@apply(
    [
        option("--sim", is_flag=True, section=MONITOR_SECTION,
               help="Watch a simulated warehouse robot driving ordinary missions, its right "
               "wheel changed after --change-after (and its laser knocked: --knock), and "
               "print what the monitor says as it changes, the truth beside at the end."),
        option("--ros2", is_flag=True, section=MONITOR_SECTION,
               help="Start the node umbmark_monitor on ROS 2 (options also as parameters: "
               "--ros-args -p name:=value)."),
        option("--ros1", is_flag=True, section=MONITOR_SECTION,
               help="Start the node umbmark_monitor on ROS 1 (parameters: _name:=value)."),
    ]
)  # fmt: skip
@apply([spec_option(spec) for spec in _NODE])
@apply([spec_option(READ[name]) for name in SHARED])
@apply([spec_option(spec) for spec in MONITOR_OPTIONS])
@apply([spec_option(spec) for spec in MONITOR_SIM_OPTIONS])
@apply(
    [
        spec_option(HISTORY, help="The history file each stretch of driving is recorded in, "
                    "and a monitor started again takes its course up from (--ros1, --ros2: "
                    "also the parameter history) [default: none]."),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print one JSON object at the end (metres, radians, seconds)."),
    ]
)  # fmt: skip
@click.pass_context
def monitor(
    ctx: click.Context, /, sim: bool, ros1: bool, ros2: bool, json_out: bool, **options: Any
) -> None:
    """Watch the robot's odometry as it works: the wheels against the laser's own motion
    and the gyro, over a window of driving; E_d, E_b, E_s, the laser's mounting, the
    gyro's scale and bias, each with its 95 % interval; a change (a wheel changed, a laser
    knocked, a payload) flagged with its size and since when. Never commands the robot.
    """
    from umbmark.monitor.ros_node import split_ros_args

    if sum((sim, ros1, ros2)) != 1:
        raise click.UsageError("give one of --sim, --ros1, --ros2")
    argv = split_ros_args(ctx.args)
    if argv.own:
        raise click.UsageError(f"no such option or argument: {argv.own[0]}")
    if sim:
        _sim(json_out, options)
        return
    from click.core import ParameterSource

    from umbmark.monitor.core import make_monitor

    given = {name: value for name, value in options.items()
             if ctx.get_parameter_source(name) == ParameterSource.COMMANDLINE}  # fmt: skip
    if ros1:
        from umbmark.monitor.ros1_node import run_ros1

        ctx.exit(run_ros1(given, argv.ros1, make_monitor, (*MONITOR_OPTIONS, HISTORY)))
    from umbmark.monitor.ros2_node import run_ros2

    ctx.exit(run_ros2(given, argv.ros2, make_monitor, (*MONITOR_OPTIONS, HISTORY)))


def _sim(json_out: bool, options: dict[str, Any]) -> None:
    from umbmark import monitor_sim

    keywords = {k: v for k, v in options.items() if k in MONITOR or k in MONITOR_SIM}
    keywords["history"] = options.get("history")
    report = monitor_sim(on_status=None if json_out else _said, **keywords)
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    _truth(report)

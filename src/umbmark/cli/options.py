"""Declaring options: click options that belong to a section of ``--help``, and the
options every command that reads runs shares (``calibrate``, ``replay``).

An option's destination is the keyword of the library function it feeds, with the same
name and meaning: ``--current-c-l`` is ``current_c_l`` of :func:`umbmark.calibrate`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import click

__all__ = [
    "BAGS",
    "LOGS",
    "OUTPUTS",
    "PARAMETERS",
    "TABLE",
    "TEST",
    "Command",
    "apply",
    "option",
    "source_options",
    "tum_time_option",
]

F = TypeVar("F", bound=Callable[..., Any])

TEST = "The square test"
TABLE = "Runs table"
PARAMETERS = "Parameters active during the runs"
LOGS = "Logged runs (run logs, OptiOdom sessions, ROS bags)"
BAGS = "ROS bags"
OUTPUTS = "Outputs"
OTHER = "Other options"


class SectionOption(click.Option):
    """A click option that knows which section of ``--help`` lists it."""

    def __init__(self, *args: Any, section: str = OTHER, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.section = section


class Command(click.Command):
    """A command whose ``--help`` lists its options by section, in declaration order.

    Sections come in the order their first option was declared, "Other options" (where
    ``--help`` is) last. Only options are listed: the docstring describes the arguments
    (click 8.5 began giving arguments a help record of their own; the layout must not
    depend on the click version).
    """

    def format_options(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        sections: dict[str, list[tuple[str, str]]] = {}
        for param in self.get_params(ctx):
            record = param.get_help_record(ctx) if isinstance(param, click.Option) else None
            if record is not None:
                section = getattr(param, "section", OTHER)
                sections.setdefault(section, []).append(record)
        others = sections.pop(OTHER, None)
        if others is not None:
            sections[OTHER] = others
        for name, rows in sections.items():
            with formatter.section(name):
                formatter.write_dl(rows)


def option(*decls: str, section: str, **attrs: Any) -> Callable[[F], F]:
    """A click option listed under ``section`` in ``--help``."""
    return click.option(*decls, cls=SectionOption, section=section, **attrs)


def apply(decorators: Sequence[Callable[[F], F]]) -> Callable[[F], F]:
    """Apply option decorators so that ``--help`` lists them in the given order."""

    def decorate(fn: F) -> F:
        for decorator in reversed(decorators):
            fn = decorator(fn)
        return fn

    return decorate


def _float(help_text: str, *decls: str, section: str, **attrs: Any) -> Callable[[F], F]:
    return option(*decls, section=section, type=float, help=help_text, **attrs)


def tum_time_option() -> Callable[[F], F]:
    """``--tum-time``: the clock of the TUM files (calibrate and replay)."""
    return option(
        "--tum-time",
        section=OUTPUTS,
        type=click.Choice(["recording", "run"]),
        default="recording",
        show_default=True,
        help="Timestamps of the TUM files: the recording's own clock (bag stamps, run-log "
        "time; evo matches them with other trajectories of the same bag) or seconds from "
        "each run's start.",
    )


def source_options(*, wheelbase: bool = True) -> Callable[[F], F]:
    """Options that say how to read a source and what was active during the runs.

    ``wheelbase=False`` leaves ``--wheelbase`` out, for commands that list it elsewhere.
    """
    decorators: list[Callable[[F], F]] = []
    if wheelbase:
        decorators.append(
            _float(
                "Wheelbase b the odometry used during the runs [m] (ros2_control "
                "wheel_separation); for logged runs, overrides the source's. Taken from "
                "--current-params if it has it.",
                "--wheelbase",
                "-b",
                section=PARAMETERS,
            )
        )
    decorators += [
        option(
            "--unit",
            section=TABLE,
            type=click.Choice(["m", "cm", "mm"]),
            default="m",
            show_default=True,
            help="Unit of the lengths in a runs table.",
        ),
        option(
            "--angle-unit",
            section=TABLE,
            type=click.Choice(["rad", "deg"]),
            default="rad",
            show_default=True,
            help="Unit of the headings in a runs table.",
        ),
        option(
            "--current-params",
            section=PARAMETERS,
            type=click.Path(dir_okay=False),
            help="What was active during the runs: a ros2_control (or ROS 1) parameter "
            "YAML (its multipliers, wheel_separation, wheel_radius) or a previous result "
            "(calibrate -o) whose new values were applied. Options below override it.",
        ),
        _float(
            "Left wheel factor c_L active during the runs (ros2_control "
            "left_wheel_radius_multiplier) [default: 1.0, or from --current-params].",
            "--current-c-l",
            section=PARAMETERS,
        ),
        _float(
            "Right wheel factor c_R active during the runs [default: 1.0, or from "
            "--current-params].",
            "--current-c-r",
            section=PARAMETERS,
        ),
        _float(
            "wheel_separation_multiplier active during the runs [default: 1.0, or from "
            "--current-params].",
            "--current-separation-multiplier",
            section=PARAMETERS,
        ),
        _float(
            "Nominal wheel diameter D_n [m]; for logged runs, overrides the source's.",
            "--wheel-diameter",
            section=PARAMETERS,
        ),
        option(
            "--controller",
            section=PARAMETERS,
            help="Controller name in parameter files [default: the one in --current-params, "
            "else diff_drive_controller].",
        ),
        option(
            "--format",
            "-f",
            "format",
            section=LOGS,
            type=click.Choice(["auto", "table", "log", "optiodom", "bag"]),
            default="auto",
            show_default=True,
            help="Source format (auto: by the path).",
        ),
        option(
            "--split",
            section=LOGS,
            type=click.Choice(["rests", "none", "windows"]),
            default="rests",
            show_default=True,
            help="How to find runs in a recording: at rests near the start (rests), the "
            "whole recording (none), or --windows.",
        ),
        option(
            "--windows",
            section=LOGS,
            help="Runs as time windows, seconds from the recording's start: '0:95,100:190'.",
        ),
        _float(
            "Longest ground-truth gap to interpolate across [s], at most 60.",
            "--max-gap",
            section=LOGS,
            default=0.25,
            show_default=True,
        ),
        _float(
            "Shortest rest between runs [s] (for --split rests), at most 600.",
            "--min-rest",
            section=LOGS,
            default=1.0,
            show_default=True,
        ),
        option(
            "--wheel-topic",
            section=BAGS,
            default="/joint_states",
            show_default=True,
            help="sensor_msgs/JointState topic; with --left-field/--right-field, a topic of "
            "any type.",
        ),
        option(
            "--left-joint",
            section=BAGS,
            help="Left wheel joint, or several separated by commas (averaged, as ros2_control "
            "does) [default: left_wheel_names of --current-params, else left_wheel_joint, "
            "else the moving joints named left].",
        ),
        option(
            "--right-joint",
            section=BAGS,
            help="Right wheel joint(s) [default: as for --left-joint].",
        ),
        option(
            "--odom-topic",
            section=BAGS,
            help="No wheel data? The controller's odometry (nav_msgs/Odometry), turned back "
            "into wheel rotation with the controller's geometry (--current-params, or "
            "--wheelbase and --wheel-diameter).",
        ),
        option(
            "--odom-tf",
            section=BAGS,
            nargs=2,
            metavar="PARENT CHILD",
            help="... or the controller's odometry as a /tf chain, e.g. odom base_link.",
        ),
        option(
            "--left-ticks-topic",
            section=BAGS,
            help="Cumulative left encoder counts (std_msgs Int*/UInt*/Float*), instead of "
            "JointState.",
        ),
        option("--right-ticks-topic", section=BAGS, help="Cumulative right encoder counts."),
        option(
            "--left-field",
            section=BAGS,
            metavar="PATH",
            help="Wheel data in a message of any type on --wheel-topic: the field with the "
            "left wheel's angle [rad], or its encoder counts with --ticks-per-rev, e.g. "
            "left_ticks, wheels.left.position, positions[0].",
        ),
        option(
            "--right-field",
            section=BAGS,
            metavar="PATH",
            help="... and the right wheel's field.",
        ),
        option(
            "--msg-dir",
            section=BAGS,
            type=click.Path(file_okay=False),
            metavar="DIR",
            help="The .msg files of --wheel-topic's type (<pkg>/msg/<Name>.msg, searched "
            "recursively), for bags that do not carry its definition (ROS 2 sqlite3 bags "
            "before Iron).",
        ),
        _float(
            "Encoder counts per wheel revolution (with the ticks topics or fields).",
            "--ticks-per-rev",
            section=BAGS,
        ),
        option(
            "--left-wheel-frame",
            section=BAGS,
            metavar="FRAME",
            help="No wheel joint states? The left wheel's frame on /tf (its transform from "
            "the base, e.g. wheel_left_link from robot_state_publisher): its rotation.",
        ),
        option("--right-wheel-frame", section=BAGS, metavar="FRAME", help="... and the right."),
        option(
            "--truth-topic",
            section=BAGS,
            help="Ground truth: geometry_msgs/PoseStamped, PoseWithCovarianceStamped, "
            "nav_msgs/Odometry or gazebo_msgs/ModelStates; or positions only: "
            "geometry_msgs/PointStamped, sensor_msgs/NavSatFix (for paper, exact, endpose).",
        ),
        option(
            "--truth-model",
            section=BAGS,
            metavar="NAME",
            help="With a gazebo_msgs/ModelStates ground truth: the robot's model [default: "
            "the one model that moves].",
        ),
        option(
            "--tf-parent",
            section=BAGS,
            help="Ground truth from /tf and /tf_static instead: the parent frame (e.g. map); "
            "any chain of transforms to the child is followed and interpolated in time.",
        ),
        option("--tf-child", section=BAGS, help="... and the child frame (e.g. base_link)."),
        option(
            "--truth-offset",
            section=LOGS,
            type=float,
            nargs=2,
            metavar="X Y",
            help="The ground truth tracks a point X forward and Y left of the axle centre "
            "[m] (a marker, an antenna): move it to the axle centre. Left in place, it adds "
            "(R(dtheta) - I)(X, Y) to every return error.",
        ),
        option(
            "--time-source",
            section=BAGS,
            type=click.Choice(["header", "bag"]),
            default="header",
            show_default=True,
            help="Message header stamps (where they have them) or bag receive times.",
        ),
    ]
    return apply(decorators)

"""Options shared by the commands that read runs (calibrate, replay), and the glue that
turns them into runs and odometry parameters."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, cast

import typer

from .common import check_length_flag, check_positive_flag

if TYPE_CHECKING:
    from ..calibration import ActiveParams
    from ..io.ros_params import ActiveMultipliers
    from ..kinematics import WheelParams
    from ..logged import SplitMode
    from ..sources.load import Format, Loaded

__all__ = [
    "FormatChoice",
    "SourceFlags",
    "SplitChoice",
    "load_source",
]

MAX_WHEELBASE = 10.0
LOGS = "Logged runs (run logs, OptiOdom, bags)"
BAGS = "ROS bags"


class FormatChoice(str, Enum):
    """Source formats."""

    auto = "auto"
    table = "table"
    log = "log"
    optiodom = "optiodom"
    bag = "bag"


class SplitChoice(str, Enum):
    """How to find runs in a recording."""

    rests = "rests"
    none = "none"
    windows = "windows"


class TimeChoice(str, Enum):
    """Which time stamps of bag messages to use."""

    header = "header"
    bag = "bag"


SourceArg = Annotated[
    Path,
    typer.Argument(
        help="Runs table (CSV), run-log folder, OptiOdom session folder, or ROS bag.",
        show_default=False,
    ),
]
FormatOpt = Annotated[
    FormatChoice, typer.Option("--format", "-f", help="Source format (auto: by the path).")
]
WheelbaseOpt = Annotated[
    float | None,
    typer.Option(
        "--wheelbase",
        "-b",
        help="Wheelbase b the odometry used [m] (ros2_control wheel_separation); for logs, "
        "overrides the source's. Taken from --current-params if it has it.",
        show_default=False,
    ),
]
WheelDiameterOpt = Annotated[
    float | None,
    typer.Option(
        "--wheel-diameter",
        help="Nominal wheel diameter D_n [m]; for logs, overrides the source's.",
        show_default=False,
    ),
]
CurrentCLOpt = Annotated[
    float | None,
    typer.Option(
        "--current-c-l",
        help="Left wheel factor c_L active during the runs (ros2_control "
        "left_wheel_radius_multiplier). Default 1.0, or from --current-params.",
        show_default=False,
    ),
]
CurrentCROpt = Annotated[
    float | None,
    typer.Option(
        "--current-c-r",
        help="Right wheel factor c_R active during the runs. Default 1.0, or from "
        "--current-params.",
        show_default=False,
    ),
]
CurrentSepOpt = Annotated[
    float | None,
    typer.Option(
        "--current-separation-multiplier",
        help="wheel_separation_multiplier active during the runs. Default 1.0, or from "
        "--current-params.",
        show_default=False,
    ),
]
CurrentParamsOpt = Annotated[
    Path | None,
    typer.Option(
        "--current-params",
        help="What was active during the runs: a ros2_control (or ROS 1) parameter YAML "
        "(its multipliers, wheel_separation, wheel_radius) or a previous result "
        "(calibrate -o) whose new values were applied. Flags override.",
        show_default=False,
    ),
]
ControllerOpt = Annotated[
    str | None,
    typer.Option(
        "--controller",
        help="Controller name in parameter files [default: the one in --current-params, "
        "else diff_drive_controller].",
        show_default=False,
    ),
]
SplitOpt = Annotated[
    SplitChoice,
    typer.Option(
        "--split",
        help="How to find runs in a recording: at rests near the start (rests), the whole "
        "recording (none), or --windows.",
        rich_help_panel=LOGS,
    ),
]
WindowsOpt = Annotated[
    str | None,
    typer.Option(
        "--windows",
        help="Runs as time windows, seconds from the recording's start: '0:95,100:190'.",
        rich_help_panel=LOGS,
        show_default=False,
    ),
]
MaxGapOpt = Annotated[
    float,
    typer.Option(
        "--max-gap",
        help="Longest ground-truth gap to interpolate across [s].",
        rich_help_panel=LOGS,
    ),
]
MinRestOpt = Annotated[
    float,
    typer.Option(
        "--min-rest",
        help="Shortest rest between runs [s] (for --split rests).",
        rich_help_panel=LOGS,
    ),
]
WheelTopicOpt = Annotated[
    str,
    typer.Option("--wheel-topic", help="sensor_msgs/JointState topic.", rich_help_panel=BAGS),
]
LeftJointOpt = Annotated[
    str, typer.Option("--left-joint", help="Left wheel joint name.", rich_help_panel=BAGS)
]
RightJointOpt = Annotated[
    str, typer.Option("--right-joint", help="Right wheel joint name.", rich_help_panel=BAGS)
]
LeftTicksOpt = Annotated[
    str | None,
    typer.Option(
        "--left-ticks-topic",
        help="Cumulative left encoder counts (std_msgs Int*/UInt*/Float*), instead of JointState.",
        rich_help_panel=BAGS,
        show_default=False,
    ),
]
RightTicksOpt = Annotated[
    str | None,
    typer.Option(
        "--right-ticks-topic",
        help="Cumulative right encoder counts.",
        rich_help_panel=BAGS,
        show_default=False,
    ),
]
TicksPerRevOpt = Annotated[
    float | None,
    typer.Option(
        "--ticks-per-rev",
        help="Encoder counts per wheel revolution (with the ticks topics).",
        rich_help_panel=BAGS,
        show_default=False,
    ),
]
TruthTopicOpt = Annotated[
    str | None,
    typer.Option(
        "--truth-topic",
        help="Ground truth: geometry_msgs/PoseStamped, PoseWithCovarianceStamped or "
        "nav_msgs/Odometry.",
        rich_help_panel=BAGS,
        show_default=False,
    ),
]
TfParentOpt = Annotated[
    str | None,
    typer.Option(
        "--tf-parent",
        help="Ground truth from /tf instead: the parent frame (e.g. world).",
        rich_help_panel=BAGS,
        show_default=False,
    ),
]
TfChildOpt = Annotated[
    str | None,
    typer.Option(
        "--tf-child",
        help="... and the child frame (e.g. base_link).",
        rich_help_panel=BAGS,
        show_default=False,
    ),
]
TimeSourceOpt = Annotated[
    TimeChoice,
    typer.Option(
        "--time-source",
        help="Message header stamps (where they have them) or bag receive times.",
        rich_help_panel=BAGS,
    ),
]


@dataclass(frozen=True)
class SourceFlags:
    """The values of the shared options, as the commands received them."""

    source: Path
    format: FormatChoice = FormatChoice.auto
    unit: str = "m"
    angle_unit: str = "rad"
    side_length: float | None = None
    wheelbase: float | None = None
    wheel_diameter: float | None = None
    current_c_l: float | None = None
    current_c_r: float | None = None
    current_separation_multiplier: float | None = None
    current_params: Path | None = None
    controller: str | None = None
    split: SplitChoice = SplitChoice.rests
    windows: str | None = None
    max_gap: float = 0.25
    min_rest: float = 1.0
    wheel_topic: str = "/joint_states"
    left_joint: str = "left_wheel_joint"
    right_joint: str = "right_wheel_joint"
    left_ticks_topic: str | None = None
    right_ticks_topic: str | None = None
    ticks_per_rev: float | None = None
    truth_topic: str | None = None
    tf_parent: str | None = None
    tf_child: str | None = None
    time_source: TimeChoice = TimeChoice.header


@dataclass(frozen=True)
class Resolved:
    """Runs and the parameters that were active while they were driven."""

    loaded: Loaded
    active: ActiveParams
    params: WheelParams | None
    controller: str


def _parse_windows(text: str) -> list[tuple[float, float]]:
    from ..errors import InputError

    out = []
    for part in text.split(","):
        try:
            a, b = (float(v) for v in part.split(":"))
        except ValueError:
            raise InputError(
                f"--windows {text!r}: write start:end pairs in seconds, e.g. '0:95,100:190'"
            ) from None
        out.append((a, b))
    return out


def _active_file(flags: SourceFlags) -> ActiveMultipliers | None:
    from ..io.result_file import is_result_file, read_active_from_result
    from ..io.ros_params import read_active_multipliers

    path = flags.current_params
    if path is None:
        return None
    if is_result_file(path):
        return read_active_from_result(path)
    return read_active_multipliers(path, flags.controller)


def load_source(flags: SourceFlags) -> Resolved:
    """Read the runs of ``flags.source`` with the odometry parameters the flags say.

    Raises
    ------
    InputError
        For bad flags or a bad source.
    """
    from ..calibration import ActiveParams
    from ..errors import InputError
    from ..io.ros_params import ActiveMultipliers
    from ..kinematics import WheelParams
    from ..segmentation import SplitOptions
    from ..sources.bag import BagOptions
    from ..sources.load import LoadOptions, detect_format, load_runs, with_params

    for name, value in (
        ("--current-c-l", flags.current_c_l),
        ("--current-c-r", flags.current_c_r),
        ("--current-separation-multiplier", flags.current_separation_multiplier),
        ("--ticks-per-rev", flags.ticks_per_rev),
    ):
        if value is not None:
            check_positive_flag(name, value)
    check_positive_flag("--max-gap", flags.max_gap, "s")
    check_positive_flag("--min-rest", flags.min_rest, "s")
    for name, length in (
        ("--wheelbase", flags.wheelbase),
        ("--wheel-diameter", flags.wheel_diameter),
    ):
        if length is not None:
            check_length_flag(name, length, MAX_WHEELBASE)
    if flags.split is SplitChoice.windows and not flags.windows:
        raise InputError("--split windows needs --windows start:end[,start:end...]")
    windows = _parse_windows(flags.windows) if flags.windows else []
    split = "windows" if windows else flags.split.value

    from_file = _active_file(flags) or ActiveMultipliers()
    controller = flags.controller or from_file.controller
    separation = (
        from_file.wheel_separation_multiplier
        if flags.current_separation_multiplier is None
        else flags.current_separation_multiplier
    )
    c_left = (
        from_file.left_wheel_radius_multiplier if flags.current_c_l is None else flags.current_c_l
    )
    c_right = (
        from_file.right_wheel_radius_multiplier if flags.current_c_r is None else flags.current_c_r
    )
    wheelbase = flags.wheelbase if flags.wheelbase is not None else from_file.wheel_separation
    diameter = flags.wheel_diameter
    if diameter is None and from_file.wheel_radius is not None:
        diameter = 2.0 * from_file.wheel_radius

    kind = detect_format(flags.source) if flags.format is FormatChoice.auto else flags.format.value
    bag = BagOptions(
        wheel_topic=flags.wheel_topic,
        left_joint=flags.left_joint,
        right_joint=flags.right_joint,
        left_ticks_topic=flags.left_ticks_topic,
        right_ticks_topic=flags.right_ticks_topic,
        ticks_per_revolution=flags.ticks_per_rev,
        truth_topic=flags.truth_topic,
        tf_parent=flags.tf_parent,
        tf_child=flags.tf_child,
        time_source=flags.time_source.value,
    )
    given: WheelParams | None = None
    if kind == "bag":
        if wheelbase is None or diameter is None:
            raise InputError(
                "a bag needs the wheel parameters: give --wheelbase and --wheel-diameter "
                "(or --current-params with wheel_separation and wheel_radius)",
                source=flags.source,
            )
        given = WheelParams(
            wheelbase=wheelbase * separation,
            wheel_diameter=diameter,
            c_left=c_left,
            c_right=c_right,
        )
    options = LoadOptions(
        unit=flags.unit,
        angle_unit=flags.angle_unit,
        side_length=flags.side_length,
        params=given,
        split=cast("SplitMode", split),
        windows=windows,
        split_options=SplitOptions(min_rest=flags.min_rest),
        max_gap=flags.max_gap,
        bag=bag,
    )
    loaded = load_runs(flags.source, cast("Format", kind), options)

    if loaded.params is None:  # a runs table: the flags are all there is
        if wheelbase is None:
            raise InputError(
                "--wheelbase is required: the wheelbase the odometry used during the runs, "
                "in metres"
            )
        active = ActiveParams(
            wheelbase=wheelbase,
            c_left=c_left,
            c_right=c_right,
            separation_multiplier=separation,
            wheel_diameter=diameter,
        )
        return Resolved(loaded=loaded, active=active, params=None, controller=controller)

    # Logged runs: the source's parameters, with whatever the flags or files override.
    base = loaded.params
    overridden = any(
        v is not None
        for v in (
            flags.wheelbase,
            flags.wheel_diameter,
            flags.current_c_l,
            flags.current_c_r,
            flags.current_separation_multiplier,
            flags.current_params,
        )
    )
    configured = wheelbase if wheelbase is not None else base.wheelbase
    use_file = flags.current_params is not None
    params = WheelParams(
        wheelbase=configured * separation,
        wheel_diameter=diameter if diameter is not None else base.wheel_diameter,
        encoder_resolution=base.encoder_resolution,
        gear_ratio=base.gear_ratio,
        c_left=c_left if flags.current_c_l is not None or use_file else base.c_left,
        c_right=c_right if flags.current_c_r is not None or use_file else base.c_right,
    )
    if overridden and params != base:
        loaded = with_params(loaded, params)
    active = ActiveParams(
        wheelbase=configured,
        c_left=params.c_left,
        c_right=params.c_right,
        separation_multiplier=separation,
        wheel_diameter=params.wheel_diameter,
    )
    return Resolved(loaded=loaded, active=active, params=params, controller=controller)

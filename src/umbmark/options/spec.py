"""Every option of the commands that read sources, written once: :class:`Spec`.

An option's keyword is the library's (``current_c_l`` of :func:`umbmark.calibrate`), its
first flag the command line's (``--current-c-l``); messages name it by its keyword
(:func:`umbmark.core.errors.option`), which the command line shows as the flag and the
library as the keyword. Its entries make the click options (``spec_option``), the
defaults and checks of ``ReadOptions`` and the defaults of ``BagOptions``. Lengths in
metres, times in seconds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal, cast

from umbmark.core.bounds import (
    MAX_SIDE_LENGTH,
    MAX_WHEELBASE,
    check_length,
    check_multiplier,
    check_positive_option,
    finite_float,
)
from umbmark.core.errors import InputError, option
from umbmark.options.checks import Bound, check_bounded, check_list

__all__ = ["BAGS", "FORCE", "HISTORY", "LOGS", "LONGEST_GAP", "LONGEST_REST", "MAX_TRUTH_OFFSET"]
__all__ += ["OUTPUTS", "OVERRIDE_VERDICT", "PARAMETERS", "READ", "READ_OPTIONS", "SIDE_LENGTH"]
__all__ += ["TABLE", "TEST", "TUM_TIME", "WHEELBASE", "Bound", "Spec", "check_choice"]
__all__ += ["check_pairs"]

# --- the sections of --help -----------------------------------------------------------

TEST = "The square test"
TABLE = "Runs table"
PARAMETERS = "Parameters active during the runs"
LOGS = "Logged runs (run logs, OptiOdom sessions, ROS bags)"
BAGS = "ROS bags"
OUTPUTS = "Outputs"

# --- bounds -----------------------------------------------------------------------------

#: Largest --max-gap [s]: interpolating ground truth across longer gaps is guessing.
LONGEST_GAP = 60.0
#: Largest --min-rest [s].
LONGEST_REST = 600.0
#: Farthest a tracked point may sit from the axle centre [m].
MAX_TRUTH_OFFSET = 5.0

Kind = Literal["text", "number", "integer", "choice", "file", "folder", "flag"]


@dataclass(frozen=True)
class Spec:
    """One option.

    Attributes
    ----------
    name : str
        The library's keyword (``max_gap``).
    flags : tuple of str
        The command line's flags, the long one first (``("--format", "-f")``).
    section : str
        The section of ``--help`` that lists it.
    help : str
        Its ``--help`` text.
    kind : {"text", "number", "integer", "choice", "file", "folder", "flag"}
        What it takes: a text, a number, a whole number, one of ``choices``, a file or a
        folder; a flag takes nothing (given: True).
    default : object
        Its value when not given (None: not given; ``--help`` shows the others).
    choices : tuple of str
        The values of a ``choice``.
    unit : str
        The unit of a number (``m``, ``s``; empty for none).
    bound : Bound or None
        The values a number may take.
    nargs : int
        How many values it takes (``--odom-tf PARENT CHILD``: 2).
    metavar : str or None
        How ``--help`` names its values.
    pair : str or None
        The option it goes with: both or neither (``left_field``: ``right_field``).
    most : int
        A list of at most this many numbers (the command line's comma-separated values:
        the grid of ``umbmark study``), each within the bound; 0: one value.
    py_type : str
        The library's Python type of its value, as text, where the kind does not say it
        (``"str | Sequence[str]"``; ``tools/gen_read_options.py`` types the rest).
    """

    name: str
    flags: tuple[str, ...]
    section: str
    help: str
    kind: Kind = "text"
    default: Any = None
    choices: tuple[str, ...] = ()
    unit: str = ""
    bound: Bound | None = None
    nargs: int = 1
    metavar: str | None = None
    pair: str | None = None
    most: int = 0
    py_type: str = ""

    @property
    def flag(self) -> str:
        """The long flag, as ``--help`` and the command line name the option."""
        return self.flags[0]

    @property
    def named(self) -> str:
        """The option as a message names it (:func:`umbmark.core.errors.option`)."""
        return option(self.name)

    def check(self, value: object, source: str | None = None) -> None:
        """Refuse a value outside the choices or the bound; None passes where it is the
        default (not given). ``source``: the file the message is about, if any.

        Raises
        ------
        InputError
            One line naming the flag and the allowed values.
        """
        if value is None and self.default is None:
            return
        if self.most:
            for one in check_list(self.named, value, self.most, source):
                self._check_one(one, source)
            return
        self._check_one(value, source)

    def _check_one(self, value: object, source: str | None) -> None:
        """:meth:`check` of one value."""
        if self.kind == "choice":
            check_choice(self.name, value, self.choices, source)
        bound = self.bound
        whole = self.kind == "integer"
        if whole or (bound is not None and bound.kind in ("range", "ratio")):
            kind = "range" if bound is None else bound.kind
            limits = (None, None) if bound is None else (bound.low, bound.high)
            check_bounded(self.named, value, kind, limits, self.unit, source, whole)
            return
        if bound is None:
            return
        high = math.inf if bound.high is None else bound.high
        number = cast("float", value)
        if bound.kind == "factor":
            check_multiplier(self.named, number, source)
        elif bound.kind == "length":
            check_length(self.named, number, high, source=source)
        elif bound.kind == "positive":
            check_positive_option(self.named, number, self.unit, source)
            if float(number) > high:
                raise InputError(
                    f"{self.named} must be at most {high:g} {self.unit}, "
                    f"got {float(number):g} {self.unit}",
                    source=source,
                )
        else:
            for one in cast("Sequence[float]", value):
                number = finite_float(self.named, one, source)
                if not abs(number) <= high:
                    raise InputError(
                        f"{self.named} must be within {high:g} {self.unit} of the axle centre, "
                        f"not {number!r}",
                        source=source,
                    )


def check_choice(
    name: str, value: object, choices: tuple[str, ...], source: str | None = None
) -> None:
    """Refuse a value of the option ``name`` (its keyword) that is not one of ``choices``."""
    if value not in choices:
        raise InputError(
            f"{option(name, repr(value))}: use one of {', '.join(choices)}", source=source
        )


def check_pairs(values: Mapping[str, object], source: str | None = None) -> None:
    """Refuse one of two reading options that go together (:attr:`Spec.pair`) given
    without the other; ``values`` by keyword (those missing count as not given)."""
    for spec in READ_OPTIONS:
        if spec.pair is None:
            continue
        if (values.get(spec.name) is None) != (values.get(spec.pair) is None):
            raise InputError(
                f"{spec.named} and {READ[spec.pair].named} go together: give both or neither",
                source=source,
            )


_FACTOR = Bound("factor")

# --- options shared by several commands ------------------------------------------------

#: ``--wheelbase``: listed under :data:`PARAMETERS` by the commands that read sources,
#: under :data:`TEST` by ``calibrate``.
WHEELBASE = Spec(
    "wheelbase",
    ("--wheelbase", "-b"),
    PARAMETERS,
    "Wheelbase b the odometry used during the runs [m] (ros2_control wheel_separation); "
    "for logged runs, overrides the source's. Taken from --current-params if it has it.",
    kind="number",
    unit="m",
    bound=Bound("length", MAX_WHEELBASE),
)
#: ``--side-length`` of ``calibrate`` and ``report``.
SIDE_LENGTH = Spec(
    "side_length",
    ("--side-length", "-L"),
    TEST,
    "Side of the square path [m]. Logged sources may know it (OptiOdom L, run-log side_length).",
    kind="number",
    unit="m",
    bound=Bound("length", MAX_SIDE_LENGTH),
)

#: ``--tum-time`` of ``calibrate`` and ``replay``.
TUM_TIME = Spec(
    "tum_time",
    ("--tum-time",),
    OUTPUTS,
    "Timestamps of the TUM files: the recording's own clock (bag stamps, run-log time; evo "
    "matches them with other trajectories of the same bag) or seconds from each run's start.",
    kind="choice",
    default="recording",
    choices=("recording", "run"),
)

#: ``--force`` of every command that writes (``force=True``): without it no file is
#: replaced (``OutputPlan``); it lifts nothing else (see :data:`OVERRIDE_VERDICT`).
FORCE = Spec(
    "force",
    ("--force",),
    OUTPUTS,
    "Replace output files that exist, and write into output folders that hold files "
    "(without it, nothing is replaced). Nothing else: see --override-verdict.",
    kind="flag",
)

#: ``--history`` of ``calibrate``, ``selfcal`` and ``history``: the robots' calibration
#: history (SQLite; the default: :func:`umbmark.store.history.default_history_path`).
HISTORY = Spec(
    "history",
    ("--history",),
    OUTPUTS,
    "The history file [default: $UMBMARK_HISTORY, else "
    "$XDG_DATA_HOME/umbmark/history.sqlite3, else ~/.local/share/umbmark/history.sqlite3].",
    kind="file",
)

#: ``--override-verdict`` of ``calibrate``, ``report``, ``replay``, ``validate`` and
#: ``history`` (``override_verdict=True`` of the library): use a result its own checks
#: advise against. Commands say after this text which refusal it lifts there.
OVERRIDE_VERDICT = Spec(
    "override_verdict",
    ("--override-verdict",),
    TEST,
    "Override a refusal that protects the robot's parameters (never needed to replace "
    "files: that is --force).",
    kind="flag",
)

# --- how to read a source (calibrate, replay, report, validate) -----------------------

#: The reading options, in the order ``--help`` lists them.
READ_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "unit",
        ("--unit",),
        TABLE,
        "Unit of the lengths in a runs table.",
        kind="choice",
        default="m",
        choices=("m", "cm", "mm"),
    ),
    Spec(
        "angle_unit",
        ("--angle-unit",),
        TABLE,
        "Unit of the headings in a runs table.",
        kind="choice",
        default="rad",
        choices=("rad", "deg"),
    ),
    Spec(
        "current_params",
        ("--current-params",),
        PARAMETERS,
        "What was active during the runs: a ros2_control (or ROS 1) parameter YAML (its "
        "multipliers, wheel_separation, wheel_radius) or a previous result (calibrate -o) "
        "whose new values were applied. Options below override it.",
        kind="file",
    ),
    Spec(
        "current_c_l",
        ("--current-c-l",),
        PARAMETERS,
        "Left wheel factor c_L active during the runs (ros2_control "
        "left_wheel_radius_multiplier) [default: 1.0, or from --current-params].",
        kind="number",
        bound=_FACTOR,
    ),
    Spec(
        "current_c_r",
        ("--current-c-r",),
        PARAMETERS,
        "Right wheel factor c_R active during the runs [default: 1.0, or from --current-params].",
        kind="number",
        bound=_FACTOR,
    ),
    Spec(
        "current_separation_multiplier",
        ("--current-separation-multiplier",),
        PARAMETERS,
        "wheel_separation_multiplier active during the runs [default: 1.0, or from "
        "--current-params].",
        kind="number",
        bound=_FACTOR,
    ),
    Spec(
        "wheel_diameter",
        ("--wheel-diameter",),
        PARAMETERS,
        "Nominal wheel diameter D_n [m]; for logged runs, overrides the source's.",
        kind="number",
        unit="m",
        bound=Bound("length", MAX_WHEELBASE),
    ),
    Spec(
        "controller",
        ("--controller",),
        PARAMETERS,
        "The diff_drive_controller's name with its namespace (/robot1/diff_cont): parameter "
        "files are read under it, overlays and the history keyed by it [default: the one a "
        "parameter file names, else diff_drive_controller].",
    ),
    Spec(
        "format",
        ("--format", "-f"),
        LOGS,
        "Source format (auto: by the path; tuples: motion intervals of the wheels against a "
        "laser's scan matching, for --method scan-matching).",
        kind="choice",
        default="auto",
        choices=("auto", "table", "log", "optiodom", "bag", "tuples"),
    ),
    Spec(
        "split",
        ("--split",),
        LOGS,
        "How to find runs in a recording: at rests near the start (rests), the whole "
        "recording cut only where its reference was reset (none), or --windows.",
        kind="choice",
        default="rests",
        choices=("rests", "none", "windows"),
    ),
    Spec(
        "windows",
        ("--windows",),
        LOGS,
        "Runs as time windows, seconds from the recording's start: '0:95,100:190'.",
        py_type="str | Sequence[tuple[float, float]]",
    ),
    Spec(
        "max_gap",
        ("--max-gap",),
        LOGS,
        f"Longest ground-truth gap to interpolate across [s], at most {LONGEST_GAP:g}.",
        kind="number",
        default=0.25,
        unit="s",
        bound=Bound("positive", LONGEST_GAP),
    ),
    Spec(
        "min_rest",
        ("--min-rest",),
        LOGS,
        f"Shortest rest between runs [s] (for --split rests), at most {LONGEST_REST:g}.",
        kind="number",
        default=1.0,
        unit="s",
        bound=Bound("positive", LONGEST_REST),
    ),
    Spec(
        "wheel_topic",
        ("--wheel-topic",),
        BAGS,
        "sensor_msgs/JointState topic; with --left-field/--right-field, a topic of any type.",
        default="/joint_states",
    ),
    Spec(
        "left_joint",
        ("--left-joint",),
        BAGS,
        "Left wheel joint, or several separated by commas (averaged, as ros2_control does) "
        "[default: left_wheel_names of --current-params, else left_wheel_joint, else the "
        "moving joints named left].",
        py_type="str | Sequence[str]",
    ),
    Spec(
        "right_joint",
        ("--right-joint",),
        BAGS,
        "Right wheel joint(s) [default: as for --left-joint].",
        py_type="str | Sequence[str]",
    ),
    Spec(
        "odom_topic",
        ("--odom-topic",),
        BAGS,
        "No wheel data? The controller's odometry (nav_msgs/Odometry), turned back into "
        "wheel rotation with the controller's geometry (--current-params, or --wheelbase "
        "and --wheel-diameter).",
    ),
    Spec(
        "odom_tf",
        ("--odom-tf",),
        BAGS,
        "... or the controller's odometry as a /tf chain, e.g. odom base_link.",
        nargs=2,
        metavar="PARENT CHILD",
    ),
    Spec(
        "left_ticks_topic",
        ("--left-ticks-topic",),
        BAGS,
        "Cumulative left encoder counts (std_msgs Int*/UInt*/Float*), instead of JointState.",
    ),
    Spec(
        "right_ticks_topic",
        ("--right-ticks-topic",),
        BAGS,
        "Cumulative right encoder counts.",
    ),
    Spec(
        "left_field",
        ("--left-field",),
        BAGS,
        "Wheel data in a message of any type on --wheel-topic: the field with the left "
        "wheel's angle [rad], or its encoder counts with --ticks-per-rev, e.g. left_ticks, "
        "wheels.left.position, positions[0].",
        metavar="PATH",
        pair="right_field",
    ),
    Spec(
        "right_field",
        ("--right-field",),
        BAGS,
        "... and the right wheel's field.",
        metavar="PATH",
    ),
    Spec(
        "msg_dir",
        ("--msg-dir",),
        BAGS,
        "The .msg files of --wheel-topic's type (<pkg>/msg/<Name>.msg, searched "
        "recursively), for bags that do not carry its definition (ROS 2 sqlite3 bags "
        "before Iron).",
        kind="folder",
        metavar="DIR",
    ),
    Spec(
        "ticks_per_rev",
        ("--ticks-per-rev",),
        BAGS,
        "Encoder counts per wheel revolution (with the ticks topics or fields).",
        kind="number",
        bound=Bound("positive"),
    ),
    Spec(
        "left_wheel_frame",
        ("--left-wheel-frame",),
        BAGS,
        "No wheel joint states? The left wheel's frame on /tf (its transform from the "
        "base, e.g. wheel_left_link from robot_state_publisher): its rotation.",
        metavar="FRAME",
        pair="right_wheel_frame",
    ),
    Spec(
        "right_wheel_frame",
        ("--right-wheel-frame",),
        BAGS,
        "... and the right.",
        metavar="FRAME",
    ),
    Spec(
        "scan_topic",
        ("--scan-topic",),
        BAGS,
        "A sensor_msgs/LaserScan topic (calibrate only): the wheels are calibrated against the "
        "laser's scan matching (--method scan-matching: both wheel diameters, the wheelbase "
        "and the laser's mounting from ordinary driving; no ground truth needed).",
        metavar="TOPIC",
    ),
    Spec(
        "imu_topic",
        ("--imu-topic",),
        BAGS,
        "A sensor_msgs/Imu topic: the gyro, its rates put into the base frame by its frame's "
        "mounting (/tf_static, /tf or the robot description).",
        metavar="TOPIC",
    ),
    Spec(
        "truth_topic",
        ("--truth-topic",),
        BAGS,
        "Ground truth: geometry_msgs/PoseStamped, PoseWithCovarianceStamped, "
        "nav_msgs/Odometry or gazebo_msgs/ModelStates; or positions only: "
        "geometry_msgs/PointStamped, sensor_msgs/NavSatFix (for paper, exact, endpose).",
    ),
    Spec(
        "truth_model",
        ("--truth-model",),
        BAGS,
        "With a gazebo_msgs/ModelStates ground truth: the robot's model [default: the one "
        "model that moves].",
        metavar="NAME",
    ),
    Spec(
        "tf_parent",
        ("--tf-parent",),
        BAGS,
        "Ground truth from /tf and /tf_static instead: the parent frame (e.g. map); any "
        "chain of transforms to the child is followed and interpolated in time.",
    ),
    Spec(
        "tf_child",
        ("--tf-child",),
        BAGS,
        "... and the child frame (e.g. base_link).",
    ),
    Spec(
        "truth_offset",
        ("--truth-offset",),
        LOGS,
        "The ground truth tracks a point X forward and Y left of the axle centre [m] (a "
        "marker, an antenna): move it to the axle centre. Left in place, it adds "
        "(R(dtheta) - I)(X, Y) to every return error.",
        kind="number",
        unit="m",
        bound=Bound("offset", MAX_TRUTH_OFFSET),
        nargs=2,
        metavar="X Y",
    ),
    Spec(
        "time_source",
        ("--time-source",),
        BAGS,
        "Message header stamps (where they have them) or bag receive times.",
        kind="choice",
        default="header",
        choices=("header", "bag"),
    ),
    Spec(
        "gyro_scale_tolerance",
        ("--gyro-scale-tolerance",),
        BAGS,
        "With an IMU and no heading reference: how far the gyro's scale may be off, as a "
        "fraction (MEMS datasheets: 0.03 for +-3 % at 25 C); E_b is then relative to the gyro "
        "and its interval is widened by this.",
        kind="number",
        default=0.03,
        bound=Bound("range", low=0.0, high=0.2),
    ),
)

#: The reading options by keyword.
READ: dict[str, Spec] = {spec.name: spec for spec in READ_OPTIONS}

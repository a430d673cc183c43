"""What the ROS 1 and ROS 2 monitor nodes share, without ROS (tested without it).

- **Options as ROS parameters** (the one place they are mapped): every option of
  ``umbmark monitor`` is also a parameter of the node ``umbmark_monitor`` under its keyword
  (``corrected_odom``, ``scan_topic``, ...), taken by the option's spec (:class:`Spec`:
  its kind, its choices, its bound): ROS 2 ``--ros-args -p name:=value`` or ``--ros-args
  --params-file f.yaml``, ROS 1 private parameters ``_name:=value`` (or ``<param>`` in a
  launch file's ``<node>``). :func:`split_ros_args` takes them out of the command line
  before click sees it; :func:`parameter_values` turns what the node holds into option
  values; an option given on the command line wins over a parameter.
- **The node's own options** (:data:`NODE_OPTIONS`, :class:`NodeOptions`): which topics,
  frames, the controller and its parameter file, the corrected odometry's topic, how long
  a topic may be silent, whether to apply at rest. The reading options of the same name
  (``odom_topic``, ``scan_topic``, ``imu_topic``, ``wheel_topic``, ``left_joint``,
  ``right_joint``, ``controller``) are the ones of :data:`umbmark.options.spec.READ`.
- **Messages to the core's values**: the wheels' angles from joint states
  (:func:`wheel_angles`), the gyro's yaw rate in the base frame (:func:`base_yaw_rate`).
- The loop that feeds the core and publishes once a second is
  :mod:`umbmark.monitor.node_loop`. The monitor publishes no velocity: it never commands
  the robot.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

from umbmark.core.errors import InputError
from umbmark.options.checks import Bound
from umbmark.options.spec import READ, Spec
from umbmark.robot.base import Pose2D
from umbmark.robot.ros_common import Mount

__all__ = ["INPUT_QUEUE", "NODE_OPTIONS", "ROS_SECTION", "NodeOptions", "RosArgv"]
__all__ += ["base_yaw_rate"]
__all__ += ["node_options", "parameter_values", "split_ros_args", "wheel_angles"]

#: The section of ``umbmark monitor --help`` listing the node's options.
ROS_SECTION = "On the robot (ROS 1, ROS 2)"
#: The joint names ros2_control's and Gazebo's diff-drive examples use.
DEFAULT_JOINTS = ("left_wheel_joint", "right_wheel_joint")
#: Longest ``stale_after`` [s].
LONGEST_SILENCE = 600.0
#: How deep the subscriptions' queues are (the publishers' are 10): the core matches a
#: chunk of driving inside the wheels' callback (a tenth of a second of CPU or more, the
#: ROS 2 node's other callbacks waiting behind it), and 10 deep a 50 Hz topic would lose
#: the messages of those moments (a simulation run faster loses more); 100 hold 2 s of
#: 50 Hz wheels. Bounded: nothing grows over days.
INPUT_QUEUE = 100

#: The node's options of its own (the reading options it shares are :data:`READ`'s).
NODE_OPTIONS: tuple[Spec, ...] = (
    Spec("base_frame", ("--base-frame",), ROS_SECTION, "The robot's base frame.",
         default="base_link"),
    Spec("robot", ("--robot",), ROS_SECTION,
         "The robot's name: the diagnostic's hardware_id and its history [default: the ROS "
         "namespace, else the host's name]."),
    Spec("corrected_odom", ("--corrected-odom",), ROS_SECTION,
         "Publish the odometry integrated from the wheels with the present calibration on "
         "this topic (nav_msgs/Odometry, the controller's frames and covariance).",
         metavar="TOPIC"),
    Spec("corrected_tf", ("--corrected-tf",), ROS_SECTION,
         "With --corrected-odom, also publish its odom -> base transform on /tf (turn the "
         "controller's own enable_odom_tf off).", kind="flag", default=False),
    Spec("apply", ("--apply",), ROS_SECTION,
         "at-rest: apply a confirmed change its verdict allows once the robot has rested "
         "(through set_parameters and the controller manager, dynamic_reconfigure, or the "
         "--params-file edited in place); never: only say it.",
         kind="choice", default="never", choices=("never", "at-rest")),
    Spec("params_file", ("--params-file",), ROS_SECTION,
         "The YAML the controller loads: applying writes the new multipliers into it in "
         "place (every other byte kept; the previous file kept as FILE.bak).", kind="file"),
    Spec("reload", ("--reload",), ROS_SECTION,
         "ROS 2: apply through the controller manager (deactivate, configure, activate; "
         "Rolling: unload and load with --params-file appended); needs "
         "controller_manager_msgs.", kind="flag", default=False),
    Spec("laser_mount", ("--laser-mount",), ROS_SECTION,
         "The laser's mounting in the base frame, x,y,yaw (metres, degrees) [default: "
         "/tf_static, else the URDF on /robot_description].", metavar="X,Y,YAW"),
    Spec("stale_after", ("--stale-after",), ROS_SECTION,
         f"A topic silent this long [s, wall clock] is said STALE (at most "
         f"{LONGEST_SILENCE:g} s).", kind="number", default=3.0, unit="s",
         bound=Bound("positive", LONGEST_SILENCE)),
    Spec("timeout", ("--timeout",), ROS_SECTION,
         "How long to wait for the robot's first messages and for services [s].",
         kind="number", default=10.0, unit="s", bound=Bound("positive", 600.0)),
)  # fmt: skip

#: The reading options the node takes too, by their keywords (:data:`READ`).
SHARED: tuple[str, ...] = ("controller", "odom_topic", "wheel_topic", "left_joint", "right_joint")
SHARED += ("scan_topic", "imu_topic")


# --- the command line and ROS parameters ---------------------------------------------------


@dataclass(frozen=True)
class RosArgv:
    """A command line split: ``own`` for click, ``ros2`` (``--ros-args ...``, without
    the closing ``--``) and ``ros1`` (``name:=value`` remaps, ``_name:=value`` private
    parameters, ``__name:=`` and ``__log:=`` as roslaunch adds them)."""

    own: tuple[str, ...]
    ros2: tuple[str, ...]
    ros1: tuple[str, ...]


def _ros1_token(token: str) -> bool:
    name, sep, _ = token.partition(":=")
    return bool(sep) and bool(name) and not name.startswith("-")


def split_ros_args(argv: Sequence[str]) -> RosArgv:
    """``argv`` (without the program) split into umbmark's own arguments and ROS's: every
    ``--ros-args`` up to the next ``--`` (or the end) is ROS 2's; a ``name:=value`` token
    outside them is ROS 1's (its remaps and private parameters)."""
    own: list[str] = []
    ros2: list[str] = []
    ros1: list[str] = []
    inside = False
    for token in argv:
        if inside:
            if token == "--":
                inside = False
            elif token != "--ros-args":
                ros2.append(token)
        elif token == "--ros-args":
            inside = True
        elif _ros1_token(token):
            ros1.append(token)
        else:
            own.append(token)
    return RosArgv(tuple(own), tuple(ros2), tuple(ros1))


def _specs(specs: Iterable[Spec]) -> dict[str, Spec]:
    return {spec.name: spec for spec in specs}


def _convert(spec: Spec, value: object, source: str) -> object:
    """A parameter's value as the option takes it (a ROS parameter comes typed: a YAML
    number, a bool, a string; ROS 1's ``_name:=value`` is YAML too)."""
    named = f"parameter {spec.name} ({source})"
    if spec.kind == "flag":
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.lower() in ("true", "false"):
            return value.lower() == "true"
        raise InputError(f"{named}: give true or false, not {value!r}"[:200])
    if spec.kind in ("number", "integer"):
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise InputError(f"{named}: give a number, not {value!r}"[:200])
        try:
            number = float(value)
        except ValueError:
            raise InputError(f"{named}: give a number, not {value!r}"[:200]) from None
        if spec.kind == "integer":
            if not number.is_integer():
                raise InputError(f"{named}: give a whole number, not {value!r}"[:200])
            return int(number)
        return number
    if isinstance(value, (list, tuple)) and spec.py_type.endswith("Sequence[str]"):
        return ",".join(str(v) for v in value)
    if isinstance(value, (bool, list, tuple, dict)) or value is None:
        raise InputError(f"{named}: give a text, not {value!r}"[:200])
    return str(value)


def parameter_values(
    parameters: Mapping[str, object], specs: Iterable[Spec], source: str
) -> dict[str, object]:
    """The node's parameters as option values by keyword, each converted and checked by
    its spec (``source``: where they came from, for the message).

    Parameters the node holds for ROS itself (``use_sim_time``, diagnostic_updater's
    ``diagnostic_updater.*``, ROS 1's ``~`` bookkeeping) are left out.

    Raises
    ------
    InputError
        A parameter no option has (the message lists those there are), or a value its
        option refuses.
    """
    known = _specs(specs)
    values: dict[str, object] = {}
    for name, value in parameters.items():
        if name in ("use_sim_time", "start_type_description_service") or "." in name:
            continue
        spec = known.get(name)
        if spec is None:
            raise InputError(
                f"parameter {name!r} ({source}): umbmark_monitor has no such option; its "
                f"parameters are {', '.join(sorted(known))}"[:600]
            )
        converted = _convert(spec, value, source)
        spec.check(converted, source)
        values[name] = converted
    return values


# --- the node's options ---------------------------------------------------------------------


@dataclass(frozen=True)
class NodeOptions:
    """What the node subscribes and publishes, and how it applies.

    Attributes
    ----------
    odom_topic : str
        The controller's odometry (``nav_msgs/Odometry``): its frames are the corrected
        odometry's, and where no wheel joint states come its poses are the wheels.
    wheel_topic : str
        ``sensor_msgs/JointState`` with the wheels (``left_joints``, ``right_joints``;
        empty: ``left_wheel_joint``/``right_wheel_joint``, else the one joint named left
        and the one named right).
    scan_topic, imu_topic : str or None
        The laser (``sensor_msgs/LaserScan``) and the IMU (``sensor_msgs/Imu``); None: not
        subscribed.
    base_frame, controller, robot : str
        The base frame; the controller's namespace; the robot's name (hardware_id).
    corrected_odom : str or None
        Where the corrected odometry goes (None: not published); ``corrected_tf`` with it,
        its transform too.
    apply : {"never", "at-rest"}
    params_file : str or None
    reload : bool
    laser_mount : Pose2D or None
    stale_after, timeout : float
        [s], wall clock.
    """

    odom_topic: str = ""
    wheel_topic: str = "/joint_states"
    left_joints: tuple[str, ...] = ()
    right_joints: tuple[str, ...] = ()
    scan_topic: str | None = "/scan"
    imu_topic: str | None = "/imu"
    base_frame: str = "base_link"
    controller: str = "/diff_drive_controller"
    robot: str = ""
    corrected_odom: str | None = None
    corrected_tf: bool = False
    apply: Literal["never", "at-rest"] = "never"
    params_file: str | None = None
    reload: bool = False
    laser_mount: Pose2D | None = None
    stale_after: float = 3.0
    timeout: float = 10.0

    def topics(self) -> tuple[str, ...]:
        """The topics whose silence is said (the wheels' is the odometry or the joint
        states, whichever speaks)."""
        return tuple(t for t in (self.scan_topic, self.imu_topic) if t)


def _joints(value: object) -> tuple[str, ...]:
    if value is None or value == "":
        return ()
    if isinstance(value, str):
        return tuple(v.strip() for v in value.split(",") if v.strip())
    return tuple(str(v) for v in value)  # type: ignore[attr-defined]


def node_options(values: Mapping[str, object], robot: str = "") -> NodeOptions:
    """The node's options from option values by keyword (the command line's, with the
    ROS parameters filling in what it did not give): those not there keep their specs'
    defaults. ``robot``: the name where none is given. Each value is checked by its spec.
    """
    from umbmark.robot.ros_common import laser_mount

    specs = {**_specs(NODE_OPTIONS), **{name: READ[name] for name in SHARED}}
    got: dict[str, object] = {}
    for name, spec in specs.items():
        value = values.get(name, spec.default)
        spec.check(value)
        got[name] = value

    def text(name: str) -> str | None:
        value = got[name]
        return None if value in (None, "", "none") else str(value)

    mount = text("laser_mount")
    return NodeOptions(
        odom_topic=text("odom_topic") or "",
        wheel_topic=text("wheel_topic") or "/joint_states",
        left_joints=_joints(got["left_joint"]),
        right_joints=_joints(got["right_joint"]),
        scan_topic=text("scan_topic") if "scan_topic" in values else "/scan",
        imu_topic=text("imu_topic") if "imu_topic" in values else "/imu",
        base_frame=text("base_frame") or "base_link",
        controller=text("controller") or "/diff_drive_controller",
        robot=text("robot") or robot or "robot",
        corrected_odom=text("corrected_odom"),
        corrected_tf=bool(got["corrected_tf"]),
        apply="at-rest" if got["apply"] == "at-rest" else "never",
        params_file=text("params_file"),
        reload=bool(got["reload"]),
        laser_mount=None if mount is None else laser_mount(mount),
        stale_after=float(got["stale_after"]),  # type: ignore[arg-type]
        timeout=float(got["timeout"]),  # type: ignore[arg-type]
    )


# --- messages to the core's values ---------------------------------------------------------


def wheel_angles(
    names: Sequence[str],
    positions: Sequence[float],
    left: Sequence[str] = (),
    right: Sequence[str] = (),
) -> tuple[float, float] | None:
    """The left and right wheels' angles [rad] from a ``sensor_msgs/JointState``: the mean
    of ``left``'s and of ``right``'s joints (several per side on a skid-steer, as
    ros2_control averages them); not given, ``left_wheel_joint`` and ``right_wheel_joint``,
    else the one joint named ``left`` and the one named ``right``. None: the message does
    not hold them all, or one is not finite (a message of other joints)."""
    if len(positions) != len(names):
        return None
    by_name = dict(zip(names, positions, strict=True))
    if not (left and right):
        if set(DEFAULT_JOINTS) <= set(by_name):
            left, right = (DEFAULT_JOINTS[0],), (DEFAULT_JOINTS[1],)
        else:
            lefts = [n for n in by_name if "left" in n.lower() and "wheel" in n.lower()]
            rights = [n for n in by_name if "right" in n.lower() and "wheel" in n.lower()]
            if len(lefts) != 1 or len(rights) != 1:
                return None
            left, right = tuple(lefts), tuple(rights)
    if not all(n in by_name for n in (*left, *right)):
        return None
    sides = [sum(float(by_name[n]) for n in side) / len(side) for side in (left, right)]
    if not all(math.isfinite(v) for v in sides):
        return None
    return sides[0], sides[1]


def base_yaw_rate(angular_velocity: Sequence[float], mount: Mount | None) -> float:
    """The gyro's rate about the base frame's z axis [rad/s] from the IMU's
    ``angular_velocity`` (x, y, z in its own frame) and its mounting (None: the IMU's
    frame is the base's): the last row of ``Rz(yaw) Ry(pitch) Rx(roll)`` times the rates,
    ``-sin(p) wx + cos(p) sin(r) wy + cos(p) cos(r) wz`` (the yaw does not enter)."""
    wx, wy, wz = (float(v) for v in angular_velocity)
    if mount is None:
        return wz
    if mount.lift is None:
        return -wz if mount.upside_down else wz
    _, roll, pitch = mount.lift
    return (
        -math.sin(pitch) * wx
        + math.cos(pitch) * math.sin(roll) * wy
        + math.cos(pitch) * math.cos(roll) * wz
    )

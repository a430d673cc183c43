"""What the ROS 1 and ROS 2 adapters share: their options, and everything that does not
need ``rospy`` or ``rclpy`` (so it is tested without them).

Defaults are what a ROS robot usually has: ``/cmd_vel``, ``/odom``, ``/scan``, the
controller at ``/diff_drive_controller``, frames from ``/tf`` and ``/tf_static``.

- Messages become the interface's values (:mod:`umbmark.robot.base`): stamps in seconds
  of ROS time, planar poses (the yaw of the quaternion), scans and ranges with their
  sensors' mountings from TF (a laser mounted upside down has its beams mirrored).
- :class:`Latest` holds the latest message of a topic for the control loop.
- :func:`wait_on_clock` lets ROS time pass (sim time too), refusing to hang when the
  clock stops.
- Applying parameters: :func:`plan_apply` decides how (dynamic_reconfigure takes only
  ``0.5 .. 1.5``: outside, the YAML file is written and the result says so),
  :func:`write_params` changes the controller's parameter file in place (every
  other byte kept, the previous file kept beside it), and
  :func:`held_problem` checks what a reconfigure server holds afterwards (it clamps
  without a word).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.core.geometry import quaternion_yaw
from umbmark.robot.base import ApplyMethod, DriveParams, Pose2D, RangeReading, ScanSweep

if TYPE_CHECKING:
    from umbmark.sources.params.edit import ParamsEdit

__all__ = [
    "MULTIPLIERS",
    "RECONFIGURE_RANGE",
    "ApplyPlan",
    "Latest",
    "Mount",
    "RosOptions",
    "controller_keys",
    "default_topics",
    "held_problem",
    "laser_mount",
    "lift_of",
    "master_problem",
    "mount_from_transform",
    "multipliers",
    "plan_apply",
    "planar_pose",
    "range_reading",
    "restart_commands",
    "scan_from_message",
    "stamp_seconds",
    "wait_on_clock",
    "write_params",
]

#: ros_controllers' ``DiffDriveController.cfg`` bounds the three multipliers to this; a
#: dynamic_reconfigure server clamps values outside it without a word.
RECONFIGURE_RANGE = (0.5, 1.5)

#: The multipliers' parameter names (``DriveParams`` fields of the same names).
MULTIPLIERS = (
    "wheel_separation_multiplier",
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
)


@dataclass(frozen=True)
class RosOptions:
    """How to reach a ROS robot.

    Attributes
    ----------
    cmd_vel, odom : str
        The velocity command topic (``geometry_msgs/Twist``, or ``TwistStamped`` where the
        controller takes that) and the odometry topic (``nav_msgs/Odometry``); empty: the
        default (:func:`default_topics`).
    scan : str or None
        The laser scan topic (``sensor_msgs/LaserScan``); its mounting comes from TF.
    ranges : tuple of str
        Three ``sensor_msgs/Range`` topics (two facing one wall, one the other), their
        mountings from TF.
    truth : str or None
        A ground-truth pose topic (``geometry_msgs/PoseStamped``, motion capture).
    base_frame : str
        The robot's base frame (``base_link``).
    controller : str
        The diff_drive_controller's namespace (its parameters and its dynamic_reconfigure
        server).
    params_file : str or None
        The YAML file the controller loads its parameters from (``--apply yaml`` writes the
        new multipliers into it, atomically).
    wheel_separation, wheel_radius : float or None
        The controller's nominal geometry [m], where its parameters cannot be read.
    reload : bool
        ROS 2: apply new multipliers through the controller manager (set them, deactivate,
        configure, activate; where they are read-only, unload and load the controller with
        ``params_file`` appended to its parameter files): :mod:`umbmark.robot.ros2_reload`.
    timeout : float
        How long to wait for the first message of each topic and for services [s].
    laser_mount : Pose2D or None
        The laser's mounting in the base frame, where neither TF nor the URDF gives it.
    imu : str or None
        The IMU's topic (``sensor_msgs/Imu``); empty: the one found on the graph
        (:func:`umbmark.robot.ros_imu.pick_imu`), where there is one; None: no IMU used.
    """

    cmd_vel: str = ""
    odom: str = ""
    scan: str | None = "/scan"
    ranges: tuple[str, ...] = ()
    truth: str | None = None
    base_frame: str = "base_link"
    controller: str = "/diff_drive_controller"
    params_file: str | None = None
    wheel_separation: float | None = None
    wheel_radius: float | None = None
    reload: bool = False
    timeout: float = 5.0
    laser_mount: Pose2D | None = None
    imu: str | None = ""


def default_topics(options: RosOptions, *, ros2: bool) -> RosOptions:
    """``options`` with its empty topics filled in: ROS 2's diff_drive_controller has its
    topics in its namespace (``<controller>/cmd_vel``, ``<controller>/odom``); on ROS 1
    they are usually remapped to ``/cmd_vel`` and ``/odom``."""
    from dataclasses import replace

    ns = "/" + "/".join(controller_keys(options.controller)) if ros2 else ""
    return replace(
        options,
        cmd_vel=options.cmd_vel or f"{ns}/cmd_vel",
        odom=options.odom or f"{ns}/odom",
    )


def laser_mount(text: str) -> Pose2D:
    """``--laser-mount x,y,yaw`` (metres, metres, degrees) as a pose in the base frame."""
    try:
        x, y, yaw = (float(v) for v in text.split(","))
    except ValueError:
        raise InputError(
            f"{option('laser_mount', repr(text[:60]))}: give x,y,yaw (metres, metres, degrees)"
        ) from None
    if not all(math.isfinite(v) and abs(v) < 100.0 for v in (x, y)) or not math.isfinite(yaw):
        raise InputError(f"{option('laser_mount', repr(text[:60]))}: give finite x, y within 100 m")
    return Pose2D(x, y, math.radians(yaw))


# --- messages -----------------------------------------------------------------------------


def stamp_seconds(stamp: object) -> float:
    """A message stamp in seconds: ROS 1's ``secs``/``nsecs`` or ROS 2's ``sec``/``nanosec``."""
    secs = getattr(stamp, "secs", None)
    if secs is not None:
        return float(secs) + 1e-9 * float(getattr(stamp, "nsecs", 0))
    sec = getattr(stamp, "sec", None)
    if sec is not None:
        return float(sec) + 1e-9 * float(getattr(stamp, "nanosec", 0))
    raise InputError(f"a stamp without seconds: {stamp!r}"[:200])


def _xyzw(q: object) -> tuple[float, float, float, float]:
    """A quaternion's components, normalized."""
    x, y, z, w = (float(getattr(q, k)) for k in "xyzw")
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not (norm > 1e-6 and math.isfinite(norm)):
        raise InputError(f"a rotation quaternion of length {norm:g} (x y z w {x} {y} {z} {w})")
    return x / norm, y / norm, z / norm, w / norm


def _position_rotation(msg: object) -> tuple[object, object]:
    """The position and rotation of a pose or transform message, however deep it sits:
    ``Pose``, ``PoseStamped``, ``PoseWithCovariance(Stamped)``, ``Odometry``,
    ``Transform``, ``TransformStamped``."""
    for _ in range(4):
        if hasattr(msg, "position") and hasattr(msg, "orientation"):
            return msg.position, msg.orientation
        if hasattr(msg, "translation") and hasattr(msg, "rotation"):
            return msg.translation, msg.rotation
        inner = getattr(msg, "pose", None)
        if inner is None:
            inner = getattr(msg, "transform", None)
        if inner is None:
            break
        msg = inner
    raise InputError(f"a message with no pose: {type(msg).__name__}")


def planar_pose(msg: object) -> Pose2D:
    """The planar pose of a pose or transform message: ``x, y`` [m] and the yaw [rad] of
    its quaternion (:func:`umbmark.core.geometry.quaternion_yaw`)."""
    position, rotation = _position_rotation(msg)
    x, y, z, w = _xyzw(rotation)
    return Pose2D(float(position.x), float(position.y), float(quaternion_yaw(x, y, z, w)))  # type: ignore[attr-defined]


@dataclass(frozen=True)
class Mount:
    """A sensor's mounting in the robot's base frame, from TF.

    Attributes
    ----------
    pose : Pose2D
        Where the sensor is and where its x axis points, in the base frame.
    upside_down : bool
        The sensor's z axis points down: its angles run clockwise seen from above.
    lift : (float, float, float) or None
        Its height and tilt ``z, roll, pitch`` [m, rad, rad] (fixed axes, yaw last: the
        URDF's ``rpy``); None where only the planar mounting is known (``--laser-mount``).
    """

    pose: Pose2D
    upside_down: bool = False
    lift: tuple[float, float, float] | None = None


def lift_of(z: float, last_row: Sequence[float]) -> tuple[float, float, float]:
    """``z, roll, pitch`` of a frame at height ``z`` [m] whose rotation ``r = Rz(yaw)
    Ry(pitch) Rx(roll)`` has the last row ``last_row`` (``r[2, :]``, (3,)): its fixed-axis
    roll and pitch, pitch within +-90 degrees (so that the yaw is the direction of the
    frame's x axis)."""
    r20, r21, r22 = (float(v) for v in last_row)
    return float(z), math.atan2(r21, r22), math.atan2(-r20, math.hypot(r21, r22))


def mount_from_transform(transform: object) -> Mount:
    """The mounting from a TF lookup ``base_frame <- sensor frame`` (a ``Transform`` or
    ``TransformStamped``): its translation, the direction of the sensor's x axis, and
    whether it is mounted upside down (its z axis below the plane)."""
    position, rotation = _position_rotation(transform)
    x, y, z, w = _xyzw(rotation)
    z_up = 1.0 - 2.0 * (x * x + y * y)  # the z component of the sensor's z axis
    pose = Pose2D(float(position.x), float(position.y), float(quaternion_yaw(x, y, z, w)))  # type: ignore[attr-defined]
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    last_row = (2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y))
    lift = lift_of(float(position.z), last_row)  # type: ignore[attr-defined]
    return Mount(pose, upside_down=z_up < 0.0, lift=lift)


def scan_from_message(msg: object, mount: Mount, base: str = "") -> ScanSweep:
    """A ``sensor_msgs/LaserScan`` as a :class:`~umbmark.robot.base.ScanSweep` with its
    mounting in the frame ``base``; a laser mounted upside down has its beams reversed, so
    that angles run counter-clockwise in the base frame again."""
    ranges = np.asarray(msg.ranges, dtype=np.float64)  # type: ignore[attr-defined]
    angle_min = float(msg.angle_min)  # type: ignore[attr-defined]
    increment = float(msg.angle_increment)  # type: ignore[attr-defined]
    if mount.upside_down:
        angle_min = -(angle_min + increment * (ranges.size - 1))
        ranges = ranges[::-1].copy()
    return ScanSweep(
        time=stamp_seconds(msg.header.stamp),  # type: ignore[attr-defined]
        angle_min=angle_min,
        angle_increment=increment,
        ranges=ranges,
        range_min=float(msg.range_min),  # type: ignore[attr-defined]
        range_max=float(msg.range_max),  # type: ignore[attr-defined]
        mount=mount.pose,
        lift=mount.lift,
        frame=str(msg.header.frame_id).lstrip("/"),  # type: ignore[attr-defined]
        base=base.lstrip("/"),
    )


def range_reading(messages: Sequence[object], mounts: Sequence[Mount]) -> RangeReading:
    """The latest ``sensor_msgs/Range`` of each sensor as one reading: a range outside the
    sensor's ``min_range .. max_range`` (or not finite) is no echo (NaN); the time is the
    latest stamp."""
    values = []
    for msg in messages:
        r = float(msg.range)  # type: ignore[attr-defined]
        low, high = float(msg.min_range), float(msg.max_range)  # type: ignore[attr-defined]
        values.append(r if math.isfinite(r) and low <= r <= high else math.nan)
    times = [stamp_seconds(m.header.stamp) for m in messages]  # type: ignore[attr-defined]
    return RangeReading(
        time=max(times),
        ranges=np.asarray(values, dtype=np.float64),
        mounts=tuple(m.pose for m in mounts),
    )


# --- the latest message of a topic, and ROS time --------------------------------------------

T = TypeVar("T")


class Latest(Generic[T]):
    """The latest message of a topic, thread-safe: a subscriber's callback :meth:`put`s,
    the control loop :meth:`get`s. Keeps the wall time it came (:attr:`received`)."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._value: T | None = None
        self._received: float | None = None
        self._count = 0

    def put(self, value: T) -> None:
        """Keep ``value`` as the latest (called from the subscriber's thread)."""
        with self._cond:
            self._value = value
            self._received = time.monotonic()
            self._count += 1
            self._cond.notify_all()

    def get(self) -> T | None:
        """The latest value, None before the first."""
        with self._cond:
            return self._value

    @property
    def received(self) -> float | None:
        """When the latest came (``time.monotonic()`` [s]), None before the first."""
        with self._cond:
            return self._received

    @property
    def count(self) -> int:
        """How many came."""
        with self._cond:
            return self._count

    def wait(self, timeout: float) -> T | None:
        """The latest value, waiting up to ``timeout`` wall seconds for a first one."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._value is None:
                left = deadline - time.monotonic()
                if left <= 0.0:
                    break
                self._cond.wait(left)
            return self._value


def wait_on_clock(
    now: Callable[[], float],
    duration: float,
    ticks: threading.Condition,
    stall: float,
    slice_: float = 0.05,
) -> None:
    """Let ``duration`` seconds of ROS time pass.

    ``now`` reads ROS time; ``ticks`` is notified whenever it changes (the clock's
    condition). The time is checked with ``ticks`` held, so a tick between the check and
    the wait is not missed.

    Raises
    ------
    InputError
        The clock stood still for ``stall`` wall seconds (a paused simulation, no
        ``/clock``), or went backwards (a restarted simulation).
    """
    if not (0.0 <= duration < math.inf):
        raise InputError(f"wait {duration!r} s: give a time from 0 s")
    start = now()
    end = start + duration
    last, last_wall = start, time.monotonic()
    with ticks:
        while True:
            t = now()
            if t >= end:
                return
            wall = time.monotonic()
            if t < last:
                raise InputError(
                    f"ROS time went back from {last:.3f} s to {t:.3f} s: was the simulation "
                    "restarted?"
                )
            if t > last:
                last, last_wall = t, wall
            elif wall - last_wall > stall:
                raise InputError(
                    f"ROS time stopped at {t:.3f} s for {stall:g} s: is the simulation "
                    "paused, or /clock not published?"
                )
            ticks.wait(min(slice_, max(end - t, 0.001)))


def master_problem(uri: str, timeout: float) -> str | None:
    """Why the ROS 1 master at ``uri`` cannot be used (None: it answers ``getPid`` within
    ``timeout`` seconds). rospy itself would wait for it forever."""
    import http.client
    import xmlrpc.client
    from urllib.parse import urlparse

    parsed = urlparse(uri)
    if parsed.scheme != "http" or not parsed.hostname:
        return f"ROS_MASTER_URI {uri!r} is not an http:// address"

    class _Transport(xmlrpc.client.Transport):
        def make_connection(self, host: Any) -> http.client.HTTPConnection:  # noqa: ANN401
            connection = super().make_connection(host)
            connection.timeout = timeout
            return connection

    try:
        with xmlrpc.client.ServerProxy(uri, transport=_Transport()) as proxy:
            answer = proxy.getPid("/umbmark")
    except (OSError, xmlrpc.client.Error, http.client.HTTPException) as exc:
        reason = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
        return f"no ROS master at {uri} ({reason}): start roscore, or set ROS_MASTER_URI"
    if not (isinstance(answer, list) and len(answer) == 3 and answer[0] == 1):
        return f"the ROS master at {uri} answers {answer!r}"[:300]
    return None


# --- applying parameters ----------------------------------------------------------------


def multipliers(params: DriveParams) -> dict[str, float]:
    """The three multipliers of ``params`` by their parameter names."""
    return {name: float(getattr(params, name)) for name in MULTIPLIERS}


@dataclass(frozen=True)
class ApplyPlan:
    """How parameters are applied: ``method``, and why it is not the one asked for
    (empty when it is)."""

    method: ApplyMethod
    reason: str = ""


def plan_apply(params: DriveParams, method: ApplyMethod) -> ApplyPlan:
    """Reconfigure when asked and every multiplier is within :data:`RECONFIGURE_RANGE`;
    outside it, write the YAML instead (the server would clamp).

    Raises
    ------
    InputError
        A multiplier that is not a positive number.
    """
    if method == "none":
        return ApplyPlan("none", "parameters not applied (apply: none)")
    values = multipliers(params)
    for name, value in values.items():
        if not (0.0 < value < math.inf):
            raise InputError(f"{name} {value!r} is not a positive number")
    if method == "yaml":
        return ApplyPlan("yaml")
    low, high = RECONFIGURE_RANGE
    outside = [f"{n} {v:.6g}" for n, v in values.items() if not low <= v <= high]
    if not outside:
        return ApplyPlan("reconfigure")
    return ApplyPlan(
        "yaml",
        f"{', '.join(outside)} outside {low:g} to {high:g}, which dynamic_reconfigure "
        "clamps: not reconfigured",
    )


def held_problem(requested: DriveParams, held: Mapping[str, object]) -> str | None:
    """What differs between the multipliers asked for and those a reconfigure server holds
    (None: all three as asked, to 1e-9)."""
    problems = []
    for name, value in multipliers(requested).items():
        got = held.get(name)
        if not isinstance(got, (int, float)) or isinstance(got, bool):
            problems.append(f"holds no {name}")
        elif not abs(float(got) - value) <= 1e-9 * max(1.0, abs(value)):
            problems.append(f"holds {name} {float(got):.10g}, not {value:.10g}")
    if not problems:
        return None
    return "the controller " + "; ".join(problems) + " (a reconfigure server clamps to its bounds)"


def controller_keys(controller: str) -> tuple[str, ...]:
    """The keys of a controller's block in a parameter file, outermost first:
    ``/robot1/diff_drive_controller`` is ``robot1: diff_drive_controller:``."""
    keys = tuple(k for k in controller.strip().split("/") if k)
    if not keys:
        raise InputError(
            f"controller {controller!r}: give its namespace, e.g. /diff_drive_controller"
        )
    return keys


def write_params(
    path: str | Path, params: DriveParams, controller: str, *, ros2: bool
) -> ParamsEdit:
    """Write the multipliers of ``params`` into the controller's parameter file.

    A file that exists is changed in place: the three values of the controller's block
    (as :func:`umbmark.sources.params.reader.read_controller_params` finds it, in the
    file's own form), a missing one added, ROS 1's ``wheel_radius_multiplier`` removed
    (it would override both wheels'), every other byte kept, the previous file kept as
    ``FILE.bak`` (``.bak.2``, ...), the new one written atomically
    (:func:`umbmark.sources.params.edit.edit_parameter_file`). A new file holds the
    controller's block only: ROS 1 ``diff_drive_controller: {wheel_separation_multiplier:
    ...}`` (the namespace's keys, as ``rosparam load`` reads it), ROS 2 the ros2_control
    overlay ``diff_drive_controller: {ros__parameters: {...}}``. Values are doubles
    (``1.0``).

    Returns
    -------
    ParamsEdit
        What was changed, with the line for people (:meth:`ParamsEdit.line`).

    Raises
    ------
    InputError
        The file cannot be read as a parameter file, changed in place, or written.
    """
    from umbmark.sources.params.edit import edit_parameter_file

    controller_keys(controller)  # a name, not an empty one
    return edit_parameter_file(path, multipliers(params), controller, ros2=ros2)


def restart_commands(controller: str, params: DriveParams, overlay: str | None) -> str:
    """How a person restarts a ROS 2 diff_drive_controller on new multipliers (it reads
    them only when configured): the overlay as a further parameter file of its spawner
    or launch file (later files override), or the three values in the launch file."""
    name = controller_keys(controller)[-1]
    values = ", ".join(f"{k}: {v:.6g}" for k, v in multipliers(params).items())
    if overlay is None:
        return f"set {values} in {name}'s parameters (the launch file's YAML) and restart it"
    return (
        f"add {overlay} after {name}'s parameter file and restart it (ros2 run "
        f"controller_manager spawner {name} --param-file YOUR_FILE --param-file {overlay}; "
        f"or in the launch file); it holds {values}"
    )

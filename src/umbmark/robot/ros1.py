"""A ROS 1 robot behind the :class:`~umbmark.robot.base.Robot` interface, through rospy.

- Velocity out: ``geometry_msgs/Twist`` on ``options.cmd_vel``.
- In: ``nav_msgs/Odometry`` (``options.odom``), ``sensor_msgs/LaserScan``
  (``options.scan``), three ``sensor_msgs/Range`` (``options.ranges``), a ground-truth
  ``geometry_msgs/PoseStamped`` (``options.truth``), the ``sensor_msgs/Imu`` topic the
  master lists (``options.imu``: :func:`umbmark.robot.ros_imu.pick_imu`); each sensor's
  mounting from TF (``/tf``, ``/tf_static``, a ``tf2_ros.Buffer``) as ``base_frame <-
  sensor frame``, the IMU's else from the ``robot_description`` parameter's fixed joints.
- Time is ROS time, so ``/use_sim_time`` works: :meth:`Ros1Robot.wait` sleeps on the ROS
  clock and refuses to hang when it stops.
- Parameters: ``apply(..., "reconfigure")`` calls the diff_drive_controller's
  dynamic_reconfigure server (``<controller>/set_parameters``), which takes multipliers
  from 0.5 to 1.5 only: outside, or with ``"yaml"``, the controller's parameter file
  (``options.params_file``) is written instead and the result says the controller must be
  restarted on it.
- Safety: a zero velocity on :meth:`close`, on rospy's shutdown, and before any error this
  adapter raises once connected.

Everything that does not need rospy (messages, TF mountings, the apply plan, the YAML) is in
:mod:`umbmark.robot.ros_common`, tested without ROS; this module is tested against a real
ROS 1 master and a simulated robot node (``tests/test_ros1.py``).
"""

from __future__ import annotations

import importlib
import math
import os
import threading
import time
from collections.abc import Callable
from types import ModuleType
from typing import Any

from umbmark.core.errors import InputError, option
from umbmark.robot.base import (
    ApplyMethod,
    ApplyResult,
    DriveParams,
)
from umbmark.robot.ros_common import (
    MULTIPLIERS,
    RosOptions,
    default_topics,
    held_problem,
    master_problem,
    multipliers,
    plan_apply,
    write_params,
)
from umbmark.robot.ros_robot import RosRobot
from umbmark.sources.bag.imu_frames import ImuMounting

__all__ = ["ROS1_MODULES", "ROS1_PACKAGES", "Ros1Robot", "apply_params", "ros1_problem"]

#: The node's base name (rospy makes it unique: ``anonymous``).
NODE_NAME = "umbmark_selfcal"

#: What the adapter imports: rospy, rosgraph (the master's address), the messages, TF and
#: the dynamic_reconfigure client (imported before the node starts, so that a missing one is
#: named at once, not after the robot has driven).
ROS1_MODULES = (
    "rospy",
    "rosgraph",
    "geometry_msgs.msg",
    "nav_msgs.msg",
    "sensor_msgs.msg",
    "tf2_ros",
    "dynamic_reconfigure.client",
)

#: The Debian package of each module the adapter (or the tests' robot node) imports,
#: directly or through the others: what a missing module's message says to install.
ROS1_PACKAGES = {
    "rospy": "python3-rospy",
    "rosgraph": "python3-rosgraph",
    "rosmaster": "python3-rosmaster",
    "roslib": "python3-roslib",
    "rospkg": "python3-rospkg",
    "catkin_pkg": "python3-catkin-pkg",
    "genpy": "python3-genpy",
    "genmsg": "python3-genmsg",
    "roscpp": "python3-roscpp-msg",
    "std_msgs": "python3-std-msgs",
    "rosgraph_msgs": "python3-rosgraph-msgs",
    "geometry_msgs": "python3-geometry-msgs",
    "nav_msgs": "python3-nav-msgs",
    "sensor_msgs": "python3-sensor-msgs",
    "actionlib": "python3-actionlib",
    "actionlib_msgs": "python3-actionlib-msgs",
    "tf2_ros": "python3-tf2-ros",
    "tf2_py": "python3-tf2",
    "tf2_msgs": "python3-tf2-msgs",
    "dynamic_reconfigure": "python3-dynamic-reconfigure",
    "yaml": "python3-yaml",
    "diagnostic_msgs": "python3-diagnostic-msgs",
}


def ros1_problem(*modules: str) -> str | None:
    """The one line naming the first of ``modules`` (default :data:`ROS1_MODULES`) that
    cannot be imported and the package to install, or None when all import.

    A module missing beneath one of them (``tf2_ros`` needs ``tf2_py``) is named as such.
    """
    for name in modules or ROS1_MODULES:
        try:
            importlib.import_module(name)
        except ImportError as exc:
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            missing = exc.name if isinstance(exc, ModuleNotFoundError) else None
            if not missing:
                owner = ROS1_PACKAGES.get(name.split(".")[0], "its package")
                return (
                    f"--ros1 cannot import {name} ({detail}): source your ROS 1 setup, or "
                    f"install {owner}"
                )
            top = missing.split(".")[0]
            needed = "" if top == name.split(".")[0] else f" (which {name} imports)"
            package = ROS1_PACKAGES.get(top)
            fix = f"install {package} (Debian)" if package else "install it"
            return (
                f"--ros1 needs {top}{needed}, which is not installed: "
                f"{fix}, or source the ROS 1 setup that has it"
            )
    return None


def _rospy() -> ModuleType:
    """rospy, once every module the adapter needs imports; else one line naming the package
    that is missing."""
    problem = ros1_problem()
    if problem is not None:
        raise InputError(problem)
    import rospy

    module: ModuleType = rospy
    return module


class Ros1Robot(RosRobot):
    """The robot behind a ROS 1 master (``ROS_MASTER_URI``), driven through rospy.

    Parameters
    ----------
    options : RosOptions
        Topics, frames, the controller and its parameter file, and ``timeout`` [s]: how
        long the master, the first odometry, a subscriber of the velocity topic, TF and the
        reconfigure server may take.

    Raises
    ------
    InputError
        rospy is missing, the master does not answer, nobody subscribes the velocity
        topic, or the odometry is silent for ``options.timeout`` (one line each).
    """

    name = "ROS 1 robot"

    def __init__(self, options: RosOptions) -> None:
        rospy = _rospy()
        from geometry_msgs.msg import PoseStamped, Twist
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import Imu, Range
        from sensor_msgs.msg import LaserScan as ScanMsg

        self._rospy = rospy
        options = default_topics(options, ros2=False)
        timeout = options.timeout
        if not (0.0 < timeout < math.inf):
            raise InputError(f"timeout {timeout!r} s: give a positive time")
        import rosgraph

        uri = rosgraph.get_master_uri()
        problem = master_problem(uri, timeout)
        if problem is not None:
            raise InputError(problem)
        rospy.init_node(NODE_NAME, anonymous=True, disable_signals=True)
        self._closed = False
        cmd = rospy.Publisher(options.cmd_vel, Twist, queue_size=1, tcp_nodelay=True)
        self._start(options, Twist, cmd)
        subs = [
            rospy.Subscriber(options.odom, Odometry, self._on_odom, queue_size=1, tcp_nodelay=True),
        ]
        if options.scan:
            subs.append(
                rospy.Subscriber(
                    options.scan, ScanMsg, self._scan.put, queue_size=1, tcp_nodelay=True
                )
            )
        for topic, latest in zip(options.ranges, self._ranges, strict=True):
            subs.append(rospy.Subscriber(topic, Range, latest.put, queue_size=1, tcp_nodelay=True))
        if options.truth:
            subs.append(
                rospy.Subscriber(
                    options.truth, PoseStamped, self._on_truth, queue_size=1, tcp_nodelay=True
                )
            )
        self._subs = subs
        import tf2_ros

        self._tf = tf2_ros.Buffer()
        self._tf_listener = tf2_ros.TransformListener(self._tf)
        rospy.on_shutdown(self._stop)
        try:
            self._wait_connected(
                self._cmd.get_num_connections, "geometry_msgs/Twist", "nav_msgs/Odometry"
            )
            imu = self._find_imu(lambda: [(n, t) for n, t in rospy.get_published_topics()], 0.0)
            if imu is not None:
                subs.append(rospy.Subscriber(imu, Imu, self._imu_buffer.put, queue_size=500,
                                             tcp_nodelay=True))  # fmt: skip
        except BaseException:
            self.close()
            raise

    def _lookup(self, base: str, frame: str) -> Any:  # noqa: ANN401 (a TransformStamped)
        rospy = self._rospy
        return self._tf.lookup_transform(
            base, frame, rospy.Time(0), rospy.Duration.from_sec(self.options.timeout)
        )

    def _imu_mounting(self, frame: str, topic: str) -> ImuMounting:
        """The IMU frame's mounting: TF (``base_frame <- frame``), else the
        ``robot_description`` parameter's fixed joints."""
        from umbmark.robot.ros_imu import imu_edges, imu_mounting_of
        from umbmark.sources.bag.imu_frames import quaternion_matrix

        base = self.options.base_frame
        if frame:
            try:
                q = self._lookup(base, frame).transform.rotation
            except Exception:  # tf2's LookupException, ...: try the robot description
                pass
            else:
                rotation = quaternion_matrix(float(q.x), float(q.y), float(q.z), float(q.w))
                if rotation is not None:
                    return ImuMounting(frame.lstrip("/"), base, rotation, "TF")
        text = self._rospy.get_param("robot_description", None)
        edges = imu_edges(None, text if isinstance(text, str) else None)
        return imu_mounting_of(edges, frame, base, topic)

    def _clock(self) -> threading.Condition:
        from rospy.rostime import get_rostime_cond

        cond: threading.Condition = get_rostime_cond()
        return cond

    # --- the Robot interface --------------------------------------------------------

    def now(self) -> float:
        """ROS time [s] (the simulation's with ``/use_sim_time``)."""
        return float(self._rospy.get_rostime().to_sec())

    def wait(self, duration: float) -> None:
        """Sleep ``duration`` seconds of ROS time (refusing to hang: :class:`RosRobot`)."""
        if self._rospy.is_shutdown():
            raise InputError("ROS shut down while the robot was driven")
        super().wait(duration)

    def drive_params(self) -> DriveParams:
        """The controller's parameters from the parameter server (``<controller>/...``;
        the reconfigure server keeps the multipliers there).

        Raises
        ------
        InputError
            No ``wheel_separation`` or ``wheel_radius`` there nor in the options.
        """
        rospy, ns = self._rospy, self.options.controller.rstrip("/")
        values: dict[str, float] = {}
        urdf = None
        for name, fallback in (
            ("wheel_separation", self.options.wheel_separation),
            ("wheel_radius", self.options.wheel_radius),
        ):
            value = rospy.get_param(f"{ns}/{name}", fallback)
            if value is None:  # as the controller does: from the URDF
                urdf = urdf or self._urdf_geometry(ns)
                value = urdf[0] if name == "wheel_separation" else urdf[1]
            values[name] = float(value)
        for name in MULTIPLIERS:
            values[name] = float(rospy.get_param(f"{ns}/{name}", 1.0))
        return DriveParams(**values)

    def footprint(self) -> tuple[float, float, float] | None:
        """The base link's outline in the ``robot_description`` parameter: length, width,
        offset [m] (:func:`umbmark.robot.urdf.urdf_footprint`); None: none there."""
        from umbmark.robot.urdf import urdf_footprint

        text = self._rospy.get_param("robot_description", None)
        return urdf_footprint(text, self.options.base_frame) if isinstance(text, str) else None

    def _urdf_geometry(self, ns: str) -> tuple[float, float]:
        """The wheel separation and radius from the ``robot_description`` parameter, with
        the controller's ``left_wheel``/``right_wheel`` joints, as the controller takes
        them (ros_controllers' ``getWheelParametersFromURDF``)."""
        from umbmark.robot.urdf import urdf_geometry

        rospy = self._rospy
        text = rospy.get_param("robot_description", None)
        names = []
        for side in ("left_wheel", "right_wheel"):
            joints = rospy.get_param(f"{ns}/{side}", [])
            names.append((joints,) if isinstance(joints, str) else tuple(joints or ()))
        geometry = None
        if isinstance(text, str):
            geometry = urdf_geometry(text, self.options.base_frame, names[0], names[1])
        if geometry is None:
            where = "no robot_description" if not isinstance(text, str) else "its URDF has not"
            raise InputError(
                f"the parameter server has no {ns}/wheel_separation or wheel_radius, and "
                f"{where} the wheels ({ns}/left_wheel, right_wheel): set them"
            )
        return geometry

    def apply(self, params: DriveParams, method: ApplyMethod) -> ApplyResult:
        """Reconfigure the controller (multipliers within 0.5 to 1.5), or write its
        parameter file (``yaml``, or outside that range), or nothing (``none``)."""
        return apply_params(self.options, params, method, self._stop)

    def close(self) -> None:
        """Send a zero velocity (and let it go out); the node stays for the process."""
        if self._closed:
            return
        self._stop()
        time.sleep(0.05)
        self._closed = True


# --- applying (the monitor's ROS 1 node applies so too) -------------------------------------


def apply_params(
    options: RosOptions, params: DriveParams, method: ApplyMethod, stop: Callable[[], None]
) -> ApplyResult:
    """Reconfigure ``options.controller`` (multipliers within 0.5 to 1.5), or write its
    parameter file (``yaml``, or outside that range), or nothing (``none``); ``stop`` is
    called before any error (the robot's zero velocity)."""
    plan = plan_apply(params, method)
    if plan.method == "none":
        return ApplyResult("none", False, plan.reason)
    if plan.method == "reconfigure":
        return _reconfigure(options, params, stop)
    return _write_yaml(options, params, plan.reason)


def _reconfigure(options: RosOptions, params: DriveParams, stop: Callable[[], None]) -> ApplyResult:
    from dynamic_reconfigure.client import Client

    ns = options.controller.rstrip("/")
    try:
        client = Client(ns, timeout=options.timeout)
        try:
            held = client.update_configuration(multipliers(params))
        finally:
            client.close()
    except Exception as exc:  # rospy.ROSException, ServiceException
        stop()
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(
            f"no dynamic_reconfigure server at {ns} ({detail}): is it a "
            f"diff_drive_controller? ({option('controller')}; or {option('apply', 'yaml')} "
            f"with {option('params_file')})"
        ) from None
    problem = held_problem(params, held)
    if problem is not None:
        return ApplyResult("reconfigure", False, problem)
    return ApplyResult("reconfigure", True, f"parameters reconfigured ({ns}/set_parameters)")


def _write_yaml(options: RosOptions, params: DriveParams, reason: str) -> ApplyResult:
    path = options.params_file
    lead = f"{reason}; " if reason else ""
    if path is None:
        return ApplyResult("none", False, f"{lead}no --params-file to write them to: not applied")
    edit = write_params(path, params, options.controller, ros2=False)
    return ApplyResult(
        "yaml",
        False,
        f"{lead}{edit.line()}: load it (rosparam load) and restart the controller to run with them",
        file=os.fspath(path),
        wrote=edit.line(),
    )

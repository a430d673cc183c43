"""The monitor's node on ROS 1 (``umbmark monitor --ros1``), through rospy.

A node ``/umbmark_monitor`` at ``ROS_MASTER_URI``; it publishes no velocity. What it
shares with ROS 2 is :mod:`umbmark.monitor.ros_node`.

- Parameters: the node's private ones (``_name:=value`` on the command line, ``<param>``
  inside a launch file's ``<node>``), by the options' specs; remaps (``scan:=/front``) and
  ``__name:=`` as rospy takes them.
- In: ``nav_msgs/Odometry`` (``/odom``; its frames the corrected odometry's, its poses the
  wheels' where no joint states with wheels come), ``sensor_msgs/JointState``,
  ``LaserScan``, ``Imu``; mountings from TF (a ``tf2_ros.Buffer``, looked up without
  waiting in the callbacks: a message before its transform is there is left out). Every
  queue is :data:`~umbmark.monitor.ros_node.INPUT_QUEUE` deep. ``/use_sim_time`` as rospy
  reads it: ROS time is the simulation's.
- Out: ``diagnostic_msgs/DiagnosticArray`` on ``/diagnostics`` every wall second (queue
  10, as diagnostic_updater), ``nav_msgs/Odometry`` on ``corrected_odom``, its transform
  on ``/tf`` with ``corrected_tf``.
- Applying at rest: :func:`umbmark.robot.ros1.apply_params` (dynamic_reconfigure, or the
  parameter file edited in place).
- Stopped by SIGINT or SIGTERM (rospy's signal handlers off): one line, exit 0.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from umbmark.core.errors import InputError
from umbmark.monitor.diagnostics import NODE_NAME, TOPIC, compose, fill_array
from umbmark.monitor.node_loop import MonitorLoop, Outputs, run_ticks, stop_on_signals, stopped_line
from umbmark.monitor.odometry_msg import Frames, fill_odometry, fill_transform, odometry_fields
from umbmark.monitor.ros2_node import Found
from umbmark.monitor.ros_node import (
    INPUT_QUEUE,
    NODE_OPTIONS,
    SHARED,
    base_yaw_rate,
    node_options,
    parameter_values,
    wheel_angles,
)
from umbmark.monitor.status import CorrectedOdometry, MonitorCore, MonitorStatus
from umbmark.options.spec import READ, Spec
from umbmark.robot.base import ApplyResult, DriveParams
from umbmark.robot.ros_common import (
    Mount,
    RosOptions,
    default_topics,
    master_problem,
    mount_from_transform,
    planar_pose,
    scan_from_message,
    stamp_seconds,
)

__all__ = ["run_ros1"]


def _say(line: str) -> None:
    print(line, flush=True)


def _nothing() -> None:
    """No zero velocity to send: the monitor has no velocity publisher."""


class Ros1Monitor:
    """The node: started, its private parameters read; :meth:`subscribe` feeds ``loop``."""

    def __init__(
        self, given: Mapping[str, object], ros_args: Sequence[str], specs: Sequence[Spec]
    ) -> None:
        from umbmark.robot.ros1 import ROS1_MODULES, ros1_problem

        problem = ros1_problem(*ROS1_MODULES, "diagnostic_msgs.msg")
        if problem is not None:
            raise InputError(problem)
        import rosgraph
        import rospy

        self._rospy = rospy
        uri = self.master = rosgraph.get_master_uri()
        timeout = float(given.get("timeout", 10.0))  # type: ignore[arg-type]
        problem = master_problem(uri, timeout)
        if problem is not None:
            raise InputError(problem)
        rospy.init_node(NODE_NAME, argv=[NODE_NAME, *ros_args], disable_signals=True)
        held = rospy.get_param("~", {})
        known = (*specs, *NODE_OPTIONS, *(READ[n] for n in SHARED))
        private = parameter_values(held if isinstance(held, dict) else {}, known,
                                   f"the private parameters of {rospy.get_name()}")  # fmt: skip
        self.values: dict[str, object] = {**private, **given}
        namespace = rospy.get_namespace().strip("/")
        self.options = node_options(self.values, namespace or socket.gethostname())
        self.ros = default_topics(
            RosOptions(odom=self.options.odom_topic, scan=self.options.scan_topic,
                       base_frame=self.options.base_frame, controller=self.options.controller,
                       params_file=self.options.params_file, timeout=self.options.timeout,
                       laser_mount=self.options.laser_mount),
            ros2=False,
        )  # fmt: skip
        import tf2_ros

        self._tf = tf2_ros.Buffer()
        self._tf_listener = tf2_ros.TransformListener(self._tf)
        self._mounts: dict[str, Mount] = {}
        self._frames: Frames | None = None
        self._covariance: tuple[Sequence[float], Sequence[float]] | None = None
        self._joint_wheels = False
        self._started = time.monotonic()
        self._said: set[str] = set()
        self.loop: MonitorLoop | None = None

    def now(self) -> float:
        """ROS time [s] (the simulation's with ``/use_sim_time``)."""
        return float(self._rospy.get_rostime().to_sec())

    def drive_params(self) -> DriveParams | None:
        """The controller's geometry from the parameter server (None: not there)."""
        ns, get = self.ros.controller.rstrip("/"), self._rospy.get_param
        sep, radius = get(f"{ns}/wheel_separation", None), get(f"{ns}/wheel_radius", None)
        if not isinstance(sep, (int, float)) or not isinstance(radius, (int, float)):
            return None
        names = ("wheel_separation_multiplier", "left_wheel_radius_multiplier",
                 "right_wheel_radius_multiplier")  # fmt: skip
        return DriveParams(float(sep), float(radius),
                           *(float(get(f"{ns}/{n}", 1.0)) for n in names))  # fmt: skip

    def subscribe(self) -> None:
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import Imu, JointState, LaserScan

        rospy, o = self._rospy, self.options
        depth = INPUT_QUEUE
        rospy.Subscriber(self.ros.odom, Odometry, self._on_odom, queue_size=depth)
        rospy.Subscriber(o.wheel_topic, JointState, self._on_joints, queue_size=depth)
        if o.scan_topic:
            rospy.Subscriber(o.scan_topic, LaserScan, self._on_scan, queue_size=depth)
        if o.imu_topic:
            rospy.Subscriber(o.imu_topic, Imu, self._on_imu, queue_size=depth)

    def publishers(self) -> Outputs:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        rospy = self._rospy
        diagnostics = rospy.Publisher(TOPIC, DiagnosticArray, queue_size=10)
        name = rospy.get_name()[1:]

        def publish_status(status: MonitorStatus) -> None:
            array = fill_array(compose(status, name), DiagnosticArray, DiagnosticStatus,
                               KeyValue, rospy.Time.from_sec(max(0.0, self.now())),
                               ros2=False)  # fmt: skip
            diagnostics.publish(array)

        corrected = self._corrected(self.options.corrected_odom)
        apply = self.apply if self.options.apply == "at-rest" else None
        return Outputs(publish_status, corrected, apply, _say)

    def _corrected(self, topic: str | None) -> Callable[[CorrectedOdometry], None] | None:
        if not topic:
            return None
        from geometry_msgs.msg import TransformStamped
        from nav_msgs.msg import Odometry
        from tf2_msgs.msg import TFMessage

        rospy = self._rospy
        odometry = rospy.Publisher(topic, Odometry, queue_size=10)
        tf = rospy.Publisher("/tf", TFMessage, queue_size=10) if self.options.corrected_tf else None

        def publish(corrected: CorrectedOdometry) -> None:
            frames = self._frames or Frames("odom", self.options.base_frame)
            pose_cov, twist_cov = self._covariance or (None, None)
            fields = odometry_fields(corrected, frames, pose_cov, twist_cov)
            stamp = rospy.Time.from_sec(max(0.0, corrected.time))
            odometry.publish(fill_odometry(fields, Odometry(), stamp))
            if tf is not None:
                tf.publish(TFMessage([fill_transform(fields, TransformStamped(), stamp)]))

        return publish

    # --- callbacks (rospy's threads) ------------------------------------------------

    def _on_odom(self, msg: Any) -> None:  # noqa: ANN401
        loop = self.loop
        if loop is None:
            return
        odom_frame = msg.header.frame_id.lstrip("/") or "odom"
        self._frames = Frames(odom_frame, msg.child_frame_id.lstrip("/") or self.options.base_frame)
        self._covariance = (tuple(msg.pose.covariance), tuple(msg.twist.covariance))
        if self._joint_wheels:
            loop.heard(self.ros.odom)
            return
        try:
            stamp, pose = stamp_seconds(msg.header.stamp), planar_pose(msg.pose.pose)
        except InputError as exc:
            loop._fault("odometry message", exc)
            return
        loop.odometry(stamp, pose)

    def _on_joints(self, msg: Any) -> None:  # noqa: ANN401
        loop = self.loop
        o = self.options
        angles = wheel_angles(list(msg.name), list(msg.position), o.left_joints, o.right_joints)
        if loop is None or angles is None:
            return
        if not self._joint_wheels:
            self._joint_wheels = True
            loop.wheels_topic = o.wheel_topic
            _say(f"umbmark_monitor: the wheels from {o.wheel_topic}")
        loop.wheels(stamp_seconds(msg.header.stamp), *angles)

    def _mount(self, frame: str, laser: bool = False) -> Mount | None:
        frame = frame.lstrip("/")
        found = self._mounts.get(frame)
        if found is not None:
            return found
        if laser and self.options.laser_mount is not None:
            found = Mount(self.options.laser_mount)
        else:
            try:
                transform = self._tf.lookup_transform(self.options.base_frame, frame,
                                                      self._rospy.Time(0))  # fmt: skip
            except Exception:  # tf2's LookupException, ...: not there yet
                if (
                    time.monotonic() - self._started > self.options.timeout
                    and frame not in self._said
                ):
                    self._said.add(frame)
                    _say(f"umbmark_monitor: no TF from {self.options.base_frame} to {frame!r}: "
                         "its messages are left out until it comes")  # fmt: skip
                return None
            found = mount_from_transform(transform.transform)
        self._mounts[frame] = found
        return found

    def _on_scan(self, msg: Any) -> None:  # noqa: ANN401
        loop = self.loop
        if loop is None:
            return
        mount = self._mount(msg.header.frame_id, laser=True)
        if mount is None:
            loop.heard(self.options.scan_topic or "")
            return
        loop.scan(lambda: scan_from_message(msg, mount, self.options.base_frame))

    def _on_imu(self, msg: Any) -> None:  # noqa: ANN401
        loop = self.loop
        if loop is None:
            return
        frame = msg.header.frame_id.lstrip("/")
        in_base = frame in ("", self.options.base_frame)
        mount = None if in_base else self._mount(frame)
        if mount is None and not in_base:
            loop.heard(self.options.imu_topic or "")
            return
        w = msg.angular_velocity
        loop.gyro(lambda: (stamp_seconds(msg.header.stamp), base_yaw_rate((w.x, w.y, w.z), mount)))

    def apply(self, params: DriveParams) -> ApplyResult:
        """dynamic_reconfigure, or the parameter file (:func:`umbmark.robot.ros1.apply_params`)."""
        from umbmark.robot.ros1 import apply_params

        return apply_params(self.ros, params, "reconfigure", _nothing)


def run_ros1(
    given: Mapping[str, object],
    ros_args: Sequence[str],
    make_core: Callable[[Found], MonitorCore],
    specs: Sequence[Spec] = (),
) -> int:
    """Run the node until SIGINT or SIGTERM; 0 then (as
    :func:`umbmark.monitor.ros2_node.run_ros2`; ``ros_args``: the ``name:=value``
    tokens)."""
    stop = stop_on_signals()
    monitor = Ros1Monitor(given, ros_args, specs)
    rospy = monitor._rospy
    sim = bool(rospy.get_param("/use_sim_time", False))
    params = monitor.drive_params()
    core = make_core(Found(monitor.values, monitor.options, params, sim))
    loop = MonitorLoop(core, monitor.options, monitor.publishers(), monitor.now, monitor.ros.odom)
    monitor.loop = loop
    monitor.subscribe()
    o = monitor.options
    _say(
        f"umbmark_monitor at {monitor.master}: robot {o.robot}, "
        f"wheels from {monitor.ros.odom} (or {o.wheel_topic}), "
        f"{', '.join(t for t in (o.scan_topic, o.imu_topic) if t) or 'no laser nor IMU'}; "
        f"{'sim time' if sim else 'system time'}; diagnostics on {TOPIC} at 1 Hz; applying "
        f"{o.apply}; Ctrl-C stops"
    )
    started = time.monotonic()
    run_ticks(loop, stop)
    loop.stop()
    _say(stopped_line(stop, loop, started))
    rospy.signal_shutdown("stopped")
    return 0

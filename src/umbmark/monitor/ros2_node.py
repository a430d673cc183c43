"""The monitor's node on ROS 2 (``umbmark monitor --ros2``), through rclpy.

A node ``umbmark_monitor`` on the graph of ``ROS_DOMAIN_ID``; it publishes no velocity
(it never commands the robot). What it shares with ROS 1 (its options as parameters, the
messages as values, the 1 Hz loop, silence, applying at rest) is
:mod:`umbmark.monitor.ros_node`; the messages' layout is
:mod:`umbmark.monitor.diagnostics` and :mod:`umbmark.monitor.odometry_msg`.

- Parameters: the node is made with ``automatically_declare_parameters_from_overrides``,
  so ``--ros-args -p name:=value`` and ``--ros-args --params-file f.yaml`` (under
  ``umbmark_monitor:`` or ``/**:``, ``ros__parameters``) reach it; remaps and a namespace
  too (``-r __ns:=/robot1``).
- In: the controller's ``nav_msgs/msg/Odometry`` (``<controller>/odom``; its frames are
  the corrected odometry's, and its poses the wheels' where no joint states with wheels
  come), ``sensor_msgs/msg/JointState``, ``sensor_msgs/msg/LaserScan`` and
  ``sensor_msgs/msg/Imu`` (sensor-data QoS), the URDF on ``/robot_description`` and
  ``/tf_static`` (transient local) for the laser's and IMU's mountings (chained as
  :func:`umbmark.robot.urdf.static_mount` does; else :func:`umbmark.robot.urdf.urdf_mount`),
  ``/clock``. Every subscription's queue is :data:`~umbmark.monitor.ros_node.INPUT_QUEUE`
  deep (sensor data best effort, as rclpy's sensor-data profile): nothing grows over days.
- Out: ``diagnostic_msgs/msg/DiagnosticArray`` on ``/diagnostics`` every wall second
  (depth 1, as diagnostic_updater), stamped on the node's clock; with ``corrected_odom``
  ``nav_msgs/msg/Odometry`` there, with ``corrected_tf`` its transform on ``/tf``.
- Time: the latest ``/clock`` where one is published (sim time), else the system clock.
- Applying at rest: through :func:`umbmark.robot.ros2.apply_params` (set_parameters and a
  configure by the controller manager, Rolling's reload, or the parameter file edited in
  place), this node the :class:`~umbmark.robot.ros2_reload.ReloadTarget`.
- Stopped by SIGINT or SIGTERM (rclpy's own handlers off): one line, exit 0.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import socket
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from umbmark.core.errors import InputError, SafetyError, option
from umbmark.monitor.diagnostics import NODE_NAME, TOPIC, compose, fill_array
from umbmark.monitor.node_loop import MonitorLoop, Outputs, run_ticks, stop_on_signals, stopped_line
from umbmark.monitor.odometry_msg import Frames, fill_odometry, fill_transform, odometry_fields
from umbmark.monitor.ros_node import (
    INPUT_QUEUE,
    NODE_OPTIONS,
    SHARED,
    NodeOptions,
    base_yaw_rate,
    node_options,
    parameter_values,
    wheel_angles,
)
from umbmark.monitor.status import CorrectedOdometry, MonitorCore, MonitorStatus
from umbmark.options.spec import READ, Spec
from umbmark.robot.base import ApplyResult, DriveParams
from umbmark.robot.ros2_reload import ReloadPlan
from umbmark.robot.ros_common import (
    Latest,
    Mount,
    RosOptions,
    default_topics,
    planar_pose,
    scan_from_message,
    stamp_seconds,
)
from umbmark.robot.urdf import static_mount, urdf_mount

__all__ = ["Found", "Ros2Monitor", "run_ros2"]


@dataclass(frozen=True)
class Found:
    """What the node found on the graph, for the core to be made with.

    Attributes
    ----------
    values : mapping
        Every option's value by keyword (the command line's, the parameters' where it
        gave none).
    options : NodeOptions
    params : DriveParams or None
        The controller's parameters (None: it did not answer within the timeout).
    sim_time : bool
        ``/clock`` is published.
    """

    values: Mapping[str, object]
    options: NodeOptions
    params: DriveParams | None
    sim_time: bool


def _rclpy() -> Any:  # noqa: ANN401 (the module)
    try:
        import rclpy
    except ImportError as exc:
        raise InputError(
            f"{option('ros2')} needs rclpy ({exc}): python -m pip install '.[ros2]' in "
            "umbmark's checkout, or source your ROS 2 setup (/opt/ros/DISTRO)"
        ) from None
    return rclpy


class Ros2Monitor:
    """The node: made, subscribed, its parameters read; :meth:`start` feeds ``loop``."""

    def __init__(
        self, given: Mapping[str, object], ros_args: Sequence[str], specs: Sequence[Spec]
    ) -> None:
        rclpy = _rclpy()
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self._context = Context()
        args = ["umbmark_monitor", "--ros-args", *ros_args] if ros_args else None
        rclpy.init(args=args, context=self._context,
                   signal_handler_options=SignalHandlerOptions.NO)  # fmt: skip
        self._running = True
        self._spin: threading.Thread | None = None
        try:
            self._node = rclpy.create_node(
                NODE_NAME,
                context=self._context,
                automatically_declare_parameters_from_overrides=True,
            )
            held = {
                name: p.value
                for name, p in self._node.get_parameters_by_prefix("").items()
                if p.value is not None
            }
            known = (*specs, *NODE_OPTIONS, *(READ[n] for n in SHARED))
            from_ros = parameter_values(held, known, "its ROS parameters")
            self.values: dict[str, object] = {**from_ros, **given}
            namespace = self._node.get_namespace().strip("/")
            self.options = node_options(self.values, namespace or socket.gethostname())
            ros = default_topics(
                RosOptions(
                    odom=self.options.odom_topic,
                    scan=self.options.scan_topic,
                    base_frame=self.options.base_frame,
                    controller=self.options.controller,
                    params_file=self.options.params_file,
                    reload=self.options.reload,
                    timeout=self.options.timeout,
                    laser_mount=self.options.laser_mount,
                ),
                ros2=True,
            )
            self._ros = ros
            self._executor = SingleThreadedExecutor(context=self._context)
            self._executor.add_node(self._node)
            self._spin = threading.Thread(target=self._spin_loop, name="umbmark-mon", daemon=True)
            self._spin.start()
        except BaseException:
            self.close()
            raise
        self._ticks = threading.Condition()
        self._sim_time: float | None = None
        self._description: Latest[str] = Latest()
        self._static: dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]] = {}
        self._mounts: dict[str, Mount | None] = {}
        self._frames: Frames | None = None
        self._covariance: tuple[Sequence[float], Sequence[float]] | None = None
        self._joint_wheels = False
        self._started = time.monotonic()
        self.loop: MonitorLoop | None = None
        self._reload_plan: ReloadPlan | None = None

    @property
    def ros_options(self) -> RosOptions:
        """The controller's topics, namespace, parameter file and timeout."""
        return self._ros

    def _spin_loop(self) -> None:
        with contextlib.suppress(Exception):  # the context shut under it: end quietly
            while self._running and self._context.ok():
                self._executor.spin_once(timeout_sec=0.05)

    # --- the graph ----------------------------------------------------------------

    def subscribe(self) -> None:
        """Subscribe every topic (the loop must be set: :meth:`start`)."""
        from nav_msgs.msg import Odometry
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import Imu, JointState, LaserScan
        from std_msgs.msg import String

        node, options = self._node, self.options
        node.create_subscription(Clock, "/clock", self._on_clock, 10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(
            String, "/robot_description", lambda m: self._description.put(m.data), latched
        )
        if importlib.util.find_spec("tf2_msgs") is not None:
            from tf2_msgs.msg import TFMessage

            static = QoSProfile(depth=100, durability=DurabilityPolicy.TRANSIENT_LOCAL)
            node.create_subscription(TFMessage, "/tf_static", self._on_static, static)
        depth = INPUT_QUEUE
        node.create_subscription(Odometry, self._ros.odom, self._on_odom, depth)
        node.create_subscription(JointState, options.wheel_topic, self._on_joints, depth)
        sensor = QoSProfile(depth=depth, reliability=ReliabilityPolicy.BEST_EFFORT)  # sensor data
        if options.scan_topic:
            node.create_subscription(LaserScan, options.scan_topic, self._on_scan, sensor)
        if options.imu_topic:
            node.create_subscription(Imu, options.imu_topic, self._on_imu, sensor)

    def publishers(self) -> Outputs:
        """Where the loop's statuses, corrected odometry and applies go."""
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        node = self._node
        diagnostics = node.create_publisher(DiagnosticArray, TOPIC, 1)
        name = node.get_name()

        def publish_status(status: MonitorStatus) -> None:
            array = fill_array(compose(status, name), DiagnosticArray, DiagnosticStatus,
                               KeyValue, self._stamp(self.now()), ros2=True)  # fmt: skip
            diagnostics.publish(array)

        corrected = None
        if self.options.corrected_odom:
            corrected = self._corrected_publisher(self.options.corrected_odom)
        apply = self.apply if self.options.apply == "at-rest" else None
        return Outputs(publish_status, corrected, apply, _say)

    def _corrected_publisher(self, topic: str) -> Callable[[CorrectedOdometry], None]:
        from geometry_msgs.msg import TransformStamped
        from nav_msgs.msg import Odometry

        odometry = self._node.create_publisher(Odometry, topic, 10)
        tf = None
        if self.options.corrected_tf:
            from tf2_msgs.msg import TFMessage

            tf = self._node.create_publisher(TFMessage, "/tf", 10)

        def publish(corrected: CorrectedOdometry) -> None:
            frames = self._frames or Frames("odom", self.options.base_frame)
            pose_cov, twist_cov = self._covariance or (None, None)
            fields = odometry_fields(corrected, frames, pose_cov, twist_cov)
            stamp = self._stamp(corrected.time)
            odometry.publish(fill_odometry(fields, Odometry(), stamp))
            if tf is not None:
                from tf2_msgs.msg import TFMessage

                tf.publish(TFMessage(transforms=[fill_transform(fields, TransformStamped(),
                                                                stamp)]))  # fmt: skip

        return publish

    # --- callbacks (the executor's thread) ------------------------------------------

    def _on_clock(self, msg: Any) -> None:  # noqa: ANN401
        with self._ticks:
            self._sim_time = float(msg.clock.sec) + 1e-9 * float(msg.clock.nanosec)
            self._ticks.notify_all()

    def _on_static(self, msg: Any) -> None:  # noqa: ANN401 (tf2_msgs TFMessage)
        edges = {}
        for tf in msg.transforms:
            t, q = tf.transform.translation, tf.transform.rotation
            edges[tf.child_frame_id.lstrip("/")] = (
                tf.header.frame_id.lstrip("/"), (t.x, t.y, t.z), (q.x, q.y, q.z, q.w),
            )  # fmt: skip
        with self._ticks:
            self._static = {**self._static, **edges}
            self._mounts = {k: v for k, v in self._mounts.items() if v is not None}

    def _on_odom(self, msg: Any) -> None:  # noqa: ANN401 (nav_msgs Odometry)
        loop = self.loop
        if loop is None:
            return
        odom_frame = msg.header.frame_id.lstrip("/") or "odom"
        self._frames = Frames(odom_frame, msg.child_frame_id.lstrip("/") or self.options.base_frame)
        self._covariance = (tuple(msg.pose.covariance), tuple(msg.twist.covariance))
        if self._joint_wheels:
            loop.heard(self._ros.odom)
            return
        try:
            stamp, pose = stamp_seconds(msg.header.stamp), planar_pose(msg.pose.pose)
        except InputError as exc:
            loop._fault("odometry message", exc)
            return
        loop.odometry(stamp, pose)

    def _on_joints(self, msg: Any) -> None:  # noqa: ANN401 (sensor_msgs JointState)
        loop = self.loop
        if loop is None:
            return
        angles = wheel_angles(list(msg.name), list(msg.position), self.options.left_joints,
                              self.options.right_joints)  # fmt: skip
        if angles is None:
            return
        if not self._joint_wheels:
            self._joint_wheels = True
            loop.wheels_topic = self.options.wheel_topic
            _say(f"umbmark_monitor: the wheels from {self.options.wheel_topic}")
        loop.wheels(stamp_seconds(msg.header.stamp), *angles)

    def _on_scan(self, msg: Any) -> None:  # noqa: ANN401 (sensor_msgs LaserScan)
        loop = self.loop
        if loop is None:
            return
        mount = self._mount(msg.header.frame_id, laser=True)
        if mount is None:
            loop.heard(self.options.scan_topic or "")
            return
        loop.scan(lambda: scan_from_message(msg, mount, self.options.base_frame))

    def _on_imu(self, msg: Any) -> None:  # noqa: ANN401 (sensor_msgs Imu)
        loop = self.loop
        if loop is None:
            return
        frame = msg.header.frame_id.lstrip("/")
        mount = None if frame in ("", self.options.base_frame) else self._mount(frame)
        if mount is None and frame not in ("", self.options.base_frame):
            loop.heard(self.options.imu_topic or "")
            return
        w = msg.angular_velocity
        loop.gyro(lambda: (stamp_seconds(msg.header.stamp), base_yaw_rate((w.x, w.y, w.z), mount)))

    def _mount(self, frame: str, *, laser: bool = False) -> Mount | None:
        """A sensor frame's mounting: ``laser_mount`` for the laser, else ``/tf_static``,
        else the URDF; None while neither holds it (said once after the timeout)."""
        frame = frame.lstrip("/")
        if frame in self._mounts and self._mounts[frame] is not None:
            return self._mounts[frame]
        given = self.options.laser_mount
        mount: Mount | None
        if laser and given is not None:
            mount = Mount(given)
        else:
            with self._ticks:
                edges = self._static
            mount = static_mount(edges, self.options.base_frame, frame)
            text = self._description.get()
            if mount is None and text is not None:
                mount = urdf_mount(text, self.options.base_frame, frame)
        if mount is None and frame not in self._mounts:
            if time.monotonic() - self._started > self.options.timeout:
                self._mounts[frame] = None
                _say(f"umbmark_monitor: no mounting of {frame!r} in {self.options.base_frame} "
                     "on /tf_static nor in the URDF: its messages are left out "
                     "(--laser-mount x,y,yaw for the laser)")  # fmt: skip
            return None
        if mount is not None:
            self._mounts[frame] = mount
        return mount

    # --- time ----------------------------------------------------------------------

    def now(self) -> float:
        """ROS time [s]: the latest ``/clock`` where one came, else the system clock."""
        with self._ticks:
            sim = self._sim_time
        if sim is not None:
            return sim
        return float(self._node.get_clock().now().nanoseconds) * 1e-9

    @staticmethod
    def _stamp(t: float) -> Any:  # noqa: ANN401 (builtin_interfaces Time)
        from builtin_interfaces.msg import Time

        ns = max(0, round(t * 1e9))
        return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    # --- the controller -----------------------------------------------------------------

    def call(self, kind: Any, service: str, request: Any) -> Any:  # noqa: ANN401
        """A service call (``timeout`` for it and its answer)."""
        from umbmark.robot.ros2 import call_service

        return call_service(self._node, kind, service, request, self._ros.timeout, _nothing)

    def drive_params(self) -> DriveParams:
        """The controller's parameters (:func:`umbmark.robot.ros2.controller_params`)."""
        from umbmark.robot.ros2 import controller_params

        return controller_params(self.call, self._ros, self._description, _nothing)

    def send_velocity(self, linear: float, angular: float) -> None:
        """Nothing: the monitor commands no velocity (applying happens at rest, and the
        reload's zero velocity is the robot's own stack's business)."""

    def wait_back(self, since: float) -> None:
        """After a reload: wait until an odometry stamped after ``since`` came."""
        from nav_msgs.msg import Odometry

        got: Latest[float] = Latest()
        sub = self._node.create_subscription(
            Odometry, self._ros.odom, lambda m: got.put(stamp_seconds(m.header.stamp)), 10
        )
        try:
            deadline = time.monotonic() + self._ros.timeout
            while time.monotonic() < deadline:
                stamp = got.get()
                if stamp is not None and stamp > since:
                    return
                time.sleep(0.02)
        finally:
            self._node.destroy_subscription(sub)
        raise SafetyError(
            f"the controller was activated again but {self._ros.odom} said nothing new in "
            f"{self._ros.timeout:g} s"
        )

    def apply(self, params: DriveParams) -> ApplyResult:
        """Apply at rest through selfcal's ROS 2 paths (:func:`apply_params`)."""
        from umbmark.robot.ros2_reload import apply_params, reload_plan

        target = _Target(self)
        if self._reload_plan is None:
            self._reload_plan = reload_plan(target)
        return apply_params(target, self._reload_plan, params, "reconfigure")

    def close(self) -> None:
        """The executor's thread joined, the node and the context gone."""
        self._running = False
        if self._spin is not None:
            self._spin.join(2.0)
        with contextlib.suppress(Exception):
            self._executor.shutdown(timeout_sec=1.0)
        with contextlib.suppress(Exception):
            self._node.destroy_node()
        with contextlib.suppress(Exception):
            self._context.try_shutdown()


class _Target:
    """The node as :class:`~umbmark.robot.ros2_reload.ReloadTarget` (its ``options`` the
    controller's :class:`RosOptions`)."""

    def __init__(self, node: Ros2Monitor) -> None:
        self._node = node
        self.options = node.ros_options

    def call(self, kind: Any, service: str, request: Any) -> Any:  # noqa: ANN401
        return self._node.call(kind, service, request)

    def send_velocity(self, linear: float, angular: float) -> None:
        self._node.send_velocity(linear, angular)

    def now(self) -> float:
        return self._node.now()

    def wait_back(self, since: float) -> None:
        self._node.wait_back(since)

    def drive_params(self) -> DriveParams:
        return self._node.drive_params()


def _nothing() -> None:
    """No zero velocity to send: the monitor has no velocity publisher."""


def _say(line: str) -> None:
    print(line, flush=True)


def run_ros2(
    given: Mapping[str, object],
    ros_args: Sequence[str],
    make_core: Callable[[Found], MonitorCore],
    specs: Sequence[Spec] = (),
) -> int:
    """Run the node until SIGINT or SIGTERM; 0 then.

    Parameters
    ----------
    given : mapping
        The options the command line gave, by keyword (they win over parameters).
    ros_args : sequence of str
        What followed ``--ros-args`` (:func:`umbmark.monitor.ros_node.split_ros_args`).
    make_core : callable
        The core from what the node found (``umbmark.monitor.core.make_monitor`` on the
        setup made of it).
    specs : sequence of Spec
        The core's options (their parameters are taken by their specs too).
    """
    stop = stop_on_signals()
    monitor = Ros2Monitor(given, ros_args, specs)
    try:
        params = None
        with contextlib.suppress(InputError):
            params = monitor.drive_params()
        sim = monitor._node.count_publishers("/clock") > 0
        core = make_core(Found(monitor.values, monitor.options, params, sim))
        outputs = monitor.publishers()
        wheels = monitor.ros_options.odom
        loop = MonitorLoop(core, monitor.options, outputs, monitor.now, wheels)
        monitor.loop = loop
        monitor.subscribe()
        _say(_started_line(monitor, params, sim))
        started = time.monotonic()
        run_ticks(loop, stop)
        loop.stop()
        _say(stopped_line(stop, loop, started))
    finally:
        monitor.close()
    return 0


def _started_line(monitor: Ros2Monitor, params: DriveParams | None, sim: bool) -> str:
    o = monitor.options
    sensors = ", ".join(t for t in (o.scan_topic, o.imu_topic) if t) or "no laser nor IMU"
    geometry = (
        "the controller's parameters not read"
        if params is None
        else f"wheel separation {params.wheel_separation:.4g} m, radius {params.wheel_radius:.4g} m"
    )
    odom = f"; corrected odometry on {o.corrected_odom}" if o.corrected_odom else ""
    return (
        f"umbmark_monitor on ROS_DOMAIN_ID {os.environ.get('ROS_DOMAIN_ID', '0')}: robot "
        f"{o.robot}, wheels from {monitor.ros_options.odom} (or {o.wheel_topic}), {sensors}; "
        f"{geometry}; {'sim time' if sim else 'system time'}; diagnostics on {TOPIC} at 1 Hz"
        f"{odom}; applying {o.apply}; Ctrl-C stops"
    )

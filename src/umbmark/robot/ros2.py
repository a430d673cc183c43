"""A ROS 2 robot behind the :class:`~umbmark.robot.base.Robot` interface, through rclpy.

Tested against a ROS 2 graph (``tests/test_ros2.py``: rclpy and the messages from the
package index, a node with ros2_controllers' ``diff_drive_controller`` interfaces and a
controller manager, 8x sim time). What it needs is rclpy and the message packages (``pip
install ".[ros2]"``); ``controller_manager_msgs`` for ``--reload`` (no wheel:
``tools/build_ros2_interfaces.py`` builds it); not ``tf2_ros``.

- Topics default from the controller: ``<controller>/odom``; the velocity topic is the
  one the controller subscribes, found on the graph (:func:`pick_velocity`):
  ``<controller>/cmd_vel`` with ``geometry_msgs/msg/TwistStamped`` (Jazzy and later;
  Humble and Iron with ``use_stamped_vel`` true, their default), stamped with the node's
  clock (sim time when ``/clock`` runs, so the controller never finds it stale), or
  ``<controller>/cmd_vel_unstamped`` with ``geometry_msgs/msg/Twist`` (Humble and Iron with
  ``use_stamped_vel: false``). ``options.cmd_vel`` (``--cmd-vel``), where given, is the
  topic, its type from the graph. :meth:`Ros2Robot.velocity_note` says which, before the
  robot moves.
- In: ``nav_msgs/msg/Odometry``, ``sensor_msgs/msg/LaserScan`` (sensor-data QoS), three
  ``sensor_msgs/msg/Range``, a ground-truth ``geometry_msgs/msg/PoseStamped``, the URDF on
  ``/robot_description`` (transient local, as robot_state_publisher latches it), the
  ``sensor_msgs/msg/Imu`` topic found on the graph (``options.imu``:
  :func:`umbmark.robot.ros_imu.pick_imu`; best effort, deep enough for 1 kHz), its
  frame's mounting from ``/tf_static``, else the URDF's fixed joints.
- Mountings: ``options.laser_mount`` (``--laser-mount``) where given, else from
  ``/tf_static`` where ``tf2_msgs`` is importable (the static transforms chained without a
  tf2 buffer: :func:`umbmark.robot.urdf.static_mount`), else from the URDF
  (:func:`umbmark.robot.urdf.urdf_mount`).
- Geometry: the controller's ``wheel_separation`` and ``wheel_radius`` (its
  ``get_parameters`` service), else the URDF's wheels, else the options.
- Time: one single-threaded executor spun in a thread of its own (joined on close). With
  ``/clock`` published when connecting, ROS time is the latest ``/clock`` (sim time, read
  in its callback, which then wakes the drive loop: no race with rclpy's time source), and
  :meth:`Ros2Robot.wait` sleeps on it.
  rclpy's signal handlers are off: Ctrl-C reaches the routine, which sends a zero velocity
  before the context goes.
- Applying: the controller reads its multipliers only when it is configured. With
  ``options.reload`` (``--reload``) and ``controller_manager_msgs`` importable, it is
  reconfigured, or on Rolling (read-only multipliers) loaded again, through the
  controller manager (:mod:`umbmark.robot.ros2_reload`; :meth:`Ros2Robot.can_apply` and
  :meth:`Ros2Robot.apply_note` say which before the robot moves). Else
  :meth:`Ros2Robot.apply` writes ``options.params_file`` (when given) and says the
  controller must be restarted on the new values (:func:`restart_commands`); the routine
  stops there and ``umbmark selfcal --resume DIR`` continues after the restart.
- Safety: a zero velocity on :meth:`close` and before any error raised once connected.
"""

from __future__ import annotations

import contextlib
import importlib.util
import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError, SafetyError, option
from umbmark.robot.base import ApplyMethod, ApplyResult, DriveParams
from umbmark.robot.ros2_reload import ReloadPlan, apply_params, reload_plan
from umbmark.robot.ros_common import (
    MULTIPLIERS,
    Latest,
    Mount,
    RosOptions,
    controller_keys,
    default_topics,
)
from umbmark.robot.ros_robot import RosRobot
from umbmark.robot.urdf import static_mount, urdf_footprint, urdf_geometry, urdf_mount

if TYPE_CHECKING:
    from umbmark.sources.bag.imu_frames import ImuMounting

__all__ = ["Ros2Robot", "call_service", "controller_params"]

#: The velocity types a diff_drive_controller subscribes.
STAMPED, UNSTAMPED = "geometry_msgs/msg/TwistStamped", "geometry_msgs/msg/Twist"
#: Its velocity topics in its namespace (diff_drive_controller.cpp's
#: ``DEFAULT_COMMAND_TOPIC``, and Humble's and Iron's ``DEFAULT_COMMAND_UNSTAMPED_TOPIC``).
VELOCITY_TOPICS = ("cmd_vel", "cmd_vel_unstamped")
#: How long a twist subscriber that is not the controller's node is waited on, for the
#: controller's own to be discovered too [s] (discovery on a loaded machine takes over 1 s).
DISCOVERY_GRACE = 3.0


def pick_velocity(
    endpoints: Sequence[tuple[str, str, str]], topics: Sequence[str], controller: str
) -> tuple[str, str, str] | None:
    """The velocity topic to publish on, from the graph's subscribers.

    Parameters
    ----------
    endpoints : sequence of (topic, node, type)
        The subscribers of the candidate topics: topic name, the subscribing node's fully
        qualified name, the message type.
    topics : sequence of str
        The candidate topics, preferred first.
    controller : str
        The controller's fully qualified node name (``/diff_drive_controller``).

    Returns
    -------
    (topic, type, node) or None
        The controller's own twist subscription where it has one, else the first twist
        subscriber in ``topics``' order (TwistStamped before Twist on one topic); None
        where no candidate topic has a twist subscriber.
    """
    twists = [e for e in endpoints if e[0] in topics and e[2] in (STAMPED, UNSTAMPED)]
    if not twists:
        return None
    own = [e for e in twists if e[1] == controller] or twists
    topic, node, kind = min(own, key=lambda e: (topics.index(e[0]), e[2] != STAMPED))
    return topic, kind, node


class Ros2Robot(RosRobot):
    """The robot behind a ROS 2 graph (``ROS_DOMAIN_ID``), driven through rclpy.

    Raises
    ------
    InputError
        rclpy is missing, nobody subscribes the velocity topic (or with another type than
        a twist), or the odometry is silent for ``options.timeout`` (one line each).
    """

    name = "ROS 2 robot"

    def __init__(self, options: RosOptions) -> None:
        try:
            import rclpy
            from rclpy.context import Context
            from rclpy.executors import SingleThreadedExecutor
            from rclpy.signals import SignalHandlerOptions
        except ImportError as exc:
            raise InputError(
                f"{option('ros2')} needs rclpy ({exc}): python -m pip install '.[ros2]' in "
                "umbmark's checkout, or source your ROS 2 setup (/opt/ros/DISTRO)"
            ) from None
        given_cmd_vel = bool(options.cmd_vel)
        options = default_topics(options, ros2=True)
        if not (0.0 < options.timeout < math.inf):
            raise InputError(f"timeout {options.timeout!r} s: give a positive time")
        self._closed = False
        self._reload_plan: ReloadPlan | None = None
        self._context = Context()
        rclpy.init(context=self._context, signal_handler_options=SignalHandlerOptions.NO)
        self._node = rclpy.create_node("umbmark_selfcal", context=self._context)
        self._executor = SingleThreadedExecutor(context=self._context)
        self._executor.add_node(self._node)
        self._running = True
        self._spin = threading.Thread(target=self._spin_loop, name="umbmark-ros2", daemon=True)
        self._spin.start()
        self._ticks = threading.Condition()
        self._description: Latest[str] = Latest()
        try:
            self._connect(options, given_cmd_vel)
        except BaseException:
            self.close()
            raise

    def _spin_loop(self) -> None:
        """The executor's thread: spins until :meth:`close` (or the context goes)."""
        with contextlib.suppress(Exception):  # the context shut under it: end quietly
            while self._running and self._context.ok():
                self._executor.spin_once(timeout_sec=0.05)

    def _connect(self, options: RosOptions, given_cmd_vel: bool) -> None:
        from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
        from nav_msgs.msg import Odometry
        from rclpy.qos import DurabilityPolicy, QoSProfile, qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan as ScanMsg
        from sensor_msgs.msg import Range
        from std_msgs.msg import String

        node = self._node
        topic, kind, whose = self._velocity_topic(options, given_cmd_vel)
        options = replace(options, cmd_vel=topic)
        self._velocity_line = _velocity_line(topic, kind, whose, options, given_cmd_vel)
        self._stamped = kind == STAMPED
        twist = TwistStamped if self._stamped else Twist
        self._use_sim = False  # sim time: decided below, once the robot's node is seen
        self._sim_time: float | None = None
        self._start(options, twist, node.create_publisher(twist, options.cmd_vel, 10))
        node.create_subscription(Odometry, options.odom, self._on_odom, 10)
        node.create_subscription(Clock, "/clock", self._on_clock, 10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(
            String, "/robot_description", lambda m: self._description.put(m.data), latched
        )
        self._static: dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]] = {}
        if importlib.util.find_spec("tf2_msgs") is not None:
            from tf2_msgs.msg import TFMessage

            static = QoSProfile(depth=100, durability=DurabilityPolicy.TRANSIENT_LOCAL)
            node.create_subscription(TFMessage, "/tf_static", self._on_static, static)
        if options.scan:
            node.create_subscription(ScanMsg, options.scan, self._scan.put, qos_profile_sensor_data)
        for topic, latest in zip(options.ranges, self._ranges, strict=True):
            node.create_subscription(Range, topic, latest.put, qos_profile_sensor_data)
        if options.truth:
            node.create_subscription(PoseStamped, options.truth, self._on_truth, 10)
        self._wait_connected(self._cmd.get_subscription_count, kind, "nav_msgs/msg/Odometry")
        # the odometry came: the robot's node is discovered, and with it its /clock
        self._use_sim = node.count_publishers("/clock") > 0
        self._subscribe_imu()
        deadline = time.monotonic() + options.timeout
        with self._ticks:
            while self._use_sim and self._sim_time is None:
                if time.monotonic() > deadline:
                    raise InputError(
                        f"/clock is published but said nothing in {options.timeout:g} s"
                    )
                self._ticks.wait(0.01)

    def _subscribe_imu(self) -> None:
        """The IMU topic found on the graph (a second for discovery), subscribed."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import Imu

        def graph() -> list[tuple[str, str]]:
            names = self._node.get_topic_names_and_types()
            return [(name, kind) for name, kinds in names for kind in kinds]

        topic = self._find_imu(graph, min(1.0, self.options.timeout))
        if topic is not None:
            deep = QoSProfile(depth=500, reliability=ReliabilityPolicy.BEST_EFFORT)
            self._node.create_subscription(Imu, topic, self._imu_buffer.put, deep)

    def _imu_mounting(self, frame: str, topic: str) -> ImuMounting:
        """The IMU frame's mounting: ``/tf_static``, else the URDF's fixed joints."""
        from umbmark.robot.ros_imu import imu_edges, imu_mounting_of
        from umbmark.sources.bag.imu_frames import mounting_in

        base = self.options.base_frame
        deadline = time.monotonic() + min(1.0, self.options.timeout)
        while True:  # the latched /tf_static may come a moment after the connection
            with self._ticks:
                static = self._static
            found = mounting_in(imu_edges(static), frame, (base.lstrip("/"),)) if frame else None
            if found is not None or time.monotonic() > deadline:
                break
            time.sleep(0.02)
        if found is not None:
            return found
        text = self._description.wait(min(1.0, self.options.timeout))
        return imu_mounting_of(imu_edges(static, text), frame, base, topic)

    def _velocity_topic(self, options: RosOptions, given: bool) -> tuple[str, str, str]:
        """The velocity topic, its twist type and the node subscribing it, from the graph:
        ``options.cmd_vel`` where ``given``, else the controller's ``cmd_vel`` or
        ``cmd_vel_unstamped`` (:func:`pick_velocity`). A subscriber not the controller's
        node is taken only after :data:`DISCOVERY_GRACE` without the controller's own."""
        timeout = options.timeout
        ns = "/" + "/".join(controller_keys(options.controller))
        topics = [options.cmd_vel] if given else [f"{ns}/{name}" for name in VELOCITY_TOPICS]
        deadline = time.monotonic() + timeout
        grace: float | None = None
        while True:
            endpoints = [
                (topic, _node_name(info.node_namespace, info.node_name), info.topic_type)
                for topic in topics
                for info in self._node.get_subscriptions_info_by_topic(topic)
            ]
            found = pick_velocity(endpoints, topics, ns)
            now = time.monotonic()
            if found is not None:
                grace = now + DISCOVERY_GRACE if grace is None else grace
                if found[2] == ns or now > min(grace, deadline):
                    return found
            elif now > deadline:
                break
            time.sleep(0.05)
        others = sorted({f"{e[0]} ({e[2]})" for e in endpoints})
        if others:
            raise InputError(
                f"the velocity topic is subscribed as no geometry_msgs Twist or TwistStamped: "
                f"{', '.join(others)} ({option('cmd_vel')})"
            )
        raise InputError(
            f"nobody subscribes {' or '.join(topics)} after {timeout:g} s: is the robot's "
            f"controller running, on this ROS_DOMAIN_ID? ({option('controller')}, "
            f"{option('cmd_vel')}) {self._twist_topics()}"
        )

    def _twist_topics(self) -> str:
        """The graph's twist topics that have a subscriber, said in a few words."""
        found = [
            f"{name} ({kind})"
            for name, kinds in self._node.get_topic_names_and_types()
            for kind in kinds
            if kind in (STAMPED, UNSTAMPED) and self._node.count_subscribers(name) > 0
        ]
        if not found:
            return "No twist topic has a subscriber."
        more = f" and {len(found) - 4} more" if len(found) > 4 else ""
        return f"Twist topics with a subscriber: {', '.join(found[:4])}{more}."

    def velocity_note(self) -> str:
        """Which velocity topic and type the robot is driven on, and why (a line for the
        checks before moving)."""
        return self._velocity_line

    def _on_static(self, msg: Any) -> None:  # noqa: ANN401 (a tf2_msgs TFMessage)
        """Keep each static transform: child frame -> parent, translation, rotation."""
        edges = {}
        for tf in msg.transforms:
            t, q = tf.transform.translation, tf.transform.rotation
            edges[tf.child_frame_id.lstrip("/")] = (
                tf.header.frame_id.lstrip("/"), (t.x, t.y, t.z), (q.x, q.y, q.z, q.w),
            )  # fmt: skip
        with self._ticks:
            self._static = {**self._static, **edges}

    def _static_mount(self, frame: str) -> Mount | None:
        """The frame's mounting through ``/tf_static`` (waiting up to a second for it to
        come; None: no ``tf2_msgs`` here, or no such chain)."""
        if importlib.util.find_spec("tf2_msgs") is None:
            return None
        deadline = time.monotonic() + min(1.0, self.options.timeout)
        while True:
            with self._ticks:
                edges = self._static
            found = static_mount(edges, self.options.base_frame, frame)
            if found is not None or time.monotonic() > deadline:
                return found
            time.sleep(0.02)

    def _on_clock(self, msg: Any) -> None:  # noqa: ANN401 (an rclpy message)
        """Sim time: kept here, then the waiting drive loop is woken (rclpy's own time
        source would update the node's clock in another callback, maybe after ours)."""
        with self._ticks:
            self._sim_time = float(msg.clock.sec) + 1e-9 * float(msg.clock.nanosec)
            self._ticks.notify_all()

    def _on_odom(self, msg: Any) -> None:  # noqa: ANN401 (an rclpy message)
        super()._on_odom(msg)
        with self._ticks:
            self._ticks.notify_all()

    def _velocity(self, linear: float, angular: float) -> Any:  # noqa: ANN401 (a message)
        msg = self._twist()
        twist = msg.twist if self._stamped else msg
        twist.linear.x, twist.angular.z = linear, angular
        if self._stamped:  # on the controller's clock: never stale, never zero
            nanoseconds = round(self.now() * 1e9)
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(nanoseconds, 1_000_000_000)
        return msg

    def _mount(self, frame: str) -> Mount:
        """The sensor frame's mounting: ``--laser-mount`` for the laser, else
        ``/tf_static``, else the URDF."""
        mount = self._mounts.get(frame)
        if mount is not None:
            return mount
        scan = self._scan.get()
        given = self.options.laser_mount
        if given is not None and scan is not None and scan.header.frame_id == frame:
            mount = Mount(given)
        elif (found := self._static_mount(frame)) is not None:
            mount = found
        else:
            text = self._description.wait(self.options.timeout)
            found = None if text is None else urdf_mount(text, self.options.base_frame, frame)
            if found is None:
                self._stop()
                where = "no URDF on /robot_description" if text is None else "not in the URDF"
                raise InputError(
                    f"no mounting of {frame!r} in {self.options.base_frame} ({where}): give "
                    f"{option('laser_mount', 'x,y,yaw')} (metres, degrees)"
                )
            mount = found
        self._mounts[frame] = mount
        return mount

    def _clock(self) -> threading.Condition:
        return self._ticks

    # --- the Robot interface --------------------------------------------------------

    def now(self) -> float:
        """ROS time [s]: the latest ``/clock`` where it was published when connecting (sim
        time), else the system clock."""
        if self._use_sim and self._sim_time is not None:
            return self._sim_time
        return float(self._node.get_clock().now().nanoseconds) * 1e-9

    def footprint(self) -> tuple[float, float, float] | None:
        """The base link's outline in the URDF on ``/robot_description``: length, width,
        offset [m] (:func:`umbmark.robot.urdf.urdf_footprint`); None: none there."""
        text = self._description.wait(min(1.0, self.options.timeout))
        return None if text is None else urdf_footprint(text, self.options.base_frame)

    def drive_params(self) -> DriveParams:
        """The controller's parameters (its ``get_parameters`` service); the wheel
        separation and radius, where it has none, from the URDF or the options."""
        return controller_params(self.call, self.options, self._description, self._stop)

    def can_apply(self) -> str | None:
        """Why the controller cannot take new parameters while the routine runs (None:
        it can, through the controller manager): said before the robot moves."""
        plan = self._plan()
        return None if plan.way is not None else plan.line

    def apply_note(self) -> str | None:
        """Which way applying goes (a line for the checks before moving), where it can."""
        plan = self._plan()
        return plan.line if plan.way is not None else None

    def _plan(self) -> ReloadPlan:
        if self._reload_plan is None:
            self._reload_plan = reload_plan(self)
        return self._reload_plan

    def apply(self, params: DriveParams, method: ApplyMethod) -> ApplyResult:
        """Write the parameter file (when given) and, where the plan found before moving
        allows, reload the controller through the controller manager; else say how to
        restart it on the new values (:func:`apply_params`)."""
        return apply_params(self, self._plan(), params, method)

    def wait_back(self, since: float) -> None:
        """After a reload: wait until the velocity topic is subscribed again and an
        odometry stamped after ``since`` came (the controller updates again)."""
        timeout = self.options.timeout
        deadline = time.monotonic() + timeout
        while True:
            odom = self._odom.get()
            if self._cmd.get_subscription_count() > 0 and odom is not None and odom.time > since:
                return
            if time.monotonic() > deadline:
                self._stop()
                raise SafetyError(
                    f"the controller was activated again but {self.options.odom} said nothing "
                    f"new in {timeout:g} s: the robot stands"
                )
            time.sleep(0.01)

    def close(self) -> None:
        """A zero velocity, then the executor's thread is joined and the node goes."""
        if self._closed:
            return
        self._closed = True
        if hasattr(self, "_cmd"):
            self._stop()
            time.sleep(0.05)
        self._running = False
        self._spin.join(2.0)
        with contextlib.suppress(Exception):
            self._executor.shutdown(timeout_sec=1.0)
            self._node.destroy_node()
        with contextlib.suppress(Exception):
            self._context.try_shutdown()

    # --- services -----------------------------------------------------------------------

    def call(self, kind: Any, service: str, request: Any) -> Any:  # noqa: ANN401
        """Call a service (waiting ``options.timeout`` for it and for its answer)."""
        return call_service(self._node, kind, service, request, self.options.timeout, self._stop)


# --- what the monitor's node shares: services, the controller's parameters, applying ------


def call_service(
    node: Any,  # noqa: ANN401 (an rclpy Node)
    kind: Any,  # noqa: ANN401 (a service type)
    service: str,
    request: Any,  # noqa: ANN401
    timeout: float,
    stop: Callable[[], None],
) -> Any:  # noqa: ANN401 (its answer)
    """Call a service of ``node``'s graph (waiting ``timeout`` for it and for its answer;
    ``stop`` called before any error: the robot's zero velocity)."""
    client = node.create_client(kind, service)
    try:
        if not client.wait_for_service(timeout_sec=timeout):
            stop()
            raise InputError(f"no service {service} after {timeout:g} s ({option('controller')})")
        future = client.call_async(request)
        deadline = time.monotonic() + timeout
        while not future.done():
            if time.monotonic() > deadline:
                stop()
                raise InputError(f"{service} did not answer in {timeout:g} s")
            time.sleep(0.005)
        return future.result()
    finally:
        node.destroy_client(client)


def controller_params(
    call: Callable[[Any, str, Any], Any],
    options: RosOptions,
    description: Latest[str],
    stop: Callable[[], None],
) -> DriveParams:
    """The controller's parameters (its ``get_parameters`` service, through ``call``); the
    wheel separation and radius, where it has none, from the URDF on
    ``/robot_description`` (``description``) or the options."""
    from rcl_interfaces.srv import GetParameters

    names = ["wheel_separation", "wheel_radius", *MULTIPLIERS]
    request = GetParameters.Request()
    request.names = names
    ns = options.controller.rstrip("/")
    answer = call(GetParameters, f"{ns}/get_parameters", request)
    got = {n: _double(v) for n, v in zip(names, answer.values, strict=False)}
    values = {name: got.get(name) or 0.0 for name in names}
    if not (values["wheel_separation"] > 0.0 and values["wheel_radius"] > 0.0):
        text = description.wait(min(1.0, options.timeout))
        geometry = None if text is None else urdf_geometry(text, options.base_frame)
        sep, radius = geometry or (options.wheel_separation, options.wheel_radius)
        if sep is None or radius is None:
            stop()
            raise InputError(
                f"{ns} has no wheel_separation and wheel_radius, nor has the URDF on "
                f"/robot_description two wheels: is {option('controller')} the "
                "diff_drive_controller?"
            )
        values["wheel_separation"] = values["wheel_separation"] or sep
        values["wheel_radius"] = values["wheel_radius"] or radius
    for name in MULTIPLIERS:
        values[name] = values[name] or 1.0
    return DriveParams(**values)


def _node_name(namespace: str, name: str) -> str:
    """A node's fully qualified name (``/ns/name``; ``/name`` in the root namespace)."""
    return f"{namespace.rstrip('/')}/{name}"


def _velocity_line(topic: str, kind: str, whose: str, options: RosOptions, given: bool) -> str:
    """The check line naming the velocity topic and type, and where they came from."""
    if given:
        why = f"as given by {option('cmd_vel')}, subscribed by {whose}"
    elif whose != "/" + "/".join(controller_keys(options.controller)):
        why = f"subscribed by {whose}, not the controller's node"
    elif topic.endswith("/cmd_vel_unstamped"):
        why = "the controller's subscription: Humble's or Iron's use_stamped_vel false"
    else:
        why = "the controller's subscription"
    return f"velocity commands: {kind} on {topic} ({why})"


def _double(value: Any) -> float | None:  # noqa: ANN401 (rcl_interfaces/ParameterValue)
    """A parameter value as a float (None: not set, or not a number)."""
    kind = getattr(value, "type", 0)
    if kind == 3:  # PARAMETER_DOUBLE
        return float(value.double_value)
    if kind == 2:  # PARAMETER_INTEGER
        return float(value.integer_value)
    return None

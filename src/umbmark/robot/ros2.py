"""A ROS 2 robot behind the :class:`~umbmark.robot.base.Robot` interface, through rclpy.

**Never run.** rclpy cannot be installed on the machines this was written on, so this
adapter has not been run against any ROS 2 system, not even once. It is kept thin on
purpose: the latest messages, the velocity out, the mountings, waiting and sleeping are
:class:`umbmark.robot.ros_robot.RosRobot`'s, every conversion, the apply plan and the
parameter file :mod:`umbmark.robot.ros_common`'s, unit-tested and exercised through the
ROS 1 adapter (:mod:`umbmark.robot.ros1`, tested against a real ROS 1 master). What is
specific to ROS 2 here (rclpy's node, executor, QoS, services) follows rclpy's and
ros2_control's documented APIs but is untested: try it on a robot that stands on blocks
first.

- Velocity out: ``geometry_msgs/msg/Twist`` on ``options.cmd_vel``.
- In: ``nav_msgs/msg/Odometry``, ``sensor_msgs/msg/LaserScan`` (sensor-data QoS), three
  ``sensor_msgs/msg/Range``, a ground-truth ``geometry_msgs/msg/PoseStamped``; mountings
  from TF (``tf2_ros.Buffer``).
- Time: the node's clock; with ``/clock`` published the node uses sim time
  (``use_sim_time``), and :meth:`Ros2Robot.wait` sleeps on it.
- Parameters: ros2_controllers' diff_drive_controller reads its multipliers when it is
  configured, so they are applied by writing the overlay YAML (``options.params_file``,
  ``ros__parameters``) and, with ``options.reload``, reloading the controller through the
  controller manager's services as ros2_control's spawner does: ``switch_controller``
  (deactivate), ``unload_controller``, the manager's ``<controller>.params_file``
  parameter, ``load_controller``, ``configure_controller``, ``switch_controller``
  (activate). Without ``reload`` the result says the controller must be restarted.
- Safety: a zero velocity on :meth:`close` and before any error raised once connected.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
import time
from typing import Any

from umbmark.core.errors import InputError
from umbmark.robot.base import (
    ApplyMethod,
    ApplyResult,
    DriveParams,
)
from umbmark.robot.ros_common import (
    MULTIPLIERS,
    RosOptions,
    plan_apply,
    write_params,
)
from umbmark.robot.ros_robot import RosRobot

__all__ = ["Ros2Robot"]

#: The controller manager's node (ros2_control's default).
CONTROLLER_MANAGER = "/controller_manager"


class Ros2Robot(RosRobot):
    """The robot behind a ROS 2 graph (``ROS_DOMAIN_ID``), driven through rclpy.
    Never run (module documentation).

    Raises
    ------
    InputError
        rclpy is missing, nobody subscribes the velocity topic, or the odometry is silent
        for ``options.timeout`` (one line each).
    """

    name = "ROS 2 robot"

    def __init__(self, options: RosOptions) -> None:
        try:
            import rclpy
            from rclpy.executors import MultiThreadedExecutor
        except ImportError as exc:
            raise InputError(
                f"--ros2 needs rclpy ({exc}): source your ROS 2 setup (/opt/ros/DISTRO)"
            ) from None
        from geometry_msgs.msg import PoseStamped, Twist
        from nav_msgs.msg import Odometry
        from rclpy.qos import qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan as ScanMsg
        from sensor_msgs.msg import Range

        if not (0.0 < options.timeout < math.inf):
            raise InputError(f"timeout {options.timeout!r} s: give a positive time")
        if not rclpy.ok():
            rclpy.init()
        node = self._node = rclpy.create_node("umbmark_selfcal")
        self._ticks = threading.Condition()
        self._start(options, Twist, node.create_publisher(Twist, options.cmd_vel, 10))
        node.create_subscription(Odometry, options.odom, self._on_odom, 10)
        node.create_subscription(Clock, "/clock", self._on_clock, 10)
        if options.scan:
            node.create_subscription(ScanMsg, options.scan, self._scan.put, qos_profile_sensor_data)
        for topic, latest in zip(options.ranges, self._ranges, strict=True):
            node.create_subscription(Range, topic, latest.put, qos_profile_sensor_data)
        if options.truth:
            node.create_subscription(PoseStamped, options.truth, self._on_truth, 10)
        import tf2_ros

        self._tf = tf2_ros.Buffer()
        self._tf_listener = tf2_ros.TransformListener(self._tf, node)
        self._executor = MultiThreadedExecutor()
        self._executor.add_node(node)
        self._spin = threading.Thread(target=self._executor.spin, daemon=True)
        self._spin.start()
        try:
            self._wait_connected(
                self._cmd.get_subscription_count,
                "geometry_msgs/msg/Twist",
                "nav_msgs/msg/Odometry",
            )
        except BaseException:
            self.close()
            raise

    def _on_clock(self, msg: Any) -> None:  # noqa: ANN401 (an rclpy message)
        from rclpy.parameter import Parameter

        if not self._node.get_parameter("use_sim_time").value:
            self._node.set_parameters([Parameter("use_sim_time", Parameter.Type.BOOL, True)])
        with self._ticks:
            self._ticks.notify_all()

    def _on_odom(self, msg: Any) -> None:  # noqa: ANN401 (an rclpy message)
        super()._on_odom(msg)
        with self._ticks:
            self._ticks.notify_all()

    def _lookup(self, base: str, frame: str) -> Any:  # noqa: ANN401 (a TransformStamped)
        from rclpy.duration import Duration
        from rclpy.time import Time

        return self._tf.lookup_transform(
            base, frame, Time(), timeout=Duration(seconds=self.options.timeout)
        )

    def _clock(self) -> threading.Condition:
        return self._ticks

    # --- the Robot interface --------------------------------------------------------

    def now(self) -> float:
        """The node's clock [s] (sim time once ``/clock`` is published)."""
        return float(self._node.get_clock().now().nanoseconds) * 1e-9

    def drive_params(self) -> DriveParams:
        """The controller's parameters, by its ``get_parameters`` service."""
        from rcl_interfaces.srv import GetParameters

        names = ["wheel_separation", "wheel_radius", *MULTIPLIERS]
        request = GetParameters.Request()
        request.names = names
        ns = self.options.controller.rstrip("/")
        answer = self._call(GetParameters, f"{ns}/get_parameters", request)
        got = {n: _double(v) for n, v in zip(names, answer.values, strict=False)}
        fallback = {
            "wheel_separation": self.options.wheel_separation,
            "wheel_radius": self.options.wheel_radius,
        }
        values: dict[str, float] = {}
        for name in names:
            value = got.get(name)
            if value is None:
                value = fallback.get(name, 1.0)
            if value is None:
                raise InputError(f"{ns} has no parameter {name}: give it in the options")
            values[name] = value
        return DriveParams(**values)

    def apply(self, params: DriveParams, method: ApplyMethod) -> ApplyResult:
        """Write the overlay YAML and, with ``options.reload``, reload the controller."""
        plan = plan_apply(params, "yaml" if method == "reconfigure" else method)
        if plan.method == "none":
            return ApplyResult("none", False, plan.reason)
        path = self.options.params_file
        if path is None:
            return ApplyResult(
                "none", False, "ROS 2: give --params-file (the controller reads its multipliers "
                "when configured, from that file): not applied"
            )  # fmt: skip
        notes = write_params(path, params, self.options.controller, ros2=True)
        extra = "".join(f"; {n}" for n in notes)
        if not self.options.reload:
            return ApplyResult(
                "yaml", False, f"wrote {os.fspath(path)}: restart the controller on it (or use "
                f"--reload){extra}", file=os.fspath(path),
            )  # fmt: skip
        self._reload(os.path.abspath(path))
        return ApplyResult(
            "yaml", True, f"wrote {os.fspath(path)} and reloaded the controller{extra}",
            file=os.fspath(path),
        )  # fmt: skip

    def close(self) -> None:
        """A zero velocity, then the node and its executor go."""
        self._stop()
        time.sleep(0.05)
        with contextlib.suppress(Exception):
            self._executor.shutdown(timeout_sec=1.0)
            self._node.destroy_node()

    # --- services -----------------------------------------------------------------------

    def _call(self, kind: Any, service: str, request: Any) -> Any:  # noqa: ANN401
        timeout = self.options.timeout
        client = self._node.create_client(kind, service)
        try:
            if not client.wait_for_service(timeout_sec=timeout):
                self._stop()
                raise InputError(f"no service {service} after {timeout:g} s")
            future = client.call_async(request)
            deadline = time.monotonic() + timeout
            while not future.done():
                if time.monotonic() > deadline:
                    self._stop()
                    raise InputError(f"{service} did not answer in {timeout:g} s")
                time.sleep(0.01)
            return future.result()
        finally:
            self._node.destroy_client(client)

    def _reload(self, path: str) -> None:
        """Reload the controller on ``path``, as ros2_control's spawner loads one."""
        from controller_manager_msgs.srv import (
            ConfigureController,
            LoadController,
            SwitchController,
            UnloadController,
        )
        from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
        from rcl_interfaces.srv import SetParameters

        name = self.options.controller.strip("/").split("/")[-1]
        cm = CONTROLLER_MANAGER

        def switch(activate: list[str], deactivate: list[str]) -> None:
            request = SwitchController.Request()
            request.activate_controllers, request.deactivate_controllers = activate, deactivate
            request.strictness = SwitchController.Request.STRICT
            if not self._call(SwitchController, f"{cm}/switch_controller", request).ok:
                raise InputError(f"{cm} refused to switch {name}")

        def named(kind: Any, service: str) -> None:  # noqa: ANN401
            request = kind.Request()
            request.name = name
            if not self._call(kind, f"{cm}/{service}", request).ok:
                raise InputError(f"{cm}/{service} refused {name}")

        self._stop()
        switch([], [name])
        named(UnloadController, "unload_controller")
        request = SetParameters.Request()
        value = ParameterValue(type=ParameterType.PARAMETER_STRING_ARRAY, string_array_value=[path])
        request.parameters = [Parameter(name=f"{name}.params_file", value=value)]
        result = self._call(SetParameters, f"{cm}/set_parameters", request).results[0]
        if not result.successful:  # ROS 2 before Jazzy: one file, a string
            value = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=path)
            request.parameters = [Parameter(name=f"{name}.params_file", value=value)]
            self._call(SetParameters, f"{cm}/set_parameters", request)
        named(LoadController, "load_controller")
        named(ConfigureController, "configure_controller")
        switch([name], [])


def _double(value: Any) -> float | None:  # noqa: ANN401 (rcl_interfaces/ParameterValue)
    """A parameter value as a float (None: not set, or not a number)."""
    kind = getattr(value, "type", 0)
    if kind == 3:  # PARAMETER_DOUBLE
        return float(value.double_value)
    if kind == 2:  # PARAMETER_INTEGER
        return float(value.integer_value)
    return None

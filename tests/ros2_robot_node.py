"""A ROS 2 node simulating a differential-drive robot behind ros2_controllers'
``diff_drive_controller``, with :class:`umbmark.robot.virtual.VirtualRobot` underneath (for
tests/test_ros2.py and benchmarks/bench_ros2.py). Run it with the ROS 2 wheels' Python
(``.venv-ros2``); it prints ``ready`` on stdout once everything is up.

The controller's interfaces as ros2_controllers has them (``diff_drive_controller.cpp``,
``odometry.cpp``, ``diff_drive_controller_parameter.yaml``; ``--distro``, default Kilted):

- the controller is a node of its own, ``/diff_drive_controller`` (``--controller``); the
  clock, laser, truth and URDF are published by ``/sim_robot``. Its velocity subscription
  is created by ``on_configure`` and dropped by ``on_cleanup`` (``reset()``), on every
  distribution: none while unconfigured, kept while inactive (commands then ignored).
  Which one (the branches' ``diff_drive_controller.cpp``):

  - Humble and Iron (``--distro humble``): the parameter ``use_stamped_vel`` (default
    true, read on configure): true, ``geometry_msgs/TwistStamped`` on ``~/cmd_vel``
    (``DEFAULT_COMMAND_TOPIC``); false, ``geometry_msgs/Twist`` on ``~/cmd_vel_unstamped``
    (``DEFAULT_COMMAND_UNSTAMPED_TOPIC``, stamped with the time it came) and nothing on
    ``~/cmd_vel``;
  - Jazzy, Kilted and Rolling: ``use_stamped_vel`` is gone (ros2_controllers #812, 4.0.0):
    ``TwistStamped`` on ``~/cmd_vel`` only, whatever the parameter files say.

  A zero stamp is taken as "now"; a message whose stamp is older than ``cmd_vel_timeout``
  (0.5 s) when it comes is ignored (Jazzy's rule, kept for Humble here); at each update a
  command older than the timeout brakes (zero velocity);
- it publishes ``~/odom`` (``nav_msgs/Odometry``, ``odom`` -> ``base_link``) every update;
  ``/tf`` too where ``tf2_msgs`` is importable;
- its parameters ``wheel_separation``, ``wheel_radius``, ``wheel_separation_multiplier``,
  ``left_wheel_radius_multiplier``, ``right_wheel_radius_multiplier``, ``cmd_vel_timeout``
  are declared from ``--params-file`` (a ros2_control YAML, ``ros__parameters``; several
  may be given, later ones override) and read only when the controller is configured
  (``on_configure``): on Humble, Jazzy and Kilted ``set_parameters`` succeeds and changes
  nothing until then; ``--distro rolling``: the multipliers are read-only (set_parameters
  refused; only the parameter files a load reads set them);
- a configure resets the odometry's pose to zero; its first update afterwards moves it
  by the wheels' rotation times the radius change (Humble to Kilted with position
  feedback: ``odometry.cpp`` keeps the last wheel positions in metres at the old radii),
  and a controller just loaded by the wheels' whole travel (its remembered positions are
  zero; the hardware's are not) (``VirtualRobot.configure_controller``). It publishes
  ``~/odom`` and takes commands only while active (``on_deactivate`` halts the wheels);
- where ``controller_manager_msgs`` is importable (``tools/build_ros2_interfaces.py``), a
  controller manager, ``/controller_manager``, with ``~/list_controllers``,
  ``~/switch_controller``, ``~/configure_controller``, ``~/load_controller`` and
  ``~/unload_controller``, ``~/cleanup_controller`` under controller_manager.cpp's rules
  (Kilted): configure only an unconfigured or inactive controller (an inactive one is
  cleaned up first), clean up only an inactive one (an unconfigured one: nothing), unload
  only one not active (its node destroyed), load only one not loaded (its node created
  on the files of the manager's ``NAME.params_file``, a string array as the spawner sets
  it), switch (STRICT) to activate only an inactive one and deactivate only an active
  one. ``--fail-configure``: every configure through the manager fails (``on_configure``
  returned FAILURE: the controller stays unconfigured). At its end the node prints
  ``final {json}``: the parameters its controller runs on, its node's parameters, its
  state, the manager's calls in order, the odometry's first pose after each activation,
  its velocity subscription (topic and type, or null);
- ``/clock`` (``rosgraph_msgs/Clock``) runs ``--rate`` times faster than real time, one
  controller period (20 ms) at a time, from 1000 s;
- ``/robot_description`` (``std_msgs/String``, transient local, as robot_state_publisher
  publishes it): a URDF with ``base_link``, the two wheel joints (``wheel_separation``
  apart, cylinders of ``wheel_radius``) and the laser joint (``--laser-x`` ahead,
  ``--upside-down``: rolled by 180 degrees, its beams then published in reverse order;
  ``--laser-only-in-tf``: left out); where ``tf2_msgs`` is importable, the laser's
  mounting on ``/tf_static`` too (``base_link`` -> ``laser_mount`` -> ``laser``); with
  ``--stated-laser x,y,yaw`` both state that mounting, while the beams are cast from the
  true one (a description that is off);
- ``/scan`` (``sensor_msgs/LaserScan``, frame ``laser``, sensor-data QoS) every
  ``--scan-every`` periods (none with ``--no-laser``); ``/ground_truth``
  (``geometry_msgs/PoseStamped``, the true pose);
- its IMU as a robot's driver publishes it (unless ``--no-imu``): ``/imu``
  (``sensor_msgs/Imu``, frame ``imu_link``, rates and accelerations in that frame, no
  orientation) at ``--imu-rate``, read from the robot's own motion by the virtual robot's
  IMU (``--gyro-scale``, ``--gyro-bias``, ``--gyro-bias-walk``, ``--imu-roll``:
  tests/robot_node_imu.py), its mounting a fixed joint of the URDF and on ``/tf_static``;
  ``--imu-truth FILE``: its truth written there at the start;
- ``/sim/control`` (``std_msgs/String``): the IMU's faults as ROS 1's node takes them
  (``mute_imu``, ``freeze_imu``, ``mend_imu``), ``mute_scan`` and ``unmute_scan``, and
  the events of tests/robot_node_events.py (a wheel changed, the laser knocked: also at a
  given time, ``--change-wheel-at``, ``--knock-laser-at``; ``--truth FILE``), the faults
  of tests/robot_node_faults.py (``reset_clock``: a simulation reset as Gazebo's;
  ``restart_controller``: the controller deactivated, configured and activated again, its
  odometry from zero; every ``set_parameters`` on the controller kept, with the robot's
  true speed then), and ``--world warehouse`` for tests/mission_driver.py.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import threading
from dataclasses import replace
from pathlib import Path
from typing import Any

import rclpy
import yaml
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, qos_profile_sensor_data
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState, LaserScan
from std_msgs.msg import String

from robot_node_events import Events, event_arguments, joint_state_values, node_world
from robot_node_faults import Faults
from robot_node_imu import ImuFault, imu_arguments, imu_setup
from robot_node_pace import Pace
from umbmark.robot.base import DriveParams
from umbmark.robot.virtual import VirtualRobot

#: ROS time at the simulation's start [s].
T0 = 1000.0
#: The parameters the controller reads when configured, and their defaults here.
DEFAULTS = {
    "wheel_separation": 0.34,
    "wheel_radius": 0.075,
    "wheel_separation_multiplier": 1.0,
    "left_wheel_radius_multiplier": 1.0,
    "right_wheel_radius_multiplier": 1.0,
    "cmd_vel_timeout": 0.5,
}


def _stamp(t: float) -> tuple[int, int]:
    ns = round((T0 + t) * 1e9)
    return ns // 1_000_000_000, ns % 1_000_000_000


def _quaternion(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def _blocks(files: list[str], controller: str) -> list[dict[str, Any]]:
    """The controller's ``ros__parameters`` in each file, in order."""
    name = controller.strip("/").split("/")[-1]
    out = []
    for path in files:
        data = yaml.safe_load(Path(path).read_text()) or {}
        out.append((data.get(name) or {}).get("ros__parameters") or {})
    return out


def read_params(files: list[str], controller: str) -> dict[str, float]:
    """The controller's parameters from ros2_control YAML files (later files override)."""
    values = dict(DEFAULTS)
    for block in _blocks(files, controller):
        for key in DEFAULTS:
            if key in block:
                values[key] = float(block[key])
    return values


def read_stamped(files: list[str], controller: str) -> bool:
    """Humble's ``use_stamped_vel`` from the files (later files override; default true)."""
    value = True
    for block in _blocks(files, controller):
        if "use_stamped_vel" in block:
            value = bool(block["use_stamped_vel"])
    return value


def urdf(
    separation: float,
    radius: float,
    laser_x: float,
    upside_down: bool,
    laser: bool = True,
    stated: tuple[float, float, float] | None = None,
    imu_roll: float | None = None,
) -> str:
    """The robot's description: base_link, two wheels, the laser (``laser``: in it) at
    ``laser_x`` ahead, or where ``stated`` (x, y, yaw) says; the IMU rolled ``imu_roll``
    [rad] (None: no IMU)."""
    roll = math.pi if upside_down else 0.0
    x, y, yaw = stated or (laser_x, 0.0, 0.0)

    def wheel(side: str, y: float) -> str:
        return f"""
  <link name="{side}_wheel"><collision><geometry>
    <cylinder radius="{radius}" length="0.04"/></geometry></collision></link>
  <joint name="{side}_wheel_joint" type="continuous">
    <parent link="base_link"/><child link="{side}_wheel"/>
    <origin xyz="0 {y} {radius}" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
  </joint>"""

    mounted = f"""
  <link name="laser"/>
  <joint name="laser_joint" type="fixed">
    <parent link="base_link"/><child link="laser"/>
    <origin xyz="{x} {y} 0.2" rpy="{roll} 0 {yaw}"/>
  </joint>"""
    wheels = wheel("left", separation / 2) + wheel("right", -separation / 2)
    imu = (
        ""
        if imu_roll is None
        else f"""
  <link name="imu_link"/>
  <joint name="imu_joint" type="fixed">
    <parent link="base_link"/><child link="imu_link"/>
    <origin xyz="-0.05 0.02 0.12" rpy="{imu_roll} 0 0"/>
  </joint>"""
    )
    return f"""<?xml version="1.0"?>
<robot name="sim_robot">
  <link name="base_link"/>{wheels}{mounted if laser else ""}{imu}
</robot>
"""


class Controller:
    """The diff_drive_controller's node: its parameters (declared from the parameter files;
    Rolling: the multipliers read-only; Humble: ``use_stamped_vel`` too), ``~/odom``, the
    velocity subscription (from configure to cleanup); its lifecycle state."""

    def __init__(self, sim: SimNode, values: dict[str, float]) -> None:
        self.sim = sim
        self.node = node = rclpy.create_node(sim.name)
        read_only = sim.args.distro == "rolling"
        for key, value in values.items():  # set_parameters changes these, not the robot
            locked = read_only and key.endswith("_multiplier")
            node.declare_parameter(key, value, ParameterDescriptor(read_only=locked))
        sim.faults.watch(node)
        if sim.args.distro == "humble":  # Humble's and Iron's parameter (gone in Jazzy)
            node.declare_parameter("use_stamped_vel", read_stamped(sim.files, sim.name))
        self.state = "unconfigured"
        self.timeout = values["cmd_vel_timeout"]
        self.command = (0.0, 0.0)
        self.command_time = -math.inf  # sim time of the command's stamp
        self.odom = node.create_publisher(Odometry, "~/odom", 10)
        self.velocity: Any = None  # velocity_command_(unstamped_)subscriber_
        self.velocity_topic: list[str] | None = None

    def values(self) -> dict[str, float]:
        """The node's parameters now (what on_configure reads)."""
        return {k: float(self.node.get_parameter(k).value) for k in DEFAULTS}

    def subscribe(self) -> None:
        """on_configure's "initialize command subscriber": Humble with ``use_stamped_vel``
        false, Twist on ``~/cmd_vel_unstamped``; else TwistStamped on ``~/cmd_vel``."""
        self.reset()
        humble = self.sim.args.distro == "humble"
        if humble and not self.node.get_parameter("use_stamped_vel").value:
            self.velocity = self.node.create_subscription(
                Twist, "~/cmd_vel_unstamped", self._on_twist, 10
            )
            self.velocity_topic = ["~/cmd_vel_unstamped", "geometry_msgs/msg/Twist"]
        else:
            self.velocity = self.node.create_subscription(
                TwistStamped, "~/cmd_vel", self._on_stamped, 10
            )
            self.velocity_topic = ["~/cmd_vel", "geometry_msgs/msg/TwistStamped"]

    def reset(self) -> None:
        """reset() (on_cleanup, on_error, the start of on_configure): the velocity
        subscription dropped."""
        if self.velocity is not None:
            self.node.destroy_subscription(self.velocity)
        self.velocity, self.velocity_topic = None, None

    def _on_twist(self, msg: Twist) -> None:
        with self.sim.lock:  # Humble's unstamped topic: stamped on arrival
            if self.state != "active":
                return  # subscriber_is_active_ is false
            self.command = (msg.linear.x, msg.angular.z)
            self.command_time = self.sim.robot.now()

    def _on_stamped(self, msg: TwistStamped) -> None:
        with self.sim.lock:
            if self.state != "active":
                return  # subscriber_is_active_ is false
            now = self.sim.robot.now()
            stamp = msg.header.stamp
            t = now if stamp.sec == 0 and stamp.nanosec == 0 else (
                stamp.sec + 1e-9 * stamp.nanosec - T0
            )  # fmt: skip
            if self.timeout != 0.0 and now - t >= self.timeout:
                return  # "Ignoring the received message ... older than the current time"
            self.command = (msg.twist.linear.x, msg.twist.angular.z)
            self.command_time = t


class Manager:
    """``/controller_manager``'s services for the one controller, with
    controller_manager.cpp's rules: configure only an unconfigured or inactive controller
    (an inactive one is cleaned up first), unload only one that is not active, load only
    one not loaded (its ``NAME.type`` set, its ``NAME.params_file`` read now), switch
    (STRICT) only to activate an inactive one and deactivate an active one."""

    def __init__(self, sim: SimNode) -> None:
        from controller_manager_msgs.srv import (
            ConfigureController,
            ListControllers,
            LoadController,
            SwitchController,
            UnloadController,
        )
        from rclpy.parameter import Parameter

        self.sim = sim
        self.node = node = rclpy.create_node(
            "controller_manager", allow_undeclared_parameters=True,
            automatically_declare_parameters_from_overrides=True,
        )  # fmt: skip
        name = sim.name
        node.declare_parameter(f"{name}.type", "diff_drive_controller/DiffDriveController")
        if sim.files:  # as the spawner sets it (--param-file)
            node.set_parameters(
                [Parameter(f"{name}.params_file", Parameter.Type.STRING_ARRAY, sim.files)]
            )
        self.switch_kind = SwitchController
        node.create_service(ListControllers, "~/list_controllers", self._list)
        node.create_service(SwitchController, "~/switch_controller", self._switch)
        node.create_service(ConfigureController, "~/configure_controller", self._configure)
        node.create_service(LoadController, "~/load_controller", self._load)
        node.create_service(UnloadController, "~/unload_controller", self._unload)
        try:  # Jazzy's and later controller_manager_msgs
            from controller_manager_msgs.srv import CleanupController
        except ImportError:
            pass
        else:
            node.create_service(CleanupController, "~/cleanup_controller", self._cleanup)
        sim.executor.add_node(node)

    def _list(self, request: object, response: Any) -> Any:
        from controller_manager_msgs.msg import ControllerState

        with self.sim.lock:
            c = self.sim.controller
            if c is not None:
                response.controller = [
                    ControllerState(
                        name=self.sim.name, state=c.state, update_rate=50,
                        type=self.node.get_parameter(f"{self.sim.name}.type").value,
                    )
                ]  # fmt: skip
        return response

    def _switch(self, request: Any, response: Any) -> Any:
        sim = self.sim
        with sim.lock:
            sim.calls.append(
                f"switch +{','.join(request.activate_controllers)} "
                f"-{','.join(request.deactivate_controllers)}"
            )
            c = sim.controller
            strict = request.strictness == self.switch_kind.Request.STRICT
            wanted = [*request.activate_controllers, *request.deactivate_controllers]
            if any(n != sim.name for n in wanted) or (wanted and c is None):
                response.ok, response.message = not strict, "controller not loaded"
                return response
            if c is not None and sim.name in request.deactivate_controllers:
                if c.state != "active":
                    response.ok, response.message = not strict, "not active"
                    return response
                c.state = "inactive"  # on_deactivate: halt()
            if c is not None and sim.name in request.activate_controllers:
                if c.state != "inactive":
                    response.ok, response.message = not strict, f"{c.state}, not inactive"
                    return response
                c.command, c.command_time = (0.0, 0.0), -math.inf
                c.state = "active"
                sim.reactivated = True
            response.ok, response.message = True, ""
        return response

    def _configure(self, request: Any, response: Any) -> Any:
        sim = self.sim
        with sim.lock:
            sim.calls.append(f"configure {request.name}")
            c = sim.controller
            if c is None or request.name != sim.name or c.state == "active":
                response.ok = False
                return response
            if c.state == "inactive":  # cleaned up first: on_cleanup's reset()
                c.reset()
                c.state = "unconfigured"
            response.ok = sim._configure()
        return response

    def _cleanup(self, request: Any, response: Any) -> Any:
        sim = self.sim
        with sim.lock:
            sim.calls.append(f"cleanup {request.name}")
            c = sim.controller
            if c is None or request.name != sim.name or c.state == "active":
                response.ok = False  # "can not be cleaned-up from 'active' state"
                return response
            if c.state == "inactive":  # an unconfigured one: "all good nothing to do!"
                c.reset()
                c.state = "unconfigured"
            response.ok = True
        return response

    def _load(self, request: Any, response: Any) -> Any:
        sim = self.sim
        with sim.lock:
            sim.calls.append(f"load {request.name}")
            if request.name != sim.name or sim.controller is not None:
                response.ok = False  # "A controller named ... was already loaded"
                return response
            files = self.node.get_parameter_or(f"{sim.name}.params_file", None).value
            sim.files = [files] if isinstance(files, str) else list(files or [])
            sim._load()
            response.ok = True
        return response

    def _unload(self, request: Any, response: Any) -> Any:
        sim = self.sim
        with sim.lock:
            sim.calls.append(f"unload {request.name}")
            c = sim.controller
            if c is None or request.name != sim.name or c.state == "active":
                response.ok = False
                return response
            sim._unload()
            response.ok = True
        return response


class SimNode:
    """The robot (clock, laser, truth, URDF: node ``sim_robot``), its controller (node
    ``--controller``, loaded, configured and active at the start, as a spawner leaves it)
    and, where controller_manager_msgs is importable, the controller manager."""

    def __init__(self, args: argparse.Namespace, executor: SingleThreadedExecutor) -> None:
        self.args, self.executor = args, executor
        self.name = args.controller.strip("/").split("/")[-1]
        self.files = list(args.params_file)
        self.node = node = rclpy.create_node("sim_robot")
        executor.add_node(node)
        configured = read_params(self.files, args.controller)
        world, self.lidar = node_world(args)
        self.robot = VirtualRobot(
            E_d=args.E_d, E_b=args.E_b, E_s=args.E_s, slip=args.slip, seed=args.seed,
            world=replace(world, lidar=None if args.no_laser else self.lidar),
            command_timeout=60.0, imu=imu_setup(args),
            params=DriveParams(**{k: v for k, v in configured.items() if k != "cmd_vel_timeout"}),
        )  # fmt: skip
        self.imu_since, self.imu_fault, self.imu_frame = -1.0, ImuFault(), args.imu_frame
        if args.imu_truth:
            Path(args.imu_truth).write_text(json.dumps(self.robot.imu_truth()), encoding="utf-8")
        self.imu = node.create_publisher(Imu, "/imu", 100)
        self.joints = (
            node.create_publisher(JointState, "/joint_states", 10) if args.joint_states else None
        )
        self.upside_down = args.upside_down
        self.rate, self.scan_every = args.rate, args.scan_every
        self.lock = threading.Lock()
        self.events = Events(args, self.robot, self._stated(), T0)
        self.faults = Faults(self)
        node.create_subscription(String, "/sim/control", self._on_control, 10)
        #: What the controller manager was asked, in order (printed at the end).
        self.calls: list[str] = []
        #: The odometry's first pose after each activation through the manager.
        self.restarts: list[list[float]] = []
        self.reactivated = False
        self.clock = node.create_publisher(Clock, "/clock", 10)
        self.scan = node.create_publisher(LaserScan, "/scan", qos_profile_sensor_data)
        self.truth = node.create_publisher(PoseStamped, "/ground_truth", 10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.description = node.create_publisher(String, "/robot_description", latched)
        self.description.publish(
            String(
                data=urdf(
                    configured["wheel_separation"], configured["wheel_radius"], args.laser_x,
                    args.upside_down, laser=not args.laser_only_in_tf, stated=self._stated(),
                    imu_roll=None if args.no_imu else math.radians(args.imu_roll),
                )
            )
        )  # fmt: skip
        try:
            from tf2_msgs.msg import TFMessage

            self.tf = node.create_publisher(TFMessage, "/tf", 10)
            self.tf_static = node.create_publisher(TFMessage, "/tf_static", latched)
            self.tf_static.publish(TFMessage(transforms=self._static_transforms()))
        except ImportError:
            self.tf = None
        self.controller: Controller | None = None
        self._load()
        self._configure()
        self.controller.state = "active"  # type: ignore[union-attr]
        try:
            import controller_manager_msgs  # noqa: F401
        except ImportError:
            self.manager = None
        else:
            self.manager = Manager(self)

    def _on_control(self, msg: String) -> None:
        """``/sim/control``: the IMU's faults (tests/robot_node_imu.py), the events and the
        laser's muting (tests/robot_node_events.py)."""
        with self.lock:
            self.imu_fault.control(msg.data)
            self.events.control(msg.data)
            self.faults.control(msg.data)

    def _stated(self) -> tuple[float, float, float]:
        """The laser's mounting the robot states (x, y, yaw): ``--stated-laser``, else the
        true one."""
        given = self.args.stated_laser
        if given is None:
            return self.args.laser_x, 0.0, 0.0
        x, y, yaw = (float(v) for v in given.split(","))
        return x, y, yaw

    def _static_transforms(self) -> list[Any]:
        """The laser's mounting as robot_state_publisher puts it on /tf_static, through a
        frame between: base_link -> laser_mount (ahead, up, turned) -> laser (rolled over
        when upside down)."""
        from geometry_msgs.msg import TransformStamped

        x, y, yaw = self._stated()
        out = []
        for parent, child, shift, roll, turn in (
            ("base_link", "laser_mount", (x, y, 0.2), 0.0, yaw),
            ("laser_mount", "laser", (0.0, 0.0, 0.0), math.pi if self.upside_down else 0.0, 0.0),
        ):
            tf = TransformStamped()
            tf.header.stamp.sec, tf.header.stamp.nanosec = _stamp(0.0)
            tf.header.frame_id, tf.child_frame_id = parent, child
            t = tf.transform.translation
            t.x, t.y, t.z = shift
            r = tf.transform.rotation  # a roll or a turn, never both
            r.x, r.y = math.sin(roll / 2), 0.0
            r.z, r.w = math.sin(turn / 2), math.cos(roll / 2) * math.cos(turn / 2)
            out.append(tf)
        truth = self.robot.imu_truth()
        if truth is not None:  # as robot_state_publisher puts the URDF's fixed joint
            tf = TransformStamped()
            tf.header.stamp.sec, tf.header.stamp.nanosec = _stamp(0.0)
            tf.header.frame_id, tf.child_frame_id = "base_link", str(truth["frame"])
            t = tf.transform.translation
            t.x, t.y, t.z = -0.05, 0.02, 0.12
            r = tf.transform.rotation
            r.x, r.y, r.z, r.w = truth["quaternion"]
            out.append(tf)
        return out

    # --- the controller's lifecycle, as controller_manager.cpp runs it ---------------------

    def _load(self) -> None:
        """A new controller node on the parameter files (later files override)."""
        self.controller = Controller(self, read_params(self.files, self.args.controller))
        self.executor.add_node(self.controller.node)
        self.loaded = True

    def _configure(self) -> bool:
        """on_configure: the parameters read now; the odometry's pose reset."""
        controller = self.controller
        assert controller is not None
        if self.args.fail_configure and self.calls:  # the spawner's first configure passes
            controller.reset()
            controller.state = "unconfigured"  # on_configure returned FAILURE
            return False
        values = controller.values()
        params = DriveParams(**{k: v for k, v in values.items() if k != "cmd_vel_timeout"})
        self.robot.configure_controller(params, loaded=self.loaded)
        self.loaded = False
        controller.timeout = values["cmd_vel_timeout"]
        controller.subscribe()
        controller.state = "inactive"
        return True

    def _unload(self) -> None:
        controller = self.controller
        assert controller is not None
        self.executor.remove_node(controller.node)
        controller.node.destroy_node()
        self.controller = None

    def final(self) -> dict[str, object]:
        """What the node ends with: the parameters the controller runs on (its configured
        ones), its node's parameters, its state, the manager's calls."""
        params = self.robot.drive_params()
        controller = self.controller
        return {
            "configured": {k: getattr(params, k) for k in DEFAULTS if k != "cmd_vel_timeout"},
            "declared": None if controller is None else controller.values(),
            "state": None if controller is None else controller.state,
            "calls": self.calls,
            "restarts": self.restarts,
            "params_file": self.files,
            "velocity": None if controller is None else controller.velocity_topic,
            **self.faults.final(),
        }

    def _step(self, step: int) -> None:
        robot, controller = self.robot, self.controller
        if controller is None or controller.state != "active":
            robot.send_velocity(0.0, 0.0)  # on_deactivate's halt(); nothing updates
        else:
            age = robot.now() - controller.command_time
            if controller.timeout != 0.0 and age > controller.timeout:
                robot.send_velocity(0.0, 0.0)  # "Velocity command timed out. Braking."
            else:
                robot.send_velocity(*controller.command)
        robot.wait(robot.period)
        self.events.step()
        self.faults.step()
        self._publish(step)

    def _publish(self, step: int) -> None:
        robot = self.robot
        sec, nanosec = _stamp(robot.now())
        clock = Clock()
        clock.clock.sec, clock.clock.nanosec = sec, nanosec
        self.clock.publish(clock)
        controller = self.controller
        silent = self.faults.odometry_silent()  # after a reset, Humble to Kilted
        if controller is not None and controller.state == "active" and not silent:
            pose = robot.odometry().pose
            msg = Odometry()
            msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
            msg.header.frame_id, msg.child_frame_id = "odom", "base_link"
            p = msg.pose.pose
            p.position.x, p.position.y = pose.x, pose.y
            q = p.orientation
            q.x, q.y, q.z, q.w = _quaternion(pose.theta)
            controller.odom.publish(msg)
            if self.reactivated:  # the first update after a reload: where it starts
                self.reactivated = False
                self.restarts.append([pose.x, pose.y, pose.theta])
            if self.tf is not None:
                self._publish_tf(msg)
        self._publish_imu()
        if self.joints is not None:
            joints = JointState()
            joints.header.stamp.sec, joints.header.stamp.nanosec = sec, nanosec
            joints.name, joints.position = joint_state_values(robot)
            self.joints.publish(joints)
        if step % self.scan_every == 0:
            self._publish_sensors(sec, nanosec)

    def _publish_imu(self) -> None:
        """The IMU's readings since the last published, each its message."""
        read = self.robot.imu_readings(self.imu_since)
        if read is None or not read.time.size:
            return
        self.imu_since = float(read.time[-1])
        for t, w, a in self.imu_fault.rows(read.time.tolist(), read.rate.tolist(),
                                           read.accel.tolist()):  # fmt: skip
            msg = Imu()
            msg.header.stamp.sec, msg.header.stamp.nanosec = _stamp(t)
            msg.header.frame_id = self.imu_frame
            msg.orientation_covariance[0] = -1.0  # no orientation, as a plain IMU driver
            v = msg.angular_velocity
            v.x, v.y, v.z = w
            f = msg.linear_acceleration
            f.x, f.y, f.z = a
            self.imu.publish(msg)

    def _publish_tf(self, odom: Odometry) -> None:
        from geometry_msgs.msg import TransformStamped
        from tf2_msgs.msg import TFMessage

        tf = TransformStamped()
        tf.header = odom.header
        tf.child_frame_id = "base_link"
        tf.transform.translation.x = odom.pose.pose.position.x
        tf.transform.translation.y = odom.pose.pose.position.y
        tf.transform.rotation = odom.pose.pose.orientation
        self.tf.publish(TFMessage(transforms=[tf]))

    def _publish_sensors(self, sec: int, nanosec: int) -> None:
        robot = self.robot
        scan = None if self.events.mute_scan else robot.scan()
        if scan is not None:
            msg = LaserScan()
            msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
            msg.header.frame_id = "laser"
            ranges, angle_min = scan.ranges, scan.angle_min
            if self.upside_down:  # its beams run clockwise seen from above
                angle_min = -(scan.angle_min + scan.angle_increment * (ranges.size - 1))
                ranges = ranges[::-1]
            msg.angle_min, msg.angle_increment = angle_min, scan.angle_increment
            msg.angle_max = angle_min + scan.angle_increment * (ranges.size - 1)
            msg.range_min, msg.range_max = scan.range_min, scan.range_max
            msg.ranges = [float(r) for r in ranges]
            self.scan.publish(msg)
        true = robot.true_pose
        truth = PoseStamped()
        truth.header.stamp.sec, truth.header.stamp.nanosec = sec, nanosec
        truth.header.frame_id = "world"
        truth.pose.position.x, truth.pose.position.y = true.x, true.y
        o = truth.pose.orientation
        o.x, o.y, o.z, o.w = _quaternion(true.theta)
        self.truth.publish(truth)

    def run(self, stop: threading.Event) -> None:
        period = self.robot.period
        wall_step = period / self.rate
        with self.lock:
            self._publish(0)
        print("ready", flush=True)
        step, pace = 0, Pace(wall_step)
        while not stop.is_set() and rclpy.ok():
            step += 1
            with self.lock:
                try:
                    self._step(step)
                except Exception:
                    if not rclpy.ok():  # Ctrl-C shut the context down under the loop
                        return
                    raise
            pace.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=8.0, help="times faster than real time")
    parser.add_argument("--scan-every", type=int, default=5, help="periods between scans")
    parser.add_argument("--controller", default="/diff_drive_controller")
    parser.add_argument("--params-file", action="append", default=[])
    parser.add_argument("--E-d", dest="E_d", type=float, default=1.004)
    parser.add_argument("--E-b", dest="E_b", type=float, default=0.97)
    parser.add_argument("--E-s", dest="E_s", type=float, default=1.0)
    parser.add_argument("--slip", type=float, default=0.0004)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--laser-x", type=float, default=0.1)
    parser.add_argument("--upside-down", action="store_true")
    parser.add_argument(
        "--stated-laser", default=None,
        help="x,y,yaw [m, m, rad]: the mounting the URDF and /tf_static state, where it is "
        "off the true one (--laser-x ahead)",
    )  # fmt: skip
    parser.add_argument(
        "--laser-only-in-tf", action="store_true",
        help="the URDF has no laser: only /tf_static mounts it (needs tf2_msgs)",
    )  # fmt: skip
    parser.add_argument(
        "--distro", choices=("humble", "jazzy", "kilted", "rolling"), default="kilted",
        help="humble (and Iron): use_stamped_vel from the parameter files (false: Twist on "
        "~/cmd_vel_unstamped); jazzy, kilted: TwistStamped on ~/cmd_vel, the multipliers "
        "can be set and are read on configure; rolling: they are read-only",
    )  # fmt: skip
    parser.add_argument(
        "--fail-configure", action="store_true",
        help="configure_controller fails (on_configure returns FAILURE) after the start",
    )  # fmt: skip
    imu_arguments(parser)
    event_arguments(parser)
    args = parser.parse_args()
    # SIGINT is KeyboardInterrupt even where the node was started with it ignored (a
    # background job of a shell), so that closing it takes no 10 s time-out
    signal.signal(signal.SIGINT, signal.default_int_handler)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    executor = SingleThreadedExecutor()
    sim = SimNode(args, executor)
    stop = threading.Event()
    runner = threading.Thread(target=sim.run, args=(stop,), daemon=True)
    runner.start()
    try:
        while rclpy.ok():  # woken every 0.1 s, so that SIGINT is seen at once
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        stop.set()
        runner.join(2.0)
        with sim.lock:
            print("final " + json.dumps(sim.final()), flush=True)
        executor.shutdown(timeout_sec=1.0)
        for node in executor.get_nodes():
            node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()

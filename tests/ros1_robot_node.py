"""A ROS 1 node simulating a differential-drive robot and its diff_drive_controller, with
:class:`umbmark.robot.virtual.VirtualRobot` underneath (for tests/test_ros1.py and
benchmarks/bench_ros1.py).

Run it with ``ROS_MASTER_URI`` set; it prints ``ready`` on stdout once everything is up.

- sets ``/use_sim_time`` and publishes ``/clock``: the simulation advances one controller
  period (20 ms) at a time, ``--rate`` times faster than real time;
- subscribes ``/cmd_vel`` (``geometry_msgs/Twist``), the command stamped with the
  simulation's time when it arrives (the controller's ``cmd_vel_timeout`` is 0.5 s);
- publishes ``/odom`` (``nav_msgs/Odometry``, frame ``odom`` -> ``base_link``) every period,
  ``/scan`` (``sensor_msgs/LaserScan``, frame ``laser``) every ``--scan-every`` periods,
  ``/ground_truth`` (``geometry_msgs/PoseStamped``, motion capture), ``/tf``
  (``odom -> base_link``) and ``/tf_static`` (``base_link -> laser``: the laser
  ``--laser-x`` metres ahead of the centre and 0.2 m up, ``--upside-down`` rolled by 180
  degrees, its beams then published in the reversed order such a laser has; with
  ``--stated-laser x,y,yaw`` that mounting stated, while the beams are cast from the true
  one); the corner behind the
  start on its right, or ``--corner-side left``;
- publishes its IMU as a robot's driver does (unless ``--no-imu``): ``/imu/data``
  (``sensor_msgs/Imu``, frame ``imu_link``, its rates and accelerations in that frame, no
  orientation) at ``--imu-rate``, read from the robot's own motion by the virtual robot's
  IMU (:class:`umbmark.sim.imu.ImuSetup`: ``--gyro-scale`` k_g, ``--gyro-bias`` [deg/s]
  with ``--gyro-bias-walk``, mounted ``--imu-roll`` [deg]), its mounting on ``/tf_static``
  beside the laser's; ``--imu-truth FILE``: its truth written there at the start;
  ``--no-laser``: no laser (no ``/scan``);
- serves dynamic_reconfigure at ``/diff_drive_controller`` with the three multipliers of
  ros_controllers' ``DiffDriveController.cfg`` (0.5 to 1.5, the server clamps), and keeps
  ``wheel_separation``, ``wheel_radius`` and the multipliers on the parameter server;
- ``/sim/control`` (``std_msgs/String``): ``mute_odom`` stops the odometry (the clock goes
  on), ``unmute_odom`` starts it again, ``mute_imu``, ``freeze_imu`` and ``mend_imu``
  make its IMU's driver fall silent, freeze, read again (tests/robot_node_imu.py);
  ``/sim/true_pose`` (``geometry_msgs/Pose2D``) is the robot's true pose in the world, for
  checks;
- ``--world warehouse`` (the fleet's warehouse, for tests/mission_driver.py), a wheel
  changed and the laser knocked mid-run (``--change-wheel-at``, ``--knock-laser-at``, or
  ``change_wheel``, ``knock_laser`` on ``/sim/control``), ``mute_scan`` and ``unmute_scan``,
  ``--truth FILE``: tests/robot_node_events.py.
"""

from __future__ import annotations

import argparse
import json
import math
import threading
import types
from dataclasses import replace

import numpy as np
import rospy
from dynamic_reconfigure.encoding import extract_params
from dynamic_reconfigure.server import Server
from geometry_msgs.msg import Pose2D as Pose2DMsg
from geometry_msgs.msg import PoseStamped, TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState, LaserScan
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from robot_node_events import Events, event_arguments, joint_state_values, node_world
from robot_node_imu import ImuFault, imu_arguments, imu_setup
from robot_node_pace import Pace
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import LCorner, World, corner_world

#: ROS time at the simulation's start [s] (ROS time 0 means "no time yet").
T0 = 1000.0
CONTROLLER = "/diff_drive_controller"
MULTIPLIERS = (
    "wheel_separation_multiplier",
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
)


def _param(name: str, description: str) -> dict[str, object]:
    return {
        "name": name,
        "type": "double",
        "default": 1.0,
        "level": 0,
        "description": description,
        "min": 0.5,
        "max": 1.5,
        "edit_method": "",
        "ctype": "double",
        "cconsttype": "const double",
    }


def diff_drive_config() -> types.SimpleNamespace:
    """What dynamic_reconfigure generates from DiffDriveController.cfg (its three
    multipliers): ``config_description`` (the Default group), ``defaults``, ``min``,
    ``max``, ``level``, ``type``, as ``dynamic_reconfigure.server.Server`` reads them."""
    description = {
        "name": "Default",
        "type": "",
        "state": True,
        "cstate": "true",
        "id": 0,
        "parent": 0,
        "parameters": [
            _param("wheel_separation_multiplier", "Wheel separation multiplier."),
            _param("left_wheel_radius_multiplier", "Left wheel radius multiplier."),
            _param("right_wheel_radius_multiplier", "Right wheel radius multiplier."),
        ],
        "groups": [],
        "class": "DEFAULT",
        "parentclass": "",
        "parentname": "Default",
        "field": "default",
        "upper": "DEFAULT",
        "lower": "groups",
    }
    config = types.SimpleNamespace(
        config_description=description, min={}, max={}, defaults={}, level={}, type={}
    )
    for p in extract_params(description):
        for key, table in (
            ("min", config.min),
            ("max", config.max),
            ("default", config.defaults),
            ("level", config.level),
            ("type", config.type),
        ):
            table[p["name"]] = p[key]
    return config


def urdf(separation: float, radius: float, laser_x: float) -> str:
    """A robot description with the wheels ``separation`` apart, the laser, and a base
    0.45 m long, 0.38 m wide, its centre 5 cm behind the axle."""
    wheels = "".join(
        f"""
  <link name="{side}_wheel"><collision><geometry><cylinder radius="{radius}" length="0.04"/>
  </geometry></collision></link>
  <joint name="{side}_wheel_joint" type="continuous">
    <parent link="base_link"/><child link="{side}_wheel"/>
    <origin xyz="0 {y} {radius}" rpy="-1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
  </joint>"""
        for side, y in (("left", separation / 2), ("right", -separation / 2))
    )
    return f"""<?xml version="1.0"?>
<robot name="sim_robot"><link name="base_link"><collision><origin xyz="-0.05 0 0.1"/>
  <geometry><box size="0.45 0.38 0.2"/></geometry></collision></link>{wheels}
  <link name="laser"/>
  <joint name="laser_joint" type="fixed"><parent link="base_link"/><child link="laser"/>
    <origin xyz="{laser_x} 0 0.2"/></joint>
</robot>
"""


def _stamp(t: float) -> rospy.Time:
    return rospy.Time.from_sec(T0 + t)


def _quaternion(yaw: float, roll: float = 0.0) -> tuple[float, float, float, float]:
    """x, y, z, w of a yaw about z followed by a roll about the new x axis."""
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    return (cy * sr, sy * sr, sy * cr, cy * cr)


class SimNode:
    def __init__(self, args: argparse.Namespace) -> None:
        world = corner_world(side=args.corner_side)
        if args.tight_corner:  # walls 0.45 m behind, 0.4 m beside the 1 m cw square's far leg
            corner = LCorner(vertex=(-0.45, -1.4), heading=0.0, x_length=3.0, y_length=3.4)
            world = World.build(np.zeros((0, 4)), (), corner, lidar=world.lidar)
        world, self.lidar = node_world(args, world)
        world = replace(world, lidar=None if args.no_laser else self.lidar)
        self.robot = VirtualRobot(
            E_d=args.E_d, E_b=args.E_b, E_s=args.E_s, slip=args.slip, seed=args.seed,
            world=world, acceleration=args.acceleration, imu=imu_setup(args),
        )  # fmt: skip
        self.imu_since, self.imu_fault, self.imu_frame = -1.0, ImuFault(), args.imu_frame
        if args.imu_truth:
            with open(args.imu_truth, "w", encoding="utf-8") as f:
                json.dump(self.robot.imu_truth(), f)
        stated = args.stated_laser
        self.stated = (
            (args.laser_x, 0.0, 0.0) if stated is None else tuple(map(float, stated.split(",")))
        )
        self.upside_down = args.upside_down
        self.rate, self.scan_every = args.rate, args.scan_every
        self.lock = threading.Lock()
        self.mute_odom = False
        self.events = Events(args, self.robot, self.stated, T0)
        if args.urdf_geometry:  # as most robots: the controller reads the URDF
            rospy.set_param("/robot_description", urdf(0.34, 0.075, args.laser_x))
            rospy.set_param(f"{CONTROLLER}/left_wheel", "left_wheel_joint")
            rospy.set_param(f"{CONTROLLER}/right_wheel", ["right_wheel_joint"])
        else:
            rospy.set_param(f"{CONTROLLER}/wheel_separation", 0.34)
            rospy.set_param(f"{CONTROLLER}/wheel_radius", 0.075)
        for name in MULTIPLIERS:  # as the controller's YAML loads them, before the server
            rospy.set_param(f"{CONTROLLER}/{name}", 1.0)
        self.clock = rospy.Publisher("/clock", Clock, queue_size=10)
        self.odom = rospy.Publisher("/odom", Odometry, queue_size=10)
        self.scan = rospy.Publisher("/scan", LaserScan, queue_size=2)
        self.truth = rospy.Publisher("/ground_truth", PoseStamped, queue_size=2)
        self.true_pose = rospy.Publisher("/sim/true_pose", Pose2DMsg, queue_size=2)
        self.tf = rospy.Publisher("/tf", TFMessage, queue_size=10)
        self.tf_static = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        self.imu = rospy.Publisher("/imu/data", Imu, queue_size=200)
        self.joints = (
            rospy.Publisher("/joint_states", JointState, queue_size=10)
            if args.joint_states else None
        )  # fmt: skip
        mounts = [self._laser_transform()]
        if self.robot.imu() is not None:
            mounts.append(self._imu_transform())
        self.tf_static.publish(TFMessage(mounts))
        self.server = Server(diff_drive_config(), self._reconfigure, namespace=CONTROLLER)
        rospy.Subscriber("/cmd_vel", Twist, self._on_cmd, queue_size=10, tcp_nodelay=True)
        rospy.Subscriber("/sim/control", String, self._on_control, queue_size=10)

    def _laser_transform(self) -> TransformStamped:
        t = TransformStamped()
        t.header.stamp = _stamp(0.0)
        t.header.frame_id, t.child_frame_id = "base_link", "laser"
        x, y, yaw = self.stated
        t.transform.translation.x, t.transform.translation.y = x, y
        t.transform.translation.z = 0.2
        q = _quaternion(yaw, math.pi if self.upside_down else 0.0)
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = q
        return t

    def _imu_transform(self) -> TransformStamped:
        """``base_link -> imu_link``: where the IMU sits, its rotation as mounted."""
        from umbmark.sim.imu import IMU_TRANSLATION

        truth = self.robot.imu_truth()
        assert truth is not None
        t = TransformStamped()
        t.header.stamp = _stamp(0.0)
        t.header.frame_id, t.child_frame_id = "base_link", str(truth["frame"])
        tr = t.transform.translation
        tr.x, tr.y, tr.z = IMU_TRANSLATION
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = truth["quaternion"]  # type: ignore[misc]
        return t

    def _publish_imu(self) -> None:
        """The IMU's readings since the last published, each its message."""
        read = self.robot.imu_readings(self.imu_since)
        if read is None or not read.time.size:
            return
        self.imu_since = float(read.time[-1])
        for t, w, a in self.imu_fault.rows(read.time.tolist(), read.rate.tolist(),
                                           read.accel.tolist()):  # fmt: skip
            msg = Imu()
            msg.header.stamp, msg.header.frame_id = _stamp(t), self.imu_frame
            msg.orientation_covariance = [-1.0] + [0.0] * 8  # no orientation, as a driver
            v, f = msg.angular_velocity, msg.linear_acceleration
            v.x, v.y, v.z = w
            f.x, f.y, f.z = a
            self.imu.publish(msg)

    def _reconfigure(self, config: dict[str, float], level: int) -> dict[str, float]:
        with self.lock:
            old = self.robot.drive_params()
            new = replace(old, **{k: float(config[k]) for k in MULTIPLIERS})
            if new != old:
                self.robot.apply(new, "reconfigure")
        return config

    def _on_cmd(self, msg: Twist) -> None:
        with self.lock:
            self.robot.send_velocity(msg.linear.x, msg.angular.z)

    def _on_control(self, msg: String) -> None:
        self.mute_odom = {"mute_odom": True, "unmute_odom": False}.get(msg.data, self.mute_odom)
        self.imu_fault.control(msg.data)
        with self.lock:
            self.events.control(msg.data)

    def _publish(self, step: int) -> None:
        robot = self.robot
        t = robot.now()
        stamp = _stamp(t)
        self.clock.publish(Clock(stamp))
        odom = robot.odometry()
        pose = odom.pose
        if not self.mute_odom:
            msg = Odometry()
            msg.header.stamp, msg.header.frame_id = stamp, "odom"
            msg.child_frame_id = "base_link"
            p = msg.pose.pose
            p.position.x, p.position.y = pose.x, pose.y
            q = _quaternion(pose.theta)
            p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = q
            self.odom.publish(msg)
            tf = TransformStamped()
            tf.header = msg.header
            tf.child_frame_id = "base_link"
            tf.transform.translation.x, tf.transform.translation.y = pose.x, pose.y
            tf.transform.rotation = p.orientation
            self.tf.publish(TFMessage([tf]))
        self._publish_imu()
        if self.joints is not None:
            joints = JointState()
            joints.header.stamp = stamp
            joints.name, joints.position = joint_state_values(robot)
            self.joints.publish(joints)
        if step % self.scan_every == 0:
            self._publish_sensors(stamp)

    def _publish_sensors(self, stamp: rospy.Time) -> None:
        robot = self.robot
        scan = None if self.events.mute_scan else robot.scan()
        if scan is not None:
            msg = LaserScan()
            msg.header.stamp, msg.header.frame_id = stamp, "laser"
            ranges = scan.ranges
            angle_min = scan.angle_min
            if self.upside_down:  # its beams run clockwise seen from above
                angle_min = -(scan.angle_min + scan.angle_increment * (ranges.size - 1))
                ranges = ranges[::-1]
            msg.angle_min, msg.angle_increment = angle_min, scan.angle_increment
            msg.angle_max = angle_min + scan.angle_increment * (ranges.size - 1)
            msg.range_min, msg.range_max = scan.range_min, scan.range_max
            msg.ranges = [float(r) for r in ranges]
            self.scan.publish(msg)
        truth = robot.ground_truth()
        if truth is not None:
            msg_t = PoseStamped()
            msg_t.header.stamp, msg_t.header.frame_id = stamp, "world"
            msg_t.pose.position.x, msg_t.pose.position.y = truth.pose.x, truth.pose.y
            o = msg_t.pose.orientation
            o.x, o.y, o.z, o.w = _quaternion(truth.pose.theta)
            self.truth.publish(msg_t)
        true = robot.true_pose
        self.true_pose.publish(Pose2DMsg(true.x, true.y, true.theta))

    def run(self) -> None:
        period = self.robot.period
        wall_step = period / self.rate
        with self.lock:
            self._publish(0)
        print("ready", flush=True)
        step, pace = 0, Pace(wall_step)
        while not rospy.is_shutdown():
            step += 1
            with self.lock:
                self.robot.wait(period)
                self.events.step()
                self._publish(step)
            pace.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=5.0, help="times faster than real time")
    parser.add_argument("--scan-every", type=int, default=5, help="periods between scans")
    parser.add_argument("--E-d", dest="E_d", type=float, default=1.004)
    parser.add_argument("--E-b", dest="E_b", type=float, default=0.97)
    parser.add_argument("--E-s", dest="E_s", type=float, default=1.0)
    parser.add_argument("--slip", type=float, default=0.0004)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--laser-x", type=float, default=0.1)
    parser.add_argument("--tight-corner", action="store_true", help="issue 29's corner")
    parser.add_argument(
        "--acceleration", type=float, default=5.0, help="the base's braking [m/s^2]"
    )
    parser.add_argument("--upside-down", action="store_true")
    parser.add_argument(
        "--stated-laser", default=None,
        help="x,y,yaw [m, m, rad]: the mounting /tf_static states, off the true one",
    )  # fmt: skip
    parser.add_argument(
        "--corner-side", choices=("right", "left"), default="right", help="the corner's side"
    )
    parser.add_argument(
        "--urdf-geometry",
        action="store_true",
        help="wheel_separation and wheel_radius only in robot_description",
    )
    imu_arguments(parser)
    event_arguments(parser)
    args = parser.parse_args()
    import rosgraph

    rosgraph.Master("/sim_robot_setup").setParam("/use_sim_time", True)
    rospy.init_node("sim_robot", disable_signals=False)
    SimNode(args).run()


if __name__ == "__main__":
    main()

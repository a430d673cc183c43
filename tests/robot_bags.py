"""Bags written the way real robots and their simulations write them, with a known truth.

Three layouts, from what these robots publish (topic names, message types, frames and
rates of their stock configurations):

- :func:`husky_bag`: a Clearpath Husky (ROS 1): the base controller's odometry
  ``/husky_velocity_controller/odom`` (``nav_msgs/Odometry``, ``odom -> base_link``,
  50 Hz), an IMU ``/imu/data``, GNSS fixes ``/navsat/fix`` (``sensor_msgs/NavSatFix`` with
  ``position_covariance``, 10 Hz), robot_localization's ``/odometry/filtered`` (wheel
  odometry fused with the IMU's heading) and the ``odom -> base_link`` transform it
  publishes; no joint states, no ground truth.
- :func:`turtlebot3_bag`: a TurtleBot3 Burger in Gazebo: ``/joint_states``
  (``wheel_left_joint``, ``wheel_right_joint``, positions only), the diff-drive plugin's
  ``/odom`` (``odom -> base_footprint``, 30 Hz, integrated from the wheel angles), Gazebo's
  ``/gazebo/model_states`` (the ground plane, a box and ``turtlebot3_burger``; no
  header), ``/tf`` with ``odom -> base_footprint`` and robot_state_publisher's
  ``base_link -> wheel_left_link`` / ``wheel_right_link`` (the joint origins' ``rpy
  -1.57 0 0`` composed with the turn about the joint axis), ``/tf_static`` and a
  ``/robot_description`` (``std_msgs/String``) whose wheels are 0.160 m apart with
  0.033 m radius; optionally a ``p3d`` ground truth ``/ground_truth/odom``.
- :func:`nav2_bag`: the same robot under Nav2: AMCL's ``/amcl_pose`` (2 Hz) and
  ``map -> odom`` transform, with the odometry.
- :func:`two_bodies_bag`: the TurtleBot3's wheels and odometry in a motion-capture lab
  that tracks two robots: ``/mocap/amr0/pose`` (another robot) and ``/mocap/amr1/pose``
  (this one; also as the mocap bridge's TF ``world -> amr1``), 100 Hz.

The motion comes from umbmark's simulator (:func:`drive`): a robot with known ``E_d``
and ``E_b`` drives squares by its own odometry, so the truth is known and differs from
the odometry. Everything written derives from the simulated wheel angles and true poses
by closed-form kinematics here (exact arcs, quaternions by hand, latitude and longitude by
the radii of curvature), not by umbmark's code.
"""

from __future__ import annotations

import math
import sqlite3
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from umbmark.model.kinematics import WheelParams
from umbmark.sim.robot import SimRobot

from helpers import simulated_session

T0 = 1_765_000_000  # epoch seconds of the first stamp
DELAY = 0.001  # bag time after the header stamp [s]
FORMATS = ("ros1", "sqlite3", "mcap")

JS = "sensor_msgs/msg/JointState"
ODOM = "nav_msgs/msg/Odometry"
TF = "tf2_msgs/msg/TFMessage"
IMU = "sensor_msgs/msg/Imu"
FIX = "sensor_msgs/msg/NavSatFix"
POINT = "geometry_msgs/msg/PointStamped"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
POSE = "geometry_msgs/msg/PoseStamped"
STRING = "std_msgs/msg/String"
MODEL_STATES = "gazebo_msgs/msg/ModelStates"

MODEL_STATES_MSG = "string[] name\ngeometry_msgs/Pose[] pose\ngeometry_msgs/Twist[] twist\n"

#: TurtleBot3 Burger: wheels 0.160 m apart, 0.066 m across; Husky: 0.555 m and 0.330 m.
TB3 = WheelParams(wheelbase=0.160, wheel_diameter=0.066, encoder_resolution=4096, gear_ratio=1)
HUSKY = WheelParams(wheelbase=0.555, wheel_diameter=0.330, encoder_resolution=4096, gear_ratio=1)

#: Where the GNSS receiver's local frame starts (WGS84) [deg, deg, m].
ORIGIN = (43.4723, -80.5449, 330.0)
_A, _F = 6_378_137.0, 1.0 / 298.257223563


def typestore(fmt: str):
    """The writer's types: ROS 1 Noetic or ROS 2, with tf2_msgs and gazebo_msgs."""
    ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
    if fmt == "ros1":
        ts.register(
            get_types_from_msg(
                "geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"
            )
        )
    ts.register(get_types_from_msg(MODEL_STATES_MSG, MODEL_STATES))
    return ts


class BagWriter:
    """Messages to write: ``(topic, stamp [s from T0], message)``; written sorted by time,
    each received :data:`DELAY` after its stamp."""

    def __init__(self, fmt: str, stamp_origin: float = T0) -> None:
        self.fmt = fmt
        self.stamp_origin = stamp_origin  # header stamps count from here [s]: T0, or sim time
        self.ts = typestore(fmt)
        self.types: dict[str, str] = {}
        self.messages: list[tuple[str, float, object]] = []

    def T(self, name: str):
        return self.ts.types[name]

    def add(self, topic: str, msgtype: str, t: float, msg: object) -> None:
        self.types[topic] = msgtype
        self.messages.append((topic, t, msg))

    # --- pieces ---------------------------------------------------------------------

    def header(self, t: float, frame: str):
        sec, nsec = divmod(round((self.stamp_origin + t) * 1e9), 1_000_000_000)
        stamp = self.T("builtin_interfaces/msg/Time")(sec=sec, nanosec=nsec)
        if self.fmt == "ros1":
            return self.T("std_msgs/msg/Header")(seq=0, stamp=stamp, frame_id=frame)
        return self.T("std_msgs/msg/Header")(stamp=stamp, frame_id=frame)

    def quaternion(self, q: Sequence[float]):
        return self.T("geometry_msgs/msg/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3])

    def vector(self, x: float = 0.0, y: float = 0.0, z: float = 0.0):
        return self.T("geometry_msgs/msg/Vector3")(x=x, y=y, z=z)

    def pose(self, x: float, y: float, yaw: float, z: float = 0.0):
        return self.T("geometry_msgs/msg/Pose")(
            position=self.T("geometry_msgs/msg/Point")(x=x, y=y, z=z),
            orientation=self.quaternion(yaw_quaternion(yaw)),
        )

    def odometry(self, t: float, frame: str, child: str, x: float, y: float, yaw: float):
        cov = np.zeros(36)
        twist = self.T("geometry_msgs/msg/Twist")(linear=self.vector(), angular=self.vector())
        return self.T(ODOM)(
            header=self.header(t, frame),
            child_frame_id=child,
            pose=self.T("geometry_msgs/msg/PoseWithCovariance")(
                pose=self.pose(x, y, yaw), covariance=cov
            ),
            twist=self.T("geometry_msgs/msg/TwistWithCovariance")(twist=twist, covariance=cov),
        )

    def transform(self, t: float, parent: str, child: str, xyz, q):
        return self.T("geometry_msgs/msg/TransformStamped")(
            header=self.header(t, parent),
            child_frame_id=child,
            transform=self.T("geometry_msgs/msg/Transform")(
                translation=self.vector(*xyz), rotation=self.quaternion(q)
            ),
        )

    def tf(self, transforms):
        return self.T(TF)(transforms=list(transforms))

    def joint_state(self, t: float, names, positions):
        return self.T(JS)(
            header=self.header(t, ""),
            name=list(names),
            position=np.array(positions, np.float64),
            velocity=np.array([], np.float64),
            effort=np.array([], np.float64),
        )

    def model_states(self, names, poses):
        twist = self.T("geometry_msgs/msg/Twist")(linear=self.vector(), angular=self.vector())
        return self.T(MODEL_STATES)(
            name=list(names), pose=[self.pose(*p) for p in poses], twist=[twist] * len(names)
        )

    def fix(self, t: float, lat: float, lon: float, alt: float, sigma: float, status: int = 2):
        cov = np.zeros(9)
        cov[0] = cov[4] = sigma**2
        cov[8] = (2 * sigma) ** 2
        return self.T(FIX)(
            header=self.header(t, "gps_link"),
            status=self.T("sensor_msgs/msg/NavSatStatus")(status=status, service=1),
            latitude=lat,
            longitude=lon,
            altitude=alt,
            position_covariance=cov,
            position_covariance_type=2,
        )

    def write(self, path: Path, *, strip_definitions: bool = False) -> Path:
        """Write the bag (``path`` gets ``.bag`` for ROS 1); ``strip_definitions``: a
        sqlite3 bag without message definitions, as rosbag2 before Iron wrote them."""
        if self.fmt == "ros1":
            path = path.with_suffix(".bag")
            writer: Writer1 | Writer2 = Writer1(path)
        else:
            plugin = StoragePlugin.MCAP if self.fmt == "mcap" else StoragePlugin.SQLITE3
            writer = Writer2(path, version=9, storage_plugin=plugin)
        serialize = self.ts.serialize_ros1 if self.fmt == "ros1" else self.ts.serialize_cdr
        with writer:
            conns = {
                topic: writer.add_connection(topic, typ, typestore=self.ts)
                for topic, typ in self.types.items()
            }
            for topic, t, msg in sorted(self.messages, key=lambda m: m[1]):
                bag_ns = round((T0 + t + DELAY) * 1e9)
                writer.write(conns[topic], bag_ns, serialize(msg, self.types[topic]))
        if strip_definitions:
            assert self.fmt == "sqlite3"
            (db,) = path.glob("*.db3")
            with sqlite3.connect(db) as con:
                con.execute("DELETE FROM message_definitions")
            con.close()
        return path


# --- closed-form kinematics ------------------------------------------------------------------


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def quat_multiply(a, b) -> tuple[float, float, float, float]:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def roll_quaternion(roll: float) -> tuple[float, float, float, float]:
    return (math.sin(roll / 2), 0.0, 0.0, math.cos(roll / 2))


def wheel_quaternion(angle: float) -> tuple[float, float, float, float]:
    """robot_state_publisher's rotation of a TurtleBot3 wheel link: the joint origin's
    ``rpy -1.57 0 0``, then the joint's turn about its axis ``0 0 1``."""
    return quat_multiply(
        roll_quaternion(-1.57), (0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2))
    )


def odometry_poses(angles: np.ndarray, params: WheelParams) -> np.ndarray:
    """A diff-drive controller's odometry from wheel angles (n, 2) [rad]: each interval
    an exact arc with the nominal radius and separation, shape (n, 3)."""
    radius = 0.5 * params.wheel_diameter
    d = np.diff(angles, axis=0) * radius
    poses = np.zeros((angles.shape[0], 3))
    x = y = th = 0.0
    for k, (dl, dr) in enumerate(d, start=1):
        ds, dth = 0.5 * (dl + dr), (dr - dl) / params.wheelbase
        if abs(dth) < 1e-12:
            x += ds * math.cos(th)
            y += ds * math.sin(th)
        else:
            r = ds / dth
            x += r * (math.sin(th + dth) - math.sin(th))
            y -= r * (math.cos(th + dth) - math.cos(th))
        th += dth
        poses[k] = (x, y, th)
    return poses


def to_fix(east: float, north: float) -> tuple[float, float, float]:
    """Latitude, longitude [deg] and altitude [m] of a point east and north [m] of
    :data:`ORIGIN`, by the meridian and prime-vertical radii of curvature there."""
    lat0, lon0, h = ORIGIN
    e2 = _F * (2 - _F)
    s = math.sin(math.radians(lat0))
    n = _A / math.sqrt(1 - e2 * s * s)
    m = _A * (1 - e2) / (1 - e2 * s * s) ** 1.5
    lat = lat0 + math.degrees(north / (m + h))
    lon = lon0 + math.degrees(east / ((n + h) * math.cos(math.radians(lat0))))
    return lat, lon, h


# --- the motion ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Drive:
    """A simulated session: wheel angles and true poses at 100 Hz.

    Attributes
    ----------
    time : array, shape (n,)
        [s] from the first sample.
    angles : array, shape (n, 2)
        Left and right wheel angles [rad].
    truth : array, shape (n, 3)
        True pose of the axle centre ``x, y`` [m], heading [rad].
    nominal : WheelParams
        What the odometry assumes.
    E_d, E_b : float
        The robot's errors.
    """

    time: np.ndarray
    angles: np.ndarray
    truth: np.ndarray
    nominal: WheelParams
    E_d: float
    E_b: float

    @property
    def odometry(self) -> np.ndarray:
        """The controller's odometry at every sample, shape (n, 3)."""
        return odometry_poses(self.angles, self.nominal)


def drive(
    nominal: WheelParams,
    E_d: float,
    E_b: float,
    directions: Sequence[str] = ("cw", "cw", "cw", "ccw", "ccw", "ccw"),
    side: float = 1.0,
) -> Drive:
    """Squares driven by a robot with errors ``E_d``, ``E_b``, rests between them."""
    robot = SimRobot.with_errors(nominal, E_d=E_d, E_b=E_b)
    time, counts, truth, _ = simulated_session(robot, list(directions), side=side, rest=2.0)
    angles = counts * nominal.radians_per_pulse
    return Drive(time, angles, truth, nominal, E_d, E_b)


# --- the robots ----------------------------------------------------------------------------


def husky_bag(
    path: Path,
    fmt: str,
    motion: Drive,
    *,
    gps_sigma: float | None = None,
    tf_from: str = "ekf",
    static_map: bool = False,
) -> Path:
    """A Husky's recording (see the module docstring): controller odometry at 50 Hz, IMU,
    fused odometry and its TF (``tf_from="ekf"``; ``"controller"``: the controller
    publishes ``odom -> base_link`` itself, robot_localization none), GNSS fixes at 10 Hz
    with ``gps_sigma`` [m] if given (exact positions, that standard deviation in their
    covariance); ``static_map``: a ``map -> odom`` transform that never moves (no
    localization running)."""
    bag = BagWriter(fmt)
    odo = motion.odometry
    # robot_localization: the wheel odometry's travel along the IMU's heading
    fused = np.zeros_like(odo)
    moved = np.diff(odo[:, :2], axis=0)
    mid = odo[:-1, 2] + 0.5 * np.diff(odo[:, 2])
    step = moved[:, 0] * np.cos(mid) + moved[:, 1] * np.sin(mid)  # along the heading
    heading = motion.truth[:, 2] - motion.truth[0, 2]
    fused[:, 2] = heading
    fused[1:, 0] = np.cumsum(step * np.cos(heading[:-1]))
    fused[1:, 1] = np.cumsum(step * np.sin(heading[:-1]))
    for k in range(0, motion.time.size, 2):  # 50 Hz
        t = float(motion.time[k])
        x, y, th = odo[k]
        controller = bag.odometry(t, "odom", "base_link", x, y, th)
        bag.add("/husky_velocity_controller/odom", ODOM, t, controller)
        fx, fy, fth = fused[k]
        bag.add("/odometry/filtered", ODOM, t, bag.odometry(t, "odom", "base_link", fx, fy, fth))
        source = (x, y, th) if tf_from == "controller" else (fx, fy, fth)
        xyz = (source[0], source[1], 0.0)
        tf = bag.transform(t, "odom", "base_link", xyz, yaw_quaternion(source[2]))
        bag.add("/tf", TF, t, bag.tf([tf]))
        imu = bag.T(IMU)(
            header=bag.header(t, "imu_link"),
            orientation=bag.quaternion(yaw_quaternion(heading[k])),
            orientation_covariance=np.zeros(9),
            angular_velocity=bag.vector(),
            angular_velocity_covariance=np.zeros(9),
            linear_acceleration=bag.vector(z=9.81),
            linear_acceleration_covariance=np.zeros(9),
        )
        bag.add("/imu/data", IMU, t, imu)
    if static_map:
        still = bag.transform(0.0, "map", "odom", (2.0, 1.0, 0.0), yaw_quaternion(0.3))
        bag.add("/tf_static", TF, 0.0, bag.tf([still]))
    if gps_sigma is not None:
        for k in range(0, motion.time.size, 10):  # 10 Hz
            t = float(motion.time[k])
            east, north = motion.truth[k, :2]
            bag.add("/navsat/fix", FIX, t, bag.fix(t, *to_fix(east, north), gps_sigma))
    return bag.write(path)


TB3_URDF = """<?xml version="1.0"?>
<robot name="turtlebot3_burger">
  <link name="base_footprint"/>
  <joint name="base_joint" type="fixed">
    <parent link="base_footprint"/><child link="base_link"/>
    <origin xyz="0 0 0.010" rpy="0 0 0"/>
  </joint>
  <link name="base_link">
    <collision><origin xyz="-0.032 0 0.070"/><geometry><box size="0.140 0.140 0.143"/></geometry>
    </collision>
  </link>
  <joint name="wheel_left_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_left_link"/>
    <origin xyz="0 0.080 0.023" rpy="-1.57 0 0"/><axis xyz="0 0 1"/>
  </joint>
  <link name="wheel_left_link">
    <visual><geometry><mesh filename="package://turtlebot3_description/meshes/wheels/left_tire.stl"/></geometry></visual>
    <collision><geometry><cylinder length="0.018" radius="0.033"/></geometry></collision>
  </link>
  <joint name="wheel_right_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_right_link"/>
    <origin xyz="0 -0.080 0.023" rpy="-1.57 0 0"/><axis xyz="0 0 1"/>
  </joint>
  <link name="wheel_right_link">
    <collision><geometry><cylinder length="0.018" radius="0.033"/></geometry></collision>
  </link>
  <joint name="caster_back_joint" type="fixed">
    <parent link="base_link"/><child link="caster_back_link"/>
    <origin xyz="-0.081 0 -0.004" rpy="-1.57 0 0"/>
  </joint>
  <link name="caster_back_link"/>
</robot>
"""


def turtlebot3_bag(
    path: Path,
    fmt: str,
    motion: Drive,
    *,
    joint_states: bool = True,
    wheel_tf: bool = True,
    model_states: bool = True,
    robot_description: bool = True,
    ground_truth: bool = False,
    strip_definitions: bool = False,
    sim_time: float | None = None,
) -> Path:
    """A TurtleBot3 Burger in Gazebo (see the module docstring); each part optional.
    ``sim_time``: header stamps on the simulation's clock, from this many seconds at the
    first sample (``use_sim_time``), while the bag's receive times stay on the wall clock."""
    bag = BagWriter(fmt, T0 if sim_time is None else sim_time)
    odo = motion.odometry
    names = ("wheel_left_joint", "wheel_right_joint")
    for k in range(0, motion.time.size, 3):  # 33 Hz
        t = float(motion.time[k])
        left, right = motion.angles[k]
        if joint_states:
            bag.add("/joint_states", JS, t, bag.joint_state(t, names, [left, right]))
        x, y, th = odo[k]
        bag.add("/odom", ODOM, t, bag.odometry(t, "odom", "base_footprint", x, y, th))
        transforms = [bag.transform(t, "odom", "base_footprint", (x, y, 0.0), yaw_quaternion(th))]
        if wheel_tf:
            for child, y_joint, angle in (
                ("wheel_left_link", 0.08, left),
                ("wheel_right_link", -0.08, right),
            ):
                xyz = (0.0, y_joint, 0.023)
                transforms.append(
                    bag.transform(t, "base_link", child, xyz, wheel_quaternion(angle))
                )
        bag.add("/tf", TF, t, bag.tf(transforms))
        if ground_truth:
            gx, gy, gth = motion.truth[k]
            p3d = bag.odometry(t, "world", "base_footprint", gx, gy, gth)
            bag.add("/ground_truth/odom", ODOM, t, p3d)
    if model_states:
        for k in range(0, motion.time.size, 1):  # 100 Hz
            t = float(motion.time[k])
            gx, gy, gth = motion.truth[k]
            msg = bag.model_states(
                ["ground_plane", "unit_box", "turtlebot3_burger"],
                [(0.0, 0.0, 0.0), (3.0, 1.0, 0.4), (gx, gy, gth)],
            )
            bag.add("/gazebo/model_states", MODEL_STATES, t, msg)
    static = [
        bag.transform(0.0, "base_footprint", "base_link", (0.0, 0.0, 0.010), (0, 0, 0, 1)),
        bag.transform(0.0, "base_link", "base_scan", (-0.032, 0.0, 0.172), (0, 0, 0, 1)),
    ]
    bag.add("/tf_static", TF, 0.0, bag.tf(static))
    if robot_description:
        bag.add("/robot_description", STRING, 0.0, bag.T(STRING)(data=TB3_URDF))
    return bag.write(path, strip_definitions=strip_definitions)


def nav2_bag(
    path: Path, fmt: str, motion: Drive, *, map_offset=(1.5, -0.5, 0.3), map_tf: bool = True
) -> Path:
    """The TurtleBot3 under Nav2: joint states, ``/odom`` and ``odom -> base_footprint``,
    AMCL's ``/amcl_pose`` at 2 Hz in a map frame turned and shifted by ``map_offset`` and
    (``map_tf``) its ``map -> odom`` at the same updates."""
    bag = BagWriter(fmt)
    odo = motion.odometry
    ox, oy, oth = map_offset
    c, s = math.cos(oth), math.sin(oth)
    names = ("wheel_left_joint", "wheel_right_joint")
    for k in range(0, motion.time.size, 3):
        t = float(motion.time[k])
        bag.add("/joint_states", JS, t, bag.joint_state(t, names, motion.angles[k]))
        x, y, th = odo[k]
        bag.add("/odom", ODOM, t, bag.odometry(t, "odom", "base_footprint", x, y, th))
        tf = bag.transform(t, "odom", "base_footprint", (x, y, 0.0), yaw_quaternion(th))
        bag.add("/tf", TF, t, bag.tf([tf]))
    for k in range(0, motion.time.size, 50):  # 2 Hz
        t = float(motion.time[k])
        gx, gy, gth = motion.truth[k]
        mx, my, mth = ox + c * gx - s * gy, oy + s * gx + c * gy, oth + gth
        cov = np.zeros(36)
        amcl = bag.T(POSE_COV)(
            header=bag.header(t, "map"),
            pose=bag.T("geometry_msgs/msg/PoseWithCovariance")(
                pose=bag.pose(mx, my, mth), covariance=cov
            ),
        )
        bag.add("/amcl_pose", POSE_COV, t, amcl)
        # map -> odom = (map -> base) (+) (odom -> base)^-1
        x, y, th = odo[k]
        dth = mth - th
        cd, sd = math.cos(dth), math.sin(dth)
        tx, ty = mx - (cd * x - sd * y), my - (sd * x + cd * y)
        tf = bag.transform(t, "map", "odom", (tx, ty, 0.0), yaw_quaternion(dth))
        if map_tf:
            bag.add("/tf", TF, t + 1e-4, bag.tf([tf]))
    return bag.write(path)


def two_bodies_bag(path: Path, fmt: str, mine: Drive, other: Drive) -> Path:
    """The TurtleBot3 ``mine`` (joint states, ``/odom``, its description) recorded where
    motion capture tracks it and ``other``, a second robot driving the same squares:
    ``/mocap/amr0/pose`` is ``other``'s truth (first by name, so what a look into the bag
    suggests), ``/mocap/amr1/pose`` and the TF ``world -> amr1`` are ``mine``'s (100 Hz)."""
    bag = BagWriter(fmt)
    n = min(mine.time.size, other.time.size)
    odo = mine.odometry
    names = ("wheel_left_joint", "wheel_right_joint")
    for k in range(0, n, 3):  # 33 Hz
        t = float(mine.time[k])
        bag.add("/joint_states", JS, t, bag.joint_state(t, names, mine.angles[k]))
        x, y, th = odo[k]
        bag.add("/odom", ODOM, t, bag.odometry(t, "odom", "base_footprint", x, y, th))
    for k in range(n):
        t = float(mine.time[k])
        for topic, motion in (("/mocap/amr0/pose", other), ("/mocap/amr1/pose", mine)):
            gx, gy, gth = motion.truth[k]
            msg = bag.T(POSE)(header=bag.header(t, "world"), pose=bag.pose(gx, gy, gth))
            bag.add(topic, POSE, t, msg)
        gx, gy, gth = mine.truth[k]
        tf = bag.transform(t, "world", "amr1", (gx, gy, 0.0), yaw_quaternion(gth))
        bag.add("/tf", TF, t, bag.tf([tf]))
    bag.add("/robot_description", STRING, 0.0, bag.T(STRING)(data=TB3_URDF))
    return bag.write(path)


def without_topics(source: Path, target: Path, drop: Sequence[str]) -> Path:
    """A copy of the ROS 2 bag folder ``source`` (sqlite3 or MCAP) at ``target`` with the
    topics ``drop`` left out: every other message as stored (its bytes, its time), each
    connection with its type's definition (a robot that never had that sensor)."""
    from rosbags.rosbag2 import Reader

    with Reader(source) as reader:
        mcap = any(p.suffix == ".mcap" for p in source.iterdir())
        plugin = StoragePlugin.MCAP if mcap else StoragePlugin.SQLITE3
        kept = [c for c in reader.connections if c.topic not in drop]
        store = get_typestore(Stores.ROS2_HUMBLE)
        for conn in kept:
            store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        with Writer2(target, version=9, storage_plugin=plugin) as writer:
            made = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=store) for c in kept}
            for conn, stamp, raw in reader.messages(connections=kept):
                writer.write(made[conn.id], stamp, raw)
    return target

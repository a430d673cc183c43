"""Controller odometry as input: the controllers' updates forward, umbmark's inverse back.

The forward updates below are written from the controllers' sources, not from umbmark:

- ros2_controllers Humble, ``diff_drive_controller/src/odometry.cpp``: ``update(left_pos,
  right_pos)`` takes wheel positions times radii, differences them, ``linear = (l + r) /
  2``, ``angular = (r - l) / wheel_separation``, then ``integrateExact``: the arc, or
  ``integrateRungeKutta2`` (mid heading) when ``|angular| < 1e-6``;
- ros2_controllers Jazzy and later: ``update_from_pos(left_pos, right_pos, dt)`` takes
  wheel velocities ``(pos - old) / dt``, ``update_from_vel`` scales them by the radii, and
  ``integrate(linear_vel, angular_vel, dt)`` moves along the arc, or straight along the
  *old* heading when ``|dheading| < 1e-6``;
- ROS 1 ``diff_drive_controller/src/odometry.cpp``: as Humble.

The simulated robot (known ``E_d``, ``E_b``) drives the squares steering by its own
odometry; its wheel angles go through each forward update at the control rate, the
published pose (every other cycle, as at 50 Hz) goes into real ROS 1 and ROS 2 bags with
a ground truth, and umbmark must recover the robot's errors from those bags alone.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.core.errors import InputError
from umbmark.model.kinematics import OdometryGeometry, WheelParams
from umbmark.model.recording import PoseSeries
from umbmark.sim.robot import SimRobot
from umbmark.sources.bag.wheels.odometry import wheels_from_odometry

from helpers import api_error, cli_error, cli_json, simulated_session

pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

ODO = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=4096, gear_ratio=1)
E_D, E_B = 1.003, 1.012
ROBOT = SimRobot.with_errors(ODO, E_d=E_D, E_b=E_B)
T0 = 1_760_000_000
SIDE = 1.0


# --- the controllers, forward, from their sources ----------------------------------------


class Humble:
    """ros2_controllers Humble ``Odometry::update`` with ``integrateExact`` (also ROS 1)."""

    def __init__(self, separation: float, left_radius: float, right_radius: float) -> None:
        self.b, self.rl, self.rr = separation, left_radius, right_radius
        self.x = self.y = self.heading = 0.0
        self.left_old = self.right_old = 0.0

    def start(self, left_pos: float, right_pos: float) -> None:
        self.left_old, self.right_old = left_pos * self.rl, right_pos * self.rr

    def update(self, left_pos: float, right_pos: float, dt: float) -> None:
        left_cur, right_cur = left_pos * self.rl, right_pos * self.rr
        left_vel, right_vel = left_cur - self.left_old, right_cur - self.right_old
        self.left_old, self.right_old = left_cur, right_cur
        linear = (left_vel + right_vel) * 0.5
        angular = (right_vel - left_vel) / self.b
        if abs(angular) < 1e-6:  # integrateRungeKutta2
            direction = self.heading + angular * 0.5
            self.x += linear * math.cos(direction)
            self.y += linear * math.sin(direction)
            self.heading += angular
        else:
            heading_old = self.heading
            r = linear / angular
            self.heading += angular
            self.x += r * (math.sin(self.heading) - math.sin(heading_old))
            self.y += -r * (math.cos(self.heading) - math.cos(heading_old))


class Jazzy(Humble):
    """ros2_controllers Jazzy ``update_from_pos`` / ``update_from_vel`` / ``integrate``."""

    def start(self, left_pos: float, right_pos: float) -> None:
        self.left_old, self.right_old = left_pos, right_pos

    def update(self, left_pos: float, right_pos: float, dt: float) -> None:
        left_vel = (left_pos - self.left_old) / dt
        right_vel = (right_pos - self.right_old) / dt
        self.left_old, self.right_old = left_pos, right_pos
        linear_vel = (left_vel * self.rl + right_vel * self.rr) * 0.5
        angular_vel = (right_vel * self.rr - left_vel * self.rl) / self.b
        dx, dheading = linear_vel * dt, angular_vel * dt
        if abs(dheading) < 1e-6:
            self.x += dx * math.cos(self.heading)
            self.y += dx * math.sin(self.heading)
            self.heading += dheading
        else:
            heading_old = self.heading
            self.heading += dheading
            self.x += (dx / dheading) * (math.sin(self.heading) - math.sin(heading_old))
            self.y += -(dx / dheading) * (math.cos(self.heading) - math.cos(heading_old))


def run_controller(controller: Humble, time, angles, publish_every: int = 2):
    """Feed wheel angles (n, 2) at the control rate; the poses published, every k-th cycle."""
    controller.start(angles[0, 0], angles[0, 1])
    out_t, out_p = [time[0]], [(0.0, 0.0, 0.0)]
    for k in range(1, time.size):
        controller.update(angles[k, 0], angles[k, 1], time[k] - time[k - 1])
        if k % publish_every == 0:
            out_t.append(time[k])
            out_p.append((controller.x, controller.y, controller.heading))
    return np.array(out_t), np.array(out_p)


# --- the inverse alone -------------------------------------------------------------------


@pytest.mark.parametrize("kind", [Humble, Jazzy])
def test_inverse_gives_back_the_wheel_angles_the_controller_read(kind):
    # wheel speeds held for 0.3 s each (driving, turning on the spot, arcs, standing), at
    # 100 Hz; every cycle published: each step is one arc, inverted exactly.
    rng = np.random.default_rng(1)
    speeds = np.repeat(rng.uniform(-3.0, 6.0, size=(40, 2)), 30, axis=0)
    speeds[::7] = 0.0
    time = 0.01 * np.arange(speeds.shape[0] + 1)
    angles = np.vstack([[0.0, 0.0], np.cumsum(speeds * 0.01, axis=0)])
    geometry = OdometryGeometry(left_radius=0.0751, right_radius=0.0748, separation=0.341)
    controller = kind(0.341, 0.0751, 0.0748)
    t, poses = run_controller(controller, time, angles, publish_every=1)
    found = wheels_from_odometry(PoseSeries(t, poses), geometry, "/odom", "test.bag")
    np.testing.assert_allclose(found.wheels.angles, angles - angles[0], atol=1e-9)
    assert found.lateral_share < 1e-9
    # Jazzy's straight step along the old heading for |dheading| < 1e-6 differs from an
    # arc by less than 1e-6 of a step; Humble's Runge-Kutta step is the arc to 1e-18.


def test_inverse_refuses_sparse_and_sideways_odometry():
    geometry = OdometryGeometry(left_radius=0.075, right_radius=0.075, separation=0.34)
    # a spot turn of 1.5 rad per second, published at 2 Hz: 0.75 rad between messages
    t = 0.5 * np.arange(8)
    sparse = PoseSeries(t, np.column_stack([np.zeros(8), np.zeros(8), 0.75 * np.arange(8)]))
    with pytest.raises(InputError, match=r"turns up to 0\.75 rad .*too sparse"):
        wheels_from_odometry(sparse, geometry, "odometry /odom", "a.bag")
    # driving straight along x while sliding 5 cm per metre sideways (a filtered odometry)
    x = 0.01 * np.arange(200)
    sideways = PoseSeries(0.01 * np.arange(200), np.column_stack([x, 0.05 * x, 0.0 * x]))
    with pytest.raises(InputError, match="sideways 50 mm per metre"):
        wheels_from_odometry(sideways, geometry, "odometry /odom", "a.bag")


# --- bags holding only controller odometry and a ground truth ----------------------------


@pytest.fixture(scope="module")
def session():
    return simulated_session(ROBOT, ["cw"] * 5 + ["ccw"] * 5, side=SIDE, rest=2.0)


def _yaw_quaternion(types, yaw: float):
    return types["geometry_msgs/msg/Quaternion"](
        x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
    )


def write_odometry_bag(
    path: Path,
    fmt: str,
    session,
    controller: Humble,
    *,
    odom_as: str = "topic",
    publish_every: int = 2,
    map_offset: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Path:
    """A bag with the controller's odometry (topic /odom or /tf odom->base_link) and
    ground truth (AMCL-style PoseWithCovarianceStamped /amcl_pose in a map frame rotated
    and shifted by ``map_offset``); no wheel data."""
    times, counts, truth, _ = session
    angles = counts * ODO.radians_per_pulse
    odom_t, odom_p = run_controller(controller, times, angles, publish_every)
    ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
    if fmt == "ros1":
        ts.register(
            get_types_from_msg(
                "geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"
            )
        )
        path = path.with_suffix(".bag")
        writer: Writer1 | Writer2 = Writer1(path)
    else:
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    types = ts.types
    serialize = ts.serialize_ros1 if fmt == "ros1" else ts.serialize_cdr

    def header(t: float, frame: str):
        sec, nsec = divmod(round((T0 + t) * 1e9), 1_000_000_000)
        stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        if fmt == "ros1":
            return types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def pose(x: float, y: float, yaw: float):
        return types["geometry_msgs/msg/Pose"](
            position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
            orientation=_yaw_quaternion(types, yaw),
        )

    covariance = np.zeros(36)
    zero3 = types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    ox, oy, oth = map_offset
    c, s = math.cos(oth), math.sin(oth)
    messages = []
    odom_type = "nav_msgs/msg/Odometry" if odom_as == "topic" else "tf2_msgs/msg/TFMessage"
    odom_topic = "/odom" if odom_as == "topic" else "/tf"
    for t, (x, y, th) in zip(odom_t, odom_p, strict=True):
        if odom_as == "topic":
            msg = types["nav_msgs/msg/Odometry"](
                header=header(t, "odom"),
                child_frame_id="base_link",
                pose=types["geometry_msgs/msg/PoseWithCovariance"](
                    pose=pose(x, y, th), covariance=covariance
                ),
                twist=types["geometry_msgs/msg/TwistWithCovariance"](
                    twist=types["geometry_msgs/msg/Twist"](linear=zero3, angular=zero3),
                    covariance=covariance,
                ),
            )
        else:
            tf = types["geometry_msgs/msg/TransformStamped"](
                header=header(t, "odom"),
                child_frame_id="base_link",
                transform=types["geometry_msgs/msg/Transform"](
                    translation=types["geometry_msgs/msg/Vector3"](x=x, y=y, z=0.0),
                    rotation=_yaw_quaternion(types, th),
                ),
            )
            msg = types["tf2_msgs/msg/TFMessage"](transforms=[tf])
        messages.append((odom_topic, t, odom_type, msg))
    for k in range(0, times.size, 2):
        x, y, th = truth[k]
        amcl = types["geometry_msgs/msg/PoseWithCovarianceStamped"](
            header=header(times[k], "map"),
            pose=types["geometry_msgs/msg/PoseWithCovariance"](
                pose=pose(ox + c * x - s * y, oy + s * x + c * y, oth + th),
                covariance=covariance,
            ),
        )
        messages.append(
            ("/amcl_pose", times[k], "geometry_msgs/msg/PoseWithCovarianceStamped", amcl)
        )
    messages.sort(key=lambda m: m[1])
    with writer:
        conns = {}
        for topic, _, typ, _ in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, typ, typestore=ts)
        for topic, t, typ, msg in messages:
            writer.write(conns[topic], round((T0 + t + 0.001) * 1e9), serialize(msg, typ))
    return path


ROS2_FILE = """\
robot1:
  diff_cont:
    ros__parameters:
      left_wheel_names: [left_wheel_joint]
      right_wheel_names: [right_wheel_joint]
      wheel_separation: 0.34
      wheel_radius: 0.075
      wheel_separation_multiplier: 1.0
      left_wheel_radius_multiplier: 1.0
      right_wheel_radius_multiplier: 1.0
      open_loop: {open_loop}
"""

# ROS 1: wheel_radius_multiplier 2 on a 0.0375 m radius is the 0.075 m the robot steered
# by; the left and right multipliers (0.5) are ignored by the controller, and so by us.
ROS1_FILE = """\
diff_drive_controller:
  type: diff_drive_controller/DiffDriveController
  left_wheel: left_wheel_joint
  right_wheel: right_wheel_joint
  wheel_separation: 0.17
  wheel_separation_multiplier: 2.0
  wheel_radius: 0.0375
  wheel_radius_multiplier: 2.0
  left_wheel_radius_multiplier: 0.5
  right_wheel_radius_multiplier: 0.5
"""


@pytest.mark.slow
@pytest.mark.parametrize(
    ("fmt", "kind", "odom_as"),
    [("ros1", Humble, "topic"), ("sqlite3", Humble, "topic"), ("mcap", Jazzy, "tf")],
)
def test_bag_of_controller_odometry_recovers_the_robots_errors(
    tmp_path, session, fmt, kind, odom_as
):
    # the map frame of the ground truth is turned and shifted: the return errors are not
    offset = (2.0, -1.0, 0.7)
    bag = write_odometry_bag(
        tmp_path / "odom",
        fmt,
        session,
        kind(0.34, 0.075, 0.075),
        odom_as=odom_as,
        map_offset=offset,
    )
    params = tmp_path / "controller.yaml"
    params.write_text(ROS1_FILE if fmt == "ros1" else ROS2_FILE.format(open_loop="false"))
    odom = {"odom_topic": "/odom"} if odom_as == "topic" else {"odom_tf": ("odom", "base_link")}
    report = umbmark.calibrate(
        bag, side_length=SIDE, current_params=params, truth_topic="/amcl_pose", **odom
    )
    est = report.estimate
    assert [run.direction.value for run in report.runs] == ["cw"] * 5 + ["ccw"] * 5
    assert est.E_d == pytest.approx(E_D, abs=1e-4)
    assert est.E_b == pytest.approx(E_B, abs=5e-4)


@pytest.mark.slow
def test_odometry_bag_through_the_command_and_its_refusals(tmp_path, session):
    bag = write_odometry_bag(tmp_path / "odom", "sqlite3", session, Humble(0.34, 0.075, 0.075))
    params = tmp_path / "diff_cont.yaml"
    params.write_text(ROS2_FILE.format(open_loop="false"))
    common = [str(bag), "-L", str(SIDE), "--truth-topic", "/amcl_pose"]
    data = cli_json("calibrate", *common, "--current-params", str(params), "--odom-topic", "/odom")
    assert data["E_d"] == pytest.approx(E_D, abs=1e-4)
    assert data["E_b"] == pytest.approx(E_B, abs=5e-4)
    # flags instead of a file work the same
    data = cli_json(
        "calibrate", *common, "-b", "0.34", "--wheel-diameter", "0.15", "--odom-topic", "/odom"
    )
    assert data["E_b"] == pytest.approx(E_B, abs=5e-4)

    open_loop = tmp_path / "open_loop.yaml"
    open_loop.write_text(ROS2_FILE.format(open_loop="true"))
    line = cli_error(
        "calibrate", *common, "--current-params", str(open_loop), "--odom-topic", "/odom"
    )
    assert bag.name in line
    assert "open_loop: true" in line
    message = api_error(
        umbmark.calibrate,
        bag,
        side_length=SIDE,
        current_params=open_loop,
        truth_topic="/amcl_pose",
        odom_topic="/odom",
    )
    assert "open_loop" in message
    line = cli_error("calibrate", *common, "--current-params", str(params), "--odom-topic", "/amcl")
    assert "/amcl " in line
    assert "/amcl_pose" in line

    # published at 2 Hz, the spot turns of about 1 rad/s cannot be told from driving
    sparse = write_odometry_bag(
        tmp_path / "sparse", "sqlite3", session, Humble(0.34, 0.075, 0.075), publish_every=50
    )
    line = cli_error(
        "calibrate",
        str(sparse),
        "-L",
        str(SIDE),
        "--truth-topic",
        "/amcl_pose",
        "--current-params",
        str(params),
        "--odom-topic",
        "/odom",
    )
    assert "too sparse" in line


@pytest.mark.slow
def test_wheel_joints_named_in_the_controller_file(tmp_path, session):
    """Joints no rule could tell apart (a spinning lidar, wheels called drive_l/drive_r)
    are read by the names of the controller's left_wheel_names / right_wheel_names."""
    times, counts, truth, _ = session
    angles = counts * ODO.radians_per_pulse
    ts = get_typestore(Stores.LATEST)
    types = ts.types
    path = tmp_path / "joints"
    with Writer2(path, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
        js = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
        gt = writer.add_connection("/mocap", "geometry_msgs/msg/PoseStamped", typestore=ts)
        for k, t in enumerate(times):
            sec, nsec = divmod(round((T0 + t) * 1e9), 1_000_000_000)
            head = types["std_msgs/msg/Header"](
                stamp=types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec), frame_id=""
            )
            msg = types["sensor_msgs/msg/JointState"](
                header=head,
                name=["lidar_joint", "drive_r", "drive_l"],
                position=np.array([20.0 * t, angles[k, 1], angles[k, 0]]),
                velocity=np.array([], np.float64),
                effort=np.array([], np.float64),
            )
            bag_ns = round((T0 + t) * 1e9)
            writer.write(js, bag_ns, ts.serialize_cdr(msg, "sensor_msgs/msg/JointState"))
            x, y, th = truth[k]
            pose = types["geometry_msgs/msg/PoseStamped"](
                header=head,
                pose=types["geometry_msgs/msg/Pose"](
                    position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                    orientation=_yaw_quaternion(types, th),
                ),
            )
            writer.write(gt, bag_ns, ts.serialize_cdr(pose, "geometry_msgs/msg/PoseStamped"))
    params = tmp_path / "diff_cont.yaml"
    params.write_text(
        ROS2_FILE.format(open_loop="false")
        .replace("[left_wheel_joint]", "[drive_l]")
        .replace("[right_wheel_joint]", "[drive_r]")
    )
    report = umbmark.calibrate(path, side_length=SIDE, current_params=params, truth_topic="/mocap")
    assert report.estimate.E_d == pytest.approx(E_D, abs=1e-4)
    assert report.estimate.E_b == pytest.approx(E_B, abs=5e-4)
    message = api_error(
        umbmark.calibrate,
        path,
        side_length=SIDE,
        wheelbase=0.34,
        wheel_diameter=0.15,
        truth_topic="/mocap",
    )
    assert "left_joint" in message
    assert "drive_l, drive_r, lidar_joint" in message

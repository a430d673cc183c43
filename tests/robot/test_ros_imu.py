"""A ROS robot's IMU without ROS (``robot/ros_imu.py``): the topic taken from the graph,
the readings its messages carry (plain namespaces shaped like rospy's and rclpy's
``sensor_msgs/Imu``), what is left out, and the frame's mounting through /tf_static and
the robot description, against rotations written by hand."""

from __future__ import annotations

import math
from types import SimpleNamespace as Msg

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.robot.ros_imu import (
    ImuBuffer,
    gyro_problem,
    imu_edges,
    imu_mounting_of,
    imu_problem,
    pick_imu,
)

IMU1, IMU2 = "sensor_msgs/Imu", "sensor_msgs/msg/Imu"


def _imu(t: float, w: tuple[float, float, float], *, frame: str = "imu_link",
         gyro: float = 0.0, accel: float = 0.0) -> Msg:  # fmt: skip
    """A ``sensor_msgs/Imu`` at ROS 2 time ``t`` [s] (covariance ``gyro``, ``accel``: -1
    says the field is not given)."""
    sec = math.floor(t)
    return Msg(
        header=Msg(stamp=Msg(sec=sec, nanosec=round((t - sec) * 1e9)), frame_id=frame),
        angular_velocity=Msg(x=w[0], y=w[1], z=w[2]),
        angular_velocity_covariance=[gyro] + [0.0] * 8,
        linear_acceleration=Msg(x=0.1, y=0.0, z=9.8),
        linear_acceleration_covariance=[accel] + [0.0] * 8,
    )


def test_the_graphs_imu_is_taken_a_filtered_one_before_a_raw_one():
    graph = [("/odom", "nav_msgs/msg/Odometry"), ("/imu/data_raw", IMU2), ("/imu/data", IMU2),
             ("/camera/imu", IMU2)]  # fmt: skip
    topic, how = pick_imu(graph, "")  # type: ignore[misc]
    assert topic == "/imu/data"  # not raw; as deep as /camera/imu, and shorter
    assert "/imu/data_raw" in how
    assert "/camera/imu" in how
    assert pick_imu([("/imu", IMU1)], "") == ("/imu", "found on the graph")
    assert pick_imu([("/odom", "nav_msgs/Odometry")], "") is None
    # given: taken where the graph has it as an IMU, else why not
    assert pick_imu(graph, "/imu/data_raw")[0] == "/imu/data_raw"  # type: ignore[index]
    assert pick_imu(graph, "/odom") is None
    assert "carries nav_msgs/msg/Odometry, not sensor_msgs/Imu" in imu_problem(graph, "/odom")
    said = imu_problem(graph, "/gyro")
    assert "nobody publishes" in said
    assert "/imu/data" in said


def test_readings_in_order_the_ones_without_a_gyro_left_out():
    buffer = ImuBuffer()
    buffer.put(_imu(1000.00, (0.0, 0.0, 0.5)))
    buffer.put(_imu(1000.01, (0.0, 0.0, 0.6)))
    buffer.put(_imu(1000.01, (0.0, 0.0, 9.0)))  # the same stamp again
    buffer.put(_imu(1000.005, (0.0, 0.0, 9.0)))  # out of order
    buffer.put(_imu(1000.02, (math.nan, 0.0, 0.6)))  # not a number
    buffer.put(_imu(1000.03, (0.0, 0.0, 9.0), gyro=-1.0))  # says it has no gyro
    buffer.put(_imu(1000.04, (0.0, 0.0, 0.7), accel=-1.0))
    assert dict(buffer.dropped) == {"not_after": 2, "not_finite": 1, "no_gyro": 1}
    assert buffer.wait_first(0.0) == "imu_link"
    from umbmark.sources.bag.imu_frames import ImuMounting

    level = ImuMounting("imu_link", "base_link", np.eye(3), "/tf_static")
    series = buffer.series(1000.0, level, "test")
    np.testing.assert_allclose(series.time, [1000.01, 1000.04])
    np.testing.assert_allclose(series.rate[:, 2], [0.6, 0.7])
    assert series.accel is None  # one of them gives none
    assert buffer.series(1000.02, level, "test").time.tolist() == [1000.04]
    assert gyro_problem(buffer, "/imu") is None


def test_the_base_frames_rates_are_the_imus_rotated_by_its_mounting():
    """An IMU turned 90 deg about z, its x axis to the base's left: the base's x rate is
    minus the IMU's y rate, the base's y rate the IMU's x rate (R = Rz(90 deg))."""
    from umbmark.sources.bag.imu_frames import ImuMounting

    buffer = ImuBuffer()
    buffer.put(_imu(5.0, (0.1, 0.2, 0.3)))
    turned = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    series = buffer.series(0.0, ImuMounting("imu_link", "base_link", turned, "x"), "test")
    np.testing.assert_allclose(series.rate, [[-0.2, 0.1, 0.3]])
    np.testing.assert_allclose(series.accel, [[0.0, 0.1, 9.8]])


@pytest.mark.parametrize(
    ("messages", "said"),
    [
        ([], "said nothing"),
        ([_imu(1.0 + k, (0.0, 0.0, 0.2), gyro=-1.0) for k in range(3)], "no angular velocity"),
        ([_imu(1.0 + k, (0.0, 0.0, 0.0)) for k in range(3)], "accelerometer-only"),
    ],
)
def test_an_imu_without_a_gyro_is_one_line(messages, said):
    buffer = ImuBuffer()
    for m in messages:
        buffer.put(m)
    problem = gyro_problem(buffer, "/imu")
    assert problem is not None
    assert said in problem
    assert "--no-imu" in problem


def test_the_mounting_through_tf_static_and_the_robot_description():
    """/tf_static: base_link -> imu_mount (yaw 90 deg) -> imu_link (roll 180 deg, upside
    down): R = Rz(90) Rx(180) = [[0, 1, 0], [1, 0, 0], [0, 0, -1]]. The URDF: a frame it
    alone mounts, pitched 1 deg."""
    s45 = math.sqrt(0.5)
    static = {
        "imu_mount": ("base_link", (0.1, 0.0, 0.2), (0.0, 0.0, s45, s45)),
        "imu_link": ("/imu_mount", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)),
    }
    urdf = """<robot name="r"><link name="base_link"/><link name="gyro"/>
      <joint name="g" type="fixed"><parent link="base_link"/><child link="gyro"/>
      <origin xyz="0 0 0.1" rpy="0 0.017453292519943295 0"/></joint></robot>"""
    edges = imu_edges(static, urdf)
    found = imu_mounting_of(edges, "imu_link", "base_link", "/imu")
    np.testing.assert_allclose(found.rotation, [[0, 1, 0], [1, 0, 0], [0, 0, -1]], atol=1e-12)
    assert found.upside_down
    assert found.source == "/tf_static"
    pitched = imu_mounting_of(edges, "gyro", "base_link", "/imu")
    c, s = math.cos(math.radians(1.0)), math.sin(math.radians(1.0))
    np.testing.assert_allclose(pitched.rotation, [[c, 0, s], [0, 1, 0], [-s, 0, c]], atol=1e-12)
    assert pitched.source == "the robot description"
    level = imu_mounting_of(edges, "base_link", "base_link", "/imu")
    np.testing.assert_allclose(level.rotation, np.eye(3))


def test_an_imu_frame_without_a_mounting_is_one_line():
    edges = imu_edges({"laser": ("base_link", (0, 0, 0), (0, 0, 0, 1))})
    with pytest.raises(InputError, match=r"reads in imu_link, which has no transform to "
                       r"base_link .*frames known: base_link, laser"):  # fmt: skip
        imu_mounting_of(edges, "imu_link", "base_link", "/imu")
    with pytest.raises(InputError, match="names no frame"):
        imu_mounting_of(edges, "", "base_link", "/imu")
    with pytest.raises(InputError, match="robot description"):
        imu_edges(None, "<robot><joint")

"""The virtual robot's IMU (``robot/virtual.py`` with ``sim/imu.py``'s model): what its
gyro reads over a turn against the robot's true motion and the IMU it was built with,
the scale, bias and mounting applied by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.robot.base import IMU_HELD
from umbmark.robot.virtual import VirtualRobot
from umbmark.sim.imu import ImuSetup

DEG = math.pi / 180.0


def _turned(robot: VirtualRobot, rate: float, seconds: float) -> None:
    for _ in range(round(seconds / robot.period)):
        robot.send_velocity(0.0, rate)
        robot.wait(robot.period)
    robot.send_velocity(0.0, 0.0)
    robot.wait(1.0)


def test_the_gyro_reads_the_true_turn_over_its_scale_plus_its_bias():
    """No noise, no walk: the base frame's yaw rate integrated over the readings is the
    true heading change over k_g plus the yaw bias times the time, the IMU rolled 3 deg
    and its x and y biases drawn (the yaw bias (R b)_z, b the IMU's bias)."""
    setup = ImuSetup(gyro_scale=0.97, gyro_bias=0.5 * DEG, gyro_noise=0.0, gyro_bias_walk=0.0,
                     imu_roll=3.0 * DEG)  # fmt: skip
    robot = VirtualRobot(E_b=0.95, seed=4, imu=setup)
    robot.wait(1.0)
    heading = robot.true_pose.theta
    start = robot.now() - 0.5  # at rest: the readings' trapezoids hold the whole turn
    _turned(robot, 0.9, 4.0)
    gyro = robot.gyro(start)
    assert gyro is not None
    assert gyro.time[0] > start
    start = float(gyro.time[0])
    raw = robot.imu_readings(start - 0.1)
    assert raw is not None
    bias = float((setup.rotation @ raw.bias[-1])[2])
    assert raw.bias[-1][2] == pytest.approx(0.5 * DEG)
    turn = robot.true_pose.theta - heading
    span = float(gyro.time[-1] - start)
    read = gyro.yaw_change(np.array([start]), np.array([gyro.time[-1]]))[0]
    assert read == pytest.approx(turn / 0.97 + bias * span, abs=1e-9)
    # the readings are the IMU's own frame rotated back: the base's x and y see no turn
    np.testing.assert_allclose(gyro.rate[:, :2], np.tile((setup.rotation @ raw.bias[-1])[:2],
                               (len(gyro), 1)), atol=1e-12)  # fmt: skip
    imu = robot.imu()
    assert imu is not None
    assert imu.topic == "/imu"
    np.testing.assert_allclose(imu.mounting.rotation, setup.rotation)


def test_the_readings_are_its_rate_and_held_for_a_minute():
    robot = VirtualRobot(seed=1, imu=ImuSetup(imu_rate=100.0))
    robot.wait(IMU_HELD + 10.0)
    gyro = robot.gyro(-math.inf)
    assert gyro is not None
    assert gyro.time[-1] == pytest.approx(robot.now())
    assert robot.now() - gyro.time[0] <= IMU_HELD + 5.0  # older ones dropped
    np.testing.assert_allclose(np.diff(gyro.time), 0.01, atol=1e-9)
    assert robot.gyro(robot.now()) is not None
    assert len(robot.gyro(robot.now())) == 0
    assert VirtualRobot().gyro(0.0) is None
    assert VirtualRobot().imu() is None


def test_the_rest_of_the_simulation_is_the_same_with_or_without_an_imu():
    poses = []
    for imu in (None, ImuSetup()):
        robot = VirtualRobot(E_d=1.01, slip=0.001, seed=7, imu=imu)
        for _ in range(100):
            robot.send_velocity(0.2, 0.3)
            robot.wait(robot.period)
        scan = robot.scan()
        assert scan is not None
        poses.append((robot.true_pose, robot.odometry().pose, scan.ranges))
    assert poses[0][:2] == poses[1][:2]
    np.testing.assert_array_equal(poses[0][2], poses[1][2])


def test_a_simulation_reset_puts_the_robot_back_and_leaves_its_controller_alone():
    """Gazebo's reset: 2 s at 0.5 m/s straight ahead (1 m), then the clock at 0, the robot
    at its start at rest, its wheels' joints at 0; the controller's odometry kept (1 m
    ahead) until its next update, which moves it back by the wheels' jump (1 m): ~0."""
    robot = VirtualRobot(seed=1)
    start = robot.true_pose
    for _ in range(100):
        robot.send_velocity(0.5, 0.0)
        robot.wait(robot.period)
    robot.send_velocity(0.0, 0.0)
    robot.wait(1.0)  # stopped (the braking's few millimetres in it)
    ahead = robot.odometry().pose.x
    assert ahead == pytest.approx(1.0, abs=0.02)
    robot.reset_simulation()
    assert robot.now() == 0.0
    assert robot.true_pose == start
    assert robot.wheel_angles() == (0.0, 0.0, 0.0)
    assert robot.odometry().pose.x == ahead
    robot.wait(robot.period)
    assert robot.odometry().pose.x == pytest.approx(0.0, abs=1e-3)
    assert robot.true_pose == start  # at rest

"""The corrected odometry as nav_msgs/Odometry without ROS running: covariance row-major,
the yaw's quaternion, the controller's covariance kept, real messages filled."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.monitor.odometry_msg import Frames, fill_odometry, fill_transform, odometry_fields
from umbmark.monitor.status import CorrectedOdometry
from umbmark.robot.base import Pose2D


def _odometry(yaw: float, covariance: np.ndarray) -> CorrectedOdometry:
    return CorrectedOdometry(12.5, Pose2D(1.0, -2.0, yaw), 0.3, -0.1, covariance, covariance)


def test_covariance_is_row_major_over_x_y_z_roll_pitch_yaw() -> None:
    """nav_msgs/Odometry's covariance is the 6 x 6 matrix row by row: element (i, j) at
    6 i + j. A matrix whose (i, j) is 10 i + j + 1 reads back its own index."""
    m = np.array([[10.0 * i + j + 1.0 for j in range(6)] for i in range(6)])
    fields = odometry_fields(_odometry(0.0, m), Frames("odom", "base_footprint"))
    for i in range(6):
        for j in range(6):
            assert fields.pose_covariance[6 * i + j] == 10 * i + j + 1
    assert fields.pose_covariance[35] == 56.0  # yaw-yaw, the last
    assert fields.frames == Frames("odom", "base_footprint")


def test_no_covariance_from_the_core_keeps_the_controllers() -> None:
    controller = [0.0] * 36
    controller[0] = controller[7] = 0.001  # diff_drive_controller's pose_covariance_diagonal
    zeros = np.zeros((6, 6))
    fields = odometry_fields(_odometry(0.0, zeros), Frames(), controller, None)
    assert fields.pose_covariance == tuple(controller)
    assert fields.twist_covariance == (0.0,) * 36
    nan = np.full((6, 6), math.nan)
    assert odometry_fields(_odometry(0.0, nan), Frames(), controller).pose_covariance[7] == 0.001


def test_the_orientation_is_the_yaws_quaternion() -> None:
    """A quarter turn left: (0, 0, sin 45 deg, cos 45 deg); a half turn: (0, 0, 1, 0)."""
    half = math.sqrt(0.5)
    q = odometry_fields(_odometry(math.pi / 2, np.eye(6)), Frames()).orientation
    assert q == pytest.approx((0.0, 0.0, half, half), abs=1e-15)
    q = odometry_fields(_odometry(math.pi, np.eye(6)), Frames()).orientation
    assert q == pytest.approx((0.0, 0.0, 1.0, 0.0), abs=1e-15)


def test_real_odometry_and_transform_messages_are_filled() -> None:
    nav = pytest.importorskip("nav_msgs.msg", reason="python3-nav-msgs (Debian)")
    geo = pytest.importorskip("geometry_msgs.msg", reason="python3-geometry-msgs (Debian)")
    fields = odometry_fields(_odometry(math.pi / 2, np.eye(6)), Frames("odom", "base_link"))
    msg = fill_odometry(fields, nav.Odometry(), "T")
    assert (msg.header.frame_id, msg.child_frame_id) == ("odom", "base_link")
    p = msg.pose.pose.position
    assert (p.x, p.y, p.z) == (1.0, -2.0, 0.0)
    assert (msg.twist.twist.linear.x, msg.twist.twist.angular.z) == (0.3, -0.1)
    assert len(msg.pose.covariance) == 36
    assert msg.pose.covariance[7] == 1.0
    tf = fill_transform(fields, geo.TransformStamped(), "T")
    assert (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_link")
    assert tf.transform.rotation.z == pytest.approx(math.sqrt(0.5))

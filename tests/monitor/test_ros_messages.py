"""The monitor's ROS messages without ROS running: /diagnostics laid out as
diagnostic_updater writes it, the corrected odometry's covariance and orientation, and the
message classes filled (ROS 1's Debian message classes, where installed: plain Python)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.monitor.diagnostics import STATUS_NAME, compose, fill_array, level_value
from umbmark.monitor.odometry_msg import Frames, fill_odometry, fill_transform, odometry_fields
from umbmark.monitor.status import FIGURES, CorrectedOdometry, Figure, MonitorStatus
from umbmark.robot.base import Pose2D


def _status(level: str = "WARN") -> MonitorStatus:
    figures = tuple(
        Figure(name, 1.0021 if name == "E_d" else None, 0.0004 if name == "E_d" else None,
               unit, "" if name == "E_d" else "turned one way only")
        for name, unit in FIGURES
    )  # fmt: skip
    return MonitorStatus(2000.0, "r7", level, "E_d changed", figures,  # type: ignore[arg-type]
                         123.4, 5.0, 6.0, 789.0, 1500.0, applied="yaml: wrote x")  # fmt: skip


def test_the_status_is_named_and_levelled_as_diagnostic_updater_writes_it() -> None:
    """diagnostic_updater names a task's status ``<node name>: <task>`` and levels it OK 0,
    WARN 1, ERROR 2, STALE 3 (diagnostic_msgs/DiagnosticStatus); ROS 2's level field is
    one byte (``b'\\x00'``), ROS 1's an integer."""
    for index, level in enumerate(("OK", "WARN", "ERROR", "STALE")):
        d = compose(_status(level))
        assert (d.name, d.level, d.hardware_id, d.message) == (
            "umbmark_monitor: odometry", index, "r7", "E_d changed",
        )  # fmt: skip
    assert STATUS_NAME == "umbmark_monitor: odometry"
    assert compose(_status(), "/ns/renamed").name == "ns/renamed: odometry"
    assert [level_value(k, ros2=True) for k in range(4)] == [b"\x00", b"\x01", b"\x02", b"\x03"]
    assert level_value(2, ros2=False) == 2
    with pytest.raises(ValueError, match="0 to 3"):
        level_value(4, ros2=True)


def test_the_key_values_are_strings_in_order() -> None:
    values = dict(compose(_status()).values)
    assert compose(_status()).values[0] == ("E_d", "1.0021 +- 0.0004")
    assert values["laser_x [m]"] == "not determined: turned one way only"
    assert values["metres observed [m]"] == "123.4"
    assert values["applied"] == "yaml: wrote x"
    assert all(isinstance(k, str) and isinstance(v, str) for k, v in compose(_status()).values)


def test_a_real_diagnostic_array_is_filled() -> None:
    msg = pytest.importorskip("diagnostic_msgs.msg", reason="python3-diagnostic-msgs (Debian)")
    array = fill_array(compose(_status("ERROR")), msg.DiagnosticArray, msg.DiagnosticStatus,
                       msg.KeyValue, "STAMP", ros2=False)  # fmt: skip
    assert array.header.stamp == "STAMP"
    (status,) = array.status
    assert (status.name, status.level, status.hardware_id) == (STATUS_NAME, 2, "r7")
    assert (status.values[0].key, status.values[0].value) == ("E_d", "1.0021 +- 0.0004")
    assert status.level == msg.DiagnosticStatus.ERROR


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

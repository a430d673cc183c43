"""The gyro's own calibration on the report page, and where common drivers take it.

A calibration with a gyro (:mod:`umbmark.calibration.gyro`) finds the gyro's scale
``k_g`` (``omega_true = k_g (omega_read - bias)``) where an absolute heading joined, its
bias, and the IMU's tilt as its turns show it;
:func:`~umbmark.calibration.gyro.gyro_lines` says them for people (the bias in deg/s,
each figure with its 95 % interval, what is not determined and why). Where they go:

- **a driver that scales its rates**: its gyro scale times ``k_g`` (the new scale is the
  one it ran with, multiplied); TurtleBot's ``create_node`` (turtlebot_create) multiplies
  its rates by ``~gyro_scale_correction``;
- **a driver that takes a bias**: subtract the bias from the yaw rate (add it to an
  offset the driver subtracts); most drivers measure it themselves while the robot
  stands still, and take no value: phidgets_spatial (the service ``imu/calibrate``),
  microstrain_inertial_driver (the service ``mip/three_dm/capture_gyro_bias``),
  imu_tools' complementary filter (``do_bias_estimation``), create_node (its offset
  averaged at rest); RealSense cameras keep scale and bias as the IMU's intrinsics on
  the camera (librealsense's ``rs-imu-calibration`` writes them);
- **the IMU's frame** where its turns show a tilt its stated transform misses: the URDF
  joint origin's ``rpy`` of the IMU frame found (:meth:`~umbmark.estimators.gyro_mounting.
  GyroMounting.found_rotation`, its yaw as stated), or, keeping the stated transform,
  ros2_controllers' ``imu_sensor_broadcaster`` ``rotation_offset`` (``roll``, ``pitch``,
  ``yaw``: it rotates the readings by ``Rz Ry Rx`` of them).

The drivers' parameters are as their sources name them (docs/reading-results.md cites
them). Angles in degrees for people, radians where ROS takes them.
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from umbmark.calibration.result import CalibrationResult

__all__ = ["DRIVERS", "gyro_html"]

#: Where common drivers take the gyro's figures: (driver, scale, bias), as their sources
#: name them.
DRIVERS = (
    (
        "turtlebot_create create_node",
        "~gyro_scale_correction: multiply it by k_g",
        "none to set: it averages its offset while the robot stands still",
    ),
    (
        "phidgets_spatial",
        "no scale parameter",
        "zeroed at start and by the service imu/calibrate, the robot standing still",
    ),
    (
        "microstrain_inertial_driver",
        "no scale parameter",
        "captured by the service mip/three_dm/capture_gyro_bias, the robot standing still",
    ),
    (
        "imu_tools imu_complementary_filter",
        "no scale parameter",
        "do_bias_estimation: true (bias_alpha) estimates it while the robot stands still",
    ),
    (
        "RealSense (librealsense)",
        "the IMU's intrinsics on the camera (rs-imu-calibration writes them)",
        "the same intrinsics",
    ),
)


def gyro_html(result: CalibrationResult) -> str:
    """The report page's gyro section's content: the gyro's figures and where they go,
    the table of :data:`DRIVERS` (empty without a gyro)."""
    from umbmark.calibration.gyro import gyro_lines
    from umbmark.outputs.html_parts import table

    gyro = result.gyro
    if gyro is None:
        return ""
    head, *lines = gyro_lines(gyro)
    items = "".join(f'<li class="command">{html.escape(line)}</li>\n' for line in lines)
    drivers = table(["driver", "the scale", "the bias"], [list(d) for d in DRIVERS], (0, 1, 2))
    return (
        f"<p>{html.escape(head)}</p>\n<ul>\n{items}</ul>\n"
        "<p>Where common drivers take them (as their sources name them; "
        "docs/reading-results.md cites them):</p>\n"
        f"{drivers}"
    )

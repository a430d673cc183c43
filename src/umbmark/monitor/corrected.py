"""The robot's odometry integrated from its wheels with the present calibration: a
calibrated odometry on every ROS distribution, whatever the controller's own multipliers.

Each wheel reading moves the pose along the exact arc of the wheels' travel (the radii
and wheelbase of the present calibration, :class:`WheelCalibration`), as
``diff_drive_controller`` integrates. Its covariance grows to first order with what the
calibration leaves uncertain (each radius' and the wheelbase's standard error: a heading
error of ``dtheta sigma_b / b`` and a travel error of ``ds sigma_r / r`` per step, the
heading's error carried into the position), and with the wheels' random slip
(:data:`SLIP`, the virtual robot's order of magnitude): what a navigation stack weighs it
by, not a bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.monitor.status import CorrectedOdometry
from umbmark.robot.base import Pose2D

__all__ = ["SLIP", "Integrator", "WheelCalibration"]

#: The wheels' random slip [m^(1/2)]: a position variance of ``SLIP^2 |ds|`` per step.
SLIP = 0.005


@dataclass(frozen=True)
class WheelCalibration:
    """The wheels as the monitor knows them now.

    Attributes
    ----------
    radius_left, radius_right, wheelbase : float
        [m]
    se_left, se_right, se_wheelbase : float
        Their standard errors [m] (0: taken as exact).
    """

    radius_left: float
    radius_right: float
    wheelbase: float
    se_left: float = 0.0
    se_right: float = 0.0
    se_wheelbase: float = 0.0


class Integrator:
    """The corrected odometry (the module's notes)."""

    def __init__(self, calibration: WheelCalibration) -> None:
        self.calibration = calibration
        self.pose = Pose2D()
        self.time: float | None = None
        self._angles: tuple[float, float] | None = None
        self._cov = np.zeros((3, 3))
        self._twist = (0.0, 0.0)

    def update(self, time: float, angles: tuple[float, float]) -> None:
        """The wheels' angles [rad] at ``time`` [s] (continuous: restarts taken out)."""
        last, was = self.time, self._angles
        self.time, self._angles = time, angles
        if last is None or was is None:
            return
        c = self.calibration
        d_left = (angles[0] - was[0]) * c.radius_left
        d_right = (angles[1] - was[1]) * c.radius_right
        ds, dth = 0.5 * (d_left + d_right), (d_right - d_left) / c.wheelbase
        p = self.pose
        mid = p.theta + 0.5 * dth
        chord = ds * (math.sin(0.5 * dth) / (0.5 * dth) if abs(dth) > 1e-9 else 1.0)
        self.pose = Pose2D(p.x + chord * math.cos(mid), p.y + chord * math.sin(mid), p.theta + dth)
        dt = time - last
        if dt > 0:
            self._twist = (ds / dt, dth / dt)
        self._grow(ds, dth, d_left, d_right, mid)

    def _grow(self, ds: float, dth: float, d_left: float, d_right: float, mid: float) -> None:
        c = self.calibration
        var_heading = (dth * c.se_wheelbase / c.wheelbase) ** 2
        var_heading += ((d_right * c.se_right / c.radius_right) ** 2
                        + (d_left * c.se_left / c.radius_left) ** 2) / c.wheelbase**2  # fmt: skip
        var_travel = 0.25 * ((d_left * c.se_left / c.radius_left) ** 2
                             + (d_right * c.se_right / c.radius_right) ** 2)  # fmt: skip
        var_travel += SLIP**2 * abs(ds)
        var_heading += SLIP**2 * (abs(d_left) + abs(d_right)) / c.wheelbase**2
        cos, sin = math.cos(mid), math.sin(mid)
        jac = np.array([[1.0, 0.0, -ds * sin], [0.0, 1.0, ds * cos], [0.0, 0.0, 1.0]])
        noise = np.array([[cos * cos, cos * sin, 0.0], [cos * sin, sin * sin, 0.0], [0, 0, 0]])
        self._cov = jac @ self._cov @ jac.T + var_travel * noise
        self._cov[2, 2] += var_heading

    def odometry(self) -> CorrectedOdometry | None:
        """The corrected odometry now, or None before the first wheel reading."""
        if self.time is None:
            return None
        pose = np.zeros((6, 6))
        index = (0, 1, 5)
        for i, a in enumerate(index):
            for j, b in enumerate(index):
                pose[a, b] = self._cov[i, j]
        for k in (2, 3, 4):
            pose[k, k] = 1e6  # z, roll, pitch: not measured (robot_localization's rule)
        twist = np.zeros((6, 6))
        linear, angular = self._twist
        twist[0, 0] = (SLIP**2) + (0.01 * linear) ** 2
        twist[5, 5] = (SLIP**2) / self.calibration.wheelbase**2 + (0.01 * angular) ** 2
        twist[1, 1] = 1e-9  # a differential drive does not move sideways
        for k in (2, 3, 4):
            twist[k, k] = 1e6
        return CorrectedOdometry(self.time, self.pose, linear, angular, pose, twist)

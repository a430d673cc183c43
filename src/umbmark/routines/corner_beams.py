"""Walls fitted to laser beams in range space: unbiased where the beams meet the walls
obliquely.

A laser's noise lies along its beams. Fitting lines to the points by their orthogonal
distances (total least squares) is then biased: where a beam meets a wall obliquely,
its noise moves the point along the wall as well as across it, and the two are
correlated, which turns the fitted line by up to a tenth of a degree on a short wall.
Here the residual is the range itself: measured minus where the beam, a noise-free ray
from the laser, meets the wall's line (maximum likelihood for Gaussian range noise),
minimized by Gauss-Newton from the closed-form fit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.robot.base import Pose2D

__all__ = ["Beams", "CornerEstimate", "fit_corner_ranges", "wall_angle"]


@dataclass(frozen=True)
class Beams:
    """Laser returns in the robot's base frame.

    Attributes
    ----------
    origins : array, shape (n, 2)
        Where each beam starts (the laser's position) [m].
    directions : array, shape (n, 2)
        Each beam's unit direction.
    ranges : array, shape (n,)
        Measured ranges [m].
    """

    origins: FloatArray
    directions: FloatArray
    ranges: FloatArray

    @property
    def points(self) -> FloatArray:
        """The returns as points, shape (n, 2) [m]."""
        return self.origins + self.ranges[:, None] * self.directions

    def __len__(self) -> int:
        return int(self.ranges.size)

    def take(self, mask: NDArray[np.bool_]) -> Beams:
        """The beams where ``mask`` holds."""
        return Beams(self.origins[mask], self.directions[mask], self.ranges[mask])


@dataclass(frozen=True)
class CornerEstimate:
    """The joint fit of a corner's two walls as perpendicular lines, in range space.

    Attributes
    ----------
    pose : Pose2D
        The robot's base frame in the corner frame.
    covariance : array, shape (3, 3)
        Of ``x, y, theta``, from the range residuals.
    range_rms : float
        Residual rms of the ranges [m].
    """

    pose: Pose2D
    covariance: FloatArray
    range_rms: float


def _axes(alpha: float) -> tuple[FloatArray, FloatArray]:
    """The corner frame's x and y axes in the base frame, x at ``alpha``."""
    ex = np.array([math.cos(alpha), math.sin(alpha)])
    return ex, np.array([-ex[1], ex[0]])


def _predict(
    beams: Beams, normal: FloatArray, offset: float, along: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Where each beam meets the line ``normal . q = offset``: the range, its derivative
    by the offset and by the line's turning (``along`` is the normal's derivative)."""
    nb = beams.directions @ normal
    t = (offset - beams.origins @ normal) / nb
    hit = beams.origins + t[:, None] * beams.directions
    return t, 1.0 / nb, -(hit @ along) / nb


def fit_corner_ranges(
    x_wall: Beams, y_wall: Beams, start: Pose2D, steps: int = 3
) -> CornerEstimate:
    """Fit the corner to the beams of its x and y walls, from ``start`` (the robot's pose
    in the corner frame, from the closed-form fit); ``steps`` Gauss-Newton steps."""
    # parameters: alpha (the corner's x axis in the base frame), c_x, c_y: the x wall is
    # e_y . q = c_x, the y wall e_x . q = c_y; the pose is (-c_y, -c_x, -alpha).
    params = np.array([-start.theta, -start.y, -start.x])
    nx, ny = len(x_wall), len(y_wall)
    for k in range(steps + 1):
        ex, ey = _axes(float(params[0]))
        tx, dcx, dax = _predict(x_wall, ey, float(params[1]), -ex)
        ty, dcy, day = _predict(y_wall, ex, float(params[2]), ey)
        jac = np.zeros((nx + ny, 3))
        jac[:nx, 0], jac[:nx, 1] = dax, dcx
        jac[nx:, 0], jac[nx:, 2] = day, dcy
        residual = np.concatenate([x_wall.ranges - tx, y_wall.ranges - ty])
        info = jac.T @ jac
        step = np.linalg.solve(info, jac.T @ residual)
        if k == steps:
            break
        params = params + step
    dof = max(nx + ny - 3, 1)
    sigma2 = float(residual @ residual) / dof
    cov_params = sigma2 * np.linalg.inv(info)
    to_pose = np.array([[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]])
    pose = Pose2D(-float(params[2]), -float(params[1]), -float(params[0]))
    rms = math.sqrt(float(residual @ residual) / (nx + ny))
    return CornerEstimate(pose, to_pose @ cov_params @ to_pose.T, rms)


def _line(beams: Beams, normal_angle: float, offset: float, steps: int = 3) -> tuple[float, float]:
    """One wall fitted on its own in range space: its normal's angle [rad] and the
    angle's standard error."""
    params = np.array([normal_angle, offset])
    for k in range(steps + 1):
        n = np.array([math.cos(params[0]), math.sin(params[0])])
        t, dc, da = _predict(beams, n, float(params[1]), np.array([-n[1], n[0]]))
        jac = np.column_stack([da, dc])
        residual = beams.ranges - t
        info = jac.T @ jac
        if k == steps:
            break
        params = params + np.linalg.solve(info, jac.T @ residual)
    sigma2 = float(residual @ residual) / max(len(beams) - 2, 1)
    return float(params[0]), math.sqrt(sigma2 * float(np.linalg.inv(info)[0, 0]))


def wall_angle(x_wall: Beams, y_wall: Beams, pose: Pose2D) -> tuple[float, float]:
    """The angle from the x wall to the y wall [rad] (pi/2 for a square corner), each
    wall fitted on its own (starting from the joint fit at ``pose``), and its standard
    error."""
    alpha = -pose.theta
    # the x wall's normal e_y is at alpha + pi/2, the y wall's e_x at alpha
    bx, sx = _line(x_wall, alpha + 0.5 * math.pi, -pose.y)
    by, sy = _line(y_wall, alpha, -pose.x)
    # the x wall runs along its normal turned -90 deg, the y wall along its normal +90
    angle = (by + 0.5 * math.pi) - (bx - 0.5 * math.pi)
    return math.remainder(angle, 2 * math.pi), math.hypot(sx, sy)

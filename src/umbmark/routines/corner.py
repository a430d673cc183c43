"""The robot's pose in an L-shaped corner: the fix, its uncertainty, and what the routine
does with two of them.

The paper (Sec. 5) measured where the robot really stopped with a "sonar calibrator":
range sensors facing the two walls of an L-shaped corner. Here a fix comes from a laser
scan (:mod:`umbmark.routines.corner_lidar`), three range sensors, motion capture or a
person with a tape measure (:mod:`umbmark.routines.corner_sensors`).

The corner frame
    Origin at the corner's vertex (where the two walls' lines meet); x along the *x wall*,
    y along the *y wall*, right-handed (y is x turned 90 degrees counter-clockwise). The
    robot stands inside the corner, so its x and y are positive: x is its distance from
    the y wall, y its distance from the x wall. Which wall is which follows from that
    handedness alone, so every fix in the same corner uses the same frame; in the
    standard world (:func:`umbmark.robot.world.corner_world`) the x wall runs beside the
    start along +x and the y wall behind it.
A fix
    The pose of the robot's base frame in the corner frame, with its covariance (x, y
    [m], theta [rad]) from the fit's residuals or the sensors' noise.
The routine
    The robot's true motion from one stop to the next is the end fix seen from the
    start fix (:func:`relative_motion`); the corner drops out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.conventions import wrap_angle
from umbmark.core.errors import InputError
from umbmark.robot.base import Pose2D

__all__ = [
    "CornerFix",
    "CornerNotFoundError",
    "RelativeMotion",
    "expected_pose",
    "relative_motion",
]


Method = Literal["lidar", "ranges", "ground_truth", "tape"]
Cause = Literal[
    "too_few_points",
    "no_corner",
    "not_perpendicular",
    "poor_fit",
    "not_where_expected",
    "missing_echo",
    "implausible",
]


class CornerNotFoundError(InputError):
    """No fix: the corner was not found or not measured well enough.

    Its text is one line naming the cause and the figure that decided it; ``cause`` is
    the cause as a word the routine can act on (retry when a person walks by, stop when
    the corner is not perpendicular).
    """

    def __init__(self, cause: Cause, problem: str) -> None:
        self.cause: Cause = cause
        super().__init__(problem)


@dataclass(frozen=True)
class CornerFix:
    """The robot's pose in the corner frame, measured while it stood still.

    Attributes
    ----------
    pose : Pose2D
        The robot's base frame in the corner frame [m, rad].
    covariance : array, shape (3, 3)
        Of ``x, y, theta`` [m^2, m rad, rad^2].
    method : str
        ``lidar``, ``ranges``, ``ground_truth`` or ``tape``.
    time : float
        The robot's clock at the (last) reading [s].
    points : int
        Points (laser returns, ranges, distances) the fix rests on.
    readings : int
        Scans, range readings or poses averaged.
    residual_rms : float
        The fit's residual rms [m] (NaN where the fit has no residuals).
    wall_angle, wall_angle_std : float
        The angle between the walls as measured [rad] and its standard error (NaN where
        the method does not measure it).
    """

    pose: Pose2D
    covariance: FloatArray
    method: Method
    time: float
    points: int
    readings: int = 1
    residual_rms: float = math.nan
    wall_angle: float = math.nan
    wall_angle_std: float = math.nan

    @property
    def std(self) -> tuple[float, float, float]:
        """Standard errors of ``x, y`` [m] and ``theta`` [rad]."""
        d = np.sqrt(np.maximum(np.diag(self.covariance), 0.0))
        return float(d[0]), float(d[1]), float(d[2])


@dataclass(frozen=True)
class RelativeMotion:
    """Where the robot really went from one fix to the next, in the first fix's frame.

    Attributes
    ----------
    pose : Pose2D
        The end pose seen from the start pose [m, rad] (heading wrapped to -pi .. pi).
    covariance : array, shape (3, 3)
        Of ``x, y, theta``, both fixes' uncertainties propagated (independent fixes).
    """

    pose: Pose2D
    covariance: FloatArray

    @property
    def std(self) -> tuple[float, float, float]:
        """Standard errors of ``x, y`` [m] and ``theta`` [rad]."""
        d = np.sqrt(np.maximum(np.diag(self.covariance), 0.0))
        return float(d[0]), float(d[1]), float(d[2])


def relative_motion(start: CornerFix, end: CornerFix) -> RelativeMotion:
    """The robot's true motion from ``start`` to ``end``: ``start.pose.inverse()
    .compose(end.pose)``, with the covariance of both fixes propagated to first order.

    Both fixes must be in the same corner (the routine gates each by its prior).
    """
    x1, y1, t1 = start.pose.x, start.pose.y, start.pose.theta
    dx, dy = end.pose.x - x1, end.pose.y - y1
    c, s = math.cos(t1), math.sin(t1)
    pose = Pose2D(c * dx + s * dy, -s * dx + c * dy, wrap_angle(end.pose.theta - t1))
    rot = np.array([[c, s], [-s, c]])
    j_start = np.zeros((3, 3))
    j_start[:2, :2] = -rot
    j_start[:2, 2] = [-s * dx + c * dy, -c * dx - s * dy]
    j_start[2, 2] = -1.0
    j_end = np.zeros((3, 3))
    j_end[:2, :2] = rot
    j_end[2, 2] = 1.0
    cov = j_start @ start.covariance @ j_start.T + j_end @ end.covariance @ j_end.T
    return RelativeMotion(pose, cov)


def expected_pose(fix: CornerFix, odom_at_fix: Pose2D, odom_now: Pose2D) -> Pose2D:
    """Where the robot should be in the corner frame now: the last fix moved on by what
    the odometry says it drove since (the prior that gates the next fix)."""
    return fix.pose.compose(odom_now.relative_to(odom_at_fix))


# --- two perpendicular lines fitted jointly -------------------------------------------------


@dataclass(frozen=True)
class CornerFit:
    """A joint fit of a corner's two walls as perpendicular lines.

    Attributes
    ----------
    pose : Pose2D
        The robot's base frame in the corner frame.
    x_points, y_points : array, shape (n, 2) and (m, 2)
        The points of each wall in the corner frame.
    inside : bool
        The robot stands inside the corner for this labelling of the walls: on the
        positive side of both, the walls extending from the vertex along +x and +y.
    """

    pose: Pose2D
    x_points: FloatArray
    y_points: FloatArray
    inside: bool

    @property
    def residuals(self) -> FloatArray:
        """Orthogonal distances [m] of the points to their walls, shape (n + m,)."""
        return np.concatenate([self.x_points[:, 1], self.y_points[:, 0]])

    @property
    def rms(self) -> float:
        """Residual rms [m]."""
        r = self.residuals
        return float(np.sqrt(np.mean(r * r))) if r.size else math.nan


def to_frame(pose: Pose2D, points: FloatArray) -> FloatArray:
    """Points of the robot's base frame (shape (n, 2)) in the frame where the robot
    stands at ``pose``."""
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    rot = np.array([[c, s], [-s, c]])  # row vectors: p @ rot = R(theta) p
    return np.asarray(points @ rot + [pose.x, pose.y])


def fit_corner(
    x_points: FloatArray, y_points: FloatArray, extent_margin: float = 0.1
) -> CornerFit | None:
    """Fit two perpendicular lines jointly (orthogonal least squares, closed form) to the
    points of the x wall and of the y wall (base frame, shapes (n, 2) and (m, 2)); the
    corner frame is oriented so that the robot is on the positive side of both.

    ``inside`` is False when the robot is not inside the corner so labelled (the walls
    labelled the other way round, a box's outer corner): the x wall's points must not
    reach below ``x = -extent_margin``, nor the y wall's below ``y = -extent_margin``.
    None when a wall has no points or the walls' directions are undetermined.
    """
    if min(len(x_points), len(y_points)) < 1 or max(len(x_points), len(y_points)) < 2:
        return None
    mx, my = x_points.mean(axis=0), y_points.mean(axis=0)
    dx, dy = x_points - mx, y_points - my
    # n^T S_x n + m^T S_y m with m = n turned 90 degrees equals n^T (S_x - S_y) n + const
    a = float(np.sum(dx[:, 0] ** 2) - np.sum(dy[:, 0] ** 2))
    b = float(np.sum(dx[:, 0] * dx[:, 1]) - np.sum(dy[:, 0] * dy[:, 1]))
    c = float(np.sum(dx[:, 1] ** 2) - np.sum(dy[:, 1] ** 2))
    if a == c and b == 0.0:
        return None
    phi = 0.5 * math.atan2(2.0 * b, a - c) + 0.5 * math.pi  # smallest eigenvector
    ey = np.array([math.cos(phi), math.sin(phi)])  # the x wall's normal
    if float(ey @ mx) > 0.0:  # toward the robot: the wall at negative y
        ey = -ey
    ex = np.array([ey[1], -ey[0]])  # ey is ex turned +90 degrees
    pose = Pose2D(-float(ex @ my), -float(ey @ mx), math.atan2(-float(ex[1]), float(ex[0])))
    px, py = to_frame(pose, x_points), to_frame(pose, y_points)
    inside = (
        pose.x > 0.0
        and pose.y > 0.0
        and float(px[:, 0].min()) > -extent_margin
        and float(py[:, 1].min()) > -extent_margin
    )
    return CornerFit(pose, px, py, inside)


def line_direction(points: FloatArray) -> FloatArray:
    """The unit direction of the total-least-squares line through ``points`` (shape
    (n, 2))."""
    d = points - points.mean(axis=0)
    a, b, c = float(d[:, 0] @ d[:, 0]), float(d[:, 0] @ d[:, 1]), float(d[:, 1] @ d[:, 1])
    phi = 0.5 * math.atan2(2.0 * b, a - c)
    return np.array([math.cos(phi), math.sin(phi)])

"""Clearance as the robot's path: the band its footprint sweeps, for the watch on a leg
or an arc and for the check before moving.

The robot's footprint is a rectangle (:class:`Footprint`) around its axle centre. Driving
a leg, it sweeps a band as wide as the footprint plus :data:`SIDE_MARGIN` on each side;
turning on the spot at a corner, a disc of the footprint's reach. A scan return matters
only inside that band: a wall beyond the end of a leg, farther than the stop margin,
does not stop a robot that was going to stop before it. Before moving, the planned path
is widened by the drift a robot's errors allow (:data:`DRIFT` of heading over a run).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from umbmark.core.bounds import check_range
from umbmark.core.errors import option
from umbmark.options.selfcal import ROBOT_WIDTH_RANGE
from umbmark.robot.base import ScanSweep

__all__ = [
    "DEFAULT_WIDTH",
    "DRIFT",
    "SIDE_MARGIN",
    "Footprint",
    "arc_band",
    "path_blocked",
    "robot_footprint",
    "scan_points",
    "straight_band",
]

#: The footprint's width [m] where the robot's description gives none: a small indoor
#: base (a TurtleBot 2 is 0.35 m across, a Pioneer 3-DX 0.38 m).
DEFAULT_WIDTH = 0.4
#: Room kept beside the footprint on each side of the band [m].
SIDE_MARGIN = 0.03
#: The heading drift [rad] a robot's errors are allowed on a leg before moving: its path
#: strays up to ``a sin(DRIFT)`` sideways ``a`` metres along a leg.
DRIFT = math.radians(2.0)


@dataclass(frozen=True)
class Footprint:
    """The robot's outline seen from above: a rectangle ``length`` by ``width`` [m] whose
    centre lies ``offset`` [m] ahead of the axle centre (the base frame's origin)."""

    length: float = DEFAULT_WIDTH
    width: float = DEFAULT_WIDTH
    offset: float = 0.0

    @property
    def half_width(self) -> float:
        """Half the width plus :data:`SIDE_MARGIN` [m]: the band's half width."""
        return 0.5 * self.width + SIDE_MARGIN

    @property
    def reach(self) -> float:
        """The farthest the outline reaches from the axle centre [m]: the disc swept
        turning on the spot, plus :data:`SIDE_MARGIN`."""
        front = abs(self.offset) + 0.5 * self.length
        return math.hypot(front, 0.5 * self.width) + SIDE_MARGIN


def scan_points(scan: ScanSweep) -> np.ndarray:
    """The scan's valid returns in the robot's base frame, shape (n, 2) [m]."""
    ranges = np.asarray(scan.ranges, dtype=np.float64)
    ok = np.isfinite(ranges) & (ranges >= scan.range_min) & (ranges <= scan.range_max)
    angles = scan.angles()[ok] + scan.mount.theta
    x = scan.mount.x + ranges[ok] * np.cos(angles)
    y = scan.mount.y + ranges[ok] * np.sin(angles)
    return np.column_stack([x, y])


def straight_band(
    points: np.ndarray, half_width: float, heading: float = 0.0, backward: bool = False
) -> float:
    """The nearest distance ahead [m] (behind, ``backward``) of a point within
    ``half_width`` of a straight path leaving the robot at ``heading`` [rad, base frame];
    inf if none.

    Parameters
    ----------
    points : array, shape (n, 2)
        Base frame [m].
    """
    c, s = math.cos(heading), math.sin(heading)
    along = points[:, 0] * c + points[:, 1] * s
    side = -points[:, 0] * s + points[:, 1] * c
    along = -along if backward else along
    inside = (along > 0.0) & (np.abs(side) <= half_width)
    return float(np.min(along[inside])) if inside.any() else math.inf


def arc_band(points: np.ndarray, half_width: float, radius: float, centre_left: bool) -> float:
    """The nearest distance along an arc [m] of a point within ``half_width`` of a circle
    of ``radius`` [m] the robot drives forward on, its centre on the left (or right);
    inf if none. (Driving backward: give the points with x negated.)

    Parameters
    ----------
    points : array, shape (n, 2)
        Base frame [m].
    """
    y = points[:, 1] if centre_left else -points[:, 1]
    qx, qy = points[:, 0], y - radius  # from the centre
    rho = np.hypot(qx, qy)
    angle = np.mod(np.arctan2(qy, qx) + 0.5 * math.pi, 2.0 * math.pi)  # from the robot
    inside = (np.abs(rho - radius) <= half_width) & (angle > 0.0)
    return float(np.min(radius * angle[inside])) if inside.any() else math.inf


def path_blocked(
    points: np.ndarray,
    path: Sequence[tuple[float, float]],
    footprint: Footprint,
    margin: float,
    drift: float = DRIFT,
) -> np.ndarray:
    """Which points stand on a planned path of straight legs with on-the-spot turns at
    each vertex: within the band of each leg (continued by ``margin`` [m] past its end,
    where the robot stops), or within the footprint's reach of a vertex. Each leg's band
    widens by ``a sin(drift)`` after ``a`` metres along it (its heading off by ``drift``),
    each vertex's disc by the arriving leg's length times ``sin(drift)``.

    Parameters
    ----------
    points : array, shape (n, 2)
        Base frame of the robot at the path's start [m].
    path : sequence of (x, y)
        The path's vertices in the same frame [m], the start first.

    Returns
    -------
    array of bool, shape (n,)
    """
    vertices = np.asarray(path, dtype=np.float64)
    blocked = np.zeros(len(points), dtype=bool)
    slope = math.sin(drift)
    arrived = 0.0  # the length of the leg arriving at the vertex [m]
    for a, b in itertools.pairwise(vertices):
        blocked |= np.hypot(*(points - a).T) <= footprint.reach + slope * arrived
        arrived = float(np.hypot(*(b - a)))
        if arrived > 0.0:
            u = (b - a) / arrived
            rel = points - a
            along = rel @ u
            side = np.abs(rel[:, 0] * u[1] - rel[:, 1] * u[0])
            blocked |= (
                (along >= 0.0)
                & (along <= arrived + margin + slope * arrived)
                & (side <= footprint.half_width + slope * np.maximum(along, 0.0))
            )
    blocked |= np.hypot(*(points - vertices[-1]).T) <= footprint.reach + slope * arrived
    return blocked


def robot_footprint(robot: object, width: float | None) -> Footprint:
    """The footprint to keep clear: a square ``width`` [m] across where given, else the
    robot's own (where the robot has a ``footprint()`` giving ``length, width, offset``
    [m]: its description's base link, :func:`umbmark.robot.urdf.urdf_footprint`), else
    :data:`DEFAULT_WIDTH` across."""
    if width is not None:
        check_range(option("robot_width"), width, ROBOT_WIDTH_RANGE)
        return Footprint(width, width)
    own = getattr(robot, "footprint", None)
    found = own() if callable(own) else None
    if isinstance(found, tuple) and len(found) == 3:
        return Footprint(*(float(v) for v in found))
    return Footprint()

"""Frame, sign and unit conventions, in one place.

Every module of umbmark follows these; ``docs/conventions.md`` explains them with the
paper's equation numbers, and ``tests/core/test_conventions.py`` pins each one.

Frame
    The origin is the run's start pose; x points along the first leg; y points to the
    robot's left (ROS REP-103). Headings are counter-clockwise positive, in radians.
Directions
    A ccw run makes left turns (heading increases); a cw run makes right turns.
Return error (Eq. 3.1)
    ``eps = absolute (true) - calculated (odometry)``.
Type A error ``alpha`` (per 90 degree turn)
    ``alpha > 0``: the robot turns *less* than commanded, so ``E_b > 1``.
Type B error ``beta`` (per leg)
    ``beta > 0``: every straight leg curves to the *left*, so ``D_R > D_L`` and ``E_d > 1``.
Tracked point
    Ground truth is the pose of the axle centre. A tracked point (a motion-capture
    marker, a GNSS antenna) at ``offset = (d_x, d_y)`` in the robot frame is moved to the
    axle centre by :func:`axle_poses`; left where it is, it adds ``(R(dtheta) - I) d`` to
    each return error, ``dtheta`` the run's true heading change.
Units
    SI inside and in every file umbmark writes: metres, radians, seconds. Input files may
    say otherwise through a flag (``--unit mm``, ``--angle-unit deg``).
"""

from __future__ import annotations

import math
from enum import Enum
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "Direction",
    "angle_to_rad",
    "axle_poses",
    "length_to_m",
    "wrap_angle",
]

#: Metres per unit of length, for every unit a file or flag may name.
LENGTH_UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001}
#: Radians per unit of angle.
ANGLE_UNITS: dict[str, float] = {"rad": 1.0, "deg": math.pi / 180.0}

_T = TypeVar("_T", float, NDArray[np.float64])


class Direction(str, Enum):
    """Direction of travel around a closed path.

    ``CCW`` runs turn left (heading increases), ``CW`` runs turn right.
    """

    CW = "cw"
    CCW = "ccw"

    @property
    def turn_sign(self) -> int:
        """+1 for ccw (left turns), -1 for cw (right turns)."""
        return 1 if self is Direction.CCW else -1

    @classmethod
    def parse(cls, label: str) -> Direction:
        """Read a direction label: ``cw``/``ccw`` in any case, with surrounding spaces.

        Also accepts the spelled-out ``clockwise`` and ``counter-clockwise``
        (``counterclockwise``, ``anticlockwise``).

        Raises
        ------
        ValueError
            If ``label`` names no direction.
        """
        key = label.strip().lower().replace("_", "-").replace(" ", "-")
        aliases = {
            "cw": cls.CW,
            "clockwise": cls.CW,
            "ccw": cls.CCW,
            "counter-clockwise": cls.CCW,
            "counterclockwise": cls.CCW,
            "anticlockwise": cls.CCW,
            "anti-clockwise": cls.CCW,
        }
        try:
            return aliases[key]
        except KeyError:
            raise ValueError(f"direction {label!r} is neither cw nor ccw") from None

    @classmethod
    def from_heading_change(cls, delta_theta: float) -> Direction:
        """The direction a closed path was driven in, from its total heading change [rad]."""
        if not math.isfinite(delta_theta) or delta_theta == 0.0:
            raise ValueError(f"total heading change {delta_theta!r} rad gives no direction")
        return cls.CCW if delta_theta > 0 else cls.CW


def length_to_m(value: _T, unit: str) -> _T:
    """Convert a length from ``unit`` (``m``, ``cm`` or ``mm``) to metres."""
    try:
        factor = LENGTH_UNITS[unit]
    except KeyError:
        raise ValueError(f"unknown length unit {unit!r}; use one of m, cm, mm") from None
    return value * factor


def angle_to_rad(value: _T, unit: str) -> _T:
    """Convert an angle from ``unit`` (``rad`` or ``deg``) to radians."""
    try:
        factor = ANGLE_UNITS[unit]
    except KeyError:
        raise ValueError(f"unknown angle unit {unit!r}; use rad or deg") from None
    return value * factor


def wrap_angle(angle: _T) -> _T:
    """Wrap an angle [rad] (or an array of them) into ``[-pi, pi)``."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def axle_poses(tracked: NDArray[np.float64], offset: tuple[float, float]) -> NDArray[np.float64]:
    """Poses of the axle centre from poses of a point fixed on the robot.

    Parameters
    ----------
    tracked : array, shape (n, 3)
        ``x, y`` [m] and heading [rad] of the tracked point (its heading is the robot's).
    offset : (float, float)
        Where the point sits in the robot frame [m]: ``d_x`` forward of the axle centre,
        ``d_y`` to its left.

    Returns
    -------
    array, shape (n, 3)
        ``x - cos(theta) d_x + sin(theta) d_y``, ``y - sin(theta) d_x - cos(theta) d_y``,
        ``theta``.
    """
    poses = np.array(tracked, dtype=np.float64)
    dx, dy = offset
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    poses[:, 0] -= c * dx - s * dy
    poses[:, 1] -= s * dx + c * dy
    return poses

"""Planar poses: composed, inverted, put in the frame of the first; yaw of a quaternion.

A planar pose is ``x, y`` [m] and a heading [rad] (``theta``, counter-clockwise from the
frame's ``x`` axis); arrays of them have shape (n, 3). Every layer that moves poses
between frames (the bag's transform chains, the runs' start frames, the independence
check of a ground truth) uses these, written once.
"""

from __future__ import annotations

import math
from typing import TypeVar, cast

import numpy as np

from umbmark.core.arrays import FloatArray

__all__ = ["compose", "invert", "quaternion_yaw", "relative_positions", "to_start_frame"]

_T = TypeVar("_T", float, FloatArray)


def quaternion_yaw(qx: _T, qy: _T, qz: _T, qw: _T) -> _T:
    """The yaw [rad] of a unit quaternion ``x, y, z, w`` (numbers or arrays of one shape):
    ``atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))``, the rotation about ``z`` of the
    Z-Y-X Euler angles. Normalize the quaternion first: the formula assumes unit length."""
    return cast("_T", np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz)))


def compose(a: FloatArray, b: FloatArray) -> FloatArray:
    """``a (+) b`` for planar poses, shape (n, 3): ``b``, given in the frames ``a``,
    expressed in ``a``'s parent frame."""
    c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
    return np.column_stack(
        [
            a[:, 0] + c * b[:, 0] - s * b[:, 1],
            a[:, 1] + s * b[:, 0] + c * b[:, 1],
            a[:, 2] + b[:, 2],
        ]
    )


def invert(a: FloatArray) -> FloatArray:
    """The inverse of planar poses, shape (n, 3): ``compose(a, invert(a))`` is zero."""
    c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
    return np.column_stack([-(c * a[:, 0] + s * a[:, 1]), s * a[:, 0] - c * a[:, 1], -a[:, 2]])


def relative_positions(positions: FloatArray, heading: float) -> FloatArray:
    """Positions, shape (n, 2) (or the ``x, y`` of poses, shape (n, 3)), relative to the
    first one and seen from axes turned by ``heading`` [rad], shape (n, 2)."""
    c, s = math.cos(heading), math.sin(heading)
    dx, dy = positions[:, 0] - positions[0, 0], positions[:, 1] - positions[0, 1]
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy])


def to_start_frame(poses: FloatArray) -> FloatArray:
    """Express poses, shape (n, 3), in the frame of the first one (x along its heading)."""
    th0 = float(poses[0, 2])
    return np.column_stack([relative_positions(poses, th0), poses[:, 2] - th0])

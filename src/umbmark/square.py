"""Geometry of the square path with Type A and Type B errors (Sec. 4.1), exactly and linearized.

The robot's odometry believes it drives four straight legs of length ``L`` and turns
on the spot by 90 degrees after each, the fourth turn included (Sec. 5). In truth each
leg is a circular arc of length ``L`` that turns the robot by ``beta`` (left positive),
and each turn falls short of 90 degrees by ``alpha``. With unequal wheels an on-the-spot
turn also moves the axle centre sideways (Sec. 2.3): the centre circles the
instantaneous centre of rotation, which sits ``y_icr = (b/2)(E_d - 1)/(E_d + 1)`` to the
left of it.

:func:`square_end_pose` computes the end pose exactly (no small-angle approximation);
:func:`linear_end_position` is the paper's first-order result, Eqs. 4.17-4.18 and their
y counterparts (see ``paper-notes.md``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .conventions import Direction

__all__ = ["icr_offset", "linear_end_position", "square_end_pose"]

FloatArray = NDArray[np.float64]


def icr_offset(E_d: ArrayLike, wheelbase: float) -> FloatArray:
    """Lateral offset [m] of the on-the-spot turn's centre of rotation (Sec. 2.3, Fig. 2).

    Positive to the robot's left. Zero for equal wheels.
    """
    e = np.asarray(E_d, dtype=np.float64)
    return np.asarray(0.5 * wheelbase * (e - 1.0) / (e + 1.0), dtype=np.float64)


def square_end_pose(
    alpha: ArrayLike,
    beta: ArrayLike,
    side_length: float,
    direction: Direction,
    *,
    turn_offset: ArrayLike = 0.0,
) -> FloatArray:
    """Exact end pose of a square run whose odometry believes it returned to the start.

    Parameters
    ----------
    alpha : array, shape (...)
        Type A error per turn [rad]: each turn falls short of 90 degrees by ``alpha``.
    beta : array, shape (...)
        Type B error per leg [rad]: heading gained along each leg (left positive).
    side_length : float
        ``L`` [m], the arc length of each leg.
    direction : Direction
    turn_offset : array, shape (...), optional
        Lateral offset of the turning centre, see :func:`icr_offset` [m].

    Returns
    -------
    pose : array, shape (..., 3)
        True ``x, y`` [m] and the heading error ``theta - theta_odometry`` [rad] at the end.
    """
    a, b, d = np.broadcast_arrays(
        np.asarray(alpha, dtype=np.float64),
        np.asarray(beta, dtype=np.float64),
        np.asarray(turn_offset, dtype=np.float64),
    )
    sign = direction.turn_sign
    turn = sign * (0.5 * np.pi - a)
    chord = side_length * np.sinc(b / (2.0 * np.pi))  # 2 (L/b) sin(b/2), exact at b = 0
    x = np.zeros_like(a)
    y = np.zeros_like(a)
    theta = np.zeros_like(a)
    for _ in range(4):
        heading = theta + 0.5 * b
        x = x + chord * np.cos(heading)
        y = y + chord * np.sin(heading)
        theta = theta + b
        # On-the-spot turn about a centre d to the left: the axle centre moves by
        # R(theta) @ (d sin(turn), d (1 - cos(turn))).
        dx_body = d * np.sin(turn)
        dy_body = d * (1.0 - np.cos(turn))
        x = x + np.cos(theta) * dx_body - np.sin(theta) * dy_body
        y = y + np.sin(theta) * dx_body + np.cos(theta) * dy_body
        theta = theta + turn
    heading_error = theta - sign * 2.0 * np.pi
    return np.stack([x, y, heading_error], axis=-1)


def linear_end_position(
    alpha: ArrayLike, beta: ArrayLike, side_length: float, direction: Direction
) -> FloatArray:
    """First-order end position (Eqs. 4.17, 4.18 and their y counterparts).

    ``cw: (-2L(alpha + beta), -2L(alpha + beta))``,
    ``ccw: (-2L(alpha - beta), +2L(alpha - beta))``.

    Returns
    -------
    position : array, shape (..., 2)
        ``x, y`` [m].
    """
    a = np.asarray(alpha, dtype=np.float64)
    b = np.asarray(beta, dtype=np.float64)
    two_l = 2.0 * side_length
    if direction is Direction.CW:
        x = -two_l * (a + b)
        y = -two_l * (a + b)
    else:
        x = -two_l * (a - b)
        y = two_l * (a - b)
    return np.stack(np.broadcast_arrays(x, y), axis=-1)

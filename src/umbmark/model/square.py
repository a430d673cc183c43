"""Geometry of the square path with Type A and Type B errors (Sec. 4.1), exactly and linearized.

The robot's odometry believes it drives four straight legs of length ``L`` and turns
on the spot by 90 degrees after each, the fourth turn included (Sec. 5). In truth each
leg is a circular arc of length ``L`` that turns the robot by ``beta`` (left positive),
and each turn falls short of 90 degrees by ``alpha``. With unequal wheels an on-the-spot
turn also moves the axle centre sideways (Sec. 2.3): the centre circles the
instantaneous centre of rotation, which sits ``y_icr = (b/2)(E_d - 1)/(E_d + 1)`` to the
left of it.

:func:`square_end_pose` computes the end pose exactly (no small-angle approximation).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from umbmark.core.arrays import FloatArray
from umbmark.core.conventions import Direction

__all__ = ["icr_offset", "square_end_pose", "square_run_end"]


def icr_offset(E_d: ArrayLike, wheelbase: ArrayLike) -> FloatArray:
    """Lateral offset [m] of the on-the-spot turn's centre of rotation (Sec. 2.3, Fig. 2).

    Positive to the robot's left. Zero for equal wheels.
    """
    e = np.asarray(E_d, dtype=np.float64)
    b = np.asarray(wheelbase, dtype=np.float64)
    return np.asarray(0.5 * b * (e - 1.0) / (e + 1.0), dtype=np.float64)


def square_end_pose(
    alpha: ArrayLike,
    beta: ArrayLike,
    side_length: float,
    direction: Direction,
    *,
    turn_offset: ArrayLike = 0.0,
    leg_length: ArrayLike | None = None,
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
    leg_length : array, shape (...), optional
        The legs' true arc length [m], when it differs from ``side_length`` (a scale
        error ``E_s``).

    Returns
    -------
    pose : array, shape (..., 3)
        True ``x, y`` [m] and the heading error ``theta - theta_odometry`` [rad] at the end.
    """
    arrays = [np.asarray(v, dtype=np.float64) for v in (alpha, beta, turn_offset)]
    if leg_length is not None:
        arrays.append(np.asarray(leg_length, dtype=np.float64))
    if all(v.ndim == 0 for v in arrays):  # one robot: plain floats are ten times faster
        leg = float(arrays[3]) if leg_length is not None else side_length
        return np.array(
            _square_end(float(arrays[0]), float(arrays[1]), float(arrays[2]), leg, direction)
        )
    a, b, d = np.broadcast_arrays(*arrays[:3])
    sign = direction.turn_sign
    turn = sign * (0.5 * np.pi - a)
    arc = side_length if leg_length is None else np.asarray(leg_length, dtype=np.float64)
    chord = arc * np.sinc(b / (2.0 * np.pi))  # 2 (L/b) sin(b/2), exact at b = 0
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


def _square_end(
    alpha: float, beta: float, offset: float, leg: float, direction: Direction
) -> tuple[float, float, float]:
    """:func:`square_end_pose` for one robot, in plain floats (the same steps)."""
    sign = direction.turn_sign
    turn = sign * (0.5 * math.pi - alpha)
    half = 0.5 * beta
    chord = leg * (math.sin(half) / half if half != 0.0 else 1.0)
    dx_body = offset * math.sin(turn)
    dy_body = offset * (1.0 - math.cos(turn))
    x = y = theta = 0.0
    for _ in range(4):
        heading = theta + half
        x += chord * math.cos(heading)
        y += chord * math.sin(heading)
        theta += beta
        c, s = math.cos(theta), math.sin(theta)
        x += c * dx_body - s * dy_body
        y += s * dx_body + c * dy_body
        theta += turn
    return x, y, theta - sign * 2.0 * math.pi


def square_run_end(
    E_d: ArrayLike,
    E_b: ArrayLike,
    E_s: ArrayLike,
    side_length: float,
    wheelbase: float,
    direction: Direction,
) -> FloatArray:
    """Exact end of a square run of a robot with errors relative to its own odometry.

    The odometry believes it drives legs of ``side_length`` and on-the-spot turns of 90
    degrees. The wheels' true travel per odometry metre is ``k_L = 2 E_s / (E_d + 1)`` and
    ``k_R = E_d k_L``, the true wheelbase ``E_b * wheelbase``. So each leg is an arc of
    length ``E_s L`` turning by ``beta = L (k_R - k_L) / (E_b b)``, each turn falls short by
    ``alpha = (pi/2)(1 - E_s / E_b)``, and turns about the point of
    :func:`icr_offset` (Sec. 2.3).

    Parameters
    ----------
    E_d, E_b, E_s : array, shape (...)
        ``D_R / D_L``, ``b_actual / b`` and ``D_avg / D_odometry``.
    side_length, wheelbase : float
        ``L`` and the odometry's ``b`` [m].
    direction : Direction

    Returns
    -------
    pose : array, shape (..., 3)
        True ``x, y`` [m] and heading error [rad] at the end (see :func:`square_end_pose`).
    """
    if all(np.ndim(v) == 0 for v in (E_d, E_b, E_s)):  # one robot: plain floats
        ed, eb, es = float(E_d), float(E_b), float(E_s)  # type: ignore[arg-type]
        k = 2.0 * es / (ed + 1.0)
        b_true = eb * wheelbase
        return np.array(
            _square_end(
                0.5 * math.pi * (1.0 - es / eb),
                side_length * (ed - 1.0) * k / b_true,
                0.5 * b_true * (ed - 1.0) / (ed + 1.0),
                side_length * es,
                direction,
            )
        )
    e_d = np.asarray(E_d, dtype=np.float64)
    e_b = np.asarray(E_b, dtype=np.float64)
    e_s = np.asarray(E_s, dtype=np.float64)
    k_left = 2.0 * e_s / (e_d + 1.0)
    true_b = e_b * wheelbase
    beta = side_length * (e_d - 1.0) * k_left / true_b
    alpha = 0.5 * np.pi * (1.0 - e_s / e_b)
    return square_end_pose(
        alpha,
        beta,
        side_length,
        direction,
        turn_offset=icr_offset(e_d, true_b),
        leg_length=side_length * e_s,
    )

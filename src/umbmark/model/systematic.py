"""The systematic error model: E_d, E_b, alpha, beta and the correction factors.

Definitions (Sec. 2.2)
    ``E_d = D_R / D_L`` (Eq. 2.3), ``E_b = b_actual / b_nominal`` (Eq. 2.4),
    ``E_s = D_avg / D_n`` (the scale error, assumed corrected beforehand).
Type A error ``alpha`` [rad]
    Shortfall of each nominal 90 degree turn; ``E_b = 90 / (90 - alpha)`` (Eq. 4.27,
    with angles in degrees; here in radians, ``(pi/2) / (pi/2 - alpha)``).
Type B error ``beta`` [rad]
    Heading gained along each leg; its radius of curvature
    ``R = (L/2) / sin(beta/2)`` (Eq. 4.21) and ``E_d = (R + b/2) / (R - b/2)`` (Eq. 4.22).
Correction (Sec. 4.2)
    ``c_L = 2 / (E_d + 1)`` (4.31), ``c_R = 2 / (1/E_d + 1)`` (4.32), ``b_new = E_b b`` (4.26).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from umbmark.core.arrays import FloatArray

__all__ = [
    "E_b_from_alpha",
    "E_d_from_beta",
    "E_d_from_beta_arc",
    "alpha_from_E_b",
    "beta_from_E_d",
    "correction_factors",
]

HALF_PI = 0.5 * np.pi


def E_b_from_alpha(alpha: ArrayLike) -> FloatArray:
    """``E_b = (pi/2) / (pi/2 - alpha)``, Eq. 4.27 (``alpha`` in radians)."""
    return np.asarray(HALF_PI / (HALF_PI - np.asarray(alpha, dtype=np.float64)))


def alpha_from_E_b(E_b: ArrayLike, E_s: ArrayLike = 1.0) -> FloatArray:
    """Type A error [rad] of a robot with wheelbase error ``E_b`` and scale error ``E_s``.

    An on-the-spot turn that the odometry counts as 90 degrees really turns by
    ``90 E_s / E_b`` (Eq. 2.13 with Eq. 2.4), so ``alpha = (pi/2)(1 - E_s / E_b)``.
    """
    return np.asarray(
        HALF_PI * (1.0 - np.asarray(E_s, dtype=np.float64) / np.asarray(E_b, dtype=np.float64))
    )


def E_d_from_beta(beta: ArrayLike, side_length: float, wheelbase: float) -> FloatArray:
    """``E_d`` from ``beta`` [rad] as printed: Eqs. 4.21 and 4.22, chord ``L``, nominal ``b``.

    Written as ``(L + b sin(beta/2)) / (L - b sin(beta/2))``, which equals
    ``(R + b/2) / (R - b/2)`` with ``R = (L/2) / sin(beta/2)`` and gives exactly 1 at
    ``beta = 0``, where ``R`` is infinite.
    """
    s = wheelbase * np.sin(0.5 * np.asarray(beta, dtype=np.float64))
    return np.asarray((side_length + s) / (side_length - s))


def E_d_from_beta_arc(beta: ArrayLike, side_length: float, wheelbase: float) -> FloatArray:
    """``E_d`` from ``beta`` [rad] for a leg that is an arc of length ``L``.

    Over the leg the wheels travel ``L +- beta b / 2`` for a wheelbase ``b`` (pass the
    actual one, ``E_b b``), so ``E_d = (2L + beta b) / (2L - beta b)``.
    """
    s = 0.5 * wheelbase * np.asarray(beta, dtype=np.float64)
    return np.asarray((side_length + s) / (side_length - s))


def beta_from_E_d(E_d: ArrayLike, side_length: float, wheelbase: float) -> FloatArray:
    """Type B error [rad] per leg of arc length ``L`` for a robot with ``E_d``.

    Inverse of :func:`E_d_from_beta_arc`: ``beta = (2L / b)(E_d - 1)/(E_d + 1)``, with
    ``b`` the actual wheelbase.
    """
    e = np.asarray(E_d, dtype=np.float64)
    return np.asarray(2.0 * side_length / wheelbase * (e - 1.0) / (e + 1.0))


def correction_factors(E_d: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Wheel correction factors ``(c_L, c_R)``, Eqs. 4.31 and 4.32.

    They keep the average diameter: ``(c_L + c_R) / 2 = 1``, and ``c_R / c_L = E_d``.
    """
    e = np.asarray(E_d, dtype=np.float64)
    return np.asarray(2.0 / (e + 1.0)), np.asarray(2.0 / (1.0 / e + 1.0))

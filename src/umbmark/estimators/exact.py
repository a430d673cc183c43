"""Inversion of the exact square geometry: no small-angle approximation.

The paper linearizes the square path (Eqs. 4.1-4.18), which loses accuracy as the errors
grow (later work; ``paper-notes.md``). This estimator instead finds the ``alpha`` and
``beta`` whose exact end positions (:func:`umbmark.square.square_end_pose`, legs as arcs
of length ``L``, the on-the-spot turns' sideways shift of Sec. 2.3 included) best match
both centres of gravity in the least-squares sense, starting from the paper's estimate.
``E_b`` then follows exactly from ``alpha`` (Eq. 4.27) and ``E_d`` from ``beta`` for an arc
of length ``L`` and the actual wheelbase ``E_b b``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from ..benchmark import Benchmark
from ..conventions import Direction
from ..model import E_b_from_alpha, E_d_from_beta_arc
from ..square import icr_offset, square_end_pose
from .base import ErrorEstimate, FloatArray, SquareTest, cg_vector, propagate
from .formulas import paper_components

__all__ = ["exact_components", "exact_end_positions", "exact_estimate"]


def exact_end_positions(alpha: float, beta: float, test: SquareTest) -> FloatArray:
    """``(x_cw, y_cw, x_ccw, y_ccw)`` [m] of a robot with errors ``alpha``, ``beta`` [rad]."""
    actual_b = float(E_b_from_alpha(alpha)) * test.wheelbase
    E_d = E_d_from_beta_arc(beta, test.side_length, actual_b)
    offset = icr_offset(E_d, actual_b)
    return np.concatenate(
        [
            square_end_pose(alpha, beta, test.side_length, d, turn_offset=offset)[:2]
            for d in (Direction.CW, Direction.CCW)
        ]
    )


def exact_components(z: FloatArray, test: SquareTest) -> dict[str, float]:
    """Solve the exact geometry for ``alpha``, ``beta`` given ``z = (x_cw, y_cw, x_ccw, y_ccw)``."""
    start = paper_components(z, test)
    guess = np.array([start["alpha"], start["beta"]])
    scale = test.side_length

    def residuals(p: FloatArray) -> FloatArray:
        return (exact_end_positions(float(p[0]), float(p[1]), test) - z) / scale

    fit = least_squares(residuals, guess, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    alpha, beta = (float(v) for v in fit.x)
    E_b = float(E_b_from_alpha(alpha))
    return {
        "alpha": alpha,
        "beta": beta,
        "E_b": E_b,
        "E_d": float(E_d_from_beta_arc(beta, test.side_length, E_b * test.wheelbase)),
        "residual_rms": float(np.sqrt(np.mean(fit.fun**2)) * scale),
    }


def exact_estimate(bench: Benchmark, test: SquareTest) -> ErrorEstimate:
    """``alpha``, ``beta``, ``E_d``, ``E_b`` from the exact square geometry."""
    z, cov = cg_vector(bench)
    parts = exact_components(z, test)
    errors = propagate(lambda v: exact_components(v, test), z, cov)
    return ErrorEstimate(
        method="exact",
        alpha=parts["alpha"],
        beta=parts["beta"],
        E_d=parts["E_d"],
        E_b=parts["E_b"],
        components={"residual_rms": parts["residual_rms"]},
        standard_errors={k: errors[k] for k in ("alpha", "beta", "E_d", "E_b")},
    )

"""Inversion of the exact square geometry: no small-angle approximation.

The paper linearizes the square path (Eqs. 4.1-4.18), which loses accuracy as the errors
grow (later work; ``paper-notes.md``). This estimator instead finds the ``alpha`` and
``beta`` whose exact end positions (:func:`umbmark.square.square_end_pose`, legs as arcs
of length ``L``, the on-the-spot turns' sideways shift of Sec. 2.3 included) best match
both centres of gravity in the least-squares sense, starting from the paper's estimate.
``E_b`` then follows exactly from ``alpha`` (Eq. 4.27) and ``E_d`` from ``beta`` for an arc
of length ``L`` and the actual wheelbase ``E_b b``.

The fit has two unknowns and four smooth residuals, and starts at the first-order
solution: Gauss-Newton with a step-halving line search converges in a handful of steps,
to the last bits for noise-free centres. It is written out here rather than taken from
``scipy.optimize`` because the paper's method runs it on every calibration (for its
warnings), and importing ``scipy.optimize`` would cost three times the whole
calibration's run time. ``tests/test_paper_method.py`` checks it against
``scipy.optimize.least_squares``.
"""

from __future__ import annotations

import numpy as np

from ..benchmark import Benchmark
from ..conventions import Direction
from ..model import E_b_from_alpha, E_d_from_beta_arc
from ..square import icr_offset, square_end_pose
from .base import ErrorEstimate, FloatArray, SquareTest, cg_vector, propagate
from .formulas import paper_components

__all__ = ["exact_components", "exact_end_positions", "exact_estimate", "fit_exact_geometry"]


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


#: Gauss-Newton iterations at most; from the first-order start a handful are used.
_MAX_ITERATIONS = 60
#: Step [rad] of the central differences of the Jacobian: truncation (~step^2) and
#: rounding (~1e-16 / step) errors both stay near 1e-11.
_JACOBIAN_STEP = 1e-5


def fit_exact_geometry(z: FloatArray, test: SquareTest, start: FloatArray) -> FloatArray:
    """The ``(alpha, beta)`` [rad] whose exact end positions best match ``z``.

    Least squares on the residuals ``(exact_end_positions(alpha, beta) - z) / L``, shape
    (4,), by Gauss-Newton from ``start`` (shape (2,)). A step that clearly raises the
    residual is halved; iteration stops when the step falls to the last bits of the
    solution, so that the solution is a smooth function of ``z`` (the standard errors
    differentiate it).
    """

    def residuals(p: FloatArray) -> FloatArray:
        return (exact_end_positions(float(p[0]), float(p[1]), test) - z) / test.side_length

    p = np.asarray(start, dtype=np.float64).copy()
    r = residuals(p)
    cost = float(r @ r)
    for _ in range(_MAX_ITERATIONS):
        jac = np.empty((4, 2))
        for j in range(2):
            dp = np.zeros(2)
            dp[j] = _JACOBIAN_STEP
            jac[:, j] = (residuals(p + dp) - residuals(p - dp)) / (2.0 * _JACOBIAN_STEP)
        step = np.linalg.lstsq(jac, -r, rcond=None)[0]
        for _ in range(40):
            r_trial = residuals(p + step)
            cost_trial = float(r_trial @ r_trial)
            if cost_trial <= cost * (1.0 + 1e-9):
                break
            step = 0.5 * step
        p, r, cost = p + step, r_trial, cost_trial
        if float(np.max(np.abs(step))) <= 1e-15 * (1.0 + float(np.max(np.abs(p)))):
            break
    return np.asarray(p, dtype=np.float64)


def exact_components(z: FloatArray, test: SquareTest) -> dict[str, float]:
    """Solve the exact geometry for ``alpha``, ``beta`` given ``z = (x_cw, y_cw, x_ccw, y_ccw)``."""
    start = paper_components(z, test)
    alpha, beta = (
        float(v) for v in fit_exact_geometry(z, test, np.array([start["alpha"], start["beta"]]))
    )
    E_b = float(E_b_from_alpha(alpha))
    residual = exact_end_positions(alpha, beta, test) - z
    return {
        "alpha": alpha,
        "beta": beta,
        "E_b": E_b,
        "E_d": float(E_d_from_beta_arc(beta, test.side_length, E_b * test.wheelbase)),
        "residual_rms": float(np.sqrt(np.mean(residual**2))),
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

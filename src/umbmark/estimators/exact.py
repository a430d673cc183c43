"""Inversion of the exact square geometry: no small-angle approximation.

The paper linearizes the square path (Eqs. 4.1-4.18), which loses accuracy as the errors
grow (later work; ``paper-notes.md``). This estimator instead finds the ``alpha`` and
``beta`` whose exact end positions (:func:`umbmark.square.square_end_pose`, legs as arcs
of length ``L``, the on-the-spot turns' sideways shift of Sec. 2.3 included) best match
both centres of gravity in the least-squares sense, starting from the paper's estimate.
``E_b`` then follows exactly from ``alpha`` (Eq. 4.27) and ``E_d`` from ``beta`` for an arc
of length ``L`` and the actual wheelbase ``E_b b``.

The fit (:mod:`umbmark.estimators.solve`) has two unknowns and four smooth residuals.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..benchmark import Benchmark
from ..conventions import Direction
from ..model import E_b_from_alpha, E_d_from_beta_arc
from ..runs import Run
from ..square import icr_offset, square_end_pose
from .base import ErrorEstimate, FloatArray, SquareTest, cg_blocks, propagate_blocks
from .formulas import paper_components
from .solve import gauss_newton, jacobian

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


def fit_exact_geometry(z: FloatArray, test: SquareTest, start: FloatArray) -> FloatArray:
    """The ``(alpha, beta)`` [rad] whose exact end positions best match ``z``.

    Least squares on the residuals ``(exact_end_positions(alpha, beta) - z) / L``, shape
    (4,), from ``start`` (shape (2,)); see :func:`umbmark.estimators.solve.gauss_newton`.
    """

    def residuals(p: FloatArray) -> FloatArray:
        return (exact_end_positions(float(p[0]), float(p[1]), test) - z) / test.side_length

    return gauss_newton(residuals, start)[0]


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


def _errors_of(angles: FloatArray, test: SquareTest) -> dict[str, float]:
    """``alpha``, ``beta``, ``E_b`` (Eq. 4.27) and ``E_d`` (an arc with ``E_b b``)."""
    alpha, beta = float(angles[0]), float(angles[1])
    E_b = float(E_b_from_alpha(alpha))
    E_d = float(E_d_from_beta_arc(beta, test.side_length, E_b * test.wheelbase))
    return {"alpha": alpha, "beta": beta, "E_b": E_b, "E_d": E_d}


def exact_estimate(
    bench: Benchmark, test: SquareTest, runs: Sequence[Run] | None = None
) -> ErrorEstimate:
    """``alpha``, ``beta``, ``E_d``, ``E_b`` from the exact square geometry.

    With ``runs`` (the same runs) the model check of
    :func:`umbmark.estimators.checks.model_warnings` is made.
    """
    from .checks import model_warnings

    z, blocks = cg_blocks(bench)
    parts = exact_components(z, test)
    # The fit's response to the centres, by the implicit function theorem at the solution
    # (Gauss-Newton's linearization): d(alpha, beta)/dz = (J^T J)^-1 J^T, J = d(ends)/d(a, b).
    angles = np.array([parts["alpha"], parts["beta"]])
    jac = jacobian(lambda p: exact_end_positions(float(p[0]), float(p[1]), test), angles)
    response = np.linalg.solve(jac.T @ jac, jac.T)
    errors, dofs = propagate_blocks(
        lambda v: _errors_of(angles + response @ (v - z), test), z, blocks, step=1e-7
    )
    return ErrorEstimate(
        method="exact",
        alpha=parts["alpha"],
        beta=parts["beta"],
        E_d=parts["E_d"],
        E_b=parts["E_b"],
        components={"residual_rms": parts["residual_rms"]},
        standard_errors={k: errors[k] for k in ("alpha", "beta", "E_d", "E_b")},
        warnings=() if runs is None else tuple(model_warnings(bench, runs, test)),
        dof={k: dofs[k] for k in ("alpha", "beta", "E_d", "E_b")},
    )

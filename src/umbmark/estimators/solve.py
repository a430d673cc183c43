"""A small least-squares solver for the estimators' fits of a few smooth parameters.

The square-path fits have two or three unknowns and a handful of smooth residuals, and
start at the first-order solution: damped Gauss-Newton (Levenberg-Marquardt) converges in
a few steps, to the last bits for noise-free data. It is written out here rather than
taken from ``scipy.optimize`` because the default estimators run it on every calibration,
and importing ``scipy.optimize`` costs three times a whole calibration.
``tests/estimators/test_paper.py`` checks it against ``scipy.optimize.least_squares``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from umbmark.core.arrays import FloatArray

__all__ = ["JACOBIAN_STEP", "gauss_newton", "jacobian", "relative_jacobian"]

#: Gauss-Newton iterations at most.
MAX_ITERATIONS = 60
#: Step of the central differences of the Jacobian (parameters of order one or
#: radians): truncation (~step^2) and rounding (~1e-16 / step) errors both stay near 1e-11.
JACOBIAN_STEP = 1e-5


def jacobian(
    residuals: Callable[[FloatArray], FloatArray], p: FloatArray, step: float = JACOBIAN_STEP
) -> FloatArray:
    """Central-difference Jacobian of ``residuals`` at ``p``, shape (m, len(p))."""
    columns = []
    for j in range(p.size):
        dp = np.zeros(p.size)
        dp[j] = step
        columns.append((residuals(p + dp) - residuals(p - dp)) / (2.0 * step))
    return np.column_stack(columns)


def relative_jacobian(model: Callable[[FloatArray], FloatArray], p: FloatArray) -> FloatArray:
    """Central-difference Jacobian of ``model`` at ``p`` for parameters of any scale (radii
    of centimetres, wheelbases, angles): each step ``1e-6`` of its parameter (``1e-9`` at
    least). ``model`` returns an array of any shape ``s``; the result is ``(*s, len(p))``."""
    columns = []
    for j in range(p.size):
        step = 1e-6 * max(abs(float(p[j])), 1e-3)
        up, down = p.copy(), p.copy()
        up[j] += step
        down[j] -= step
        columns.append((model(up) - model(down)) / (2.0 * step))
    return np.stack(columns, axis=-1)


def gauss_newton(
    residuals: Callable[[FloatArray], FloatArray], start: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Minimize ``|residuals(p)|^2`` from ``start``.

    Gauss-Newton steps, damped as Levenberg and Marquardt do where the problem is nearly
    singular (the damping grows tenfold while a step raises the residual, and shrinks
    after each step that lowers it); iteration stops when the step falls below ``1e-13``
    of the solution, or stalls at rounding level (``1e-11``) without shrinking.

    Returns
    -------
    p : array, shape (k,)
        The solution.
    r : array, shape (m,)
        The residuals there.
    jac : array, shape (m, k)
        Their Jacobian there.
    """
    p = np.asarray(start, dtype=np.float64).copy()
    r = residuals(p)
    cost = float(r @ r)
    jac = jacobian(residuals, p)
    damping = 1e-6
    previous = np.inf
    for _ in range(MAX_ITERATIONS):
        normal = jac.T @ jac
        gradient = jac.T @ r
        scale = np.diag(np.diag(normal)) + 1e-300 * np.eye(p.size)
        while True:
            try:
                step = np.linalg.solve(normal + damping * scale, -gradient)
            except np.linalg.LinAlgError:
                step = np.linalg.lstsq(normal + damping * scale, -gradient, rcond=None)[0]
            r_trial = residuals(p + step)
            cost_trial = float(r_trial @ r_trial)
            if cost_trial <= cost * (1.0 + 1e-9):
                damping = max(damping / 10.0, 1e-12)
                break
            damping *= 10.0
            if damping > 1e12:
                return p, r, jac  # no step lowers the residual: converged
        p, r, cost = p + step, r_trial, cost_trial
        jac = jacobian(residuals, p)
        size = float(np.max(np.abs(step))) / (1.0 + float(np.max(np.abs(p))))
        if size <= 1e-13 or (size <= 1e-11 and size > 0.5 * previous):
            break
        previous = size
    return p, r, jac

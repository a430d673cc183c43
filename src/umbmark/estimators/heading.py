"""Estimate from the final heading errors (Jung & Chung, IJARS 2011).

A cw run ends with ``eps_theta,cw = 4 alpha + 4 beta`` and a ccw run with
``eps_theta,ccw = -4 alpha + 4 beta`` (four turns, four legs; exact, no small-angle
approximation), so ``alpha = (eps_cw - eps_ccw) / 8`` and ``beta = (eps_cw + eps_ccw) / 8``.
``E_b`` and ``E_d`` then follow by Eqs. 4.27 and 4.21-4.22, as in the paper's method.
Needs ``theta_abs`` and ``theta_odo`` for every run.
"""

from __future__ import annotations

import numpy as np

from ..benchmark import Benchmark
from ..model import E_b_from_alpha, E_d_from_beta
from ..runs import Run, split_by_direction
from .base import ErrorEstimate, FloatArray, SquareTest, propagate

__all__ = ["heading_components", "heading_estimate"]


def heading_components(m: FloatArray, test: SquareTest) -> dict[str, float]:
    """Figures from ``m = (mean eps_theta,cw, mean eps_theta,ccw)`` [rad]."""
    cw, ccw = float(m[0]), float(m[1])
    alpha = (cw - ccw) / 8.0
    beta = (cw + ccw) / 8.0
    return {
        "alpha": alpha,
        "beta": beta,
        "E_b": float(E_b_from_alpha(alpha)),
        "E_d": float(E_d_from_beta(beta, test.side_length, test.wheelbase)),
        "eps_theta_cw": cw,
        "eps_theta_ccw": ccw,
    }


def heading_estimate(bench: Benchmark, runs: list[Run], test: SquareTest) -> ErrorEstimate:
    """Jung & Chung's estimate from the runs' heading errors.

    Raises
    ------
    ValueError
        If a run has no headings.
    """
    del bench  # the heading method does not use the position clusters
    means = []
    variances = []
    for direction, group in split_by_direction(runs).items():
        headings = [run.heading_error for run in group]
        missing = [
            run.label or "a run" for run, e in zip(group, headings, strict=True) if e is None
        ]
        if missing:
            raise ValueError(
                f"the heading method needs theta_abs and theta_odo; missing for {missing[0]}"
            )
        values = np.array(headings, dtype=np.float64)
        if len(values) < 2:
            raise ValueError(f"fewer than 2 {direction.value} runs")
        means.append(values.mean())
        variances.append(values.var(ddof=1) / len(values))
    m = np.array(means)
    parts = heading_components(m, test)
    errors = propagate(lambda v: heading_components(v, test), m, np.diag(variances), step=1e-7)
    return ErrorEstimate(
        method="heading",
        alpha=parts["alpha"],
        beta=parts["beta"],
        E_d=parts["E_d"],
        E_b=parts["E_b"],
        components={k: parts[k] for k in ("eps_theta_cw", "eps_theta_ccw")},
        standard_errors={k: errors[k] for k in ("alpha", "beta", "E_d", "E_b")},
    )

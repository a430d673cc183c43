"""Estimate from the final heading errors (Jung & Chung, IJARS 2011).

A cw run ends with ``eps_theta,cw = 4 alpha + 4 beta`` and a ccw run with
``eps_theta,ccw = -4 alpha + 4 beta`` (four turns, four legs; exact, no small-angle
approximation), so ``alpha = (eps_cw - eps_ccw) / 8`` and ``beta = (eps_cw + eps_ccw) / 8``.
``E_b`` then follows by Eq. 4.27, and ``E_d`` from ``beta`` for a leg that is an arc of
length ``L`` driven with the actual wheelbase ``E_b b`` (as the exact method does; the
paper's Eqs. 4.21-4.22 with the nominal wheelbase would be off by about ``E_b - 1``).
Needs ``theta_abs`` and ``theta_odo`` for every run. Heading errors are known only up to
whole turns: they are unwrapped to the turns the positions say
(:func:`umbmark.estimators.endpose.heading_errors`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.conventions import Direction
from umbmark.estimators.base import ErrorEstimate, SquareTest, propagate_blocks
from umbmark.estimators.endpose import heading_errors
from umbmark.estimators.registry import HEADING
from umbmark.model.run import Run
from umbmark.model.systematic import E_b_from_alpha, E_d_from_beta_arc
from umbmark.returns.clusters import Benchmark

__all__ = ["heading_components", "heading_estimate"]


def heading_components(m: FloatArray, test: SquareTest) -> dict[str, float]:
    """Figures from ``m = (mean eps_theta,cw, mean eps_theta,ccw)`` [rad]."""
    cw, ccw = float(m[0]), float(m[1])
    alpha = (cw - ccw) / 8.0
    beta = (cw + ccw) / 8.0
    E_b = float(E_b_from_alpha(alpha))
    return {
        "alpha": alpha,
        "beta": beta,
        "E_b": E_b,
        "E_d": float(E_d_from_beta_arc(beta, test.side_length, E_b * test.wheelbase)),
        "eps_theta_cw": cw,
        "eps_theta_ccw": ccw,
    }


def heading_estimate(bench: Benchmark, runs: Sequence[Run], test: SquareTest) -> ErrorEstimate:
    """Jung & Chung's estimate from the runs' heading errors (the positions only check it).

    Raises
    ------
    ValueError
        If a run has no headings.
    """
    missing = [run.label or "a run" for run in runs if run.heading_error is None]
    if missing:
        raise ValueError(
            f"the heading method needs theta_abs and theta_odo; missing for {missing[0]}"
        )
    unwrapped = heading_errors(bench, runs, test)
    assert unwrapped is not None
    means = []
    variances = []
    counts = []
    for direction in (Direction.CW, Direction.CCW):
        values = unwrapped[direction]
        if len(values) < 2:
            raise ValueError(f"fewer than 2 {direction.value} runs")
        means.append(values.mean())
        variances.append(values.var(ddof=1) / len(values))
        counts.append(len(values))
    m = np.array(means)
    parts = heading_components(m, test)
    blocks = [(np.array([[v]]), float(n - 1)) for v, n in zip(variances, counts, strict=True)]
    errors, dofs = propagate_blocks(lambda v: heading_components(v, test), m, blocks, step=1e-7)
    return ErrorEstimate(
        method=HEADING.name,
        alpha=parts["alpha"],
        beta=parts["beta"],
        E_d=parts["E_d"],
        E_b=parts["E_b"],
        components={k: parts[k] for k in ("eps_theta_cw", "eps_theta_ccw")},
        standard_errors={k: errors[k] for k in ("alpha", "beta", "E_d", "E_b")},
        dof={k: dofs[k] for k in ("alpha", "beta", "E_d", "E_b")},
    )

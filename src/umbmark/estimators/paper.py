"""The paper's correction, exactly as printed (Sec. 4, Eqs. 4.17-4.27).

The equations are in :mod:`umbmark.estimators.formulas`. As in the paper's experiments
(Sec. 5, footnote 2), ``E_d`` and ``E_b`` are computed from x and from y and the two
averaged. The reported ``alpha`` and ``beta`` are the averages of their x and y estimates.

Errors so large that the small-angle formulas misjudge them are reported as a warning,
never as an error. (Runs that one robot of the model does not explain, x- and y-based
estimates that differ by more than the spread of the runs and the exact geometry explain,
get the model check's warning: :mod:`umbmark.estimators.diagnostics`.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from umbmark.estimators.base import ErrorEstimate, SquareTest, cg_blocks, propagate_blocks
from umbmark.estimators.exact import exact_end_positions
from umbmark.estimators.formulas import paper_components
from umbmark.estimators.registry import PAPER
from umbmark.model.run import Run
from umbmark.returns.clusters import Benchmark

__all__ = ["SMALL_ANGLE_TOLERANCE", "exact_view", "paper_estimate", "small_angle_shortfall"]

#: Relative error of the small-angle inversion above which a warning is given.
SMALL_ANGLE_TOLERANCE = 0.10


def exact_view(alpha: float, beta: float, test: SquareTest) -> dict[str, float]:
    """What the paper's formulas see of a robot with errors ``alpha`` and ``beta`` [rad].

    The centres come from the exact square geometry
    (:func:`umbmark.model.square.square_end_pose`), without small-angle approximations.
    """
    return paper_components(exact_end_positions(alpha, beta, test), test)


def small_angle_shortfall(alpha: float, beta: float, test: SquareTest) -> float:
    """How far the small-angle inversion is off for errors of this size (relative).

    The paper's x-based and y-based inversions of the exact centres of a robot with
    ``alpha`` and ``beta`` are compared with the truth; the worse of the two is returned
    as ``|(alpha - alpha', beta - beta')| / |(alpha, beta)|``.
    """
    size = math.hypot(alpha, beta)
    if size == 0.0:
        return 0.0
    seen = exact_view(alpha, beta, test)
    return max(
        math.hypot(alpha - seen[f"alpha_{axis}"], beta - seen[f"beta_{axis}"]) / size
        for axis in ("x", "y")
    )


def paper_estimate(
    bench: Benchmark, test: SquareTest, runs: Sequence[Run] | None = None
) -> ErrorEstimate:
    """The paper's estimate of ``alpha``, ``beta``, ``E_d`` and ``E_b`` (Sec. 4).

    ``runs`` are not used: the centres of gravity are all the equations need (the
    dispatch gives every square estimator the runs).
    """
    z, blocks = cg_blocks(bench)
    parts = paper_components(z, test)
    errors, dofs = propagate_blocks(lambda v: paper_components(v, test), z, blocks)
    warnings: list[str] = []
    shortfall = small_angle_shortfall(parts["alpha"], parts["beta"], test)
    if shortfall > SMALL_ANGLE_TOLERANCE:
        warnings.append(
            f"errors this large (alpha = {math.degrees(parts['alpha']):.2f} deg, "
            f"beta = {math.degrees(parts['beta']):.2f} deg) stretch the small-angle "
            f"formulas (Eqs. 4.17-4.24): the x- and y-based estimates are each off by up "
            f"to {100 * shortfall:.0f} %; apply this correction and run a second pass, "
            "or use --method endpose or exact"
        )
    return ErrorEstimate(
        method=PAPER.name,
        alpha=parts["alpha"],
        beta=parts["beta"],
        E_d=parts["E_d"],
        E_b=parts["E_b"],
        components={k: v for k, v in parts.items() if not k.endswith("_minus_y")},
        standard_errors={k: errors[k] for k in ("alpha", "beta", "E_d", "E_b")},
        warnings=tuple(warnings),
        dof={k: dofs[k] for k in ("alpha", "beta", "E_d", "E_b")},
    )

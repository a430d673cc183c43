"""The paper's correction, exactly as printed (Sec. 4, Eqs. 4.17-4.27).

The equations are in :mod:`umbmark.estimators.formulas`. As in the paper's experiments
(Sec. 5, footnote 2), ``E_d`` and ``E_b`` are computed from x and from y and the two
averaged. The reported ``alpha`` and ``beta`` are the averages of their x and y estimates.

Two doubts are reported as warnings, never as errors: x- and y-based estimates that
differ by more than the spread of the runs and the exact geometry explain, and errors so
large that the small-angle formulas misjudge them.
"""

from __future__ import annotations

import math

from ..benchmark import Benchmark
from .base import ErrorEstimate, SquareTest, cg_vector, propagate
from .exact import exact_components, exact_end_positions
from .formulas import paper_components

__all__ = [
    "DISAGREEMENT_TOLERANCE",
    "SMALL_ANGLE_TOLERANCE",
    "exact_view",
    "paper_estimate",
    "small_angle_shortfall",
]

#: x and y estimates may differ by this much of the cluster centres [m] (tape-measure
#: resolution) before the spread is consulted.
DISAGREEMENT_TOLERANCE = 0.002
#: Relative error of the small-angle inversion above which a warning is given.
SMALL_ANGLE_TOLERANCE = 0.10


def exact_view(alpha: float, beta: float, test: SquareTest) -> dict[str, float]:
    """What the paper's formulas see of a robot with errors ``alpha`` and ``beta`` [rad].

    The centres come from the exact square geometry
    (:func:`umbmark.square.square_end_pose`), without small-angle approximations.
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


def paper_estimate(bench: Benchmark, test: SquareTest) -> ErrorEstimate:
    """The paper's estimate of ``alpha``, ``beta``, ``E_d`` and ``E_b`` (Sec. 4)."""
    z, cov = cg_vector(bench)
    parts = paper_components(z, test)
    errors = propagate(lambda v: paper_components(v, test), z, cov)
    # What the exact geometry predicts the x and y estimates to be, for the robot that
    # best explains both centres: their difference is no sign of trouble.
    best = exact_components(z, test)
    expected = exact_view(best["alpha"], best["beta"], test)
    warnings = list(_disagreement_warnings(parts, expected, errors, test))
    shortfall = small_angle_shortfall(parts["alpha"], parts["beta"], test)
    if shortfall > SMALL_ANGLE_TOLERANCE:
        warnings.append(
            f"errors this large (alpha = {math.degrees(parts['alpha']):.2f} deg, "
            f"beta = {math.degrees(parts['beta']):.2f} deg) stretch the small-angle "
            f"formulas (Eqs. 4.17-4.24): the x- and y-based estimates are each off by up "
            f"to {100 * shortfall:.0f} %; apply this correction and run a second pass, "
            "or use --method exact"
        )
    return ErrorEstimate(
        method="paper",
        alpha=parts["alpha"],
        beta=parts["beta"],
        E_d=parts["E_d"],
        E_b=parts["E_b"],
        components={k: v for k, v in parts.items() if not k.endswith("_minus_y")},
        standard_errors={k: errors[k] for k in ("alpha", "beta", "E_d", "E_b")},
        warnings=tuple(warnings),
    )


def _disagreement_warnings(
    parts: dict[str, float],
    expected: dict[str, float],
    errors: dict[str, float],
    test: SquareTest,
) -> list[str]:
    """x and y estimates that differ by more than spread and geometry explain.

    Even noise-free, the x and y estimates differ slightly for large errors; ``expected``
    holds what the exact geometry predicts for the estimated errors.
    """
    out = []
    for name in ("alpha", "beta"):
        diff = parts[f"{name}_x_minus_y"]
        excess = diff - expected[f"{name}_x_minus_y"]
        se = errors[f"{name}_x_minus_y"]
        in_length = 4.0 * test.side_length * abs(excess)
        if abs(excess) > 3.0 * se and in_length > DISAGREEMENT_TOLERANCE:
            out.append(
                f"{name} from x ({math.degrees(parts[name + '_x']):.3f} deg) and from y "
                f"({math.degrees(parts[name + '_y']):.3f} deg) disagree by more than the "
                f"spread and the geometry explain ({abs(math.degrees(excess)):.3f} deg > "
                f"3 x {math.degrees(se):.3f} deg): check the runs' directions, axes and signs; "
                "if they are right, the robot has errors the paper's model leaves out (E_s, slip)"
            )
    return out

"""Estimators of the systematic errors ``alpha``, ``beta``, ``E_d`` and ``E_b``.

From the runs of a square path test:

- ``paper``: the paper's equations exactly as printed (Sec. 4).
- ``exact``: the same centres of gravity, with the exact geometry inverted.
- ``heading``: from the final heading errors (Jung & Chung 2011); needs headings.
- ``endpose``: maximum likelihood on every run's end pose (positions and headings),
  exact geometry, weighted by the runs' scatter.

From recorded trajectories of any shape: :mod:`umbmark.estimators.trajectory`; what such
recordings hold (straight legs, arcs, turns on the spot) and whether that identifies the
scrub model's turn-rate term: :mod:`umbmark.estimators.motions`.

Estimators never print: doubts come back as ``ErrorEstimate.warnings``. Each method judges
the plausibility of the runs for itself (:mod:`umbmark.estimators.checks`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from umbmark.benchmark.returns import Benchmark
from umbmark.estimators.base import ErrorEstimate, SquareTest
from umbmark.model.runs import Run

__all__ = [
    "METHODS",
    "ErrorEstimate",
    "Method",
    "SquareTest",
    "estimate_errors",
    "estimate_square_test",
]

Method = Literal["paper", "exact", "heading", "endpose"]
METHODS: tuple[Method, ...] = ("paper", "exact", "heading", "endpose")


def estimate_errors(
    method: str,
    bench: Benchmark,
    runs: Sequence[Run],
    test: SquareTest,
    *,
    E_s: float | None = None,
) -> ErrorEstimate:
    """Run the estimator named ``method`` on a square path test.

    ``E_s``, measured by straight runs, is held fixed by ``endpose`` and scales ``E_b``
    of the others (their turns see ``E_b / E_s``).

    Raises
    ------
    ValueError
        For an unknown method, or runs the method cannot use.
    """
    from umbmark.estimators.checks import check_reachable, check_within_side

    if method == "paper":
        from umbmark.estimators.paper import paper_estimate

        check_within_side(runs, test)
        estimate = paper_estimate(bench, test, runs)
    elif method == "exact":
        from umbmark.estimators.exact import exact_estimate

        check_reachable(runs, test)
        estimate = exact_estimate(bench, test, runs)
    elif method == "heading":
        from umbmark.estimators.heading import heading_estimate

        estimate = heading_estimate(bench, list(runs), test)
    elif method == "endpose":
        from umbmark.estimators.endpose import endpose_estimate

        check_reachable(runs, test)
        return endpose_estimate(bench, runs, test, E_s=E_s)
    else:
        raise ValueError(f"unknown method {method!r}; use one of {', '.join(METHODS)}")
    return estimate if E_s is None else estimate.with_scale(E_s)


def estimate_square_test(
    method: str, runs: Sequence[Run], test: SquareTest
) -> tuple[ErrorEstimate, Benchmark | None]:
    """The estimate from square runs and, where the runs include them, straight runs.

    Straight runs measure ``E_s`` (:mod:`umbmark.estimators.scale`), which completes the
    square test's estimate; alone, they give ``E_s`` only.

    Returns
    -------
    estimate : ErrorEstimate
    benchmark : Benchmark or None
        The UMBmark figures of the square runs (None without square runs).

    Raises
    ------
    ValueError
        For too few runs in a direction, or runs the method cannot use.
    """
    import math
    from dataclasses import replace

    from umbmark.benchmark.returns import umbmark_benchmark
    from umbmark.estimators.scale import scale_from_straights, scale_only

    squares = [run for run in runs if run.kind == "square"]
    straights = [run for run in runs if run.kind == "straight"]
    scale = scale_from_straights(straights) if straights else None
    if not squares and scale is not None:
        return scale_only(scale), None
    bench = umbmark_benchmark(squares)
    estimate = estimate_errors(
        method, bench, squares, test, E_s=None if scale is None else scale.E_s
    )
    if scale is None or scale.standard_error is None:
        return estimate, bench
    errors = dict(estimate.standard_errors)
    errors["E_s"] = scale.standard_error
    if "E_b" in errors:
        relative = scale.standard_error / scale.E_s
        errors["E_b"] = math.hypot(errors["E_b"], estimate.E_b * relative)
    return replace(estimate, standard_errors=errors), bench

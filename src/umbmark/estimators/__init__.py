"""Estimators of the systematic errors ``alpha``, ``beta``, ``E_d`` and ``E_b``.

- ``paper``: the paper's equations exactly as printed (Sec. 4).
- ``exact``: the same square-path measurements, with the exact geometry inverted.
- ``heading``: from the final heading errors (Jung & Chung 2011); needs headings.

Estimators never print: doubts come back as ``ErrorEstimate.warnings``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

from ..benchmark import Benchmark
from ..runs import Run
from .base import ErrorEstimate, SquareTest
from .exact import exact_estimate
from .heading import heading_estimate
from .paper import paper_estimate

__all__ = ["METHODS", "ErrorEstimate", "Method", "SquareTest", "estimate_errors"]

Method = Literal["paper", "exact", "heading"]
METHODS: tuple[Method, ...] = ("paper", "exact", "heading")


def estimate_errors(
    method: Method, bench: Benchmark, runs: Sequence[Run], test: SquareTest
) -> ErrorEstimate:
    """Run the estimator named ``method`` on a square path test."""
    if method == "paper":
        return paper_estimate(bench, test)
    if method == "exact":
        return exact_estimate(bench, test)
    if method == "heading":
        return heading_estimate(bench, list(runs), test)
    raise ValueError(f"unknown method {method!r}; use one of {', '.join(METHODS)}")

"""Estimators of the systematic errors ``alpha``, ``beta``, ``E_d`` and ``E_b``.

Every estimator is one entry of :mod:`umbmark.estimators.registry` (its name, what it
needs, its function), run by :mod:`umbmark.estimators.dispatch`, which makes the checks
every estimate gets once (:mod:`umbmark.estimators.diagnostics`).

From the runs of a square path test: ``paper`` (:mod:`~umbmark.estimators.paper` on
:mod:`~umbmark.estimators.formulas`, the paper's equations as printed), ``exact``,
``heading``, ``endpose``. From recorded trajectories of any shape: ``endpoints``,
``trajectory`` and ``trajectory-scrub`` (:mod:`umbmark.estimators.trajectory`); what such
recordings hold (straight legs, arcs, turns on the spot) and whether that identifies the
scrub model's turn-rate term: :mod:`umbmark.estimators.motions`. The scale ``E_s`` of
straight runs: :mod:`umbmark.estimators.scale`.

Estimators never print: doubts come back as ``ErrorEstimate.warnings``. This package
imports nothing until a module of it is used, so that the command line reads the
registry before numpy is loaded.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

# Kept for callers not yet moved to the names' homes (umbmark.sim.experiments, on another
# branch of issue 16): imported on first use, so that the package stays cheap to import.
_MOVED = {
    "Method": "umbmark.estimators.registry",
    "SquareTest": "umbmark.estimators.base",
    "estimate_errors": "umbmark.estimators.dispatch",
}

if TYPE_CHECKING:
    from umbmark.estimators.base import SquareTest
    from umbmark.estimators.dispatch import estimate_errors
    from umbmark.estimators.registry import Method

__all__ = ["Method", "SquareTest", "estimate_errors"]


def __getattr__(name: str) -> object:
    home = _MOVED.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(home), name)

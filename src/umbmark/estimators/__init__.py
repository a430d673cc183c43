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
imports nothing, so that the command line reads the registry before numpy is loaded.
"""

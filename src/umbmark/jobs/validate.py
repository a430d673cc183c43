"""The validation job: which estimator and model predict the robot best, on its own data.

Calibrating and checking on the same runs says little. :func:`validate` holds each source
out in turn (leave one source out; with a single source, leave one run out), calibrates on
the rest with every estimator that can use them, replays the held-out runs with each
calibration, and compares their mean end-position errors: the held-out error is what a
user will see on runs the calibration never saw. The estimator with the lowest mean
held-out error is recommended; ``umbmark calibrate --method auto`` calibrates with it.

The figures say how well each calibration predicts the kinds of motion held out, and
nothing of others: :attr:`umbmark.calibration.validation.ValidationReport.coverage`
states which (straight legs, arcs, turns on the spot; :mod:`umbmark.estimators.motions`).
An estimator of a turn-rate term (``trajectory-scrub``) is credited only where the rest of
the runs identify it (they hold arcs and turns on the spot, and the fit pins the term),
so that it is never credited with runs it extrapolates to, nor with the single
wheelbase it falls back to.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.calibration.active import read_runs
from umbmark.calibration.validation import Fold, ValidationReport
from umbmark.core.errors import InputError
from umbmark.core.messages import info, split_messages
from umbmark.estimators.motions import SCRUB_FALLBACK, MotionCoverage, motion_coverage
from umbmark.estimators.registry import RUNS, names
from umbmark.model.kinematics import WheelParams
from umbmark.model.runs import Run, end_errors
from umbmark.runs.options import ReadOptions, SourceOptions
from umbmark.runs.read import Runs, is_table, pool_runs, source_name

if TYPE_CHECKING:
    from typing_extensions import Unpack

__all__ = ["CANDIDATES", "validate"]

#: What is compared: the nominal parameters and every estimator.
CANDIDATES = ("nominal", *RUNS)
_MM = 1000.0


def validate(
    source: str | os.PathLike[str],
    *more_sources: str | os.PathLike[str],
    methods: Sequence[str] | None = None,
    side_length: float | None = None,
    wheelbase: float | None = None,
    override_verdict: bool = False,
    progress: Callable[[float], None] | None = None,
    **options: Unpack[SourceOptions],
) -> ValidationReport:
    """Hold out each source (or, from one source, each run), calibrate on the rest with
    every estimator, replay what was held out, and compare the end errors.

    Parameters
    ----------
    source, *more_sources : path
        Recorded runs (run logs, OptiOdom sessions, bags): replaying needs their wheel
        data.
    methods : sequence of str, optional
        The estimators to compare (default: all of :data:`CANDIDATES`).
    side_length, wheelbase : float, optional
        As for :func:`umbmark.calibrate`.
    override_verdict : bool
        Take ``current_params`` even when it is a result for another robot's nominal
        wheelbase or wheel diameter (as for :func:`umbmark.calibrate`).
    progress : callable, optional
        Called with the fraction done.
    **options
        How to read the sources (:class:`umbmark.runs.options.ReadOptions`).

    Raises
    ------
    InputError
        For sources without recorded wheel data, or too little to hold anything out.
    """
    read_options = ReadOptions.of(options)
    chosen = tuple(CANDIDATES if methods is None else ("nominal", *methods))
    for name in chosen:
        if name not in CANDIDATES:
            raise InputError(f"--methods {name!r}: use some of {', '.join(CANDIDATES[1:])}")
    paths = (source, *more_sources)
    for path in paths:
        if is_table(path, read_options):
            raise InputError(
                "validation replays recorded runs: give run logs, OptiOdom sessions or bags, "
                "not a runs table",
                source=source_name(path),
            )
    read = [
        read_runs(
            [path],
            read_options,
            wheelbase=wheelbase,
            side_length=side_length,
            override_verdict=override_verdict,
        )
        for path in paths
    ]
    for one in read:
        if one.params is None:
            raise InputError(
                "validation replays recorded runs: give run logs, OptiOdom sessions or bags, "
                "not a runs table",
                source=one.sources[0],
            )
    if len(read) > 1:
        scheme = "leave one source out"
        parts = [(r.sources[0], [r], [o for o in read if o is not r]) for r in read]
    else:
        scheme = "leave one run out"
        whole = read[0]
        if len(whole.runs) < 3:
            raise InputError(
                f"holds {len(whole.runs)} run(s): leaving one out needs at least 3",
                source=whole.sources[0],
            )
        parts = [
            (
                run.label,
                [replace(whole, runs=(run,))],
                [replace(whole, runs=tuple(r for r in whole.runs if r is not run))],
            )
            for run in whole.runs
        ]
    folds = []
    for k, (name, held, training) in enumerate(parts):
        folds.append(_fold(name, held[0], pool_runs(training), chosen))
        if progress is not None:
            progress((k + 1) / len(parts))
    notes, warnings = split_messages([*(n for r in read for n in r.notes), *_refusals(folds)])
    return ValidationReport(
        sources=tuple(source_name(p) for p in paths),
        scheme=scheme,
        candidates=chosen,
        folds=tuple(folds),
        notes=notes,
        warnings=warnings,
    )


def _refusals(folds: Sequence[Fold]) -> list[str]:
    """One note per reason the validation refused a candidate, naming the folds."""
    reasons: dict[tuple[str, str], list[str]] = {}
    for fold in folds:
        for candidate, why in fold.refused.items():
            reasons.setdefault((candidate, why), []).append(Path(fold.held_out).name)
    return [
        info(f"{candidate} not calibrated with {', '.join(names)} held out: {why}")
        for (candidate, why), names in reasons.items()
    ]


def _coverage(runs: Runs) -> MotionCoverage:
    assert runs.params is not None
    return motion_coverage([run.log for run in runs.runs if run.log is not None], runs.params)


def _fold(name: str, held: Runs, training: Runs, candidates: Sequence[str]) -> Fold:
    assert held.params is not None
    trained_on = _coverage(training)
    errors: dict[str, float | None] = {}
    refused: dict[str, str] = {}
    for candidate in candidates:
        turn_rate = candidate in names(turn_rate=True)
        if turn_rate and not trained_on.holds_both_turns:
            errors[candidate] = None
            refused[candidate] = (
                f"the rest hold {trained_on.held_text(only=True)}, which do not identify "
                "its turn-rate term"
            )
            continue
        params, fell_back = _calibrated(training, candidate, held.params)
        if fell_back is not None:  # not credited with the single wheelbase's figures
            errors[candidate] = None
            refused[candidate] = fell_back
            continue
        errors[candidate] = None if params is None else _mean_error(held.runs, params)
    return Fold(
        held_out=name,
        runs=len(held.runs),
        errors=errors,
        motions=_coverage(held).held,
        trained_on=trained_on.held,
        refused=refused,
    )


def _calibrated(
    training: Runs, candidate: str, nominal: WheelParams
) -> tuple[WheelParams | None, str | None]:
    """The held-out source's parameters after calibrating on ``training`` (None: the
    candidate cannot calibrate on it), and why a scrub fit gave one wheelbase (None: it
    gave two, or is not one)."""
    from umbmark.calibration.estimate import calibrate_runs

    if candidate == "nominal":
        return nominal, None
    try:
        report = calibrate_runs(training, candidate)
    except ValueError:  # InputError included: the candidate cannot calibrate on these runs
        return None, None
    fit = report.model_fit
    fell_back = None
    if candidate in names(turn_rate=True) and (fit is None or fit.spot_wheelbase is None):
        said = [w for w in report.estimate.warnings if "turn-rate term" in w]
        fell_back = said[0].split(f"; {SCRUB_FALLBACK}")[0] if said else SCRUB_FALLBACK
    return report.new_params().applied_to(nominal), fell_back


def _mean_error(runs: Sequence[Run], params: WheelParams) -> float:
    errors = end_errors([run.reintegrated(params) for run in runs])
    value = float(errors.mean())
    return value if math.isfinite(value) else math.inf

"""Held-out validation of calibrations on runs already read: hold out each source (or,
from one source, each run), calibrate on the rest with every candidate estimator, replay
what was held out, and compare the mean end-position errors (:class:`ValidationReport`).

``umbmark validate`` (:func:`umbmark.jobs.validate.validate`) reads its sources and calls
:func:`validate_read`; ``calibrate --method auto`` (:mod:`umbmark.calibration.auto`) calls
it with the sources it has read for the calibration, so that each is read once.

An estimator of a turn-rate term (``trajectory-scrub``) is credited only where the rest of
the runs identify it (they hold arcs and turns on the spot, and the fit pins the term), so
that it is never credited with runs it extrapolates to, nor with the single wheelbase it
falls back to.

The ``gyro`` estimator (a bag read with ``imu_topic``) is a candidate where the recording's
wheels and gyro are given (:class:`~umbmark.calibration.gyro_bag.GyroRecording`, with the
ground truth's heading as its reference): a run held out is a stretch of the recording
left out of its intervals and its reference (the rests around it kept). It calibrates
one recording at a time: with several sources (leave one source out) it is refused, and
said so.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.calibration.validation import Fold, ValidationReport
from umbmark.core.errors import InputError
from umbmark.core.messages import info, split_messages
from umbmark.estimators.motions import SCRUB_FALLBACK, MotionCoverage, motion_coverage
from umbmark.estimators.registry import GYROS, RUNS, names
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run, end_errors
from umbmark.runs.read import SourceRuns, pool_runs

if TYPE_CHECKING:
    from umbmark.calibration.gyro_bag import GyroRecording

__all__ = ["CANDIDATES", "validate_read"]

#: What is compared: the nominal parameters and every estimator of runs.
CANDIDATES = ("nominal", *RUNS)


def validate_read(
    read: Sequence[SourceRuns],
    candidates: Sequence[str] = CANDIDATES,
    progress: Callable[[float], None] | None = None,
    gyro: GyroRecording | None = None,
) -> ValidationReport:
    """The held-out end errors of ``candidates`` on sources read one by one.

    Parameters
    ----------
    read : sequence of Runs
        Each source read on its own (:func:`umbmark.runs.active.read_each`), with
        recorded wheel data (``params`` set).
    candidates : sequence of str
        ``"nominal"`` and names of estimators of runs (default: all of :data:`CANDIDATES`),
        and ``gyro`` with ``gyro``.
    progress : callable, optional
        Called with the fraction done.
    gyro : GyroRecording, optional
        The one source's wheels and gyro, for the ``gyro`` candidate.

    Raises
    ------
    InputError
        For a source without recorded wheel data, or a single source of fewer than 3 runs.
    """
    for one in read:
        if one.params is None:
            raise InputError(
                "validation replays recorded runs: give run logs, OptiOdom sessions or bags, "
                "not a runs table",
                source=one.sources[0],
            )
    if len(read) > 1:
        scheme = "leave one source out"
        parts = [(r.sources[0], r, [o for o in read if o is not r]) for r in read]
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
                replace(whole, runs=(run,)),
                [replace(whole, runs=tuple(r for r in whole.runs if r is not run))],
            )
            for run in whole.runs
        ]
    folds = []
    recording = gyro if len(read) == 1 else None
    for k, (name, held, training) in enumerate(parts):
        folds.append(_fold(name, held, pool_runs(training), candidates, recording))
        if progress is not None:
            progress((k + 1) / len(parts))
    notes, warnings = split_messages([*(n for r in read for n in r.notes), *_refusals(folds)])
    return ValidationReport(
        sources=tuple(one.sources[0] for one in read),
        scheme=scheme,
        candidates=tuple(candidates),
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


def _coverage(runs: SourceRuns) -> MotionCoverage:
    assert runs.params is not None
    return motion_coverage([run.log for run in runs.runs if run.log is not None], runs.params)


def _fold(
    name: str,
    held: SourceRuns,
    training: SourceRuns,
    candidates: Sequence[str],
    gyro: GyroRecording | None = None,
) -> Fold:
    assert held.params is not None
    trained_on = _coverage(training)
    errors: dict[str, float | None] = {}
    refused: dict[str, str] = {}
    for candidate in candidates:
        if candidate in GYROS:
            errors[candidate], why = _gyro_error(gyro, held)
            if why is not None:
                refused[candidate] = why
            continue
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
    training: SourceRuns, candidate: str, nominal: WheelParams
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


def _gyro_error(gyro: GyroRecording | None, held: SourceRuns) -> tuple[float | None, str | None]:
    """The held-out runs' mean end error with the gyro's calibration of the rest of the
    recording (their stretches left out of it), and why there is none."""
    from umbmark.core.errors import ProblemError

    if gyro is None:
        return None, "the gyro calibrates one recording at a time (leave one run out)"
    assert held.params is not None
    spans = [
        (run.log.start, run.log.start + float(run.log.time[-1])) for run in held.runs if run.log
    ]
    try:
        report = gyro.without(spans).calibrate().result
    except (InputError, ProblemError, ValueError) as exc:
        return None, str(exc).splitlines()[0]
    return _mean_error(held.runs, report.new_params().applied_to(held.params)), None

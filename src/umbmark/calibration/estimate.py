"""The estimation step of a calibration: runs as read, one estimator, a result.

:func:`calibrate_runs` runs the estimator a method names on runs already read
(:func:`umbmark.runs.active.read_runs`), through
:func:`umbmark.estimators.dispatch.estimate_runs`, and returns the
:class:`~umbmark.calibration.result.CalibrationResult`; :func:`umbmark.calibrate` and the
held-out validation (:func:`umbmark.validate`) share it.
"""

from __future__ import annotations

from collections.abc import Sequence

from umbmark.calibration.compose import Calibration, check_calibration
from umbmark.calibration.result import CalibrationResult
from umbmark.core.messages import info, split_messages
from umbmark.estimators.dispatch import estimate_runs
from umbmark.estimators.registry import estimator
from umbmark.runs.read import SourceRuns

__all__ = ["calibrate_runs", "sessions_disagree"]


def calibrate_runs(
    read: SourceRuns, method: str, *, fit_truth_offset: bool = False
) -> CalibrationResult:
    """The calibration of runs already read, by ``method``.

    Raises
    ------
    InputError
        For runs the method cannot use, or a fit that fails (why, and what to try).
    """
    active = read.active
    found = estimate_runs(
        method,
        read.runs,
        wheelbase=active.effective_wheelbase,
        params=read.params,
        side_length=read.side_length,
        square_side=read.square_side,
        fit_truth_offset=fit_truth_offset,
        where=read.sources[0] if len(read.sources) == 1 else None,
        stretches=read.stretches,
    )
    check_calibration(Calibration(found.estimate, active), read.origins)
    notes, warnings = split_messages([*read.notes, *_stretches_used(read, method)])
    return CalibrationResult(
        sources=read.sources,
        format=read.format,
        runs=read.runs,
        benchmark=found.benchmark,
        test=found.test,
        calibration=Calibration(found.estimate, active),
        params=read.params,
        controller=read.controller,
        associations=read.associations,
        notes=notes,
        input_warnings=warnings,
        model_fit=found.model_fit,
    )


def _stretches_used(read: SourceRuns, method: str) -> list[str]:
    """A line saying that ``method`` fitted the motion left out of the runs too, if it
    did (an estimator of paths of any shape)."""
    if not read.stretches or estimator(method).needs != "logs":
        return []
    seconds = sum(float(run.log.time[-1]) for run in read.stretches if run.log is not None)
    return [
        info(
            f"the {method} fit used the {len(read.runs)} run(s) and {len(read.stretches)} "
            f"stretch(es) of motion left out of them ({seconds:.1f} s), every stretch with "
            "a reference"
        )
    ]


def sessions_disagree(parts: Sequence[SourceRuns], *, fit_truth_offset: bool = False) -> list[str]:
    """Warnings where the sources, fitted one by one, want different wheels."""
    from umbmark.estimators.trajectory import source_disagreement

    sources = [
        (part.sources[0], [run.log for run in part.runs if run.log is not None], part.params)
        for part in parts
    ]
    return source_disagreement(sources, fit_truth_offset=fit_truth_offset)

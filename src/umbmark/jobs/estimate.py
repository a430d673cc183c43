"""The estimation step of a calibration: runs as read, one estimator, a report.

:func:`calibrate_runs` runs the estimator a method names on runs already read
(:func:`umbmark.jobs.inputs.read_runs`) and returns the
:class:`~umbmark.jobs.calibrate.CalibrationReport`; :func:`umbmark.calibrate` and the
held-out validation (:func:`umbmark.validate`) share it. An estimator that fails says
why and what to try: never a bare "the fit diverged".
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from umbmark.benchmark.returns import umbmark_benchmark
from umbmark.calibration.compose import Calibration
from umbmark.core.errors import InputError
from umbmark.core.messages import split_messages
from umbmark.estimators.base import SquareTest
from umbmark.jobs.inputs import Runs, check_calibration
from umbmark.runs.logged import require_headings

if TYPE_CHECKING:
    from umbmark.jobs.calibrate import CalibrationReport

__all__ = ["LOGGED_METHODS", "calibrate_runs", "sessions_disagree"]

#: The methods that need recorded runs (time series).
LOGGED_METHODS = ("endpoints", "trajectory", "trajectory-scrub")


def _failed(method: str, why: str) -> str:
    """What an estimator that could not compute says: why, and what to try."""
    return (
        f"the {method} estimate could not be computed ({why}): the runs do not determine the "
        "errors; try another --method, more runs (in both directions, with turns both "
        "ways), and check the units, the nominal wheelbase and wheel diameter and, for "
        "recorded runs, the time offset between wheels and ground truth"
    )


def calibrate_runs(read: Runs, method: str, *, fit_truth_offset: bool = False) -> CalibrationReport:
    """The calibration of runs already read, by ``method``.

    Raises
    ------
    InputError
        For runs the method cannot use, or a fit that fails (why, and what to try).
    """
    import numpy as np

    from umbmark.jobs.calibrate import CalibrationReport

    where = read.sources[0] if len(read.sources) == 1 else None
    runs, active = read.runs, read.active
    bench = None
    fit = None
    try:
        require_headings(runs, method, where)
        if method in LOGGED_METHODS:
            logs = [run.log for run in runs if run.log is not None]
            if not logs or read.params is None:
                raise InputError(
                    f"the {method} method needs logged runs (a run log, an OptiOdom session "
                    "or a bag), not a runs table",
                    source=where,
                )
            if method == "endpoints":
                from umbmark.estimators.endpoints import endpoints_estimate

                estimate, _ = endpoints_estimate(logs, read.params, read.side_length)
            else:
                from umbmark.estimators.trajectory import trajectory_estimate

                estimate, fit = trajectory_estimate(
                    logs,
                    read.params,
                    read.side_length,
                    model="scrub" if method == "trajectory-scrub" else "diff",
                    fit_truth_offset=fit_truth_offset,
                )
            test = SquareTest(read.side_length or 1.0, active.effective_wheelbase)
            # UMBmark's figures where the runs are squares of a known side.
            directions = {run.direction for run in runs if run.kind == "square"}
            if read.side_length is not None and len(directions) == 2:
                try:
                    bench = umbmark_benchmark(runs)
                except ValueError:
                    bench = None
        else:
            from umbmark.estimators import estimate_square_test

            squares = any(run.kind == "square" for run in runs)
            side = read.square_side() if squares else (read.side_length or 1.0)
            test = SquareTest(side, active.effective_wheelbase)
            estimate, bench = estimate_square_test(method, runs, test)
    except InputError:
        raise
    except np.linalg.LinAlgError as exc:  # a ValueError: caught before the others
        raise InputError(_failed(method, f"a singular system: {exc}"), source=where) from None
    except ValueError as exc:
        raise InputError(str(exc), source=where) from None
    check_calibration(Calibration(estimate, active), read.origins)
    notes, warnings = split_messages(read.notes)
    return CalibrationReport(
        sources=read.sources,
        format=read.format,
        runs=read.runs,
        benchmark=bench,
        test=test,
        calibration=Calibration(estimate, active),
        params=read.params,
        controller=read.controller,
        associations=read.associations,
        notes=notes,
        input_warnings=warnings,
        model_fit=fit,
    )


def sessions_disagree(parts: Sequence[Runs], *, fit_truth_offset: bool = False) -> list[str]:
    """Warnings where the sources, fitted one by one, want different wheels."""
    from umbmark.estimators.trajectory import disagreement_warnings, fit_trajectories

    fits = []
    for part in parts:
        logs = [run.log for run in part.runs if run.log is not None]
        if part.params is None or not logs:
            continue
        try:
            fit = fit_trajectories(logs, part.params, fit_truth_offset=fit_truth_offset)
            fits.append((part.sources[0], fit))
        except ValueError:
            continue  # a source too small to fit alone says nothing against the others
    return disagreement_warnings(fits)

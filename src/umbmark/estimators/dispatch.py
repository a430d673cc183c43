"""Run the estimator a method names: the one way from runs to an error estimate.

The table of :mod:`umbmark.estimators.registry` says what each estimator needs and how it
is called; this module calls it, and around it what every estimate gets:

- :func:`estimate_errors`: a square estimator on a square test's runs, with the refusals
  before and the model check's warnings after (:mod:`umbmark.estimators.diagnostics`),
  made once here for every estimator;
- :func:`estimate_square_test`: that, completed by the scale ``E_s`` of straight runs
  (:mod:`umbmark.estimators.scale`) where the runs include them;
- :func:`estimate_runs`: any estimator on a calibration's runs (square tests or
  recordings), whose failures say why and what to try, as one line: never a bare "the
  fit diverged".

Estimators never print: doubts come back as ``ErrorEstimate.warnings``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.estimators.base import ErrorEstimate, SquareTest
from umbmark.estimators.diagnostics import check_model, check_reach, require_headings
from umbmark.estimators.endpose import fit_end_poses
from umbmark.estimators.registry import SQUARE, estimator, find
from umbmark.estimators.scale import scale_from_straights, scale_only
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run
from umbmark.returns.clusters import Benchmark, umbmark_benchmark

if TYPE_CHECKING:
    from umbmark.estimators.trajectory_fit import TrajectoryFit

__all__ = ["Estimated", "estimate_errors", "estimate_runs", "estimate_square_test"]

#: Runs read with another wheel diameter are taken for the right reading when their
#: E_max,syst is within this fraction of the side (the paper's uncalibrated robots: 7 %).
_IDENTIFIED = 0.25
#: ... or, fitted, when the fit holds: its rms residual within these [m, rad] (the
#: refusal floors of ``calibration.verdict``: MISFIT_FLOOR, HEADING_REFUSE); a fit that
#: stayed at its start, missing the ground truth by metres, gives E_s = 1 and says nothing.
_FIT_HOLDS = (0.1, math.radians(8.0))
#: The factors a wheel diameter is tried with where runs cannot be estimated, likeliest
#: first: a radius given for a diameter (or the reverse), a unit or decimal-point slip
#: (``umbmark.estimators.scale.UNIT_SLIPS``).
_MIXUPS = (2.0, 0.5, 10.0, 0.1, 100.0, 0.01)


def estimate_errors(
    method: str,
    bench: Benchmark,
    runs: Sequence[Run],
    test: SquareTest,
    *,
    E_s: float | None = None,
) -> ErrorEstimate:
    """Run the estimator named ``method`` on a square path test.

    ``E_s``, measured by straight runs, is held fixed by the end-pose fit (``endpose``)
    and scales ``E_b`` of the others (their turns see ``E_b / E_s``). The model check's
    warnings come first, then the estimator's own.

    Raises
    ------
    ValueError
        For an unknown method, or runs the method cannot use.
    """
    entry = find(method)
    if entry is None or entry.needs != "square":
        raise ValueError(f"unknown method {method!r}; use one of {', '.join(SQUARE)}")
    check_reach(entry, runs, test)
    function = entry.load()
    fit = None
    if entry.fits_end_poses:  # the estimate is the fit the model check judges: made once
        fit = fit_end_poses(bench, runs, test, E_s=1.0 if E_s is None else E_s)
        estimate: ErrorEstimate = function(bench, runs=runs, test=test, E_s=E_s, fit=fit)
    else:
        estimate = function(bench, runs=runs, test=test)
        if E_s is not None:
            estimate = estimate.with_scale(E_s)
    warnings, failure = check_model(bench, runs, test, fit, E_s=1.0 if E_s is None else E_s)
    return replace(estimate, warnings=(*warnings, *estimate.warnings), model_failure=failure)


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


@dataclass(frozen=True)
class Estimated:
    """What an estimator made of a calibration's runs.

    Attributes
    ----------
    estimate : ErrorEstimate
    test : SquareTest
        Side [m] and wheelbase [m] the estimate assumed.
    benchmark : Benchmark or None
        The UMBmark figures (Eqs. 3.1-3.4); None when the runs are not squares of a known
        side in both directions.
    model_fit : TrajectoryFit or None
        The trajectory methods' fit of the odometry model, which replays use.
    """

    estimate: ErrorEstimate
    test: SquareTest
    benchmark: Benchmark | None
    model_fit: TrajectoryFit | None = None


def _failed(method: str, why: str) -> str:
    """What an estimator that could not compute says: why, and what to try."""
    return (
        f"the {method} estimate could not be computed ({why}): the runs do not determine the "
        f"errors; try another {option('method')}, more runs (in both directions, with turns "
        "both "
        "ways), and check the units, the nominal wheelbase and wheel diameter and, for "
        "recorded runs, the time offset between wheels and ground truth"
    )


def estimate_runs(
    method: str,
    runs: Sequence[Run],
    *,
    wheelbase: float,
    params: WheelParams | None,
    side_length: float | None,
    square_side: Callable[[], float],
    fit_truth_offset: bool = False,
    where: str | None = None,
    stretches: Sequence[Run] = (),
) -> Estimated:
    """The estimate of ``method`` from a calibration's runs, square tests or recordings.

    Parameters
    ----------
    method : str
        The estimator (:data:`umbmark.estimators.registry.NAMES`).
    runs : sequence of Run
        Every run; recorded ones with their time series.
    wheelbase : float
        The wheelbase [m] the odometry used during the runs.
    params : WheelParams or None
        What recorded runs were integrated with (None for end points only).
    side_length : float or None
        The square's side [m], where given or known to the sources.
    square_side : callable
        The side [m] of the square every source drove, asked only of square runs for a
        square estimator (raises :class:`InputError` where the sources disagree).
    fit_truth_offset : bool
        The trajectory methods: fit the ground truth's tracked point.
    where : str, optional
        The source named in errors.
    stretches : sequence of Run
        Motion left out of the runs (:attr:`umbmark.runs.read.SourceRuns.stretches`): the
        estimators of paths of any shape fit it with the runs.

    Raises
    ------
    InputError
        For runs the method cannot use, or a fit that fails (why, and what to try).
    """
    try:
        return _estimate(
            method, runs, wheelbase, params, side_length, square_side, fit_truth_offset, where,
            stretches,
        )  # fmt: skip
    except InputError:
        raise
    except np.linalg.LinAlgError as exc:  # a ValueError: caught before the others
        raise InputError(_failed(method, f"a singular system: {exc}"), source=where) from None
    except ValueError as exc:  # a ProblemError keeps the options it names
        problem = getattr(exc, "problem", None) or str(exc)
    mixup = _diameter_mixup(method, runs, params, wheelbase, square_side, fit_truth_offset)
    said = problem if mixup is None else f"{mixup}. Read as given: {problem}"
    raise InputError(said, source=where) from None


def _estimate(
    method: str,
    runs: Sequence[Run],
    wheelbase: float,
    params: WheelParams | None,
    side_length: float | None,
    square_side: Callable[[], float],
    fit_truth_offset: bool,
    where: str | None,
    stretches: Sequence[Run] = (),
) -> Estimated:
    """:func:`estimate_runs` without its translation of failures."""
    entry = estimator(method)
    if entry.needs == "intervals":
        raise InputError(
            f"the {method} method needs motion intervals (a .tuple file of the wheels "
            "against a laser's scan matching), not runs",
            source=where,
        )
    if entry.needs == "imu":
        raise InputError(
            f"the {method} method needs a recording's wheels and its gyro (a bag with "
            f"{option('imu_topic')}), not runs",
            source=where,
        )
    require_headings(entry, runs, where)
    if entry.needs == "square":
        squares = any(run.kind == "square" for run in runs)
        side = square_side() if squares else (side_length or 1.0)
        test = SquareTest(side, wheelbase)
        estimate, bench = estimate_square_test(method, runs, test)
        return Estimated(estimate, test, bench)
    logs = [run.log for run in (*runs, *stretches) if run.log is not None]
    if not logs or params is None:
        raise InputError(
            f"the {method} method needs logged runs (a run log, an OptiOdom session "
            "or a bag), not a runs table",
            source=where,
        )
    options: dict[str, object] = dict(entry.options)
    if entry.trajectories:
        options["fit_truth_offset"] = fit_truth_offset
    estimate, fit = entry.load()(logs, params, side_length, **options)
    test = SquareTest(side_length or 1.0, wheelbase)
    # UMBmark's figures where the runs are squares of a known side.
    bench = None
    directions = {run.direction for run in runs if run.kind == "square"}
    if side_length is not None and len(directions) == 2:
        try:
            bench = umbmark_benchmark(runs)
        except ValueError:
            bench = None
    return Estimated(estimate, test, bench, fit if entry.trajectories else None)


def _diameter_mixup(
    method: str,
    runs: Sequence[Run],
    params: WheelParams | None,
    wheelbase: float,
    square_side: Callable[[], float],
    fit_truth_offset: bool,
) -> str | None:
    """Where recorded runs cannot be estimated, whether they can with the wheel diameter
    doubled or halved (a radius given for a diameter, or the reverse) or a power of ten
    off (a unit slip): the cause and the fix
    (:func:`umbmark.estimators.scale.diameter_mixup`), or None."""
    from umbmark.estimators.scale import OBSERVED_TOLERANCE, diameter_mixup, observed_scale

    if params is None or not runs or any(run.log is None for run in runs):
        return None
    observed = observed_scale(runs, params)
    for factor in _MIXUPS:
        if observed is not None and abs(observed / factor - 1.0) > OBSERVED_TOLERANCE:
            continue  # the ground truth's own path says it is not this factor
        scaled = replace(params, wheel_diameter=params.wheel_diameter * factor)
        try:
            again = [run.reintegrated(scaled) for run in runs]
            found = _estimate(method, again, wheelbase, scaled, None, square_side,
                              fit_truth_offset, None)  # fmt: skip
        except (ValueError, InputError):
            continue
        bench, E_s = found.benchmark, found.estimate.E_s
        comp = found.estimate.components
        holds = comp.get("rms_position", 0.0) <= _FIT_HOLDS[0]
        holds = holds and comp.get("rms_heading", 0.0) <= _FIT_HOLDS[1]
        if bench is not None and bench.e_max_syst <= _IDENTIFIED * found.test.side_length:
            how = f"the runs are squares a robot drives: E_max,syst {bench.e_max_syst * 1e3:.0f} mm"
        elif bench is None and E_s is not None and abs(E_s - 1.0) <= _IDENTIFIED and holds:
            how = f"the runs are fitted with E_s = {E_s:.3f}"
        else:
            continue
        times = {2.0: "twice", 0.5: "half"}.get(factor, f"{factor:g} times")
        said = f"read with {times} that, {how}"
        return diameter_mixup(factor, params.wheel_diameter, said)
    return None

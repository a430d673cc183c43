"""A calibration of sources: read them with the parameters that were active, estimate,
compose; what they hold decides how (a bag's scans with ``scan_topic``, motion intervals,
or runs, ``--method auto`` choosing among the estimators).

:func:`calibrate_sources` is what ``umbmark calibrate`` computes before it writes files or
records the history (:func:`umbmark.jobs.calibrate.calibrate`); ``umbmark report`` and the
self-calibration calibrate their passes with it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from umbmark.calibration.diameter import diameter_warnings
from umbmark.calibration.estimate import calibrate_runs, sessions_disagree
from umbmark.calibration.result import CalibrationResult, Without
from umbmark.core.bounds import check_square_geometry
from umbmark.core.errors import InputError, ProblemError, option
from umbmark.estimators.plausibility import judge_table
from umbmark.estimators.registry import (
    AUTO,
    CHOICES,
    DEFAULT,
    GYROS,
    INTERVALS,
    NAMES,
    SQUARE,
    find,
    names,
)
from umbmark.estimators.rows import FarRow, far_rows
from umbmark.runs.active import read_each
from umbmark.runs.read import (
    RunSource,
    SourceRuns,
    holds_gyro,
    is_bag,
    is_intervals,
    is_runs,
    pool_runs,
    source_name,
)
from umbmark.runs.read_options import ReadOptions

__all__ = ["calibrate_sources"]


def calibrate_sources(
    sources: Sequence[RunSource],
    options: ReadOptions,
    *,
    method: str | None = None,
    wheelbase: float | None = None,
    side_length: float | None = None,
    override_verdict: bool = False,
    fit_truth_offset: bool = False,
) -> CalibrationResult:
    """The calibration of ``sources`` (the keywords as :func:`umbmark.calibrate`'s).

    Raises
    ------
    InputError
        Bad options, a bad source, sources that disagree, a method that cannot
        calibrate what they hold.
    """
    _check_method(method, fit_truth_offset)
    result = _calibrate(
        sources, options, method, wheelbase, side_length,
        override_verdict=override_verdict, fit_truth_offset=fit_truth_offset,
    )  # fmt: skip
    return replace(result, forced=override_verdict)


def _check_method(method: str | None, fit_truth_offset: bool) -> None:
    if method is not None and method not in CHOICES:
        raise InputError(
            f"{option('method', repr(method))}: use one of {', '.join(NAMES)} or {AUTO}"
        )
    fitting = names(trajectories=True)
    if fit_truth_offset and method not in fitting:
        raise InputError(
            f"{option('fit_truth_offset')} needs {option('method', ' or '.join(fitting))}, not "
            f"{method or DEFAULT.name}"
        )


def _calibrate(
    sources: Sequence[RunSource],
    read_options: ReadOptions,
    method: str | None,
    wheelbase: float | None,
    side_length: float | None,
    *,
    override_verdict: bool,
    fit_truth_offset: bool,
) -> CalibrationResult:
    """The calibration of the sources by what they hold: a bag's gyro (with its scans),
    a bag's scans, motion intervals, or runs (with the note of ``auto``'s choice)."""
    gyro = method in GYROS and all(is_bag(s, read_options) for s in sources)
    if read_options.imu_topic is not None or gyro:
        return _calibrate_gyro(sources, read_options, method, wheelbase, side_length)
    if read_options.scan_topic is not None:
        return _calibrate_scans(sources, read_options, method, wheelbase, side_length)
    if any(is_intervals(s, read_options) for s in sources) or method in INTERVALS:
        return _calibrate_intervals(sources, read_options, method or AUTO, wheelbase, side_length)
    result, note, nominal_best = _calibrate_runs(
        sources, read_options, method or DEFAULT.name, wheelbase, side_length,
        override_verdict=override_verdict, fit_truth_offset=fit_truth_offset,
    )  # fmt: skip
    result = replace(result, nominal_best=nominal_best)
    return result if note is None else replace(result, notes=(*result.notes, note))


def _calibrate_intervals(
    sources: Sequence[RunSource],
    options: ReadOptions,
    method: str,
    wheelbase: float | None,
    side_length: float | None,
) -> CalibrationResult:
    """A calibration of tuple files by an estimator of motion intervals (``auto`` takes
    the first)."""
    from umbmark.calibration.scan import calibrate_intervals

    if method not in (*INTERVALS, AUTO):
        raise InputError(
            "motion intervals (tuple files) are calibrated by "
            f"{option('method', ' or '.join(INTERVALS))}, not {method}"
        )
    if not all(is_intervals(s, options) for s in sources):
        raise InputError(
            f"{option('method', method)} calibrates motion intervals (tuple files; "
            "docs/formats.md), "
            "not runs"
        )
    chosen = INTERVALS[0] if method == AUTO else method
    paths = [Path(source_name(s)) for s in sources]
    return calibrate_intervals(paths, options, chosen, wheelbase=wheelbase, side_length=side_length)


def _calibrate_gyro(
    sources: Sequence[RunSource],
    options: ReadOptions,
    method: str | None,
    wheelbase: float | None,
    side_length: float | None,
) -> CalibrationResult:
    """A calibration of a bag's wheels against its gyro (``--imu-topic``; with
    ``--scan-topic``, its laser's scan matching the gyro's reference)."""
    from umbmark.calibration.gyro_bag import calibrate_gyro_bags

    if method is not None and method not in (*GYROS, AUTO):
        raise InputError(
            f"{option('imu_topic')} calibrates by {option('method', ' or '.join(GYROS))} (the "
            f"default with it), not {method}: leave {option('imu_topic')} out to calibrate "
            f"by {method}"
        )
    for source in sources:
        if not holds_gyro(source, options) and options.imu_topic is not None:
            raise InputError(
                f"{option('imu_topic')} reads a bag's IMU: {source_name(source)} is not a bag"
            )
    paths = [Path(source_name(s)) for s in sources]
    return calibrate_gyro_bags(paths, options, wheelbase=wheelbase, side_length=side_length).result


def _calibrate_scans(
    sources: Sequence[RunSource],
    options: ReadOptions,
    method: str | None,
    wheelbase: float | None,
    side_length: float | None,
) -> CalibrationResult:
    """A calibration of bags' wheels against their laser's scan matching (``--scan-topic``)."""
    from umbmark.calibration.scan import calibrate_scan_bags
    from umbmark.runs.read import is_runs

    if method is not None and method not in (*INTERVALS, AUTO):
        raise InputError(
            f"{option('scan_topic')} calibrates by {option('method', ' or '.join(INTERVALS))} "
            f"(the default with it), not {method}"
        )
    if any(is_runs(s) for s in sources):
        raise InputError(f"{option('scan_topic')} reads bags, not runs in memory")
    chosen = INTERVALS[0] if method in (None, AUTO) else method
    paths = [Path(source_name(s)) for s in sources]
    return calibrate_scan_bags(paths, options, chosen, wheelbase=wheelbase, side_length=side_length)


def _calibrate_runs(
    sources: Sequence[RunSource],
    read_options: ReadOptions,
    method: str,
    wheelbase: float | None,
    side_length: float | None,
    *,
    override_verdict: bool,
    fit_truth_offset: bool,
) -> tuple[CalibrationResult, str | None, bool]:
    """A calibration of runs: the result, a note on the method chosen, and whether
    ``auto`` found the nominal parameters best."""
    entry = find(method)
    if side_length is None and entry is not None and entry.side_required:
        from umbmark.runs.read import is_table

        if any(is_table(s, read_options) for s in sources):
            raise InputError(
                f"{option('side_length')} is required: the side of the square path, in metres"
            )
    each = [
        judge_table(one, read_options.unit, read_options.angle_unit, side_length)
        if not is_runs(source) and one.formats == ("table",)
        else one
        for source, one in zip(
            sources,
            read_each(
                sources,
                read_options,
                wheelbase=wheelbase,
                side_length=side_length,
                override_verdict=override_verdict,
                stretches=method == AUTO or (entry is not None and entry.needs == "logs"),
            ),
            strict=True,
        )
    ]
    far = [
        row
        for source, one in zip(sources, each, strict=True)
        if not is_runs(source) and one.formats == ("table",)
        for row in far_rows(one.runs, read_options.unit)
    ]
    read = each[0] if len(each) == 1 else pool_runs(each)
    if any(run.kind == "square" for run in read.runs):
        active = read.active
        check_square_geometry(
            read.side_length, active.effective_wheelbase, read.origins, active.separation_multiplier
        )
    chosen, note, nominal_best = method, None, False
    if method == AUTO:
        from umbmark.calibration.auto import auto_method

        chosen, note, nominal_best = auto_method(each, read)
    wheels = diameter_warnings(read) if chosen in SQUARE else []  # E_s unobserved
    warned = replace(read, notes=(*read.notes, *(row.warning() for row in far), *wheels))
    result = calibrate_runs(warned, chosen, fit_truth_offset=fit_truth_offset)
    if far:
        result = replace(result, without=_without(read, far, chosen))
    if chosen in names(trajectories=True) and len(read.parts) > 1:
        disagree = sessions_disagree(read.parts, fit_truth_offset=fit_truth_offset)
        result = replace(result, input_warnings=(*result.input_warnings, *disagree))
    return result, note, nominal_best


def _without(read: SourceRuns, far: Sequence[FarRow], method: str) -> Without | None:
    """The calibration of the runs without the rows ``far`` names (None where the rest
    cannot be calibrated: too few runs left)."""
    gone = {id(row.run) for row in far}
    kept = tuple(run for run in read.runs if id(run) not in gone)
    try:
        alone = calibrate_runs(replace(read, runs=kept), method)
    except (InputError, ProblemError, ValueError):
        return None
    est = alone.estimate
    rows = tuple(row.label for row in far)
    return Without(rows, alone.e_max_syst, est.E_d, est.E_b, alone.verdict.level)

"""A calibration from motion intervals: the wheels against a laser's own motion.

:func:`calibrate_intervals` runs an estimator of motion intervals (``needs="intervals"``
in :mod:`umbmark.estimators.registry`: the scan-matching calibration of Censi et al.
2013) on tuple files or intervals in memory, with the parameters active while they were
driven, and returns the same :class:`~umbmark.calibration.report.CalibrationResult` as a
calibration from runs: ``E_d``, ``E_b``, ``E_s``, the verdict, the overlay; and the
sensor's mounting (:attr:`CalibrationResult.sensor`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

from umbmark.calibration.active import check_calibration, choose_active
from umbmark.calibration.compose import Calibration
from umbmark.calibration.report import CalibrationResult
from umbmark.core.errors import InputError
from umbmark.core.messages import split_messages
from umbmark.estimators.base import SquareTest
from umbmark.estimators.registry import INTERVALS, estimator
from umbmark.model.active import ActiveParams
from umbmark.model.kinematics import WheelParams
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.runs.options import ReadOptions
from umbmark.runs.read import parameter_file

__all__ = ["IntervalSource", "calibrate_intervals", "read_intervals"]

IntervalSource = str | os.PathLike[str] | MotionIntervals


def read_intervals(sources: Sequence[IntervalSource]) -> MotionIntervals:
    """The motion intervals of tuple files (or in memory), pooled in order.

    Raises
    ------
    InputError
        For a file that is not a tuple file (its line and problem).
    """
    from umbmark.sources.tuples import read_tuples

    parts = [s if isinstance(s, MotionIntervals) else read_tuples(s) for s in sources]
    return parts[0] if len(parts) == 1 else MotionIntervals.concatenate(parts)


def calibrate_intervals(
    sources: Sequence[IntervalSource],
    options: ReadOptions,
    method: str,
    *,
    wheelbase: float | None = None,
    side_length: float | None = None,
) -> CalibrationResult:
    """The calibration of motion intervals by ``method`` (an estimator of intervals).

    Parameters
    ----------
    sources : sequence of path or MotionIntervals
        Tuple files (``docs/formats.md``) or intervals in memory; several are pooled.
    options : ReadOptions
        The active parameters: ``wheel_diameter`` (the nominal ``D_n`` [m], required:
        ``E_s`` is the diameters against it), ``current_params``, ``current_c_l``,
        ``current_c_r``, ``current_separation_multiplier``.
    method : str
        An estimator with ``needs="intervals"``.
    wheelbase : float, optional
        The wheelbase the odometry used [m] (else from ``current_params``).
    side_length : float, optional
        The square [m] ``alpha`` and ``beta`` are stated for (1 m by default).

    Raises
    ------
    InputError
        Unreadable intervals, a missing nominal parameter, or motion that does not excite
        the parameters (what to drive).
    """
    entry = estimator(method)
    if entry.needs != "intervals":
        raise InputError(f"motion intervals are calibrated by --method {' or '.join(INTERVALS)}")
    names = [os.fspath(s) if not isinstance(s, MotionIntervals) else s.source for s in sources]
    where = names[0] if len(names) == 1 and names[0] else None
    intervals = read_intervals(sources)
    file = parameter_file(options)
    chosen = choose_active(options, file, wheelbase, None)
    if chosen.wheelbase is None:
        raise InputError(
            "--wheelbase is required: the wheelbase the odometry used [m] (or --current-params)",
            source=where,
        )
    if chosen.wheel_diameter is None:
        raise InputError(
            "--wheel-diameter is required: the nominal wheel diameter D_n the odometry used "
            "[m] (or --current-params)",
            source=where,
        )
    active = ActiveParams(
        wheelbase=chosen.wheelbase,
        c_left=1.0 if chosen.c_left is None else chosen.c_left,
        c_right=1.0 if chosen.c_right is None else chosen.c_right,
        separation_multiplier=1.0 if chosen.separation is None else chosen.separation,
        wheel_diameter=chosen.wheel_diameter,
    )
    used = WheelParams(
        wheelbase=active.effective_wheelbase,
        wheel_diameter=chosen.wheel_diameter,
        c_left=active.c_left,
        c_right=active.c_right,
    )
    estimate, sensor = entry.load()(intervals, used, side_length, **dict(entry.options))
    calibration = Calibration(estimate, active)
    check_calibration(calibration, chosen.origins)
    notes, warnings = split_messages(chosen.notes)
    return CalibrationResult(
        sources=tuple(n or "intervals" for n in names),
        format="tuples",
        runs=(),
        benchmark=None,
        test=SquareTest(side_length or 1.0, active.effective_wheelbase),
        calibration=calibration,
        controller=file,
        notes=notes,
        input_warnings=warnings,
        sensor=sensor,
    )

"""A calibration from motion intervals: the wheels against a laser's own motion.

:func:`calibrate_intervals` runs an estimator of motion intervals (``needs="intervals"``
in :mod:`umbmark.estimators.registry`: the scan-matching calibration of Censi et al.
2013) on tuple files or intervals in memory, with the parameters active while they were
driven, and returns the same :class:`~umbmark.calibration.result.CalibrationResult` as a
calibration from runs: ``E_d``, ``E_b``, ``E_s``, the verdict, the overlay; and the
sensor's mounting (:attr:`CalibrationResult.sensor`). :func:`calibrate_scan_bags` does
the same from bags: the laser's sweeps and the wheels read, matched into intervals, and
calibrated.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.calibration.compose import Calibration, check_calibration
from umbmark.calibration.result import CalibrationResult
from umbmark.core.errors import InputError, option
from umbmark.core.messages import info, split_messages
from umbmark.estimators.base import SquareTest
from umbmark.estimators.registry import INTERVALS, Estimator, estimator
from umbmark.model.active import ActiveParams
from umbmark.model.kinematics import WheelParams
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.scans import LaserMounting
from umbmark.options.spec import WHEELBASE
from umbmark.runs.active import choose_active
from umbmark.runs.read import Chosen, bag_options, check_invertible, parameter_file
from umbmark.runs.read_options import ReadOptions
from umbmark.sources.params.reader import ControllerParams

if TYPE_CHECKING:
    from umbmark.scans.intervals import IntervalReport, OdometryGuess

__all__ = [
    "IntervalSource",
    "bag_guess",
    "calibrate_intervals",
    "calibrate_scan_bags",
    "no_intervals",
    "read_intervals",
    "scan_report",
]

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
    entry = _interval_estimator(method)
    names = [os.fspath(s) if not isinstance(s, MotionIntervals) else s.source for s in sources]
    where = names[0] if len(names) == 1 and names[0] else None
    intervals = read_intervals(sources)
    file = parameter_file(options)
    chosen = choose_active(options, file, wheelbase, None)
    return _calibrate(
        intervals, entry, chosen, file, tuple(n or "intervals" for n in names), where,
        "tuples", side_length,
    )  # fmt: skip


def _interval_estimator(method: str) -> Estimator:
    entry = estimator(method)
    if entry.needs != "intervals":
        raise InputError(
            f"motion intervals are calibrated by {option('method', ' or '.join(INTERVALS))}"
        )
    return entry


def _calibrate(
    intervals: MotionIntervals,
    entry: Estimator,
    chosen: Chosen,
    file: ControllerParams,
    names: tuple[str, ...],
    where: str | None,
    format: str,
    side_length: float | None,
    notes: Sequence[str] = (),
    stated: LaserMounting | None = None,
) -> CalibrationResult:
    """The estimator ``entry`` on ``intervals`` with the active parameters ``chosen``;
    without a nominal wheelbase or wheel diameter, against the geometry it measures (the
    result's ``nominal`` False: absolute figures only)."""
    run = entry.load()
    nominal = chosen.wheelbase is not None and chosen.wheel_diameter is not None
    if not nominal:
        _, found = run(intervals, WheelParams(1.0, 1.0), side_length, **dict(entry.options))
        measured = found.radius_left + found.radius_right
        chosen = replace(
            chosen, wheelbase=found.wheelbase, wheel_diameter=measured, c_left=None,
            c_right=None, separation=None,
        )  # fmt: skip
        notes = [*notes, _ABSOLUTE]
    assert chosen.wheelbase is not None
    assert chosen.wheel_diameter is not None
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
    estimate, sensor = run(intervals, used, side_length, **dict(entry.options))
    if not nominal:  # against the measured geometry: E_b = E_s = 1 by construction
        errors = {k: v for k, v in estimate.standard_errors.items() if k not in _NOMINAL_ONLY}
        estimate = replace(estimate, E_s=None, standard_errors=errors)
    calibration = Calibration(estimate, active)
    check_calibration(calibration, chosen.origins)
    said, warnings = split_messages([*chosen.notes, *notes])
    return CalibrationResult(
        sources=names,
        format=format,
        runs=(),
        benchmark=None,
        test=SquareTest(side_length or 1.0, active.effective_wheelbase),
        calibration=calibration,
        controller=file,
        notes=said,
        input_warnings=warnings,
        sensor=sensor,
        stated_mounting=stated,
        nominal=nominal,
    )


#: The figures that say nothing without a nominal geometry.
_NOMINAL_ONLY = ("E_b", "E_s", "alpha")
#: The note of a calibration given no nominal geometry.
_ABSOLUTE = info(
    "no nominal geometry given (wheelbase and wheel diameter): the figures are absolute "
    "(the wheel diameters, the wheelbase, the laser's mounting and E_d = D_R / D_L); E_b, "
    "E_s and the multipliers need the nominal the odometry uses"
)


def calibrate_scan_bags(
    bags: Sequence[str | os.PathLike[str]],
    options: ReadOptions,
    method: str = INTERVALS[0],
    *,
    wheelbase: float | None = None,
    side_length: float | None = None,
) -> CalibrationResult:
    """The calibration of the wheels against a laser's scan matching, from bags.

    Each bag is read (the sweeps of ``options.scan_topic``, the wheels as the other
    reading options say: joint states, encoder ticks, fields, wheel transforms, or the
    controller's odometry turned back into wheel rotation), cut into motion intervals
    (:func:`umbmark.scans.bag.scan_intervals_from_bag`), pooled, and calibrated by
    ``method`` as :func:`calibrate_intervals` does. The nominal parameters: ``wheelbase``
    and ``options.wheel_diameter`` (or ``current_params``), else the bag's robot
    description; the first guess of every match is the nominal geometry with the
    laser's mounting from ``/tf_static``, else from the robot description (where the bag
    has either; a note says which).

    Raises
    ------
    InputError
        One line naming the bag: no or a wrong scan topic, no wheels, no nominal
        parameters, too few intervals, or motion that does not excite the parameters
        (what to drive).
    """
    entry = _interval_estimator(method)
    topic = options.scan_topic
    if not bags:
        raise InputError("no bag given: name the bag that holds the scans and the wheels")
    if topic is None:
        raise InputError(
            f"{option('scan_topic')} is required: the bag's sensor_msgs/LaserScan topic"
        )
    WHEELBASE.check(wheelbase)
    file = parameter_file(options)
    chosen = choose_active(options, file, wheelbase, None)
    paths = [Path(b) for b in bags]
    parts, notes = [], list[str]()
    stated: LaserMounting | None = None
    for path in paths:
        report, _, chosen = scan_report(path, options, file, chosen, notes)
        stated = stated or report.stated
        if len(report.intervals):
            parts.append(report.intervals)
    if not parts:
        raise no_intervals(topic, paths[0])
    intervals = parts[0] if len(parts) == 1 else MotionIntervals.concatenate(parts)
    where = str(paths[0]) if len(paths) == 1 else None
    try:
        return _calibrate(
            intervals, entry, chosen, file, tuple(map(str, paths)), where, "bag",
            side_length, notes, stated,
        )  # fmt: skip
    except InputError as error:
        if error.source is None and where is not None:
            raise InputError(error.problem, source=where) from None
        raise


def scan_report(
    path: Path, options: ReadOptions, file: ControllerParams, chosen: Chosen, notes: list[str]
) -> tuple[IntervalReport, WheelParams | None, Chosen]:
    """A bag's motion intervals against its laser (``options.scan_topic``), matched from
    the nominal geometry (given, else the bag's robot description: ``chosen`` with it),
    and the geometry its wheels were read with; what was found and left out appended to
    ``notes``.

    Raises
    ------
    InputError
        As :func:`calibrate_scan_bags`.
    """
    from umbmark.scans.bag import scan_intervals_from_bag
    from umbmark.scans.intervals import IntervalOptions

    topic = options.scan_topic
    assert topic is not None
    name = str(path)
    guess, used, chosen = bag_guess(path, options, file, chosen, notes)
    report = scan_intervals_from_bag(
        path, topic, bag_options(options, used, file), IntervalOptions(guess=guess),
        tf_mounting=True,
    )  # fmt: skip
    notes += report.notes
    notes += _guess_given_up(name, topic, report)
    kept = len(report.intervals)
    dropped = ", ".join(f"{n} {why}" for why, n in sorted(report.left_out.items()))
    notes.append(
        info(
            f"{name} {topic}: {kept} motion intervals matched of {report.tried}"
            + (f" (left out: {dropped})" if dropped else "")
        )
    )
    return report, used, chosen


def no_intervals(topic: str, path: Path) -> InputError:
    """The line where a laser's sweeps gave no motion interval."""
    return InputError(
        f"{topic}: no motion interval could be matched (the robot stood still, or the "
        "scans are of a corridor or open space): drive turns on the spot and straights "
        "where the laser sees walls",
        source=str(path),
    )


def _guess_given_up(name: str, topic: str, report: IntervalReport) -> list[str]:
    """The warning where the matches' first guess, the nominal geometry, was given up
    (:attr:`~umbmark.scans.intervals.IntervalReport.guess_off`)."""
    if report.guess_off is None or report.lost is None:
        return []
    straight, turning = report.guess_off
    lost, moving = report.lost
    return [
        f"{name} {topic}: the matches started from the nominal geometry lost {lost} of "
        f"{moving} moving intervals; matched from the sweeps alone, the laser moves "
        f"{straight:.3g} times as far per wheel rotation as the nominal wheel diameter "
        f"says, and turns {turning:.3g} times as far as it and the nominal wheelbase say: "
        "the nominal geometry is far off (the figures below are against it)"
    ]


def bag_guess(
    path: Path, options: ReadOptions, file: ControllerParams, chosen: Chosen, notes: list[str]
) -> tuple[OdometryGuess | None, WheelParams | None, Chosen]:
    """The first guess of a bag's matches, the geometry its wheels are read with and the
    active parameters with it: the nominal given, else the bag's robot description's (a
    note in ``notes`` says so), else none (the matches start from the scans alone; wheels
    read as odometry need one)."""
    from umbmark.scans.intervals import OdometryGuess
    from umbmark.sources.bag.urdf import described_geometry

    configured, diameter = chosen.wheelbase, chosen.wheel_diameter
    if configured is None or diameter is None:
        joints = bag_options(options, None, file)
        try:
            configured, diameter, described = described_geometry(
                path, joints.left_joints, joints.right_joints, configured, diameter
            )
        except InputError:
            if options.odom_topic is not None or options.odom_tf is not None:
                raise
            return None, None, chosen
        notes.append(described)
        chosen = replace(chosen, wheelbase=configured, wheel_diameter=diameter)
    c_left = 1.0 if chosen.c_left is None else chosen.c_left
    c_right = 1.0 if chosen.c_right is None else chosen.c_right
    separation = 1.0 if chosen.separation is None else chosen.separation
    used = WheelParams(
        wheelbase=configured * separation, wheel_diameter=diameter, c_left=c_left, c_right=c_right
    )
    if options.odom_topic is not None or options.odom_tf is not None:
        check_invertible(file, str(path))
    radius = 0.5 * diameter
    return OdometryGuess(c_left * radius, c_right * radius, used.wheelbase), used, chosen

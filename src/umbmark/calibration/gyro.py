"""A recording's wheels calibrated with its gyro, and the gyro with them.

:func:`calibrate_gyro` cuts a recording's wheels and gyro into rests and driving
(:func:`umbmark.scans.gyro_intervals.gyro_intervals`), runs the ``gyro`` estimator of
:mod:`umbmark.estimators.registry` (:mod:`umbmark.estimators.gyro`) with the parameters
active while they were recorded, with an absolute heading reference where the recording
has one (scan matching's motion intervals, motion capture's heading changes), and returns
a :class:`GyroResult`: the :class:`~umbmark.calibration.result.CalibrationResult` every
calibration gives (``E_d``, ``E_b``, ``E_s`` where determined, the verdict, the overlay)
and the gyro's own calibration (its scale ``k_g``, its bias, the IMU's mounting as the
readings show it). Without a reference ``E_b`` is relative to the gyro (``E_b k_g``), its
interval widened by ``options.gyro_scale_tolerance``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from umbmark.calibration.compose import Calibration, check_calibration
from umbmark.calibration.result import CalibrationResult
from umbmark.core.errors import InputError, option
from umbmark.core.messages import split_messages
from umbmark.estimators.base import SquareTest
from umbmark.estimators.registry import GYRO, GYROS, estimator
from umbmark.model.active import ActiveParams
from umbmark.model.kinematics import WheelParams
from umbmark.options.spec import WHEELBASE
from umbmark.runs.active import choose_active
from umbmark.runs.read import parameter_file
from umbmark.scans.gyro_intervals import (
    DEFAULT_GYRO_OPTIONS,
    GyroIntervalOptions,
    HeadingReference,
    gyro_intervals,
    gyro_reference,
)

if TYPE_CHECKING:
    from umbmark.calibration.verdict import Verdict
    from umbmark.core.arrays import FloatArray
    from umbmark.estimators.gyro import GyroCalibration
    from umbmark.model.gyro_series import GyroSeries
    from umbmark.model.motion_intervals import MotionIntervals
    from umbmark.model.recording import WheelSeries
    from umbmark.model.scans import LaserMounting
    from umbmark.runs.read_options import ReadOptions

__all__ = ["GyroResult", "calibrate_gyro", "gyro_lines"]


@dataclass(frozen=True)
class GyroResult:
    """A calibration of the wheels with a gyro, and the gyro's own.

    Attributes
    ----------
    result : CalibrationResult
        The wheels' calibration (its verdict: :attr:`verdict`).
    gyro : GyroCalibration
        The gyro's scale and bias, the figures each with its standard error, what is not
        determined, the IMU's mounting found.
    """

    result: CalibrationResult
    gyro: GyroCalibration

    @property
    def verdict(self) -> Verdict:
        """The result's :class:`~umbmark.calibration.verdict.Verdict`."""
        return self.result.verdict

    def to_dict(self) -> dict[str, Any]:
        """The result's JSON with the gyro's calibration under ``gyro_calibration``."""
        return {**self.result.to_dict(), "gyro_calibration": self.gyro.to_dict()}


def gyro_lines(gyro: GyroCalibration) -> list[str]:
    """The gyro's figures for people, each with its unit and what it is for."""
    v, se = gyro.values, gyro.standard_errors
    out: list[str] = []
    if "k_g" in v:
        out.append(
            f"gyro scale k_g = {v['k_g']:.5f} +- {se['k_g']:.5f} (omega_true = k_g "
            "(omega_read - bias): multiply the gyro's rates by it, a driver's gyro scale)"
        )
    if "bias" in v:
        out.append(
            f"gyro bias = {math.degrees(v['bias']):.4f} +- {math.degrees(se['bias']):.4f} deg/s "
            f"({v['bias']:.3e} rad/s; mean over the recording): subtract it from the yaw rate "
            "(a driver's gyro offset)"
        )
    if "E_b_k_g" in v and "k_g" not in v:
        out.append(
            f"E_b k_g = {v['E_b_k_g']:.5f} +- {se['E_b_k_g']:.5f}: the wheelbase relative to the "
            f"gyro (its scale known to +-{100 * gyro.scale_tolerance:g} %)"
        )
    for name, why in gyro.undetermined.items():
        out.append(f"{name} not determined: {why}")
    return out


def calibrate_gyro(
    wheels: WheelSeries,
    gyro: GyroSeries,
    options: ReadOptions,
    *,
    wheelbase: float | None = None,
    side_length: float | None = None,
    reference: HeadingReference | MotionIntervals | None = None,
    stated: FloatArray | None = None,
    source: str | None = None,
    format: str = "bag",
    notes: Sequence[str] = (),
    stated_mounting: LaserMounting | None = None,
    cut: GyroIntervalOptions = DEFAULT_GYRO_OPTIONS,
) -> GyroResult:
    """The wheels calibrated with the gyro (the module's documentation).

    Parameters
    ----------
    wheels : WheelSeries
        The wheels' cumulative angles over time.
    gyro : GyroSeries
        The gyro's rates in the base frame (its accelerations too, for the tilt at rest).
    options : ReadOptions
        The active parameters (``wheel_diameter`` and the wheelbase required, or
        ``current_params``; ``current_c_l``, ``current_c_r``,
        ``current_separation_multiplier``) and ``gyro_scale_tolerance``.
    wheelbase : float, optional
        The wheelbase the odometry used [m] (else from ``current_params``).
    side_length : float, optional
        The square [m] ``alpha`` and ``beta`` are stated for (1 m by default).
    reference : HeadingReference or MotionIntervals, optional
        An absolute heading reference over the same recording: heading changes (motion
        capture, corner fixes), or scan matching's motion intervals with their start
        times (heading and distance: ``E_s`` and the laser's mounting too).
    stated : array, shape (3, 3), optional
        The rotation ``base <- imu`` the gyro's rates were put in the base frame with.
    source : str, optional
        The recording, for messages and the result (else the gyro's source).
    format : str
        The recording's format, for the result.
    notes : sequence of str
        What reading the recording said (information and warnings).
    stated_mounting : LaserMounting, optional
        The laser's stated mounting, for a scan-matching reference.
    cut : GyroIntervalOptions
        How the recording is cut into intervals.

    Raises
    ------
    InputError
        One line naming the recording: no nominal wheelbase or wheel diameter, the gyro
        and the wheels not overlapping, too few intervals, a reference without times.
    """
    where = source or gyro.source or None
    WHEELBASE.check(wheelbase)
    file = parameter_file(options)
    chosen = choose_active(options, file, wheelbase, None)
    if chosen.wheelbase is None or chosen.wheel_diameter is None:
        missing = [
            option(name)
            for name, value in (
                ("wheelbase", chosen.wheelbase),
                ("wheel_diameter", chosen.wheel_diameter),
            )
            if value is None
        ]
        raise InputError(
            "the gyro calibration needs the odometry's nominal geometry: give "
            f"{' and '.join(missing)} (or {option('current_params')})",
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
    entry = estimator(GYRO.name)
    assert entry.name in GYROS
    try:
        intervals = gyro_intervals(wheels, gyro, cut)
        ref = None if reference is None else gyro_reference(gyro, reference)
        estimate, found = entry.load()(
            intervals, used, side_length, reference=ref,
            scale_tolerance=options.gyro_scale_tolerance, stated=stated,
        )  # fmt: skip
    except InputError as error:
        raise InputError(error.problem, source=error.source or where) from None
    except ValueError as exc:
        raise InputError(f"gyro calibration: {exc}", source=where) from None
    calibration = Calibration(estimate, active)
    check_calibration(calibration, chosen.origins)
    said, warnings = split_messages([*chosen.notes, *notes, *_left_out(intervals.left_out)])
    result = CalibrationResult(
        sources=(where or "recording",),
        format=format,
        runs=(),
        benchmark=None,
        test=SquareTest(side_length or 1.0, active.effective_wheelbase),
        calibration=calibration,
        controller=file,
        notes=said,
        input_warnings=warnings,
        sensor=found.scan,
        stated_mounting=stated_mounting,
    )
    return GyroResult(result, found)


def _left_out(left: dict[str, int]) -> list[str]:
    """The line of the intervals left out: a warning where the gyro saturated (turns
    faster than its range), information otherwise."""
    from umbmark.core.messages import info

    if not left:
        return []
    said = "gyro intervals left out: " + ", ".join(f"{n} {why}" for why, n in sorted(left.items()))
    if "gyro saturated" in left:
        return [f"{said}: the gyro's range was exceeded in fast turns; turn slower"]
    return [info(said)]

"""A recording's wheels calibrated with its gyro, and the gyro with them.

:func:`calibrate_gyro` cuts a recording's wheels and gyro into rests and driving
(:func:`umbmark.scans.gyro_intervals.gyro_intervals`), runs the ``gyro`` estimator of
:mod:`umbmark.estimators.registry` (:mod:`umbmark.estimators.gyro`) with the parameters
active while they were recorded, with an absolute heading reference where the recording
has one (scan matching's motion intervals, motion capture's heading changes), and returns
a :class:`GyroResult`: the :class:`~umbmark.calibration.result.CalibrationResult` every
calibration gives (``E_d``, ``E_b``, ``E_s`` where determined, the verdict, the overlay)
and the gyro's own calibration (its scale ``k_g``, its bias, the IMU's mounting as the
readings show it), the latter also as :attr:`CalibrationResult.gyro
<umbmark.calibration.result.CalibrationResult.gyro>`. Without a reference ``E_b`` is
relative to the gyro (``E_b k_g``), its interval widened by
``options.gyro_scale_tolerance``. A gyro that saturated in the recording's turns is
refused (its clipped turns, and the readings around them, read short): one line saying
how fast it turned and what to do.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
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
    SATURATED,
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
    from umbmark.runs.read import Chosen
    from umbmark.runs.read_options import ReadOptions

__all__ = ["GyroResult", "calibrate_gyro", "gyro_lines", "refuse_saturated"]


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
        """The result's JSON (the gyro's calibration under ``gyro_calibration``)."""
        return self.result.to_dict()


def _interval(gyro: GyroCalibration, name: str, scale: float, fmt: str) -> str:
    found = gyro.interval(name)
    if found is None:
        return ""
    low, high = found
    return f" (95 %: {format(low * scale, fmt)} to {format(high * scale, fmt)})"


#: What each reference makes of the gyro, for people.
_AGAINST = {
    "no reference": "the wheels alone",
    "heading changes": "the wheels and an absolute heading",
    "scan matching": "the wheels and the laser's scan matching",
}


def gyro_lines(gyro: GyroCalibration) -> list[str]:
    """The gyro's figures for people, each with its unit, its 95 % interval and where it
    goes (``docs/reading-results.md`` names the drivers' parameters), what is not
    determined and why, and the IMU frame's origin where its turns show a tilt its
    stated transform misses; the first line says what the gyro was calibrated against."""
    v, se = gyro.values, gyro.standard_errors
    out = [f"Gyro ({gyro.mounting.frame}), against {_AGAINST.get(gyro.reference, gyro.reference)}:"]
    if "k_g" in v:
        out.append(
            f"scale k_g = {v['k_g']:.5f} ± {se['k_g']:.5f}{_interval(gyro, 'k_g', 1.0, '.5f')}"
            ": omega_true = k_g (omega_read - bias); a driver that scales its rates: its "
            "gyro scale times k_g"
        )
    if "bias" in v:
        deg = 180.0 / math.pi
        out.append(
            f"bias = {v['bias'] * deg:.4f} ± {se['bias'] * deg:.4f} deg/s"
            f"{_interval(gyro, 'bias', deg, '.4f')} ({v['bias']:.3e} rad/s, its mean over the "
            "recording): subtract it from the yaw rate (a driver's gyro offset; most drivers "
            "measure it themselves while the robot stands still)"
        )
    if "E_b_k_g" in v and "k_g" not in v:
        out.append(
            f"E_b k_g = {v['E_b_k_g']:.5f} ± {se['E_b_k_g']:.5f}: the wheelbase relative to "
            f"the gyro (its scale known to ±{100 * gyro.scale_tolerance:g} %, "
            "--gyro-scale-tolerance), not E_b itself"
        )
    for name, why in gyro.undetermined.items():
        out.append(f"{name} not determined: {why}")
    return out + _mounting_lines(gyro)


def _mounting_lines(gyro: GyroCalibration) -> list[str]:
    """The IMU's tilt where its turns show one its stated transform misses."""
    mounting = gyro.mounting
    if not mounting.differs:
        return []
    out = mounting.notes(mounting.frame)
    apply = gyro.to_apply()
    found, stated, offset = (
        apply[k] for k in ("origin_rpy_found", "origin_rpy_stated", "rotation_offset")
    )
    if found is not None and stated is not None and offset is not None:
        out.append(
            f'{mounting.frame}\'s URDF joint origin: rpy="{_rpy(found)}" (stated: '
            f'"{_rpy(stated)}"; its yaw as stated, which the turns do not show) [rad]; or, '
            "keeping the stated transform, imu_sensor_broadcaster's rotation_offset roll, "
            f"pitch, yaw = {_rpy(offset)} [rad]"
        )
    return out


def _rpy(values: Sequence[float]) -> str:
    text = " ".join(f"{v:.5f}" for v in values)
    return text.replace("-0.00000", "0.00000")


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
    excluded: Mapping[str, FloatArray] | None = None,
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
    excluded : mapping of str to array, shape (k, 2), optional
        Stretches [s] the gyro's reader found it did not read, by reason (a frozen IMU:
        :attr:`umbmark.sources.bag.imu.ImuRead.frozen`; saturated ones where it found
        them): the intervals across them are left out.

    Raises
    ------
    InputError
        One line naming the recording: no nominal wheelbase or wheel diameter, the gyro
        and the wheels not overlapping, too few intervals, a reference without times, a
        gyro that saturated in the turns.
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
    active, used = _active_and_used(chosen, chosen.wheelbase, chosen.wheel_diameter)
    entry = estimator(GYRO.name)
    assert entry.name in GYROS
    try:
        intervals = gyro_intervals(wheels, gyro, cut, excluded=excluded)
        refuse_saturated(gyro, intervals.left_out.get(SATURATED, 0), _TURNS, where)
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
        gyro=found,
    )
    return GyroResult(result, found)


def _active_and_used(
    chosen: Chosen, wheelbase: float, wheel_diameter: float
) -> tuple[ActiveParams, WheelParams]:
    """The parameters active while the recording was made (``chosen``: the options' and
    the parameter file's, :func:`umbmark.runs.active.choose_active`, with its nominal
    ``wheelbase`` and ``wheel_diameter`` [m]), and the wheels the odometry integrated with
    them."""
    active = ActiveParams(
        wheelbase=wheelbase,
        c_left=1.0 if chosen.c_left is None else chosen.c_left,
        c_right=1.0 if chosen.c_right is None else chosen.c_right,
        separation_multiplier=1.0 if chosen.separation is None else chosen.separation,
        wheel_diameter=wheel_diameter,
    )
    used = WheelParams(
        wheelbase=active.effective_wheelbase,
        wheel_diameter=wheel_diameter,
        c_left=active.c_left,
        c_right=active.c_right,
    )
    return active, used


#: What a calibration's saturated count is of.
_TURNS = "interval(s) of the turns"


def refuse_saturated(gyro: GyroSeries, count: int, what: str, where: str | None) -> None:
    """Refuse a gyro that saturated (``count`` of ``what``: the intervals of the turns
    across a stretch :func:`umbmark.model.gyro_series.saturated_stretches` found, or the
    stretches themselves): the clipped readings read the turns short, and where a turn
    only touched the full scale the clipping is not seen. Nothing is calibrated, replayed
    or validated from it: the one refusal of a saturating gyro."""
    if not count:
        return
    peak = math.degrees(float(abs(gyro.rate).max()))
    raise InputError(
        f"the gyro saturates: an axis held at its extreme reading ({peak:.1f} deg/s) in "
        f"{count} {what}, its full scale exceeded, so the turns read short: record again "
        f"turning slower than {0.8 * peak:.0f} deg/s, or set the gyro's range higher",
        source=where,
    )


def _left_out(left: dict[str, int]) -> list[str]:
    """The line of the intervals left out (information; a frozen IMU a warning)."""
    from umbmark.core.messages import info

    if not left:
        return []
    said = "gyro intervals left out: " + ", ".join(f"{n} {why}" for why, n in sorted(left.items()))
    if any("frozen" in why for why in left):
        return [f"{said}: the IMU repeated its readings exactly there (a driver that hung)"]
    return [info(said)]

"""The self-calibration anywhere with the robot's gyro: its pattern's wheels against the
gyro, and the gyro against the laser's own motion
(:func:`umbmark.calibration.gyro.calibrate_gyro`, the ``gyro`` estimator).

- **With a laser**: the motion intervals scan matching found
  (:func:`umbmark.routines.anywhere.pattern_intervals`) are the gyro's absolute heading
  reference: the gyro's scale ``k_g`` and bias, ``E_d``, ``E_b``, ``E_s`` and the laser's
  mounting, fitted together (:mod:`umbmark.estimators.gyro_scan`: at least as tight as
  scan matching alone).
- **Without a laser**: the wheels against the gyro alone. ``E_d`` does not depend on the
  gyro's scale; the wheelbase is found relative to it (``E_b k_g``), its interval widened
  by the gyro scale tolerance, and the result carries the warning :data:`GYRO_ONLY`, so
  that its verdict is "apply with care" at best: the gyro's scale error, 3 % for a MEMS
  part, goes whole into the wheelbase.

The result is composed with the parameters active during the drive and, with a robot's
name, refused for another robot and recorded in its history, as
:func:`umbmark.store.calibrations.calibrate_recorded` does for the tuple files.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.core.errors import InputError

if TYPE_CHECKING:
    from umbmark.calibration.gyro import GyroResult
    from umbmark.routines.anywhere import PatternRecording
    from umbmark.runs.read_fields import SourceOptions
    from umbmark.scans.intervals import IntervalReport

__all__ = ["GYRO_ONLY", "calibrate_pattern_gyro"]

#: The warning of a calibration against the gyro alone (said in the terminal, in the
#: result's warnings and on the page): its verdict is "apply with care" at best.
GYRO_ONLY = (
    "calibrated against the gyro alone (no laser): E_d does not depend on the gyro's "
    "scale, but the wheelbase does (E_b k_g), known only as well as the gyro's scale "
    "(--gyro-scale-tolerance): at best apply with care; a laser (or motion capture) "
    "separates the two"
)


def calibrate_pattern_gyro(
    recording: PatternRecording,
    matched: IntervalReport | None,
    *,
    tolerance: float,
    source: Path | None = None,
    robot: str | None = None,
    history: str | os.PathLike[str] | None = None,
    controller: str | None = None,
) -> GyroResult:
    """The pattern's wheels and gyro calibrated together (the module's documentation).

    Parameters
    ----------
    recording : PatternRecording
        One drive of the pattern, with the gyro's readings.
    matched : IntervalReport or None
        Its scan-matched motion intervals (None: the robot has no laser).
    tolerance : float
        The gyro scale tolerance (a fraction) without a laser.
    source : Path, optional
        The drive's file (its intervals), named in the result and the history.
    robot, history, controller
        As :func:`umbmark.store.calibrations.calibrate_recorded`.

    Raises
    ------
    InputError
        The recording has no gyro, or the calibration refuses it (one line).
    """
    from umbmark.calibration.gyro import GyroResult, calibrate_gyro
    from umbmark.runs.read_options import ReadOptions

    gyro, imu = recording.gyro, recording.imu
    if gyro is None or imu is None:
        raise InputError("the robot has no IMU: nothing to calibrate against a gyro")
    p = recording.params
    options: SourceOptions = {
        "wheel_diameter": 2.0 * p.wheel_radius,
        "current_c_l": p.left_wheel_radius_multiplier,
        "current_c_r": p.right_wheel_radius_multiplier,
        "current_separation_multiplier": p.wheel_separation_multiplier,
        "gyro_scale_tolerance": tolerance,
    }
    if controller is not None:
        options["controller"] = controller
    store, composed = None, None
    if robot is not None:
        from umbmark.store.history import History, compose_last_applied

        store = History(history)
        options, composed = compose_last_applied(store, robot, options)
    name = os.fspath(source) if source is not None else gyro.source
    found = calibrate_gyro(
        recording.wheels, gyro, ReadOptions.of(options),
        wheelbase=p.wheel_separation,
        reference=None if matched is None else matched.intervals,
        stated=imu.mounting.rotation, source=name, format="selfcal",
        notes=() if matched is not None else (GYRO_ONLY,),
        stated_mounting=recording.stated,
    )  # fmt: skip
    result = found.result
    if store is not None and robot is not None:
        from umbmark.store.calibrations import recorded, same_robot

        result = same_robot(replace(result, robot=robot), store, robot, composed)
        result = recorded(result, store, robot, [name], False)
    return GyroResult(result, found.gyro)

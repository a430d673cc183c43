"""A bag's wheels calibrated with its IMU's gyro (``--imu-topic``), and the gyro with them.

:func:`read_gyro_recording` reads what :func:`~umbmark.calibration.gyro.calibrate_gyro`
compares: the wheels (joint states, encoder ticks, fields, wheel transforms or the
controller's odometry turned back into wheel rotation, as the reading options say), the
gyro (:func:`umbmark.sources.bag.imu.read_imu`: its rates in the base frame by its
frame's mounting, with the stretches it could not have read), and an absolute heading
where the recording has one:

- the laser's scan matching (``scan_topic``): its motion intervals
  (:func:`umbmark.calibration.scan.scan_report`), which give distance too, so ``E_s`` and
  the laser's mounting;
- else a ground truth that measures headings (``truth_topic``, or ``tf_parent`` and
  ``tf_child``: motion capture): its heading changes over pieces of :data:`PIECE`.

:func:`calibrate_gyro_bags` is what :func:`~umbmark.calibration.sources.calibrate_sources`
runs for ``imu_topic`` (or ``method="gyro"`` on a bag with one IMU): one recording at a
time, its gyro's bias and its wheels on one clock.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from umbmark.calibration.scan import bag_guess, no_intervals, scan_report
from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError, option
from umbmark.core.messages import info
from umbmark.runs.active import choose_active
from umbmark.runs.read import bag_options, parameter_file
from umbmark.scans.gyro_intervals import SATURATED, HeadingReference

if TYPE_CHECKING:
    from umbmark.calibration.gyro import GyroResult
    from umbmark.model.motion_intervals import MotionIntervals
    from umbmark.model.recording import PoseSeries, WheelSeries
    from umbmark.model.scans import LaserMounting
    from umbmark.runs.read_options import ReadOptions
    from umbmark.sources.bag.imu import ImuRead
    from umbmark.sources.params.reader import CalibratedParams

__all__ = [
    "PIECE",
    "GyroRecording",
    "calibrate_gyro_bags",
    "gyro_figures",
    "gyro_heading_errors",
    "heading_reference",
    "imu_topic_of",
    "read_gyro_recording",
]

#: A ground truth's heading changes are taken over pieces this long [s].
PIECE = 1.0


@dataclass(frozen=True)
class GyroRecording:
    """A bag's wheels and gyro as :func:`read_gyro_recording` read them.

    Attributes
    ----------
    path : str
    options : ReadOptions
        The reading options, with the IMU topic found and the nominal geometry the bag's
        robot description gave where the options did not.
    wheelbase : float or None
        The nominal wheelbase [m] (given, or the description's).
    wheels : WheelSeries
    imu : ImuRead
    reference : HeadingReference or MotionIntervals or None
        The absolute heading of the same recording: scan matching's motion intervals, a
        ground truth's heading changes, or none.
    stated_mounting : LaserMounting or None
        The laser's stated mounting (with scan matching).
    notes : tuple of str
        What reading said (information and warnings).
    held_out : array, shape (k, 2)
        Stretches [s] left out (:meth:`without`).
    """

    path: str
    options: ReadOptions
    wheelbase: float | None
    wheels: WheelSeries
    imu: ImuRead
    reference: HeadingReference | MotionIntervals | None = None
    stated_mounting: LaserMounting | None = None
    notes: tuple[str, ...] = ()

    held_out: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def excluded(self) -> dict[str, FloatArray]:
        """The stretches the gyro's reader found it did not read, by reason (and those
        held out: :meth:`without`)."""
        out = {"gyro frozen": self.imu.frozen, SATURATED: self.imu.saturated}
        if self.held_out.size:
            out["held out"] = self.held_out
        return out

    def refuse_saturated(self) -> None:
        """Refuse the recording where its gyro saturated anywhere
        (:func:`umbmark.calibration.gyro.refuse_saturated`): what reads the gyro over
        whole runs (replay, validate) uses no stretch of it."""
        from umbmark.calibration.gyro import refuse_saturated

        saturated = self.imu.saturated
        refuse_saturated(self.imu.gyro, len(saturated), "stretch(es) of the recording", self.path)

    def without(self, spans: Sequence[tuple[float, float]]) -> GyroRecording:
        """The recording with the stretches ``spans`` [s] left out (a held-out run): of
        its intervals (:attr:`excluded`) and its reference's."""
        cut = np.array(spans, dtype=np.float64).reshape(-1, 2)
        reference = self.reference
        if isinstance(reference, HeadingReference):
            keep = np.ones(reference.start.shape, dtype=bool)
            for a, b in cut.tolist():
                keep &= ~((reference.start < b) & (reference.end > a))
            reference = HeadingReference(
                reference.start[keep], reference.end[keep], reference.yaw[keep],
                None if reference.variance is None else reference.variance[keep],
                reference.source,
            )  # fmt: skip
        elif reference is not None and reference.start_time is not None:
            start, end = reference.start_time, reference.start_time + reference.duration
            keep = np.ones(start.shape, dtype=bool)
            for a, b in cut.tolist():
                keep &= ~((start < b) & (end > a))
            reference = reference.rows(keep)
        held = np.concatenate([self.held_out, cut]) if self.held_out.size else cut
        return replace(self, reference=reference, held_out=held)

    def calibrate(self, side_length: float | None = None) -> GyroResult:
        """The wheels and the gyro calibrated together
        (:func:`~umbmark.calibration.gyro.calibrate_gyro`)."""
        from umbmark.calibration.gyro import calibrate_gyro

        return calibrate_gyro(
            self.wheels, self.imu.gyro, self.options, wheelbase=self.wheelbase,
            side_length=side_length, reference=self.reference,
            stated=self.imu.mounting.rotation, source=self.path, notes=self.notes,
            stated_mounting=self.stated_mounting, excluded=self.excluded,
        )  # fmt: skip


def imu_topic_of(path: str | os.PathLike[str], given: str | None) -> tuple[str, str | None]:
    """The IMU topic to read: ``given``, else the bag's one ``sensor_msgs/Imu`` topic
    (and the note saying so).

    Raises
    ------
    InputError
        None given and the bag holds none, or several (named).
    """
    if given is not None:
        return given, None
    from umbmark.sources.bag.msgtypes import IMU
    from umbmark.sources.bag.recording import bag_topics

    src = os.fspath(path)
    found = sorted(topic for topic, kind in bag_topics(src).items() if kind == IMU)
    if len(found) == 1:
        said = f"{option('imu_topic', found[0])}: the bag's one sensor_msgs/Imu topic"
        return found[0], info(said)
    if not found:
        raise InputError(
            f"{option('method', 'gyro')} needs an IMU: the bag holds no sensor_msgs/Imu topic",
            source=src,
        )
    raise InputError(
        f"{option('method', 'gyro')} needs {option('imu_topic')}: the bag holds "
        f"{len(found)} sensor_msgs/Imu topics ({', '.join(found)})",
        source=src,
    )


def heading_reference(truth: PoseSeries, source: str, piece: float = PIECE) -> HeadingReference:
    """A ground truth's heading changes over consecutive pieces of ``piece`` seconds
    (those across a gap in it left out), counter-clockwise positive, unwrapped."""
    from umbmark.model.recording import gap_mask

    time = truth.time
    heading = np.unwrap(truth.poses[:, 2])
    count = max(int((time[-1] - time[0]) // piece), 0)
    edges = time[0] + piece * np.arange(count + 1, dtype=np.float64)
    start, end = edges[:-1], edges[1:]
    gaps = gap_mask(time)
    where = np.flatnonzero(gaps)
    keep = np.ones(start.shape, dtype=bool)
    for k in where.tolist():
        keep &= ~((start < time[k + 1]) & (end > time[k]))
    start, end = start[keep], end[keep]
    yaw = np.interp(end, time, heading) - np.interp(start, time, heading)
    return HeadingReference(start, end, np.asarray(yaw), source=source)


def read_gyro_recording(
    path: str | os.PathLike[str], options: ReadOptions, wheelbase: float | None = None
) -> GyroRecording:
    """A bag's wheels, gyro and absolute heading (the module's documentation).

    Raises
    ------
    InputError
        One line naming the bag: no IMU topic or a wrong one, an IMU without gyro
        readings or frozen throughout, its frame without a transform, no wheels, no scan
        interval matched.
    """
    from umbmark.sources.bag.imu import check_against_wheels, read_imu
    from umbmark.sources.bag.recording import read_recording

    name = os.fspath(path)
    topic, found = imu_topic_of(path, options.imu_topic)
    options = replace(options, imu_topic=topic)
    notes: list[str] = [] if found is None else [found]
    file = parameter_file(options)
    chosen = choose_active(options, file, wheelbase, None)
    reference: HeadingReference | MotionIntervals | None = None
    stated = None
    if options.scan_topic is not None:
        report, used, chosen = scan_report(Path(name), options, file, chosen, notes)
        if not len(report.intervals):
            raise no_intervals(options.scan_topic, Path(name))
        reference, stated = report.intervals, report.stated
    else:
        _, used, chosen = bag_guess(Path(name), options, file, chosen, notes)
    bag = bag_options(options, used, file)
    read = read_recording(name, bag)
    notes += read.notes
    imu = read_imu(name, bag)
    notes += [*imu.notes, *check_against_wheels(imu, read.wheels)]
    if reference is None and read.truth is not None:
        if read.truth.headings:
            reference = heading_reference(read.truth, f"{name} ground truth")
            notes.append(info(f"{name}: the ground truth's heading is the gyro's reference"))
        else:
            notes.append(
                info(f"{name}: the ground truth has no headings: not the gyro's reference")
            )
    if options.wheel_diameter is None and file.wheel_radius is None:  # the description's
        options = replace(options, wheel_diameter=chosen.wheel_diameter)
    if wheelbase is None and file.wheel_separation is None:
        wheelbase = chosen.wheelbase
    return GyroRecording(
        name, options, wheelbase, read.wheels, imu, reference, stated, tuple(notes)
    )


def calibrate_gyro_bags(
    bags: Sequence[str | os.PathLike[str]],
    options: ReadOptions,
    *,
    wheelbase: float | None = None,
    side_length: float | None = None,
) -> GyroResult:
    """The calibration of a bag's wheels with its gyro (with its laser or its motion
    capture too, where the options name them).

    Raises
    ------
    InputError
        No bag or several (one recording at a time), and as :func:`read_gyro_recording`
        and :func:`~umbmark.calibration.gyro.calibrate_gyro`.
    """
    if len(bags) != 1:
        raise InputError(
            f"{option('imu_topic')} calibrates one recording at a time (its gyro's bias and "
            f"its wheels on one clock): give one bag, not {len(bags)}"
        )
    return read_gyro_recording(bags[0], options, wheelbase).calibrate(side_length)


def gyro_figures(params: CalibratedParams) -> tuple[float, float] | None:
    """The gyro's scale ``k_g`` and bias [rad/s] of a calibration's new parameters
    (``k_g`` 1 where it was not determined: wheels and gyro alone); None without a
    gyro's."""
    if params.gyro_bias is None:
        return None
    return (1.0 if params.gyro_scale is None else params.gyro_scale), params.gyro_bias


def gyro_heading_errors(
    path: str | os.PathLike[str],
    options: ReadOptions,
    spans: Sequence[tuple[float, float, float] | None],
    figures: tuple[float, float] | None,
) -> dict[str, tuple[float | None, ...]]:
    """Each run's true heading change less the gyro's over it [rad]: ``as read`` (its
    rates integrated as they are) and, with a calibration's ``figures`` (``k_g``,
    bias), ``calibrated`` (``k_g`` times the rates less the bias); None where the gyro
    did not read the whole run.

    Parameters
    ----------
    spans : sequence of (float, float, float) or None
        Each run's start and end [s, the recording's clock] and its true heading change
        [rad] (:meth:`umbmark.model.recording.RunLog.truth_turn`; None: no truth).

    Raises
    ------
    InputError
        As :func:`umbmark.sources.bag.imu.read_imu`; a gyro that saturated
        (:func:`umbmark.calibration.gyro.refuse_saturated`).
    """
    from umbmark.sources.bag.imu import read_imu

    name = os.fspath(path)
    topic, _ = imu_topic_of(path, options.imu_topic)
    read = read_imu(
        name, bag_options(replace(options, imu_topic=topic), None, parameter_file(options))
    )
    rows = np.array([s or (0.0, 0.0, np.nan) for s in spans], dtype=np.float64).reshape(-1, 3)
    start, end, truth = rows[:, 0], rows[:, 1], rows[:, 2]
    from umbmark.calibration.gyro import refuse_saturated

    refuse_saturated(read.gyro, len(read.saturated), "stretch(es) of the recording", name)
    usable = read.usable(start, end) & np.isfinite(truth)
    raw = np.full(start.shape, np.nan)
    if usable.any():
        raw[usable] = read.gyro.yaw_change(start[usable], end[usable])
    sets = {"as read": raw}
    if figures is not None:
        k_g, bias = figures
        sets["calibrated"] = k_g * (raw - bias * (end - start))
    return {
        key: tuple(
            None if not np.isfinite(v) else float(t - v) for t, v in zip(truth, values, strict=True)
        )
        for key, values in sets.items()
    }

"""Reading an IMU's gyro from a bag: ``sensor_msgs/Imu`` into a
:class:`umbmark.model.gyro_series.GyroSeries` in the robot's base frame.

:func:`read_imu` reads the topic ``BagOptions.imu_topic`` (``--imu-topic``) of a ROS 1
bag, a ROS 2 bag folder (sqlite3 or MCAP) or an MCAP file, within a window of the
recording where given (:func:`~umbmark.sources.bag.reader.open_bag`; the windows of
:func:`~umbmark.sources.bag.reader.time_windows`, the ones the wheels and the sweeps are
read in): a long recording is read one window at a time, its memory that of one window.
The messages are read by the byte-level decoder (:mod:`umbmark.sources.bag.fastpath`),
rosbags deserializing only those of another layout. The readings are rotated into the
base frame by the IMU frame's mounting (:mod:`umbmark.sources.bag.imu_frames`); they are
as the gyro gave them (scale error, bias and noise in them).

Time: the header stamps (``time_source="header"``), else the bag's receive times.

What is left out, each said in one line naming the bag and the topic (a warning where
the rest is usable, an :class:`~umbmark.core.errors.InputError` where nothing is):

- messages that say they have no angular velocity (``angular_velocity_covariance[0] ==
  -1``, the ROS convention); all of them: an IMU that gives only accelerations or an
  orientation, refused;
- readings that are not finite numbers (NaN);
- a stream whose angular velocity is exactly 0 in every message (an accelerometer-only
  stream), refused;
- messages that repeat an earlier stamp (the first kept, the later dropped, counted), and
  messages out of order (read in the order of their stamps, counted);
- gaps (:func:`umbmark.model.recording.gap_mask`): kept, named, in :attr:`ImuRead.gaps`;
- a frozen IMU (:func:`umbmark.model.gyro_series.frozen_stretches`: exactly the same three
  rates for at least :data:`FROZEN` seconds), in :attr:`ImuRead.frozen`; every reading
  the same: refused. :func:`check_against_wheels` says where the wheels turned meanwhile;
- a saturating gyro (:func:`umbmark.model.gyro_series.saturated_stretches`: one axis held at
  its extreme for :data:`SATURATED_RUN` readings in a row), in :attr:`ImuRead.saturated`.

Both rules are :mod:`umbmark.model.gyro_series`'s, the ones the gyro's intervals leave out by
(:func:`umbmark.scans.gyro_intervals.gyro_intervals`).

:meth:`ImuRead.usable` says which motion intervals cross none of these stretches.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray, IntArray
from umbmark.core.errors import InputError, option
from umbmark.model.gyro_series import (
    FROZEN,
    MIN_FULL_SCALE,
    SATURATED_RUN,
    GyroSeries,
    frozen_stretches,
    saturated_stretches,
)
from umbmark.model.recording import WheelSeries, gap_mask
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.fastpath import POSITION, Decoded, Sample, decode_messages, fast_layout
from umbmark.sources.bag.imu_frames import ImuMounting, imu_mounting
from umbmark.sources.bag.msgtypes import IMU, Imu
from umbmark.sources.bag.samples import seconds, time_ns

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = [
    "FROZEN",
    "MAX_SAMPLES",
    "MIN_FULL_SCALE",
    "SATURATED_RUN",
    "ImuRead",
    "check_against_wheels",
    "frozen_stretches",
    "read_gyro",
    "read_imu",
    "read_imu_topic",
    "read_imu_windows",
]

#: Readings held at most in one read (2.2 hours at 1 kHz, 11 hours at 200 Hz): more, and
#: the recording is read in windows.
MAX_SAMPLES = 8_000_000
#: Wheel rotation [rad] over a frozen stretch above which the wheels turned meanwhile.
_TURNING = 0.5
#: Stretches named in a message at most.
_NAMED = 3


@dataclass(frozen=True)
class ImuRead:
    """What :func:`read_imu` read.

    Attributes
    ----------
    gyro : GyroSeries
        The rates (and accelerations, where the IMU gives them) in the base frame.
    mounting : ImuMounting
        The IMU frame's rotation into the base frame, and where it was stated.
    topic : str
    notes : tuple of str
        Warnings: what was left out and what is doubtful (module notes), each naming the
        bag and the topic.
    gaps, frozen, saturated : array, shape (k, 2)
        Stretches ``[start, end]`` [s, the gyro's clock] with no readings, with frozen
        readings, with a saturated axis.
    dropped : dict of str to int
        Messages left out: ``no_gyro`` (covariance -1), ``not_finite``, ``repeated``
        (stamps), and ``reordered`` (read in stamp order, not left out).
    """

    gyro: GyroSeries
    mounting: ImuMounting
    topic: str
    notes: tuple[str, ...] = ()
    gaps: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    frozen: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    saturated: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    dropped: dict[str, int] | None = None

    def usable(self, start: FloatArray, end: FloatArray) -> BoolArray:
        """Which intervals ``[start, end]`` [s] (shape (k,)) the gyro measured: inside
        its readings, crossing no gap, frozen or saturated stretch, shape (k,)."""
        start, end = np.asarray(start, np.float64), np.asarray(end, np.float64)
        time = self.gyro.time
        ok = (start >= time[0]) & (end <= time[-1]) & (start <= end)
        bad = np.concatenate([self.gaps, self.frozen, self.saturated])
        for a, b in bad.tolist():
            ok &= ~((start < b) & (end > a))
        return np.asarray(ok)


def read_imu(
    path: str | Path, options: BagOptions, *, window: tuple[int, int] | None = None
) -> ImuRead:
    """The IMU ``options.imu_topic`` of the bag at ``path`` (the module's notes), within
    ``window`` (bag times [ns], from and before) where given, on the clock
    ``options.time_source`` says.

    Raises
    ------
    InputError
        No ``imu_topic``; the bag, the topic or its frame's mounting cannot be read; the
        messages hold no gyro readings (one line naming the bag, the topic and why).
    """
    src = str(path)
    topic = _imu_topic(options, src)
    with bag_reader.open_bag(Path(path), src, window) as reader:
        topics = bag_reader.topic_types(reader)
        return read_imu_topic(reader, topics, topic, src, header=options.time_source == "header")


def _imu_topic(options: BagOptions, src: str) -> str:
    """The IMU topic the options name; none is one line."""
    if options.imu_topic is None:
        raise InputError(
            f"reading a gyro needs {option('imu_topic')}: a sensor_msgs/Imu topic (umbmark "
            "info lists the bag's)",
            source=src,
        )
    return options.imu_topic


def read_imu_windows(path: str | Path, options: BagOptions, seconds: float) -> Iterator[ImuRead]:
    """:func:`read_imu` of each window of ``seconds`` of the bag
    (:func:`~umbmark.sources.bag.reader.reader_windows`), the bag opened once: the memory
    of one window, the time of one read. A window with no readings (a pause in the
    recording) is passed over; the error of the first such window is raised where no
    window has any.

    Raises
    ------
    InputError
        As :func:`read_imu`.
    """
    src = str(path)
    topic = _imu_topic(options, src)
    header = options.time_source == "header"
    failed: InputError | None = None
    read_any = False
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)
        windows = bag_reader.reader_windows(reader, seconds)
        for window in windows:
            try:
                read = read_imu_topic(bag_reader.windowed(reader, window), topics, topic, src,
                                      header=header)  # fmt: skip
            except InputError as err:
                if len(windows) == 1 or not _paused(err):
                    raise
                failed = failed or err
                continue
            read_any = True
            yield read
    if not read_any and failed is not None:
        raise failed


def _paused(err: InputError) -> bool:
    """Whether a window's error is a pause: no readings, or too few, in it."""
    return err.problem.endswith("has no messages") or "fewer than 2 readings" in err.problem


def read_gyro(
    path: str | Path, options: BagOptions, window: tuple[int, int] | None = None
) -> GyroSeries:
    """The gyro of :func:`read_imu` (its warnings left out: read them there)."""
    return read_imu(path, options, window=window).gyro


def read_imu_topic(
    reader: AnyReader, topics: dict[str, str], topic: str, src: str, *, header: bool = True
) -> ImuRead:
    """:func:`read_imu` of the open bag (``header``: stamp with the header stamps)."""
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (IMU,), "an IMU's readings", src
    )
    frame = _first_frame(reader, conns, msgtype, topic, src)
    scan = _decoded(reader, conns, msgtype, topic, src)
    where = f"{src}: {topic}:"
    values, stamps = scan.values, time_ns(scan, header)
    total = values.shape[0]
    dropped = {"no_gyro": 0, "not_finite": 0, "repeated": 0, "reordered": 0}
    no_gyro = values[:, 3] == -1.0
    if no_gyro.all():
        raise InputError(f"{topic}: {_no_gyro(values)}", source=src)
    finite = np.all(np.isfinite(values[:, :3]), axis=1)
    dropped["no_gyro"] = int(np.count_nonzero(no_gyro))
    dropped["not_finite"] = int(np.count_nonzero(~finite & ~no_gyro))
    keep = finite & ~no_gyro
    if not keep.any():
        raise InputError(
            f"{topic}: no message has angular velocities that are finite numbers", source=src
        )
    values, stamps = values[keep], stamps[keep]
    if not np.any(values[:, :3]):
        raise InputError(
            f"{topic}: the angular velocity is exactly 0 in every message: an "
            "accelerometer-only stream, no gyro readings",
            source=src,
        )
    stamps, values, dropped["reordered"], dropped["repeated"] = _ordered(stamps, values)
    if stamps.size < 2:
        hint = " (are the header stamps all equal? try --time-source bag)" if header else ""
        raise InputError(f"{topic}: fewer than 2 readings with distinct stamps{hint}", source=src)
    time = seconds(stamps)
    notes = _dropped_notes(where, dropped, total)
    origin = float(reader.start_time) * 1e-9
    origin = origin if abs(float(time[0]) - origin) < 86_400.0 else 0.0
    rates = values[:, :3]
    frozen = frozen_stretches(time, rates)
    if frozen.shape[0] == 1 and frozen[0, 0] == time[0] and frozen[0, 1] == time[-1]:
        raise InputError(
            f"{topic}: every reading is the same ({_rates(rates[0])}) from the first to the "
            f"last, {time[-1] - time[0]:.1f} s: a frozen IMU",
            source=src,
        )
    saturated = saturated_stretches(time, rates, frozen)
    gaps = _gaps(time)
    peak = float(np.max(np.abs(rates)))
    notes += _stretch_notes(where, gaps, frozen, saturated, peak, origin)
    mounting = imu_mounting(reader, topics, frame, topic, src)
    accel = values[:, 4:7]
    has_accel = bool(np.all(values[:, 7] != -1.0) and np.all(np.isfinite(accel)))
    gyro = GyroSeries(
        time=time,
        rate=rates @ mounting.rotation.T,
        accel=accel @ mounting.rotation.T if has_accel else None,
        frame=mounting.frame,
        source=f"{src} {topic}",
    )
    return ImuRead(gyro, mounting, topic, tuple(notes), gaps, frozen, saturated, dropped)


def _first_frame(
    reader: AnyReader, conns: list[Connection], msgtype: str, topic: str, src: str
) -> str:
    """The frame of the topic's first message (its readings' frame)."""
    stream = bag_reader.raw_messages(reader, conns, topic, src)
    try:
        for _, raw in stream:
            msg: Imu = bag_reader.deserialize(reader, raw, msgtype, topic, src)  # type: ignore[assignment]
            return str(msg.header.frame_id)
    finally:
        stream.close()
    raise InputError(f"topic {topic} has no messages", source=src)


def _decoded(
    reader: AnyReader, conns: list[Connection], msgtype: str, topic: str, src: str
) -> Decoded:
    """Every message's stamp and values (:data:`~umbmark.sources.bag.fastpath.IMU_VALUES`),
    at most :data:`MAX_SAMPLES` of them."""

    def bounded() -> Iterator[tuple[int, bytes]]:
        for k, item in enumerate(bag_reader.messages(reader, conns, topic, src)):
            if k >= MAX_SAMPLES:
                raise InputError(
                    f"{topic}: more than {MAX_SAMPLES:,} readings in one read: read the "
                    "recording in windows (umbmark.sources.bag.reader.time_windows)",
                    source=src,
                )
            yield item

    def decode(raw: bytes) -> list[Sample]:
        msg: Imu = bag_reader.deserialize(reader, raw, msgtype, topic, src)  # type: ignore[assignment]
        w, a = msg.angular_velocity, msg.linear_acceleration
        stamp = msg.header.stamp
        values = (float(w.x), float(w.y), float(w.z), float(msg.angular_velocity_covariance[0]),
                  float(a.x), float(a.y), float(a.z), float(msg.linear_acceleration_covariance[0]),
                  float(msg.orientation_covariance[0]))  # fmt: skip
        return [(int(stamp.sec), int(stamp.nanosec), values, POSITION)]

    scan = decode_messages(
        bounded(), ros2=bool(reader.is2), width=9, decode=decode, layout_of=fast_layout(msgtype)
    )
    if scan.messages == 0:
        raise InputError(f"topic {topic} has no messages", source=src)
    return scan


def _no_gyro(values: FloatArray) -> str:
    """Why a topic whose every message says it has no angular velocity is no gyro."""
    gives = [
        what
        for what, column in (("accelerations", 7), ("an orientation", 8))
        if np.any(values[:, column] != -1.0)
    ]
    given = " and ".join(gives) if gives else "neither accelerations nor an orientation"
    return (
        "every message says it has no angular velocity (angular_velocity_covariance[0] = -1): "
        f"this IMU gives {given}, no gyro readings"
    )


def _ordered(stamps: IntArray, values: FloatArray) -> tuple[IntArray, FloatArray, int, int]:
    """The readings in stamp order, each stamp once (the first of equal ones): stamps,
    values, how many arrived out of order, and how many repeated a stamp."""
    before = np.maximum.accumulate(stamps)
    reordered = int(np.count_nonzero(stamps[1:] < before[:-1]))
    order = np.argsort(stamps, kind="stable")
    stamps, values = stamps[order], values[order]
    time = seconds(stamps)
    keep = np.ones(stamps.size, np.bool_)
    keep[1:] = np.diff(time) > 0  # float seconds resolve 0.2 us: closer stamps are one
    return stamps[keep], values[keep], reordered, int(np.count_nonzero(~keep))


def _dropped_notes(where: str, dropped: dict[str, int], total: int) -> list[str]:
    texts = {
        "no_gyro": "say they have no angular velocity (angular_velocity_covariance[0] = -1): "
        "left out",
        "not_finite": "have angular velocities that are not finite numbers (NaN): left out",
        "repeated": "repeat an earlier message's stamp: dropped (the first of each stamp kept)",
        "reordered": "arrive out of order (stamped before a message received before them): "
        "read in the order of their stamps",
    }
    return [f"{where} {n:,} of {total:,} messages {texts[key]}" for key, n in dropped.items() if n]


def _gaps(time: FloatArray) -> FloatArray:
    """Stretches ``[start, end]`` [s] without readings (:func:`gap_mask`), shape (k, 2)."""
    at = np.flatnonzero(gap_mask(time))
    return np.column_stack([time[at], time[at + 1]])


def _rates(rates: FloatArray) -> str:
    return ", ".join(f"{math.degrees(float(v)):.4g}" for v in rates) + " deg/s"


def _stretch_notes(
    where: str,
    gaps: FloatArray,
    frozen: FloatArray,
    saturated: FloatArray,
    peak: float,
    origin: float,
) -> list[str]:
    """The warnings of the gaps, frozen and saturated stretches; times from ``origin``."""

    def named(stretches: FloatArray) -> str:
        shown = ", ".join(f"{a - origin:.2f} to {b - origin:.2f} s" for a, b in stretches[:_NAMED])
        more = len(stretches) - _NAMED
        return shown + (f" and {more} more" if more > 0 else "")

    clock = "of the recording" if origin else "(header stamps)"
    notes = []
    if len(gaps):
        longest = float(np.max(gaps[:, 1] - gaps[:, 0]))
        notes.append(
            f"{where} {len(gaps)} gap(s) without readings (longest {longest:.2f} s; "
            f"{named(gaps)} {clock}): the gyro's heading change across them is not measured"
        )
    if len(frozen):
        notes.append(
            f"{where} the IMU repeats exactly the same rates for {FROZEN:g} s or more "
            f"({named(frozen)} {clock}): frozen (a real gyro's noise changes every reading); "
            "those readings are left out"
        )
    if len(saturated):
        notes.append(
            f"{where} the gyro saturates: an axis held at its extreme reading (up to "
            f"{math.degrees(peak):.1f} deg/s) for {SATURATED_RUN} readings or more "
            f"({named(saturated)} {clock}), a rate beyond its full scale clipped: the turns "
            "there read too slow; left out"
        )
    return notes


def check_against_wheels(read: ImuRead, wheels: WheelSeries) -> tuple[str, ...]:
    """Warnings of an IMU read against the wheels of the same recording (on one clock):
    frozen stretches while the wheels turned, and readings that do not overlap the
    wheels' in time (another clock: try the other ``time_source``).

    Parameters
    ----------
    read : ImuRead
    wheels : WheelSeries
        The wheels' rotation [rad] over time [s].
    """
    where = f"{read.gyro.source}:"
    time = read.gyro.time
    if time[-1] < wheels.time[0] or time[0] > wheels.time[-1]:
        return (
            f"{where} the IMU's readings ({time[0]:.3f} to {time[-1]:.3f} s) do not overlap "
            f"the wheels' ({wheels.time[0]:.3f} to {wheels.time[-1]:.3f} s): another clock "
            f"(try {option('time_source', 'bag')})",
        )
    out = []
    for a, b in read.frozen.tolist():
        turned = [
            abs(float(np.interp(b, wheels.time, wheels.angles[:, k]))
                - float(np.interp(a, wheels.time, wheels.angles[:, k])))
            for k in range(2)
        ]  # fmt: skip
        if max(turned) > _TURNING:
            out.append(
                f"{where} the IMU reads the same rates for {b - a:.1f} s while the wheels "
                f"turn ({math.degrees(max(turned)):.0f} deg of wheel rotation): frozen, its "
                "readings there are left out"
            )
    return tuple(out)

"""Reading fixed-layout ROS messages straight from their bytes, checked against rosbags.

Why
---
rosbags' way to read a topic is a loop that deserializes every message into Python
objects and picks the wanted fields out of them, and deserialization dominates that loop.
Yet most messages of a wheel or ground-truth topic have the same byte layout: the same
joint names, the same array lengths, the same ``frame_id`` length, so their stamp and
values sit at the same byte offsets. This module reads such messages in batches of up to
65 536 with one numpy view per field, and deserializes only the rest.

Measured with ``benchmarks/bench_bag_ingest.py --seconds 600`` (60 000
``sensor_msgs/JointState`` messages, best of 3, rosbags 0.11.9): rosbags' deserializer
alone takes 56-83 % of rosbags' read-and-deserialize loop; on the same raw messages in
memory this decoder is 16-24x faster than it; end to end, opening the bag included,
``read_bag`` is 2.5x (ROS 1), 3.9x (MCAP) and 5.1x (sqlite3) faster than the loop. What
is left is reading the bag's storage, which both share.

What it reads
-------------
- ``sensor_msgs/JointState``: the wheel joints' positions (kind
  :data:`POSITION`) if ``position`` has one entry per name, or their velocities (kind
  :data:`VELOCITY`) if ``position`` is empty and ``velocity`` has one per name;
- ``geometry_msgs/PoseStamped``, ``geometry_msgs/PoseWithCovarianceStamped`` and
  ``nav_msgs/Odometry``: position ``x, y`` and orientation ``x, y, z, w`` of the pose;
- the ``std_msgs`` numbers ``Int16`` ... ``UInt64``, ``Float32``, ``Float64``: ``data``;
- ``sensor_msgs/Imu``: the angular velocity, the linear acceleration and the first
  element of each covariance (:data:`IMU_VALUES`);

each with its ``header.stamp`` where it has one, from ROS 1 messages or from ROS 2 CDR
(little- or big-endian). Messages of other types are all deserialized.

How it stays correct
--------------------
- A layout is derived from one message by walking its bytes (``_Cursor``), and accepted
  only if reading that message through the layout gives exactly the stamp, values and
  kind that deserializing it with rosbags and picking the fields gives (NaN equal to
  NaN). Up to ``_LAYOUT_ATTEMPTS`` messages are tried before the topic is deserialized
  whole.
- A later message is read through the layout only if it has the same length and the same
  bytes at every place the layout checks: the CDR encapsulation (byte order), the length
  of every string and array in front of the values, and the text of the joint names.
  These bytes fix every offset the values are read from (CDR alignment included), so a
  message that passes has its stamp and values exactly where the layout reads them. Every
  other message is deserialized by rosbags, one by one.
- ``header.stamp.sec`` is read as the int32 rosbags makes of it, also from ROS 1, whose
  wire type is uint32 (stamps after 2038-01-19 come out negative either way).
- The samples read through the layout and the deserialized ones are put back into the
  messages' order.

``tests/sources/test_bag_fastpath.py`` proves it: with hypothesis it draws random messages of
every supported type (stamps over the whole range of their type, empty and non-ASCII
``frame_id``, joint-name lists with the wheel joints anywhere, empty and non-finite
arrays, numbers over their type's full range), serializes them with rosbags as ROS 1 and
as little- and big-endian CDR, decodes batches mixing messages of one layout with
messages of other layouts and lengths through :func:`decode_messages`, and asserts that
the stamps and values equal, bit for bit, what rosbags' ``deserialize_ros1`` and
``deserialize_cdr`` give, that the messages sharing the first one's layout were read
without deserializing them, and that messages differing from it in one checked place
(joint order, ``frame_id`` length, byte order) of the same length were deserialized.

Interface
---------
:func:`fast_layout` gives the layout derivation of a message type, and
:func:`decode_messages` reads raw messages with it, deserializing through a callback
where it does not fit. Neither needs a bag or rosbags::

    decoded = decode_messages(
        [(bag_ns, raw), ...],  # one topic's raw messages
        ros2=True,  # CDR; False: ROS 1
        width=2,
        decode=lambda raw: samples_of(deserialize(raw)),  # the reference, and fallback
        layout_of=fast_layout("sensor_msgs/msg/JointState", ("left", "right")),
    )
    decoded.sec, decoded.nsec, decoded.values, decoded.kind, decoded.deserialized
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray, IntArray
from umbmark.sources.bag.msgtypes import IMU, JOINT_STATE, ODOMETRY, TICK_TYPES, TRUTH_TYPES

__all__ = [
    "IMU_VALUES",
    "POSITION",
    "VELOCITY",
    "Decoded",
    "Layout",
    "LayoutOf",
    "Sample",
    "decode_messages",
    "fast_layout",
]


POSITION = 0
"""Kind of sample: the values are positions (joint angles, poses, counts)."""
VELOCITY = 1
"""Kind of sample: the values are joint velocities."""

Sample = tuple[int, int, tuple[float, ...], int]
"""A sample read from one message: header stamp ``sec``, ``nanosec`` (zeros for messages
without a header), the values, and the kind (:data:`POSITION` or :data:`VELOCITY`)."""

#: What a ``sensor_msgs/Imu`` sample holds, in order (``_cov``: the first element of the
#: covariance, -1 where the message has no such data).
IMU_VALUES = ("wx", "wy", "wz", "angular_velocity_cov", "ax", "ay", "az",
              "linear_acceleration_cov", "orientation_cov")  # fmt: skip
_BATCH = 1 << 16  # raw messages stacked per vectorized read
_LAYOUT_ATTEMPTS = 8  # messages tried for a fast layout before giving up on one


@dataclass(frozen=True)
class Layout:
    """Where a fixed-layout message keeps its stamp and values, and what must match.

    Attributes
    ----------
    length : int
        Length of the raw messages this layout reads.
    check_at : array, shape (c,)
        Byte offsets whose values must equal ``check_bytes`` (string and array lengths,
        joint names, CDR encapsulation), increasing.
    check_bytes : array, shape (c,)
    stamp : int or None
        Offset of ``header.stamp.sec`` (``nanosec`` follows it), or None.
    fields : tuple of int
        Offsets of the values.
    dtype : str
        numpy dtype of every value, with byte order (``"<f8"``).
    sec_dtype, nsec_dtype : str
        numpy dtypes of the stamp's seconds and nanoseconds.
    kind : int
        Kind of sample (:data:`POSITION` or :data:`VELOCITY`) the values are.
    """

    length: int
    check_at: NDArray[np.intp]
    check_bytes: NDArray[np.uint8]
    stamp: int | None
    fields: tuple[int, ...]
    dtype: str
    sec_dtype: str
    nsec_dtype: str
    kind: int = POSITION

    def read(self, rows: NDArray[np.uint8]) -> tuple[IntArray, IntArray, FloatArray]:
        """Stamps and values of the raw messages ``rows``, shape (k, length).

        Returns
        -------
        sec, nsec : array, shape (k,)
            Header stamp (zeros without a stamp).
        values : array, shape (k, len(fields))
        """
        k = rows.shape[0]
        if self.stamp is None:
            sec = np.zeros(k, np.int64)
            nsec = np.zeros(k, np.int64)
        else:
            at = self.stamp
            sec = _column(rows, at, self.sec_dtype).astype(np.int64)
            nsec = _column(rows, at + 4, self.nsec_dtype).astype(np.int64)
        values = np.empty((k, len(self.fields)), np.float64)
        for j, at in enumerate(self.fields):
            values[:, j] = _column(rows, at, self.dtype)
        return sec, nsec, values

    def fits(self, rows: NDArray[np.uint8]) -> NDArray[np.bool_]:
        """Which raw messages, shape (k, length), have this layout, shape (k,)."""
        ok = np.ones(rows.shape[0], np.bool_)
        if self.check_at.size == 0:
            return ok
        # compare runs of consecutive checked bytes as slices: faster than gathering them
        breaks = np.flatnonzero(np.diff(self.check_at) != 1) + 1
        for run in np.split(np.arange(self.check_at.size), breaks):
            start, stop = int(self.check_at[run[0]]), int(self.check_at[run[-1]]) + 1
            want = self.check_bytes[run[0] : run[-1] + 1]
            ok &= np.all(rows[:, start:stop] == want, axis=1)
        return ok


LayoutOf = Callable[[bytes, bool], Layout]
"""Derives the :class:`Layout` of one raw message (``raw``, ``ros2``: CDR, else ROS 1);
raises ValueError, struct.error, IndexError or UnicodeDecodeError if it has none."""


def _column(rows: NDArray[np.uint8], at: int, dtype: str) -> NDArray[Any]:
    """The value of type ``dtype`` at byte ``at`` of every row, shape (k,)."""
    size = np.dtype(dtype).itemsize
    return np.ascontiguousarray(rows[:, at : at + size]).view(dtype)[:, 0]


class _Cursor:
    """Walks a serialized message (ROS 1, or CDR after its 4-byte encapsulation header).

    ``pos`` is the offset in ``raw`` of what comes next; ``check`` collects the offsets
    of the bytes every message of the layout must share (``Layout.check_at``).
    """

    def __init__(self, raw: bytes, ros2: bool) -> None:
        self.raw = raw
        self.ros2 = ros2
        self.base = 4 if ros2 else 0
        if ros2 and (len(raw) < 4 or raw[0] != 0 or raw[1] not in (0, 1)):
            raise ValueError("unsupported CDR encapsulation")
        self.order = ">" if ros2 and raw[1] == 0 else "<"
        self.pos = self.base
        self.check: list[int] = [0, 1] if ros2 else []

    def align(self, size: int) -> None:
        """Move to the next multiple of ``size`` after the CDR header (ROS 1: none)."""
        if self.ros2:
            offset = self.pos - self.base
            self.pos = self.base + -(-offset // size) * size

    def skip(self, size: int) -> None:
        """Skip an aligned primitive of ``size`` bytes whose value does not matter."""
        self.align(size)
        self.pos += size

    def uint32(self) -> int:
        """A length field; it must be the same in every message of the layout."""
        self.align(4)
        (value,) = struct.unpack_from(self.order + "I", self.raw, self.pos)
        self.check.extend(range(self.pos, self.pos + 4))
        self.pos += 4
        return int(value)

    def stamp(self) -> int:
        """Skip a ``builtin_interfaces/Time``; return its offset."""
        self.align(4)
        at = self.pos
        self.pos += 8
        return at

    def string(self, *, same: bool) -> str:
        """A string; with ``same`` its text must match too, else only its length."""
        size = self.uint32()
        start = self.pos
        self.pos += size
        if self.pos > len(self.raw):
            raise ValueError("string runs past the end of the message")
        if same:
            self.check.extend(range(start, self.pos))
        text = self.raw[start : self.pos - 1 if self.ros2 else self.pos]
        return text.decode()

    def float64_array(self) -> tuple[int, int]:
        """``(offset of the first element, count)`` of a float64 sequence."""
        count = self.uint32()
        if count:
            self.align(8)
        at = self.pos
        self.pos += 8 * count
        return at, count

    def layout(
        self, stamp: int | None, fields: tuple[int, ...], dtype: str, kind: int = POSITION
    ) -> Layout:
        """The layout of this message: stamp and values at these offsets, of ``dtype``."""
        size = np.dtype(dtype).itemsize
        if self.pos > len(self.raw) or any(f + size > len(self.raw) for f in fields):
            raise ValueError("message shorter than its layout")
        at = np.array(sorted(set(self.check)), np.intp)
        return Layout(
            length=len(self.raw),
            check_at=at,
            check_bytes=np.frombuffer(self.raw, np.uint8)[at].copy(),
            stamp=stamp,
            fields=fields,
            dtype=self.order + dtype,
            # rosbags reads ``sec`` as int32 in both formats (ROS 1 sends an uint32):
            # read it so, or fast and deserialized samples of one bag would differ
            sec_dtype=self.order + "i4",
            nsec_dtype=self.order + "u4",
            kind=kind,
        )

    def header(self) -> int:
        """Skip a ``std_msgs/Header``; return the offset of its stamp."""
        if not self.ros2:
            self.skip(4)  # seq, different in every message
        at = self.stamp()
        self.string(same=False)  # frame_id
        return at


# --- the layouts of the supported message types ----------------------------------------


def _joint_state_layout(joints: tuple[str, ...]) -> LayoutOf:
    """``sensor_msgs/JointState``: the joints' positions, or velocities if no position.

    Checked: the ``frame_id`` length, the names (count, lengths, text), the position
    count and, for velocities, the velocity count. Velocities (after positions) and
    efforts are not read, so their counts need not match.
    """

    def layout_of(raw: bytes, ros2: bool) -> Layout:
        cur = _Cursor(raw, ros2)
        stamp = cur.header()
        names = [cur.string(same=True) for _ in range(cur.uint32())]
        where = [names.index(joint) for joint in joints]
        at, count = cur.float64_array()
        kind = POSITION
        if count != len(names):
            if count != 0:
                raise ValueError("position and name differ in length")
            at, count = cur.float64_array()
            kind = VELOCITY
            if count != len(names):
                raise ValueError("velocity and name differ in length")
        return cur.layout(stamp, tuple(at + 8 * i for i in where), "f8", kind)

    return layout_of


def _number_layout(code: str) -> LayoutOf:
    """A ``std_msgs`` number whose ``data`` has numpy type ``code`` (``"i4"``); no stamp."""
    size = int(code[1])

    def layout_of(raw: bytes, ros2: bool) -> Layout:
        cur = _Cursor(raw, ros2)
        cur.align(size)
        at = cur.pos
        cur.pos += size
        return cur.layout(None, (at,), code)

    return layout_of


#: The float64s read after the header (counted from the first), and how many follow it:
#: the pose types' ``x, y`` and quaternion; ``sensor_msgs/Imu``'s angular velocity and its
#: covariance's first element, linear acceleration and its, and orientation covariance's.
_FLOATS = {
    **dict.fromkeys(TRUTH_TYPES, ((0, 1, 3, 4, 5, 6), 7)),
    IMU: ((13, 14, 15, 16, 25, 26, 27, 28, 4), 37),
}


def _floats_layout(msgtype: str) -> LayoutOf:
    """A header then float64s (:data:`_FLOATS`): the three pose types and
    ``sensor_msgs/Imu``.

    Checked: the ``frame_id`` length and, for ``nav_msgs/Odometry``, the
    ``child_frame_id`` length; the floats follow them (in the covariance types the
    ``pose`` comes first).
    """
    read, count = _FLOATS[msgtype]

    def layout_of(raw: bytes, ros2: bool) -> Layout:
        cur = _Cursor(raw, ros2)
        stamp = cur.header()
        if msgtype == ODOMETRY:
            cur.string(same=False)  # child_frame_id
        cur.align(8)
        at = cur.pos
        cur.pos += count * 8
        return cur.layout(stamp, tuple(at + 8 * i for i in read), "f8")

    return layout_of


def fast_layout(msgtype: str, joints: tuple[str, ...] | None = None) -> LayoutOf | None:
    """The layout derivation for messages of ``msgtype``, or None if it has none.

    Parameters
    ----------
    msgtype : str
        rosbags' name of the message type (``"sensor_msgs/msg/JointState"``).
    joints : tuple of str, optional
        The joint names (the left wheels', then the right wheels'); required for
        ``sensor_msgs/JointState``.

    Returns
    -------
    LayoutOf or None
        For ``decode_messages(layout_of=...)``. The samples it reads are:
        ``sensor_msgs/JointState``: one value per joint, its position or velocity;
        pose types: width 6, ``x, y`` and quaternion ``x, y, z, w``;
        ``sensor_msgs/Imu``: width 9 (:data:`IMU_VALUES`); ``std_msgs`` numbers: width 1,
        ``data``, no stamp (zeros). None for other types.
    """
    if msgtype == JOINT_STATE:
        if joints is None:
            raise ValueError("the layout of sensor_msgs/JointState needs the joint names")
        return _joint_state_layout(joints)
    if msgtype in _FLOATS:
        return _floats_layout(msgtype)
    if msgtype in TICK_TYPES:
        return _number_layout(TICK_TYPES[msgtype][0])
    return None


# --- reading a topic ---------------------------------------------------------------------


@dataclass(frozen=True)
class Decoded:
    """The samples of a topic's messages, in the messages' order.

    Attributes
    ----------
    sec, nsec : array, shape (k,)
        Header stamp of each sample (zeros for messages without a header).
    bag_ns : array, shape (k,)
        The time given with each sample's message (the bag's receive time [ns]).
    values : array, shape (k, w)
    kind : array, shape (k,)
        :data:`POSITION` or :data:`VELOCITY`.
    messages : int
        Messages read.
    deserialized : int
        Of them, the ones given to the ``decode`` callback (the rest were read through
        a layout).
    """

    sec: IntArray
    nsec: IntArray
    bag_ns: IntArray
    values: FloatArray
    kind: NDArray[np.int8]
    messages: int
    deserialized: int


@dataclass
class _Collected:
    """Samples gathered from one topic, in pieces (any order; ``index`` restores it)."""

    width: int
    index: list[IntArray] = field(default_factory=list)
    sec: list[IntArray] = field(default_factory=list)
    nsec: list[IntArray] = field(default_factory=list)
    bag_ns: list[IntArray] = field(default_factory=list)
    values: list[FloatArray] = field(default_factory=list)
    kind: list[NDArray[np.int8]] = field(default_factory=list)
    # samples of deserialized messages: (index, bag_ns, sample)
    single: list[tuple[int, int, Sample]] = field(default_factory=list)
    deserialized: int = 0

    def add(self, index: int, bag_ns: int, samples: list[Sample]) -> None:
        self.deserialized += 1
        self.single.extend((index, bag_ns, sample) for sample in samples)

    def add_block(
        self,
        index: IntArray,
        bag_ns: IntArray,
        sec: IntArray,
        nsec: IntArray,
        values: FloatArray,
        kind: NDArray[np.int8],
    ) -> None:
        self.index.append(index)
        self.sec.append(sec)
        self.nsec.append(nsec)
        self.bag_ns.append(bag_ns)
        self.values.append(values)
        self.kind.append(kind)

    def result(self, messages: int) -> Decoded:
        if self.single:
            index, bag_ns, samples = zip(*self.single, strict=True)
            self.single = []
            self.add_block(
                np.array(index, np.int64),
                np.array(bag_ns, np.int64),
                np.array([s[0] for s in samples], np.int64),
                np.array([s[1] for s in samples], np.int64),
                np.array([s[2] for s in samples], np.float64).reshape(-1, self.width),
                np.array([s[3] for s in samples], np.int8),
            )
        if not self.index:
            none = np.zeros(0, np.int64)
            values = np.zeros((0, self.width))
            kind = np.zeros(0, np.int8)
            return Decoded(none, none, none, values, kind, messages, self.deserialized)
        order = np.argsort(np.concatenate(self.index), kind="stable")
        return Decoded(
            sec=np.concatenate(self.sec)[order],
            nsec=np.concatenate(self.nsec)[order],
            bag_ns=np.concatenate(self.bag_ns)[order],
            values=np.concatenate(self.values)[order],
            kind=np.concatenate(self.kind)[order],
            messages=messages,
            deserialized=self.deserialized,
        )


def decode_messages(
    messages: Iterable[tuple[int, bytes]],
    *,
    ros2: bool,
    width: int,
    decode: Callable[[bytes], list[Sample]],
    layout_of: LayoutOf | None,
) -> Decoded:
    """Read every message: through a layout where one fits, else with ``decode``.

    Parameters
    ----------
    messages : iterable of (int, bytes)
        ``(bag time [ns], raw message)`` of one topic, all of one message type.
    ros2 : bool
        The messages are CDR (ROS 2), else ROS 1.
    width : int
        Values per sample.
    decode : callable
        Deserializes a raw message and returns its samples (none to skip it; a
        ``sensor_msgs/JointState`` without the wheel joints); the reference the layouts
        are checked against. Whatever it raises propagates.
    layout_of : LayoutOf or None
        Derives a layout from a raw message (:func:`fast_layout`); each derived layout is
        accepted only if it reads that message exactly as ``decode`` does. None:
        ``decode`` every message.

    Returns
    -------
    Decoded
        The samples, ``k`` of them, in the messages' order.
    """
    got = _Collected(width)
    layout: Layout | None = None
    attempts = 0 if layout_of is not None else _LAYOUT_ATTEMPTS
    batch: list[bytes] = []
    batch_ns: list[int] = []
    batch_index: list[int] = []

    def slow(index: int, bag_ns: int, raw: bytes) -> list[Sample]:
        samples = decode(raw)
        got.add(index, bag_ns, samples)
        return samples

    def flush() -> None:
        assert layout is not None
        rows = np.frombuffer(b"".join(batch), np.uint8).reshape(len(batch), layout.length)
        fits = layout.fits(rows)
        index = np.array(batch_index, np.int64)
        bag_ns = np.array(batch_ns, np.int64)
        if fits.all():
            sec, nsec, values = layout.read(rows)
        else:
            sec, nsec, values = layout.read(rows[fits])
            index, bag_ns = index[fits], bag_ns[fits]
            for i in np.flatnonzero(~fits).tolist():
                slow(batch_index[i], batch_ns[i], batch[i])
        got.add_block(index, bag_ns, sec, nsec, values, np.full(sec.size, layout.kind, np.int8))
        batch.clear()
        batch_ns.clear()
        batch_index.clear()

    count = 0
    length = -1  # of the raw messages the layout reads; none before there is a layout
    add_raw, add_ns, add_index = batch.append, batch_ns.append, batch_index.append
    for bag_ns, raw in messages:
        count += 1
        if len(raw) == length:  # the hot path: just collect, read in batches
            add_raw(raw)
            add_ns(bag_ns)
            add_index(count)
            if len(batch) >= _BATCH:
                flush()
            continue
        samples = slow(count, bag_ns, raw)
        if layout is None and attempts < _LAYOUT_ATTEMPTS and len(samples) == 1:
            assert layout_of is not None
            attempts += 1
            layout = _checked_layout(layout_of, raw, ros2, samples[0])
            length = -1 if layout is None else layout.length
    if batch:
        flush()
    return got.result(count)


def _checked_layout(layout_of: LayoutOf, raw: bytes, ros2: bool, sample: Sample) -> Layout | None:
    """The layout of ``raw`` if it reads ``raw`` exactly as deserialization did."""
    try:
        layout = layout_of(raw, ros2)
    except (ValueError, struct.error, IndexError, UnicodeDecodeError):
        return None
    rows = np.frombuffer(raw, np.uint8).reshape(1, -1)
    sec, nsec, values = layout.read(rows)
    want_sec, want_nsec, want_values, want_kind = sample
    same = (
        bool(layout.fits(rows)[0])
        and layout.kind == want_kind
        and (layout.stamp is None or (int(sec[0]), int(nsec[0])) == (want_sec, want_nsec))
        and np.array_equal(values[0], np.array(want_values, np.float64), equal_nan=True)
    )
    return layout if same else None

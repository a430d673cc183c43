"""ROS bags: wheel rotation and ground truth from ROS 1 and ROS 2 recordings.

Reads ROS 1 bags (``.bag`` files) and ROS 2 bags (a folder with ``metadata.yaml`` and
sqlite3 ``.db3`` or ``.mcap`` storage; the path of the storage file or of
``metadata.yaml`` itself also works and means its folder) through ``rosbags``
(``pip install 'umbmark[ros]'``), and returns a :class:`umbmark.recording.WheelSeries`
and, if asked for, a :class:`umbmark.recording.PoseSeries` of ground truth.

Options (:class:`BagOptions`)
-----------------------------
Wheels, one of:

- ``wheel_topic`` (``sensor_msgs/JointState``, default ``/joint_states``) with the joints
  ``left_joint`` and ``right_joint``. Each message's ``name`` list is searched for them,
  so joint order may change between messages and other joints may be present; messages
  without both joints (another joint group published on the same topic) are skipped. The
  angle is ``position``; if ``position`` is empty and ``velocity`` is not, the velocity is
  integrated over time with the trapezoid rule (angle 0 at the first sample).
- ``left_ticks_topic`` and ``right_ticks_topic`` (``std_msgs`` ``Int16``, ``Int32``,
  ``Int64``, ``UInt16``, ``UInt32``, ``UInt64``, ``Float32`` or ``Float64``): cumulative
  encoder counts of each wheel, with ``ticks_per_revolution`` counts per wheel
  revolution. 16- and 32-bit counters wrap around; a jump of more than half the type's
  range between two messages is taken as a wrap and unwrapped. Angle
  ``= counts * 2 pi / ticks_per_revolution``.

Ground truth, optional: ``truth_topic`` (``geometry_msgs/PoseStamped``,
``geometry_msgs/PoseWithCovarianceStamped`` or ``nav_msgs/Odometry``), else the direct
transform ``tf_parent -> tf_child`` on ``/tf`` (``tf2_msgs/TFMessage``; leading slashes of
frame names are ignored). The pose is ``x, y`` of the position and the yaw of the
orientation, ``atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))`` of the normalized quaternion.

Time
----
``time_source="header"`` (default) stamps each sample with its message's
``header.stamp`` (the transform's own stamp for TF): the time the data was measured,
which is what wheel and ground-truth samples must be matched on. ``"bag"`` uses the time
the recorder received the message instead: use it when the publishers leave their stamps
empty or their clocks are not synchronized. ``std_msgs`` numbers have no header, so the
ticks topics always use the bag time. Times are seconds (``sec + nanosec * 1e-9``).

Samples are sorted by time; of samples with exactly the same time only the first (in
the bag's order) is kept, and samples with values that are not finite numbers are
dropped. Wheel samples of the two ticks topics arrive at different times: the right
wheel's angle is interpolated linearly onto the left wheel's times, inside the time both
topics cover. Every problem with the bag or the options raises
:class:`umbmark.errors.InputError`, one line naming the bag.

Speed
-----
``sensor_msgs/JointState``, the three pose types and the ``std_msgs`` numbers are read
without deserializing every message: the byte layout (offsets of ``header.stamp`` and of
the values) is computed from the first usable message and checked against rosbags'
deserialization of it; every later message of the same length whose layout bytes (string
lengths, joint names, array lengths, CDR encapsulation) equal the first one's is read
with vectorized numpy views over the stacked raw messages. Other messages are
deserialized one by one.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..recording import PoseSeries, WheelSeries

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = ["BagOptions", "bag_topics", "read_bag"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

JOINT_STATE = "sensor_msgs/msg/JointState"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
POSE_COV_STAMPED = "geometry_msgs/msg/PoseWithCovarianceStamped"
ODOMETRY = "nav_msgs/msg/Odometry"
TRUTH_TYPES = (POSE_STAMPED, POSE_COV_STAMPED, ODOMETRY)
TF_TOPIC = "/tf"
TF_TYPES = ("tf2_msgs/msg/TFMessage", "tf/msg/tfMessage")

# std_msgs number types: numpy type code and bits of a counter that wraps (None: no wrap).
TICK_TYPES: dict[str, tuple[str, int | None]] = {
    "std_msgs/msg/Int16": ("i2", 16),
    "std_msgs/msg/Int32": ("i4", 32),
    "std_msgs/msg/Int64": ("i8", None),
    "std_msgs/msg/UInt16": ("u2", 16),
    "std_msgs/msg/UInt32": ("u4", 32),
    "std_msgs/msg/UInt64": ("u8", None),
    "std_msgs/msg/Float32": ("f4", None),
    "std_msgs/msg/Float64": ("f8", None),
}

_BATCH = 1 << 16  # raw messages stacked per vectorized read
_LAYOUT_ATTEMPTS = 8  # messages tried for a fast layout before giving up on one
_LISTED = 25  # names listed in an error message at most

_POSITION, _VELOCITY = 0, 1


@dataclass(frozen=True)
class BagOptions:
    """What to read from a bag; see the module docstring for the details.

    Attributes
    ----------
    wheel_topic : str
        ``sensor_msgs/JointState`` topic with the wheel joints.
    left_joint, right_joint : str
        Names of the left and right wheel joints in it.
    left_ticks_topic, right_ticks_topic : str or None
        Instead of the joint states: ``std_msgs`` number topics with each wheel's
        cumulative encoder counts (both or neither).
    ticks_per_revolution : float or None
        Encoder counts per wheel revolution; required with the ticks topics.
    truth_topic : str or None
        Ground truth: ``geometry_msgs/PoseStamped``,
        ``geometry_msgs/PoseWithCovarianceStamped`` or ``nav_msgs/Odometry``.
    tf_parent, tf_child : str or None
        Ground truth from the direct transform ``tf_parent -> tf_child`` on ``/tf``
        (used when ``truth_topic`` is not given).
    time_source : {"header", "bag"}
        Stamp samples with ``header.stamp`` (where messages have one) or with the time the
        bag recorded them.
    """

    wheel_topic: str = "/joint_states"
    left_joint: str = "left_wheel_joint"
    right_joint: str = "right_wheel_joint"
    left_ticks_topic: str | None = None
    right_ticks_topic: str | None = None
    ticks_per_revolution: float | None = None
    truth_topic: str | None = None
    tf_parent: str | None = None
    tf_child: str | None = None
    time_source: Literal["header", "bag"] = "header"


def read_bag(path: str | Path, options: BagOptions) -> tuple[WheelSeries, PoseSeries | None]:
    """Read the wheel rotation and, if configured, the ground truth from a bag.

    Parameters
    ----------
    path : str or Path
        A ROS 1 ``.bag`` file, a ROS 2 bag folder, or the ``.db3``/``.mcap`` file (or
        ``metadata.yaml``) of one.
    options : BagOptions
        Topics, joints and time source.

    Returns
    -------
    wheels : WheelSeries
        ``time`` shape (n,) [s], ``angles`` shape (n, 2) [rad], left and right.
    truth : PoseSeries or None
        ``time`` shape (m,) [s], ``poses`` shape (m, 3): ``x, y`` [m], yaw [rad]; None
        if neither ``truth_topic`` nor a TF pair is given.

    Raises
    ------
    InputError
        The bag cannot be read, or lacks what the options ask for.
    """
    src = str(path)
    _check_options(options, src)
    with _open_bag(Path(path), src) as reader:
        topics = _topic_types(reader)
        if options.left_ticks_topic is not None and options.right_ticks_topic is not None:
            assert options.ticks_per_revolution is not None  # _check_options
            wheels = _read_ticks(
                reader,
                topics,
                options.left_ticks_topic,
                options.right_ticks_topic,
                options.ticks_per_revolution,
                src,
            )
        else:
            wheels = _read_joint_states(reader, topics, options, src)
        truth: PoseSeries | None = None
        if options.truth_topic is not None:
            truth = _read_pose_topic(reader, topics, options.truth_topic, options, src)
        elif options.tf_parent is not None and options.tf_child is not None:
            truth = _read_tf(reader, topics, options.tf_parent, options.tf_child, options, src)
    return wheels, truth


def bag_topics(path: str | Path) -> dict[str, str]:
    """The topics of a bag and their message types (``"sensor_msgs/msg/JointState"``).

    A topic recorded with several types lists them separated by ``", "``.

    Raises
    ------
    InputError
        The bag cannot be read.
    """
    src = str(path)
    with _open_bag(Path(path), src) as reader:
        return _topic_types(reader)


# --- options, opening, topics ---------------------------------------------------------


def _check_options(options: BagOptions, src: str) -> None:
    def fail(problem: str) -> None:
        raise InputError(problem, source=src)

    if options.time_source not in ("header", "bag"):
        fail(f"time source must be 'header' or 'bag', not {options.time_source!r}")
    if (options.left_ticks_topic is None) != (options.right_ticks_topic is None):
        fail("the left and right ticks topics go together: give both or neither")
    if options.left_ticks_topic is not None:
        tpr = options.ticks_per_revolution
        if tpr is None:
            fail("reading ticks topics needs ticks_per_revolution (counts per wheel revolution)")
        elif not (math.isfinite(tpr) and tpr > 0):
            fail(f"ticks_per_revolution must be a positive number, not {tpr!r}")
        if options.left_ticks_topic == options.right_ticks_topic:
            fail(f"the left and right ticks topics are the same: {options.left_ticks_topic}")
    elif options.left_joint == options.right_joint:
        fail(f"the left and right wheel joints are the same: {options.left_joint!r}")
    if options.truth_topic is None and (options.tf_parent is None) != (options.tf_child is None):
        fail("a TF ground truth needs both tf_parent and tf_child")


def _one_line(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return text or type(err).__name__


def _bag_location(path: Path, src: str) -> Path:
    """The path to give rosbags: a ``.bag`` file, a ROS 2 folder or a storage file."""
    if not path.exists():
        raise InputError("no such bag: the file or folder does not exist", source=src)
    if path.is_dir():
        if (path / "metadata.yaml").is_file():
            return path
        raise InputError("not a bag: a ROS 2 bag folder needs a metadata.yaml", source=src)
    if path.suffix == ".bag":
        return path
    if path.suffix in (".db3", ".mcap"):
        return path.parent if (path.parent / "metadata.yaml").is_file() else path
    if path.name == "metadata.yaml":
        return path.parent
    try:
        with path.open("rb") as file:
            magic = file.read(13)
    except OSError as err:
        raise InputError(f"cannot read the bag: {_one_line(err)}", source=src) from None
    if magic.startswith(b"#ROSBAG"):
        raise InputError(
            "this looks like a ROS 1 bag, but it must be named *.bag to be read", source=src
        )
    raise InputError(
        "not a bag: expected a ROS 1 .bag file, a ROS 2 bag folder, or its .db3/.mcap file",
        source=src,
    )


def _missing_rosbags(src: str) -> InputError:
    return InputError("reading bags needs rosbags: pip install 'umbmark[ros]'", source=src)


@contextmanager
def _open_bag(path: Path, src: str) -> Iterator[AnyReader]:
    """An open ``AnyReader``; every failure to open becomes an :class:`InputError`."""
    location = _bag_location(path, src)
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise _missing_rosbags(src) from None
    try:
        reader = AnyReader([location], default_typestore=get_typestore(Stores.LATEST))
        reader.open()
    except Exception as err:  # rosbags, sqlite, mcap, yaml, decompression: all bad input
        problem = f"cannot read the bag: {_one_line(err)}"
        if location.suffix == ".bag" and "index" in problem.lower():
            problem += " (a recording that was cut short needs `rosbag reindex` first)"
        raise InputError(problem, source=src) from None
    try:
        yield reader
    finally:
        reader.close()


def _topic_types(reader: AnyReader) -> dict[str, str]:
    out: dict[str, str] = {}
    for topic, info in sorted(reader.topics.items()):
        if info.msgtype is not None:
            out[topic] = info.msgtype
        else:
            out[topic] = ", ".join(sorted({c.msgtype for c in info.connections}))
    return out


def _listing(items: Sequence[str]) -> str:
    shown = ", ".join(items[:_LISTED])
    more = len(items) - _LISTED
    return f"{shown}, and {more} more" if more > 0 else shown


def _connections(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    allowed: Sequence[str],
    what: str,
    src: str,
) -> tuple[list[Connection], str]:
    """The connections of ``topic`` and its message type, checked against ``allowed``."""
    if topic not in topics:
        present = [f"{name} ({typ})" for name, typ in topics.items()]
        listed = f"topics present: {_listing(present)}" if present else "the bag has no topics"
        raise InputError(f"no topic {topic} ({what}) in the bag; {listed}", source=src)
    msgtype = topics[topic]
    if msgtype not in allowed:
        raise InputError(
            f"topic {topic} has messages of type {msgtype}; {what} must be " + " or ".join(allowed),
            source=src,
        )
    return [c for c in reader.connections if c.topic == topic], msgtype


# --- reading messages ------------------------------------------------------------------


def _messages(
    reader: AnyReader, conns: Sequence[Connection], topic: str, src: str
) -> Iterator[tuple[int, bytes]]:
    """``(bag time [ns], raw message)`` of ``conns``; read errors become InputError."""
    stream = reader.messages(connections=conns)
    while True:
        try:
            _, timestamp, raw = next(stream)
        except StopIteration:
            return
        except Exception as err:  # corrupt storage, truncated chunk, bad compression
            raise InputError(
                f"cannot read the messages of {topic}: {_one_line(err)}", source=src
            ) from None
        yield timestamp, raw


def _deserialize(reader: AnyReader, raw: bytes, msgtype: str, topic: str, src: str) -> object:
    try:
        return reader.deserialize(raw, msgtype)
    except Exception as err:  # malformed message bytes
        raise InputError(
            f"a message of {topic} cannot be decoded: {_one_line(err)}", source=src
        ) from None


# What the readers use of rosbags' message classes.


class _Time(Protocol):
    sec: int
    nanosec: int


class _Header(Protocol):
    stamp: _Time
    frame_id: str


class _Stamped(Protocol):
    header: _Header


class _JointState(_Stamped, Protocol):
    name: list[str]
    position: NDArray[np.float64]
    velocity: NDArray[np.float64]


class _Number(Protocol):
    data: float


class _Vector(Protocol):
    x: float
    y: float
    z: float


class _Quaternion(_Vector, Protocol):
    w: float


class _Pose(Protocol):
    position: _Vector
    orientation: _Quaternion


class _PoseStamped(_Stamped, Protocol):
    pose: _Pose


class _PoseWithCovariance(Protocol):
    pose: _Pose


class _PoseWithCovarianceStamped(_Stamped, Protocol):
    pose: _PoseWithCovariance


class _Transform(Protocol):
    translation: _Vector
    rotation: _Quaternion


class _TransformStamped(_Stamped, Protocol):
    child_frame_id: str
    transform: _Transform


class _TFMessage(Protocol):
    transforms: list[_TransformStamped]


# A sample read from one message: header stamp (sec, nanosec), values, kind.
_Sample = tuple[int, int, tuple[float, ...], int]


@dataclass(frozen=True)
class _Layout:
    """Where a fixed-layout message keeps its stamp and values, and what must match.

    Attributes
    ----------
    length : int
        Length of the raw messages this layout reads.
    check_at : array, shape (c,)
        Byte offsets whose values must equal ``check_bytes`` (string and array lengths,
        joint names, CDR encapsulation).
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
        Kind of sample (position or velocity) the values are.
    """

    length: int
    check_at: NDArray[np.intp]
    check_bytes: NDArray[np.uint8]
    stamp: int | None
    fields: tuple[int, ...]
    dtype: str
    sec_dtype: str
    nsec_dtype: str
    kind: int = _POSITION

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


def _column(rows: NDArray[np.uint8], at: int, dtype: str) -> NDArray[Any]:
    """The value of type ``dtype`` at byte ``at`` of every row, shape (k,)."""
    size = np.dtype(dtype).itemsize
    return np.ascontiguousarray(rows[:, at : at + size]).view(dtype)[:, 0]


class _Cursor:
    """Walks a serialized message (ROS 1, or CDR after its 4-byte encapsulation header)."""

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
        if self.ros2:
            offset = self.pos - self.base
            self.pos = self.base + -(-offset // size) * size

    def skip(self, size: int) -> None:
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
        self, stamp: int | None, fields: tuple[int, ...], dtype: str, kind: int = _POSITION
    ) -> _Layout:
        size = np.dtype(dtype).itemsize
        if self.pos > len(self.raw) or any(f + size > len(self.raw) for f in fields):
            raise ValueError("message shorter than its layout")
        at = np.array(sorted(set(self.check)), np.intp)
        return _Layout(
            length=len(self.raw),
            check_at=at,
            check_bytes=np.frombuffer(self.raw, np.uint8)[at].copy(),
            stamp=stamp,
            fields=fields,
            dtype=self.order + dtype,
            sec_dtype=self.order + ("i4" if self.ros2 else "u4"),
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
    single: list[tuple[int, int, _Sample]] = field(default_factory=list)

    def add(self, index: int, bag_ns: int, samples: list[_Sample]) -> None:
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

    def result(self) -> _Scan:
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
            return _Scan(none, none, none, np.zeros((0, self.width)), np.zeros(0, np.int8))
        order = np.argsort(np.concatenate(self.index), kind="stable")
        return _Scan(
            sec=np.concatenate(self.sec)[order],
            nsec=np.concatenate(self.nsec)[order],
            bag_ns=np.concatenate(self.bag_ns)[order],
            values=np.concatenate(self.values)[order],
            kind=np.concatenate(self.kind)[order],
        )


@dataclass(frozen=True)
class _Scan:
    """The samples of a topic in the bag's order.

    Attributes
    ----------
    sec, nsec : array, shape (k,)
        Header stamp of each sample.
    bag_ns : array, shape (k,)
        Bag receive time [ns].
    values : array, shape (k, w)
    kind : array, shape (k,)
        Position or velocity (joint states).
    """

    sec: IntArray
    nsec: IntArray
    bag_ns: IntArray
    values: FloatArray
    kind: NDArray[np.int8]

    def time_ns(self, header: bool) -> IntArray:
        """Sample times [ns], shape (k,): header stamps or bag receive times."""
        if header:
            return self.sec * 1_000_000_000 + self.nsec
        return self.bag_ns


def _seconds(time_ns: IntArray) -> FloatArray:
    """Times [s] of ``time_ns`` [ns], shape (k,), as ``sec + nanosec * 1e-9``."""
    sec, nsec = np.divmod(time_ns, 1_000_000_000)
    return np.asarray(sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9)


def _scan(
    reader: AnyReader,
    conns: Sequence[Connection],
    msgtype: str,
    topic: str,
    src: str,
    *,
    width: int,
    decode: Callable[[Any], list[_Sample]],
    layout_of: Callable[[bytes, bool], _Layout] | None,
) -> _Scan:
    """Read every message of ``topic``: vectorized where a layout fits, else deserialized.

    ``decode`` turns a deserialized message into samples; ``layout_of`` derives the fast
    layout from a raw message (raising ValueError or struct.error if it cannot); each
    derived layout is accepted only if it reads that message exactly as ``decode`` does.
    """
    ros2 = bool(reader.is2)
    got = _Collected(width)
    layout: _Layout | None = None
    attempts = 0 if layout_of is not None else _LAYOUT_ATTEMPTS
    batch: list[bytes] = []
    batch_ns: list[int] = []
    batch_index: list[int] = []

    def slow(index: int, bag_ns: int, raw: bytes) -> list[_Sample]:
        samples = decode(_deserialize(reader, raw, msgtype, topic, src))
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
    for bag_ns, raw in _messages(reader, conns, topic, src):
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
    if count == 0:
        raise InputError(f"topic {topic} has no messages", source=src)
    return got.result()


def _checked_layout(
    layout_of: Callable[[bytes, bool], _Layout], raw: bytes, ros2: bool, sample: _Sample
) -> _Layout | None:
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


def _stamp(msg: _Stamped) -> tuple[int, int]:
    stamp = msg.header.stamp
    return int(stamp.sec), int(stamp.nanosec)


# --- series ----------------------------------------------------------------------------


def _clean(
    time_ns: IntArray, values: FloatArray, what: str, src: str, *, header: bool
) -> tuple[IntArray, FloatArray, FloatArray]:
    """Drop non-finite samples, sort by time, keep the first of equal times.

    Returns
    -------
    time_ns : array, shape (k,)
        Times [ns], strictly increasing: differences are exact, for integrating over.
    time : array, shape (k,)
        The same times in seconds, strictly increasing. Float seconds since 1970 resolve
        only about 0.2 microseconds, so of stamps closer than that only the first is kept.
    values : array, shape (k, w)
    """
    finite = np.all(np.isfinite(values), axis=1)
    time_ns, values = time_ns[finite], values[finite]
    order = np.argsort(time_ns, kind="stable")
    time_ns, values = time_ns[order], values[order]
    time = _seconds(time_ns)
    keep = np.ones(time.size, np.bool_)
    keep[1:] = np.diff(time) > 0
    time_ns, time, values = time_ns[keep], time[keep], values[keep]
    if time.size < 2:
        hint = " (are the header stamps all equal? try the bag time)" if header else ""
        plural = "" if time_ns.size == 1 else "s"
        raise InputError(
            f"{what} has {time_ns.size} usable sample{plural} with distinct times, at least 2"
            f" are needed{hint}",
            source=src,
        )
    return time_ns, time, values


def _read_joint_states(
    reader: AnyReader,
    topics: dict[str, str],
    options: BagOptions,
    src: str,
) -> WheelSeries:
    topic = options.wheel_topic
    conns, msgtype = _connections(reader, topics, topic, (JOINT_STATE,), "wheel joint states", src)
    left, right = options.left_joint, options.right_joint
    seen: set[str] = set()

    def decode(msg: _JointState) -> list[_Sample]:
        names = list(msg.name)
        try:
            i, j = names.index(left), names.index(right)
        except ValueError:
            seen.update(names)
            return []
        sec, nsec = _stamp(msg)
        position, velocity = msg.position, msg.velocity
        if len(position) > max(i, j):
            return [(sec, nsec, (float(position[i]), float(position[j])), _POSITION)]
        if len(velocity) > max(i, j):
            return [(sec, nsec, (float(velocity[i]), float(velocity[j])), _VELOCITY)]
        raise InputError(
            f"a message of {topic} (stamp {sec + nsec * 1e-9:.9f} s) has neither position"
            f" nor velocity for the joints {left!r} and {right!r}",
            source=src,
        )

    def layout_of(raw: bytes, ros2: bool) -> _Layout:
        cur = _Cursor(raw, ros2)
        stamp = cur.header()
        names = [cur.string(same=True) for _ in range(cur.uint32())]
        i, j = names.index(left), names.index(right)
        at, count = cur.float64_array()
        kind = _POSITION
        if count != len(names):
            if count != 0:
                raise ValueError("position and name differ in length")
            at, count = cur.float64_array()
            kind = _VELOCITY
            if count != len(names):
                raise ValueError("velocity and name differ in length")
        return cur.layout(stamp, (at + 8 * i, at + 8 * j), "f8", kind)

    scan = _scan(
        reader,
        conns,
        msgtype,
        topic,
        src,
        width=2,
        decode=decode,
        layout_of=layout_of,
    )
    if scan.values.shape[0] == 0:
        missing = [name for name in (left, right) if name not in seen]
        present = _listing(sorted(seen)) if seen else "none"
        if missing:
            joints = " and ".join(repr(name) for name in missing)
            raise InputError(f"no joint {joints} in {topic}; joints present: {present}", source=src)
        raise InputError(
            f"the joints {left!r} and {right!r} never appear in the same message of {topic}",
            source=src,
        )
    header = options.time_source == "header"
    kinds = np.unique(scan.kind)
    if kinds.size > 1:
        raise InputError(
            f"{topic} mixes messages with wheel positions and messages with only velocities",
            source=src,
        )
    time_ns, time, values = _clean(
        scan.time_ns(header), scan.values, f"topic {topic}", src, header=header
    )
    if kinds[0] == _VELOCITY:
        dt = np.diff(time_ns).astype(np.float64) * 1e-9
        steps = 0.5 * (values[1:] + values[:-1]) * dt[:, None]
        values = np.concatenate([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    return WheelSeries(time=time, angles=values)


def _read_counts(
    reader: AnyReader, topics: dict[str, str], topic: str, side: str, src: str
) -> tuple[IntArray, FloatArray]:
    """Time [ns] and unwrapped cumulative counts, each shape (k,), of a ticks topic."""
    conns, msgtype = _connections(
        reader, topics, topic, tuple(TICK_TYPES), f"{side} wheel ticks", src
    )
    code, bits = TICK_TYPES[msgtype]

    def decode(msg: _Number) -> list[_Sample]:
        return [(0, 0, (float(msg.data),), _POSITION)]

    def layout_of(raw: bytes, ros2: bool) -> _Layout:
        cur = _Cursor(raw, ros2)
        cur.align(int(code[1]))
        at = cur.pos
        cur.pos += int(code[1])
        return cur.layout(None, (at,), code)

    scan = _scan(reader, conns, msgtype, topic, src, width=1, decode=decode, layout_of=layout_of)
    time_ns, _, counts = _clean(
        scan.time_ns(False), scan.values, f"topic {topic}", src, header=False
    )
    ticks = counts[:, 0]
    if bits is not None:
        span = float(2**bits)
        step = np.diff(ticks)
        step = step - span * (step > span / 2) + span * (step < -span / 2)
        ticks = ticks[0] + np.concatenate([[0.0], np.cumsum(step)])
    return time_ns, ticks


def _read_ticks(
    reader: AnyReader,
    topics: dict[str, str],
    left_topic: str,
    right_topic: str,
    ticks_per_revolution: float,
    src: str,
) -> WheelSeries:
    t_left, n_left = _read_counts(reader, topics, left_topic, "left", src)
    t_right, n_right = _read_counts(reader, topics, right_topic, "right", src)
    inside = (t_left >= t_right[0]) & (t_left <= t_right[-1])
    if np.count_nonzero(inside) < 2:
        raise InputError(
            f"the ticks topics {left_topic} and {right_topic} overlap in time in fewer than"
            " 2 samples of the left wheel",
            source=src,
        )
    # interpolate on times relative to a common origin: exact to the nanosecond
    origin = min(int(t_left[0]), int(t_right[0]))
    at = (t_left[inside] - origin).astype(np.float64)
    right = np.interp(at, (t_right - origin).astype(np.float64), n_right)
    counts = np.column_stack([n_left[inside], right])
    # both are strictly increasing: _clean made the float seconds so
    return WheelSeries(
        time=_seconds(t_left[inside]), angles=counts * (2.0 * math.pi / ticks_per_revolution)
    )


def _truth(
    time_ns: IntArray, values: FloatArray, what: str, src: str, *, header: bool
) -> PoseSeries:
    """Ground truth from ``values`` shape (k, 6): ``x, y`` and quaternion ``x, y, z, w``."""
    quat = values[:, 2:6]
    with np.errstate(invalid="ignore", divide="ignore"):
        quat = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    qx, qy, qz, qw = quat.T
    yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    poses = np.column_stack([values[:, 0], values[:, 1], yaw])
    _, time, poses = _clean(time_ns, poses, what, src, header=header)
    return PoseSeries(time=time, poses=poses)


def _pose_values(p: _Vector, q: _Quaternion) -> tuple[float, ...]:
    """``x, y`` of ``p`` and the quaternion ``q``'s ``x, y, z, w``."""
    return (float(p.x), float(p.y), float(q.x), float(q.y), float(q.z), float(q.w))


def _read_pose_topic(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    options: BagOptions,
    src: str,
) -> PoseSeries:
    conns, msgtype = _connections(reader, topics, topic, TRUTH_TYPES, "ground truth", src)

    def decode_pose(msg: _PoseStamped) -> list[_Sample]:
        sec, nsec = _stamp(msg)
        pose = msg.pose
        return [(sec, nsec, _pose_values(pose.position, pose.orientation), _POSITION)]

    def decode_covariance(msg: _PoseWithCovarianceStamped) -> list[_Sample]:
        sec, nsec = _stamp(msg)
        pose = msg.pose.pose  # nav_msgs/Odometry has the same pose.pose
        return [(sec, nsec, _pose_values(pose.position, pose.orientation), _POSITION)]

    decode = decode_pose if msgtype == POSE_STAMPED else decode_covariance

    def layout_of(raw: bytes, ros2: bool) -> _Layout:
        cur = _Cursor(raw, ros2)
        stamp = cur.header()
        if msgtype == ODOMETRY:
            cur.string(same=False)  # child_frame_id
        cur.align(8)
        at = cur.pos
        cur.pos += 7 * 8
        fields = (at, at + 8, at + 24, at + 32, at + 40, at + 48)
        return cur.layout(stamp, fields, "f8")

    scan = _scan(
        reader,
        conns,
        msgtype,
        topic,
        src,
        width=6,
        decode=decode,
        layout_of=layout_of,
    )
    header = options.time_source == "header"
    return _truth(scan.time_ns(header), scan.values, f"topic {topic}", src, header=header)


def _read_tf(
    reader: AnyReader,
    topics: dict[str, str],
    parent: str,
    child: str,
    options: BagOptions,
    src: str,
) -> PoseSeries:
    conns, msgtype = _connections(reader, topics, TF_TOPIC, TF_TYPES, "TF ground truth", src)
    want = (parent.lstrip("/"), child.lstrip("/"))
    pairs: set[tuple[str, str]] = set()

    def decode(msg: _TFMessage) -> list[_Sample]:
        samples: list[_Sample] = []
        for tf in msg.transforms:
            pair = (tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/"))
            if pair != want:
                pairs.add(pair)
                continue
            sec, nsec = _stamp(tf)
            values = _pose_values(tf.transform.translation, tf.transform.rotation)
            samples.append((sec, nsec, values, _POSITION))
        return samples

    scan = _scan(reader, conns, msgtype, TF_TOPIC, src, width=6, decode=decode, layout_of=None)
    if scan.values.shape[0] == 0:
        present = _listing([f"{p}->{c}" for p, c in sorted(pairs)]) if pairs else "none"
        raise InputError(
            f"no transform {want[0]}->{want[1]} in {TF_TOPIC}; parent->child pairs"
            f" present: {present}",
            source=src,
        )
    what = f"transform {want[0]}->{want[1]} in {TF_TOPIC}"
    header = options.time_source == "header"
    return _truth(scan.time_ns(header), scan.values, what, src, header=header)

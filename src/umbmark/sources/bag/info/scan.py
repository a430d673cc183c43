"""Looking into a bag's topics, within bounds: what ``umbmark info`` reports
(:mod:`umbmark.sources.bag.info.summary`).

:func:`inspect_topics` finds each topic's first and last receive times and deserializes
at most ``max_messages`` of the messages whose content matters, spread over
:data:`CHUNKS` stretches of the topic's time span (see the docstring of
:mod:`umbmark.sources.bag.info.summary`). What they show is kept per topic (:class:`Content`):
the joints' ranges and speeds, the transforms' ranges and intervals, the ranges of
positions and counters, the models of Gazebo's model states, the scatter of GNSS fixes,
and the intervals between consecutive messages read (within a stretch), from which the
``--max-gap`` a ground truth needs is computed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from umbmark.core.errors import InputError
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.msgtypes import (
    JOINT_STATE,
    MODEL_STATES,
    NAV_SAT_FIX,
    POINT_STAMPED,
    POSE_STAMPED,
    REFERENCE_TYPES,
    TF_TYPES,
    TICK_TYPES,
    TRUTH_TYPES,
    JointState,
    ModelStates,
    NavSatFix,
    Number,
    PointStamped,
    PoseStamped,
    PoseWithCovarianceStamped,
    Stamped,
    TFMessage,
)
from umbmark.sources.bag.truth.references import ModelMotion, ModelRanges, register_model_states

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = [
    "CHUNKS",
    "GAP_SHARE",
    "MOVING_ANGLE",
    "MOVING_DISTANCE",
    "MOVING_SPEED",
    "Content",
    "ScannedTopic",
    "inspect_topics",
    "needed_gap",
]

#: Stretches of a long topic that the messages read are spread over.
CHUNKS = 8
#: A joint moves if its position ranges over more than this [rad] ...
MOVING_ANGLE = 1e-3
#: ... or its speed exceeds this [rad/s].
MOVING_SPEED = 1e-3
#: A pose moves if its position ranges over more than this [m].
MOVING_DISTANCE = 1e-3
#: Share of the intervals between a topic's messages its suggested --max-gap covers.
GAP_SHARE = 0.95

_PROBE = 8  # messages read per probe when looking for a topic's last message
_MAX_PAIRS = 1000  # transforms pairs tracked per topic
_MAX_MODELS = 1000  # models tracked per model-states topic
_METRES_PER_DEGREE = 111_320.0  # of latitude, near enough to tell a moving receiver


def needed_gap(intervals: Sequence[float]) -> float | None:
    """The ``--max-gap`` [s] that interpolates across :data:`GAP_SHARE` of ``intervals``
    [s] (between consecutive messages), with 10 % to spare (rounded to two significant
    digits: at least 5 %); None without intervals."""
    values = np.asarray([v for v in intervals if v > 0], dtype=np.float64)
    if values.size == 0:
        return None
    gap = 1.1 * float(np.quantile(values, GAP_SHARE))
    digits = 1 - math.floor(math.log10(gap))
    return round(gap, digits)


# --- reading a topic -------------------------------------------------------------------


def _take(stream: Iterator[tuple[int, bytes]], n: int) -> list[tuple[int, bytes]]:
    """The first ``n`` items of ``stream``, which is closed after."""
    out: list[tuple[int, bytes]] = []
    try:
        for item in stream:
            out.append(item)
            if len(out) >= n:
                break
    finally:
        close = getattr(stream, "close", None)
        if close is not None:
            close()
    return out


def _last_time(
    reader: AnyReader,
    conns: Sequence[Connection],
    known: int,
    end: int,
    topic: str,
    src: str,
) -> int:
    """The bag time [ns] of the last message of ``conns``.

    ``known`` is the time of one of its messages and no message is at or after ``end``.
    Reads :data:`_PROBE` messages at a time from windows that grow from the end of the
    bag, and bisects where a window holds more.
    """
    lo, hi = known, end
    step = max((hi - lo) // 1024, 1)
    while hi - lo > 1:
        start = max(hi - step, lo + 1)
        times = [
            t for t, _ in _take(bag_reader.raw_messages(reader, conns, topic, src, start), _PROBE)
        ]
        if not times:
            hi = start
            step *= 2
        elif len(times) < _PROBE:
            return times[-1]
        else:
            lo = times[-1]
            step = max((hi - lo) // 2, 1)
    return lo


@dataclass
class _Scan:
    """What was read of one topic: ``items`` in stretches starting at ``starts``."""

    first: int | None = None  # bag time [ns]
    last: int | None = None
    items: list[tuple[int, bytes]] = field(default_factory=list)
    complete: bool = True
    starts: list[int] = field(default_factory=lambda: [0])

    def stretches(self) -> Iterator[tuple[int, int, bytes]]:
        """``(stretch, bag time [ns], raw message)`` of the items, in order."""
        bounds = [*self.starts[1:], len(self.items)]
        stretch = 0
        for k, (bag_ns, raw) in enumerate(self.items):
            while k >= bounds[stretch]:
                stretch += 1
            yield stretch, bag_ns, raw


def _scan_topic(
    reader: AnyReader,
    conns: Sequence[Connection],
    topic: str,
    count: int,
    src: str,
    *,
    content: int,
) -> _Scan:
    """The first and last bag times of ``topic`` and at most ``content`` of its messages:
    all of them if it has no more, else ``content`` spread over :data:`CHUNKS` stretches
    of its time span; see the module docstring."""
    if count == 0:
        return _Scan()
    if content >= count:
        items = list(bag_reader.messages(reader, conns, topic, src))
        if not items:
            return _Scan()
        return _Scan(items[0][0], items[-1][0], items, True)
    per_chunk = max(content // CHUNKS, 1) if content > 0 else 1
    head = _take(bag_reader.messages(reader, conns, topic, src), per_chunk)
    if not head:
        return _Scan()
    scan = _Scan(head[0][0], head[-1][0], head if content > 0 else [], complete=False)
    assert scan.first is not None
    last = _last_time(reader, conns, head[-1][0], int(reader.end_time), topic, src)
    scan.last = last
    if content > 0:
        span = last - scan.first
        for k in range(1, CHUNKS):
            start = scan.first + span * k // CHUNKS
            scan.starts.append(len(scan.items))
            taken = _take(bag_reader.raw_messages(reader, conns, topic, src, start), per_chunk)
            scan.items.extend(taken)
            if len(scan.items) >= content:
                break
        del scan.items[content:]
    return scan


# --- looking into messages -------------------------------------------------------------


@dataclass
class _Interval:
    """Consecutive times within a stretch: the intervals between them [s]."""

    last: tuple[int, int] | None = None  # (stretch, time [ns])
    intervals: list[float] = field(default_factory=list)

    def step(self, stretch: int, time_ns: int) -> float | None:
        """Note ``time_ns`` [ns]; the interval [s] since the previous one in the stretch,
        if any (from integer nanoseconds: float seconds since 1970 resolve only about
        0.2 microseconds)."""
        interval = None
        if self.last is not None and self.last[0] == stretch and time_ns > self.last[1]:
            interval = (time_ns - self.last[1]) * 1e-9
            self.intervals.append(interval)
        self.last = (stretch, time_ns)
        return interval


@dataclass
class JointStats:
    """One joint in the messages read: samples, position range, speeds."""

    samples: int = 0
    low: float = math.inf
    high: float = -math.inf
    speed: float = -math.inf
    position_speed: float = -math.inf
    times: _Interval = field(default_factory=_Interval)
    last_position: float | None = None

    @property
    def position_range(self) -> float | None:
        """``max - min`` of its positions, None without."""
        return self.high - self.low if self.high >= self.low else None

    @property
    def max_speed(self) -> tuple[float | None, str | None]:
        """The largest speed [rad/s] and where it comes from (velocities, else positions)."""
        if self.speed >= 0:
            return self.speed, "velocity"
        if self.position_speed >= 0:
            return self.position_speed, "positions"
        return None, None

    @property
    def moving(self) -> bool:
        """Its position ranges over :data:`MOVING_ANGLE` or its speed exceeds
        :data:`MOVING_SPEED`."""
        position, speed = self.position_range, self.max_speed[0]
        return bool(
            (position is not None and position > MOVING_ANGLE)
            or (speed is not None and speed > MOVING_SPEED)
        )

    def add_position(self, stretch: int, time_ns: int, position: float) -> None:
        """A position [rad] at ``time_ns`` [ns]: its range, and its speed since the last."""
        self.low = min(self.low, position)
        self.high = max(self.high, position)
        previous = self.last_position
        interval = self.times.step(stretch, time_ns)
        if interval is not None and previous is not None:
            self.position_speed = max(self.position_speed, abs(position - previous) / interval)
        self.last_position = position


@dataclass
class PairStats:
    """The transforms of one parent->child pair: how many, how far they range, and the
    intervals between them."""

    count: int = 0
    low: list[float] = field(default_factory=lambda: [math.inf] * 7)
    high: list[float] = field(default_factory=lambda: [-math.inf] * 7)
    times: _Interval = field(default_factory=_Interval)

    def add(self, translation: Sequence[float], rotation: Sequence[float]) -> None:
        """One transform: ``translation`` [m] shape (3,), quaternion ``x, y, z, w``."""
        self.count += 1
        q = list(rotation)
        if q[3] < 0:  # q and -q are the same rotation
            q = [-v for v in q]
        for i, v in enumerate((*translation, *q)):
            if math.isfinite(v):
                self.low[i] = min(self.low[i], v)
                self.high[i] = max(self.high[i], v)

    def _spans(self) -> list[float]:
        return [h - lo for lo, h in zip(self.low, self.high, strict=True) if h >= lo]

    @property
    def moving(self) -> bool:
        """Translation ranging over ``MOVING_DISTANCE`` [m], or the rotation's quaternion
        components over ``MOVING_ANGLE / 2`` (a turn of about ``MOVING_ANGLE`` [rad])."""
        spans = self._spans()
        if len(spans) < 7:
            return False
        return max(spans[:3]) > MOVING_DISTANCE or max(spans[3:]) > 0.5 * MOVING_ANGLE

    @property
    def turns_only(self) -> bool:
        """It moves, and only turns (its translation within ``MOVING_DISTANCE``)."""
        spans = self._spans()
        return len(spans) == 7 and self.moving and max(spans[:3]) <= MOVING_DISTANCE


@dataclass
class Content:
    """What the messages of one topic showed."""

    joints: dict[str, JointStats] = field(default_factory=dict)
    pairs: dict[tuple[str, str], PairStats] = field(default_factory=dict)
    models: ModelRanges = field(default_factory=lambda: ModelRanges(limit=_MAX_MODELS))
    sigmas: list[float] = field(default_factory=list)  # GNSS horizontal sigma [m]
    low: NDArray[np.float64] | None = None
    high: NDArray[np.float64] | None = None
    frames: tuple[str, str] | None = None  # header frame, child frame (Odometry)
    empty_stamps: int = 0
    stamped: int = 0
    decoded: int = 0
    times: _Interval = field(default_factory=_Interval)
    now: tuple[int, int] = (0, 0)  # the message being looked into: (stretch, bag time [ns])

    def extend(self, values: Sequence[float]) -> None:
        """Widen the value range by ``values``, shape (k,) (positions or counts)."""
        v = np.asarray(values, dtype=np.float64)
        if not np.all(np.isfinite(v)):
            return
        self.low = v if self.low is None else np.minimum(self.low, v)
        self.high = v if self.high is None else np.maximum(self.high, v)

    @property
    def value_range(self) -> float | None:
        """The largest range of the values [m, or counts]; None without values."""
        if self.low is None or self.high is None:
            return None
        return float(np.max(self.high - self.low))

    def stamp(self, msg: Stamped) -> int:
        """Count ``msg``'s header stamp, and whether it is empty; its time [ns] (the bag
        time where the stamp is empty)."""
        stamp = msg.header.stamp
        self.stamped += 1
        if int(stamp.sec) == 0 and int(stamp.nanosec) == 0:
            self.empty_stamps += 1
            return self.now[1]
        return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)

    def model_motion(self) -> list[ModelMotion]:
        """The models seen, and how far each moved."""
        return self.models.motion()

    @property
    def sigma(self) -> float | None:
        """Median horizontal standard deviation [m] of the GNSS fixes, None without."""
        return float(np.median(self.sigmas)) if self.sigmas else None


def _joint_state(msg: JointState, out: Content) -> None:
    time = out.stamp(msg)
    position = np.asarray(msg.position, dtype=np.float64)
    velocity = np.asarray(msg.velocity, dtype=np.float64)
    for i, name in enumerate(msg.name):
        stats = out.joints.get(name)
        if stats is None:
            stats = out.joints[name] = JointStats()
        stats.samples += 1
        if i < position.size and math.isfinite(position[i]):
            stats.add_position(out.now[0], time, float(position[i]))
        if i < velocity.size and math.isfinite(velocity[i]):
            stats.speed = max(stats.speed, abs(float(velocity[i])))


def _pose(msg: PoseStamped, out: Content) -> None:
    out.stamp(msg)
    out.extend((float(msg.pose.position.x), float(msg.pose.position.y)))
    if out.frames is None:
        out.frames = (str(msg.header.frame_id), "")


def _pose_with_covariance(msg: PoseWithCovarianceStamped, out: Content) -> None:
    """``geometry_msgs/PoseWithCovarianceStamped`` and ``nav_msgs/Odometry``."""
    out.stamp(msg)
    pose = msg.pose.pose
    out.extend((float(pose.position.x), float(pose.position.y)))
    if out.frames is None:
        out.frames = (str(msg.header.frame_id), str(getattr(msg, "child_frame_id", "")))


def _point(msg: PointStamped, out: Content) -> None:
    out.stamp(msg)
    out.extend((float(msg.point.x), float(msg.point.y)))
    if out.frames is None:
        out.frames = (str(msg.header.frame_id), "")


def _fix(msg: NavSatFix, out: Content) -> None:
    out.stamp(msg)
    if int(msg.status.status) < 0:
        return
    lat, lon = float(msg.latitude), float(msg.longitude)
    east = lon * _METRES_PER_DEGREE * math.cos(math.radians(lat)) if math.isfinite(lat) else lat
    out.extend((lat * _METRES_PER_DEGREE, east))
    c = np.asarray(msg.position_covariance, dtype=np.float64)
    if int(msg.position_covariance_type) > 0 and c.size == 9:
        variance = 0.5 * (float(c[0]) + float(c[4]))
        if math.isfinite(variance) and variance >= 0:
            out.sigmas.append(math.sqrt(variance))


def _model_states(msg: ModelStates, out: Content) -> None:
    out.models.add(msg)


def _number(msg: Number, out: Content) -> None:
    out.extend((float(msg.data),))


def _transforms(msg: TFMessage, out: Content) -> None:
    stretch, bag_ns = out.now
    for tf in msg.transforms:
        pair = (str(tf.header.frame_id).lstrip("/"), str(tf.child_frame_id).lstrip("/"))
        stats = out.pairs.get(pair)
        if stats is None:
            if len(out.pairs) >= _MAX_PAIRS:
                continue
            stats = out.pairs[pair] = PairStats()
        t, q = tf.transform.translation, tf.transform.rotation
        stats.add(
            (float(t.x), float(t.y), float(t.z)), (float(q.x), float(q.y), float(q.z), float(q.w))
        )
        stats.times.step(stretch, bag_ns)


def _reader_of(msgtype: str) -> Callable[[Any, Content], None] | None:
    """How to look into messages of ``msgtype``; None for types not looked into."""
    readers: dict[str, Callable[[Any, Content], None]] = {
        JOINT_STATE: _joint_state,
        POSE_STAMPED: _pose,
        POINT_STAMPED: _point,
        NAV_SAT_FIX: _fix,
        MODEL_STATES: _model_states,
    }
    if msgtype in readers:
        return readers[msgtype]
    if msgtype in TRUTH_TYPES:
        return _pose_with_covariance
    if msgtype in TICK_TYPES:
        return _number
    if msgtype in TF_TYPES:
        return _transforms
    return None


@dataclass
class ScannedTopic:
    """One topic: its counts and times, and what its messages showed (None: not looked
    into)."""

    name: str
    msgtype: str
    count: int
    scan: _Scan
    content: Content | None

    @property
    def duration(self) -> float | None:
        """From its first to its last message [s]."""
        if self.scan.first is None or self.scan.last is None:
            return None
        return (self.scan.last - self.scan.first) * 1e-9

    @property
    def rate(self) -> float | None:
        """``(count - 1) / duration`` [Hz]."""
        duration = self.duration
        if duration is None or duration <= 0 or self.count < 2:
            return None
        return (self.count - 1) / duration

    @property
    def moving(self) -> bool | None:
        """Whether its positions (or counts) range over the threshold; None if unknown."""
        if self.content is None or self.content.decoded == 0:
            return None
        if self.msgtype == MODEL_STATES:
            return any(m.moving for m in self.content.model_motion())
        value_range = self.content.value_range
        if value_range is None:
            return None
        threshold = MOVING_DISTANCE if self.msgtype in REFERENCE_TYPES else 0.5
        return value_range > threshold

    @property
    def needed_gap(self) -> float | None:
        """The ``--max-gap`` [s] it needs as a ground truth (between consecutive messages
        read; :func:`needed_gap`)."""
        return None if self.content is None else needed_gap(self.content.times.intervals)


def inspect_topics(
    reader: AnyReader,
    topics: dict[str, str],
    src: str,
    max_messages: int,
    *,
    wanted: Callable[[str, str], bool],
    notes: list[str],
) -> list[ScannedTopic]:
    """Scan the topics ``wanted(topic, msgtype)``: their times and, for the types looked
    into, up to ``max_messages`` messages each."""
    out = []
    infos = reader.topics
    for name, msgtype in topics.items():
        if not wanted(name, msgtype):
            continue
        conns = [c for c in reader.connections if c.topic == name]
        count = int(infos[name].msgcount)
        look = _reader_of(msgtype) if "," not in msgtype else None
        content = Content() if look is not None else None
        scan = _scan_topic(
            reader,
            conns,
            name,
            count,
            src,
            content=max_messages if look is not None else 0,
        )
        if look is not None and content is not None:
            try:
                if msgtype == MODEL_STATES:
                    register_model_states(reader, src)
                for stretch, bag_ns, raw in scan.stretches():
                    content.now = (stretch, bag_ns)
                    content.times.step(stretch, bag_ns)
                    look(bag_reader.deserialize(reader, raw, msgtype, name, src), content)
                    content.decoded += 1
            except InputError as err:
                notes.append(f"{name}: {err.problem}; looked into {content.decoded} messages")
        out.append(ScannedTopic(name, msgtype, count, scan, content))
    return out

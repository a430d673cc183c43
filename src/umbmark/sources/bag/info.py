"""What is in a bag: topics, wheel joints, transforms, and the options to read it with.

:func:`bag_info` lists every topic of a ROS 1 or ROS 2 bag with its message type, count,
rate and duration; for ``sensor_msgs/JointState`` topics the joints and which of them
move; the parent->child pairs of ``/tf`` and ``/tf_static`` and the chains they form
from their roots (``map -> odom -> base_link``); and the candidates for each input:
wheels (a moving left/right pair of joints, or left/right ``std_msgs`` counter topics),
controller odometry (``nav_msgs/Odometry`` topics, ``odom -> base_*`` transforms) and
ground truth (pose topics, odometry topics, transforms from a fixed frame such as
``map`` or ``world``). :func:`truth_candidates` is the short version for an error
message that asks for ground truth.

The work is bounded
-------------------
Counts come from the bag's index. Times are receive (bag) times: a topic's first message
is read, and its last one found by reading a few messages at a time from the end of the
bag (bisection). Only the topics whose content matters are deserialized, at most
``max_messages`` messages each (default :data:`DEFAULT_MAX_MESSAGES`): all of them when
the topic has no more, else ``max_messages`` spread over :data:`CHUNKS` stretches evenly
spaced over its time span, so that a robot that stands still at first still shows its
wheels moving. Transform rates are the topic's rate times each pair's share of the
messages read. At most :data:`MAX_LISTED` names (topics, joints, transforms, candidates)
and :data:`MAX_CHAINS` chains are listed; the rest are counted.

"Moving" means, in the messages read: a joint's position range over
:data:`MOVING_ANGLE` [rad] or a speed over :data:`MOVING_SPEED` [rad/s]; a pose's
position range over :data:`MOVING_DISTANCE` [m]; a counter's range of at least one
count.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from . import reader as bag_reader
from .msgtypes import (
    JOINT_STATE,
    ODOMETRY,
    POSE_COV_STAMPED,
    POSE_STAMPED,
    TF_TYPES,
    TICK_TYPES,
    TRUTH_TYPES,
    JointState,
    Number,
    PoseStamped,
    PoseWithCovarianceStamped,
    Stamped,
    TFMessage,
)
from .series import BagOptions

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = [
    "CHUNKS",
    "DEFAULT_MAX_MESSAGES",
    "MAX_CHAINS",
    "MAX_LISTED",
    "MOVING_ANGLE",
    "MOVING_DISTANCE",
    "MOVING_SPEED",
    "BagInfo",
    "Candidate",
    "JointInfo",
    "JointStateInfo",
    "TopicInfo",
    "TransformInfo",
    "bag_info",
    "mirrored_pairs",
    "tf_chains",
    "truth_candidates",
]

#: Messages deserialized per topic at most.
DEFAULT_MAX_MESSAGES = 2000
#: Stretches of a long topic that the messages read are spread over.
CHUNKS = 8
#: Names listed at most (topics, joints of a topic, transforms, candidates of a role).
MAX_LISTED = 50
#: Chains listed at most.
MAX_CHAINS = 20
#: A joint moves if its position ranges over more than this [rad] ...
MOVING_ANGLE = 1e-3
#: ... or its speed exceeds this [rad/s].
MOVING_SPEED = 1e-3
#: A pose moves if its position ranges over more than this [m].
MOVING_DISTANCE = 1e-3

_PROBE = 8  # messages read per probe when looking for a topic's last message
_MAX_PAIRS = 1000  # transforms pairs tracked per topic
_MAX_DEPTH = 32  # frames in a chain at most
TF_TOPIC, TF_STATIC = "/tf", "/tf_static"

Role = Literal["wheels", "odometry", "truth"]


# --- what the report holds -------------------------------------------------------------


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a bag.

    Attributes
    ----------
    name, msgtype : str
        Topic and message type (``sensor_msgs/msg/JointState``; several joined by ``", "``).
    count : int
        Messages in the bag.
    duration : float or None
        Receive time from the first to the last message [s]; None without messages.
    rate : float or None
        ``(count - 1) / duration`` [Hz]; None with fewer than two distinct times.
    scanned : int
        Messages deserialized to look into them (0 for types not looked into).
    """

    name: str
    msgtype: str
    count: int
    duration: float | None
    rate: float | None
    scanned: int = 0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``name``, ``type``, ``count``, ``rate`` [Hz], ``duration`` [s] and
        ``scanned``."""
        return {
            "name": self.name,
            "type": self.msgtype,
            "count": self.count,
            "rate": self.rate,
            "duration": self.duration,
            "scanned": self.scanned,
        }


@dataclass(frozen=True)
class JointInfo:
    """One joint of a ``sensor_msgs/JointState`` topic, in the messages read.

    Attributes
    ----------
    name : str
    samples : int
        Messages read that carry it.
    position_range : float or None
        ``max - min`` of its finite positions [rad, or m for prismatic joints]; None
        without positions.
    max_speed : float or None
        Largest ``|velocity|`` [rad/s]; None without velocities.
    moving : bool
        ``position_range > MOVING_ANGLE`` or ``max_speed > MOVING_SPEED``.
    """

    name: str
    samples: int
    position_range: float | None
    max_speed: float | None
    moving: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the attributes by name."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class JointStateInfo:
    """The joints of a ``sensor_msgs/JointState`` topic.

    Attributes
    ----------
    topic : str
    joints : tuple of JointInfo
        In order of first appearance, at most :data:`MAX_LISTED`.
    not_listed : int
        Joints found beyond those listed.
    scanned : int
        Messages read.
    complete : bool
        Every message of the topic was read.
    """

    topic: str
    joints: tuple[JointInfo, ...]
    not_listed: int
    scanned: int
    complete: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``topic``, ``scanned``, ``complete``, ``joints``, ``joints_not_listed``."""
        return {
            "topic": self.topic,
            "scanned": self.scanned,
            "complete": self.complete,
            "joints": [joint.to_dict() for joint in self.joints],
            "joints_not_listed": self.not_listed,
        }


@dataclass(frozen=True)
class TransformInfo:
    """A parent->child pair of ``/tf`` or ``/tf_static`` (leading slashes dropped).

    Attributes
    ----------
    parent, child : str
    topic : str
        ``/tf`` or ``/tf_static``.
    count : int
        Transforms of the pair in the messages read.
    rate : float or None
        Estimated rate [Hz] (the topic's rate times the pair's share of the messages
        read); None for ``/tf_static``.
    moving : bool
        Its translation ranges over :data:`MOVING_DISTANCE` or its rotation over about
        :data:`MOVING_ANGLE`, in the messages read.
    """

    parent: str
    child: str
    topic: str
    count: int
    rate: float | None
    moving: bool = False

    @property
    def static(self) -> bool:
        """Whether it comes from ``/tf_static``."""
        return self.topic == TF_STATIC

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``parent``, ``child``, ``topic``, ``static``, ``count``, ``rate``
        [Hz], ``moving``."""
        return {
            "parent": self.parent,
            "child": self.child,
            "topic": self.topic,
            "static": self.static,
            "count": self.count,
            "rate": self.rate,
            "moving": self.moving,
        }


@dataclass(frozen=True)
class Candidate:
    """A way to read one input from the bag.

    Attributes
    ----------
    role : {"wheels", "odometry", "truth"}
        The input: wheel rotation, the controller's own odometry, ground truth.
    kind : str
        ``joint_states``, ``ticks``, ``topic``, ``tf`` (a direct transform) or
        ``tf_chain`` (transforms to compose).
    label : str
        What it is, for people: ``/mocap/pose (geometry_msgs/msg/PoseStamped)``.
    options : tuple of (str, str)
        The command-line options that select it (empty where no option reads it).
    moving : bool or None
        Whether it moves in the messages read; None if not looked into.
    """

    role: Role
    kind: str
    label: str
    options: tuple[tuple[str, str], ...] = ()
    moving: bool | None = None

    @property
    def command_line(self) -> str:
        """The options as typed: ``--truth-topic /mocap/pose``."""
        return " ".join(f"{flag} {value}" for flag, value in self.options)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``kind``, ``label``, ``options`` (flag to value), ``moving``."""
        return {
            "kind": self.kind,
            "label": self.label,
            "options": dict(self.options),
            "moving": self.moving,
        }


@dataclass(frozen=True)
class BagInfo:
    """What is in a bag (see the module docstring).

    Attributes
    ----------
    path : str
    storage : str
        ``ros1``, ``sqlite3`` or ``mcap``.
    start : float or None
        Receive time of the first message [s since 1970]; None for an empty bag.
    duration : float
        From the first to the last message [s].
    messages : int
        Messages in the bag.
    topics : tuple of TopicInfo
        Sorted by name, at most :data:`MAX_LISTED`; ``topics_not_listed`` more.
    joint_states : tuple of JointStateInfo
    transforms : tuple of TransformInfo
        ``/tf`` pairs, then ``/tf_static`` pairs, at most :data:`MAX_LISTED`.
    chains : tuple of tuple of str
        Frames from a root down to the last frame that moves (``("map", "odom",
        "base_link")``): transforms that only mount sensors are left out. At most
        :data:`MAX_CHAINS`.
    wheels, odometry, truth : tuple of Candidate
        The candidates of each input, likeliest first.
    max_messages : int
        Messages deserialized per topic at most.
    complete : bool
        Every message of the topics looked into was read.
    notes : tuple of str
        What people should know (topics that could not be decoded, empty stamps).
    """

    path: str
    storage: str
    start: float | None
    duration: float
    messages: int
    topics: tuple[TopicInfo, ...]
    topics_not_listed: int
    joint_states: tuple[JointStateInfo, ...]
    transforms: tuple[TransformInfo, ...]
    transforms_not_listed: int
    chains: tuple[tuple[str, ...], ...]
    chains_not_listed: int
    wheels: tuple[Candidate, ...]
    odometry: tuple[Candidate, ...]
    truth: tuple[Candidate, ...]
    max_messages: int
    complete: bool
    notes: tuple[str, ...] = ()
    empty_stamps: tuple[str, ...] = field(default=(), repr=False)

    @property
    def suggested_options(self) -> str | None:
        """Options to read the wheels and the ground truth with, from the likeliest
        candidates: ``--truth-topic /mocap/pose --left-joint wheel_left_joint ...``; the
        controller's odometry instead of the wheels when no wheel candidate is found.

        Options that equal the defaults are left out; ``--time-source bag`` is added when
        a chosen topic's header stamps are empty. None when the bag has neither.
        """
        inputs = self.wheels[:1] or self.odometry[:1]
        chosen = [c for c in (self.truth[:1] + inputs) if c.options]
        if not chosen:
            return None
        defaults = _DEFAULT_OPTIONS
        parts = [
            f"{flag} {value}"
            for candidate in chosen
            for flag, value in candidate.options
            if defaults.get(flag) != value
        ]
        if any(_topic_of(c) in self.empty_stamps for c in chosen):
            parts.append("--time-source bag")
        return " ".join(parts) or None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (seconds, hertz, radians, metres); see :class:`BagInfo`."""
        return {
            "storage": self.storage,
            "start": self.start,
            "duration": self.duration,
            "messages": self.messages,
            "max_messages": self.max_messages,
            "complete": self.complete,
            "topics": [topic.to_dict() for topic in self.topics],
            "topics_not_listed": self.topics_not_listed,
            "joint_states": [js.to_dict() for js in self.joint_states],
            "transforms": [tf.to_dict() for tf in self.transforms],
            "transforms_not_listed": self.transforms_not_listed,
            "chains": [list(chain) for chain in self.chains],
            "chains_not_listed": self.chains_not_listed,
            "candidates": {
                "wheels": [c.to_dict() for c in self.wheels],
                "odometry": [c.to_dict() for c in self.odometry],
                "truth": [c.to_dict() for c in self.truth],
            },
            "suggested_options": self.suggested_options,
            "notes": list(self.notes),
        }


_DEFAULT_OPTIONS = {"--wheel-topic": BagOptions().wheel_topic}


def _topic_of(candidate: Candidate) -> str | None:
    options = dict(candidate.options)
    for flag in ("--truth-topic", "--wheel-topic", "--odom-topic"):
        if flag in options:
            return options[flag]
    return None


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
    """What was read of one topic."""

    first: int | None = None  # bag time [ns]
    last: int | None = None
    items: list[tuple[int, bytes]] = field(default_factory=list)
    complete: bool = True


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
            taken = _take(bag_reader.raw_messages(reader, conns, topic, src, start), per_chunk)
            scan.items.extend(taken)
            if len(scan.items) >= content:
                break
        del scan.items[content:]
    return scan


# --- looking into messages -------------------------------------------------------------


@dataclass
class _JointStats:
    samples: int = 0
    low: float = math.inf
    high: float = -math.inf
    speed: float = -math.inf

    def info(self, name: str) -> JointInfo:
        position = self.high - self.low if self.high >= self.low else None
        speed = self.speed if self.speed >= 0 else None
        moving = (position is not None and position > MOVING_ANGLE) or (
            speed is not None and speed > MOVING_SPEED
        )
        return JointInfo(name, self.samples, position, speed, bool(moving))


@dataclass
class _PairStats:
    """The transforms of one parent->child pair: how many, and how far they range."""

    count: int = 0
    low: list[float] = field(default_factory=lambda: [math.inf] * 7)
    high: list[float] = field(default_factory=lambda: [-math.inf] * 7)

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

    @property
    def moving(self) -> bool:
        """Translation ranging over ``MOVING_DISTANCE`` [m], or the rotation's quaternion
        components over ``MOVING_ANGLE / 2`` (a turn of about ``MOVING_ANGLE`` [rad])."""
        spans = [h - lo for lo, h in zip(self.low, self.high, strict=True) if h >= lo]
        if len(spans) < 7:
            return False
        return max(spans[:3]) > MOVING_DISTANCE or max(spans[3:]) > 0.5 * MOVING_ANGLE


@dataclass
class _Content:
    """What the messages of one topic showed."""

    joints: dict[str, _JointStats] = field(default_factory=dict)
    pairs: dict[tuple[str, str], _PairStats] = field(default_factory=dict)
    low: NDArray[np.float64] | None = None
    high: NDArray[np.float64] | None = None
    frames: tuple[str, str] | None = None  # header frame, child frame (Odometry)
    empty_stamps: int = 0
    stamped: int = 0
    decoded: int = 0

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

    def stamp(self, msg: Stamped) -> None:
        """Count ``msg``'s header stamp, and whether it is empty."""
        stamp = msg.header.stamp
        self.stamped += 1
        if int(stamp.sec) == 0 and int(stamp.nanosec) == 0:
            self.empty_stamps += 1


def _joint_state(msg: JointState, out: _Content) -> None:
    out.stamp(msg)
    position = np.asarray(msg.position, dtype=np.float64)
    velocity = np.asarray(msg.velocity, dtype=np.float64)
    for i, name in enumerate(msg.name):
        stats = out.joints.get(name)
        if stats is None:
            stats = out.joints[name] = _JointStats()
        stats.samples += 1
        if i < position.size and math.isfinite(position[i]):
            stats.low = min(stats.low, float(position[i]))
            stats.high = max(stats.high, float(position[i]))
        if i < velocity.size and math.isfinite(velocity[i]):
            stats.speed = max(stats.speed, abs(float(velocity[i])))


def _pose(msg: PoseStamped, out: _Content) -> None:
    out.stamp(msg)
    out.extend((float(msg.pose.position.x), float(msg.pose.position.y)))
    if out.frames is None:
        out.frames = (str(msg.header.frame_id), "")


def _pose_with_covariance(msg: PoseWithCovarianceStamped, out: _Content) -> None:
    """``geometry_msgs/PoseWithCovarianceStamped`` and ``nav_msgs/Odometry``."""
    out.stamp(msg)
    pose = msg.pose.pose
    out.extend((float(pose.position.x), float(pose.position.y)))
    if out.frames is None:
        out.frames = (str(msg.header.frame_id), str(getattr(msg, "child_frame_id", "")))


def _number(msg: Number, out: _Content) -> None:
    out.extend((float(msg.data),))


def _transforms(msg: TFMessage, out: _Content) -> None:
    for tf in msg.transforms:
        pair = (str(tf.header.frame_id).lstrip("/"), str(tf.child_frame_id).lstrip("/"))
        stats = out.pairs.get(pair)
        if stats is None:
            if len(out.pairs) >= _MAX_PAIRS:
                continue
            stats = out.pairs[pair] = _PairStats()
        t, q = tf.transform.translation, tf.transform.rotation
        stats.add(
            (float(t.x), float(t.y), float(t.z)), (float(q.x), float(q.y), float(q.z), float(q.w))
        )


def _reader_of(msgtype: str) -> Callable[[Any, _Content], None] | None:
    """How to look into messages of ``msgtype``; None for types not looked into."""
    if msgtype == JOINT_STATE:
        return _joint_state
    if msgtype == POSE_STAMPED:
        return _pose
    if msgtype in TRUTH_TYPES:
        return _pose_with_covariance
    if msgtype in TICK_TYPES:
        return _number
    if msgtype in TF_TYPES:
        return _transforms
    return None


@dataclass
class _Topic:
    name: str
    msgtype: str
    count: int
    scan: _Scan
    content: _Content | None

    @property
    def duration(self) -> float | None:
        if self.scan.first is None or self.scan.last is None:
            return None
        return (self.scan.last - self.scan.first) * 1e-9

    @property
    def rate(self) -> float | None:
        duration = self.duration
        if duration is None or duration <= 0 or self.count < 2:
            return None
        return (self.count - 1) / duration

    @property
    def moving(self) -> bool | None:
        if self.content is None or self.content.decoded == 0:
            return None
        value_range = self.content.value_range
        if value_range is None:
            return None
        threshold = MOVING_DISTANCE if self.msgtype in TRUTH_TYPES else 0.5
        return value_range > threshold


def _inspect(
    reader: AnyReader,
    topics: dict[str, str],
    src: str,
    max_messages: int,
    *,
    wanted: Callable[[str, str], bool],
    notes: list[str],
) -> list[_Topic]:
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
        content = _Content() if look is not None else None
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
                for _, raw in scan.items:
                    look(bag_reader.deserialize(reader, raw, msgtype, name, src), content)
                    content.decoded += 1
            except InputError as err:
                notes.append(f"{name}: {err.problem}; looked into {content.decoded} messages")
        out.append(_Topic(name, msgtype, count, scan, content))
    return out


# --- candidates --------------------------------------------------------------------------

_MIRRORS: tuple[tuple[re.Pattern[str], str], ...] = (
    (re.compile(r"left"), "right"),
    (re.compile(r"Left"), "Right"),
    (re.compile(r"LEFT"), "RIGHT"),
    (re.compile(r"(?<![A-Za-z])l(?![a-z])"), "r"),  # wheel_l, l_wheel, /l/
    (re.compile(r"(?<![A-Za-z])L(?![a-z])"), "R"),
    (re.compile(r"(?<![A-Za-z])l(?=wheel|_?whl|enc|tick)"), "r"),  # lwheel, lenc
    (re.compile(r"(?<![A-Za-z])([fbrm])l(?![a-z])"), r"\1r"),  # fl_wheel, rl_wheel
)


def mirrored_pairs(names: Sequence[str]) -> list[tuple[str, str]]:
    """``(left, right)`` pairs of ``names`` whose names differ by left for right.

    ``left``/``right`` in any case, and ``l``/``r`` as a word of their own (``wheel_l``,
    ``l_wheel``), before ``wheel`` (``lwheel``) or after ``f``, ``b``, ``r``, ``m``
    (``fl_wheel``); in the order of ``names``.
    """
    present = set(names)
    pairs: list[tuple[str, str]] = []
    for name in names:
        for pattern, repl in _MIRRORS:
            for match in pattern.finditer(name):
                other = name[: match.start()] + match.expand(repl) + name[match.end() :]
                if other != name and other in present and (name, other) not in pairs:
                    pairs.append((name, other))
    return pairs


_TRUTH_WORDS = ("mocap", "vicon", "optitrack", "qualisys", "ground_truth", "groundtruth",
                "truth", "gt", "natnet", "motion_capture", "tracker")  # fmt: skip
_FIXED_FRAMES = ("world", "map", "mocap", "vicon", "optitrack", "earth", "odom_gt")


def _words(name: str) -> set[str]:
    return {w for w in re.split(r"[^a-z0-9]+", name.lower()) if w}


def _truth_like(name: str) -> bool:
    low = name.lower()
    return any(w in _words(name) for w in _TRUTH_WORDS) or any(
        w in low for w in _TRUTH_WORDS if len(w) > 3
    )


def _fixed_frame(frame: str) -> bool:
    low = frame.lower()
    return low in _FIXED_FRAMES or any(w in _words(low) for w in _FIXED_FRAMES)


def _wheel_candidates(scanned: Sequence[_Topic]) -> list[Candidate]:
    found: list[tuple[tuple[int, int, int], Candidate]] = []
    for topic in scanned:
        content = topic.content
        if topic.msgtype != JOINT_STATE or content is None:
            continue
        stats = {name: s.info(name) for name, s in content.joints.items()}
        for left, right in mirrored_pairs(list(stats)):
            moving = stats[left].moving and stats[right].moving
            wheel = "wheel" in left.lower() and "wheel" in right.lower()
            options = (("--wheel-topic", topic.name), ("--left-joint", left),
                       ("--right-joint", right))  # fmt: skip
            label = f"{topic.name}: joints {left} and {right}"
            rank = (
                0 if moving else 1,
                0 if wheel else 1,
                0 if topic.name == "/joint_states" else 1,
            )
            found.append((rank, Candidate("wheels", "joint_states", label, options, moving)))
    ticks = [t for t in scanned if t.msgtype in TICK_TYPES]
    by_name = {t.name: t for t in ticks}
    for left, right in mirrored_pairs([t.name for t in ticks]):
        moving_l, moving_r = by_name[left].moving, by_name[right].moving
        counting = None if moving_l is None or moving_r is None else moving_l and moving_r
        options = (("--left-ticks-topic", left), ("--right-ticks-topic", right),
                   ("--ticks-per-rev", "N"))  # fmt: skip
        label = (
            f"{left} and {right} ({by_name[left].msgtype}; N: encoder counts per wheel revolution)"
        )
        rank = (0 if counting else 1, 1, 1)
        found.append((rank, Candidate("wheels", "ticks", label, options, counting)))
    found.sort(key=lambda item: item[0])
    return [c for _, c in found]


def _odometry_label(topic: _Topic) -> str:
    frames = topic.content.frames if topic.content is not None else None
    if frames is not None and frames[0] and frames[1]:
        return f"{topic.name} ({topic.msgtype}, {frames[0]} -> {frames[1]})"
    if frames is not None and frames[0]:
        return f"{topic.name} ({topic.msgtype}, frame {frames[0]})"
    return f"{topic.name} ({topic.msgtype})"


def _odometry_candidates(
    scanned: Sequence[_Topic], transforms: Sequence[TransformInfo]
) -> list[Candidate]:
    out = [
        Candidate("odometry", "topic", _odometry_label(t), (("--odom-topic", t.name),), t.moving)
        for t in scanned
        if t.msgtype == ODOMETRY and not _truth_like(t.name)
    ]
    for tf in transforms:
        if not tf.static and "odom" in _words(tf.parent) and not _fixed_frame(tf.parent):
            options = (("--odom-tf", f"{tf.parent} {tf.child}"),)
            label = f"TF {tf.parent} -> {tf.child}"
            out.append(Candidate("odometry", "tf", label, options, tf.moving))
    out.sort(key=lambda c: c.moving is False)
    return out


def _truth_candidates(
    scanned: Sequence[_Topic],
    transforms: Sequence[TransformInfo],
    chains: Sequence[tuple[str, ...]],
) -> list[Candidate]:
    found: list[tuple[int, Candidate]] = []
    order = {POSE_STAMPED: 0, POSE_COV_STAMPED: 1, ODOMETRY: 2}
    for t in scanned:
        if t.msgtype not in TRUTH_TYPES:
            continue
        rank = order[t.msgtype] - (3 if _truth_like(t.name) else 0)
        if t.msgtype == ODOMETRY and not _truth_like(t.name):
            rank += 3  # the controller's own odometry is no ground truth
        if t.moving is False:
            rank += 10
        label = _odometry_label(t) if t.msgtype == ODOMETRY else f"{t.name} ({t.msgtype})"
        candidate = Candidate("truth", "topic", label, (("--truth-topic", t.name),), t.moving)
        found.append((rank, candidate))
    seen: set[tuple[str, str]] = set()
    for tf in transforms:
        if tf.static or not _fixed_frame(tf.parent) or "odom" in _words(tf.child):
            continue
        seen.add((tf.parent, tf.child))
        options = (("--tf-parent", tf.parent), ("--tf-child", tf.child))
        label = f"TF {tf.parent} -> {tf.child}"
        rank = (1 if _truth_like(tf.parent) else 2) + (0 if tf.moving else 10)
        found.append((rank, Candidate("truth", "tf", label, options, tf.moving)))
    for chain in chains:
        if len(chain) < 3 or not _fixed_frame(chain[0]):
            continue
        bases = [f for f in chain[1:] if f.lower().startswith("base")]
        child = bases[0] if bases else chain[-1]
        path = chain[: chain.index(child) + 1]
        if len(path) < 3 or (path[0], child) in seen:
            continue
        seen.add((path[0], child))
        options = (("--tf-parent", path[0]), ("--tf-child", child))
        label = "TF chain " + " -> ".join(path)
        found.append((4, Candidate("truth", "tf_chain", label, options)))
    found.sort(key=lambda item: item[0])
    return [c for _, c in found]


# --- transforms and chains ----------------------------------------------------------------


def _transform_infos(scanned: Sequence[_Topic]) -> list[TransformInfo]:
    out = []
    for topic in sorted(scanned, key=lambda t: t.name == TF_STATIC):
        content = topic.content
        if (
            topic.msgtype not in TF_TYPES
            or content is None
            or topic.name not in (TF_TOPIC, TF_STATIC)
        ):
            continue
        read = max(content.decoded, 1)
        static = topic.name == TF_STATIC
        for (parent, child), stats in content.pairs.items():
            rate = None if static or topic.rate is None else topic.rate * stats.count / read
            out.append(TransformInfo(parent, child, topic.name, stats.count, rate, stats.moving))
    return out


def tf_chains(transforms: Sequence[TransformInfo]) -> list[tuple[str, ...]]:
    """Chains of frames from each root (a frame that is no child) down to the last frame
    that moves: a static transform is followed only if a moving one lies below it.

    Without any moving transform, the chains follow the static ones to their leaves.
    """
    children: dict[str, list[tuple[str, bool]]] = {}
    parents: set[str] = set()
    kids: set[str] = set()
    for tf in transforms:
        if tf.parent == tf.child:
            continue
        edge = (tf.child, tf.static)
        siblings = children.setdefault(tf.parent, [])
        if (tf.child, False) in siblings:
            continue
        if edge[1] is False and (tf.child, True) in siblings:
            siblings.remove((tf.child, True))
        if edge not in siblings:
            siblings.append(edge)
        parents.add(tf.parent)
        kids.add(tf.child)
    any_moving = any(not tf.static for tf in transforms)
    memo: dict[str, bool] = {}

    def moving_below(frame: str, path: frozenset[str]) -> bool:
        if frame in memo:
            return memo[frame]
        result = False
        for child, static in children.get(frame, []):
            if child in path:
                continue
            if not static or moving_below(child, path | {child}):
                result = True
                break
        memo[frame] = result
        return result

    chains: list[tuple[str, ...]] = []

    def walk(path: tuple[str, ...]) -> None:
        frame = path[-1]
        nexts = [
            child
            for child, static in children.get(frame, [])
            if child not in path
            and (not any_moving or not static or moving_below(child, frozenset(path) | {child}))
        ]
        if not nexts or len(path) >= _MAX_DEPTH:
            if len(path) > 1:
                chains.append(path)
            return
        for child in nexts:
            walk((*path, child))

    roots = sorted(parents - kids) or sorted(parents)[:1]
    for root in roots:
        walk((root,))
    return chains


# --- the entry points -------------------------------------------------------------------


def _storage(path: Path) -> str:
    if path.suffix == ".bag":
        return "ros1"
    folder = path if path.is_dir() else path.parent
    if path.suffix == ".mcap" or (path.is_dir() and any(folder.glob("*.mcap"))):
        return "mcap"
    return "sqlite3"


def bag_info(path: str | Path, *, max_messages: int = DEFAULT_MAX_MESSAGES) -> BagInfo:
    """What is in a bag, and the options to read it with (see the module docstring).

    Parameters
    ----------
    path : str or Path
        A ROS 1 ``.bag`` file, a ROS 2 bag folder, or its ``.db3``/``.mcap`` file.
    max_messages : int
        Messages deserialized per topic at most (at least 1).

    Raises
    ------
    InputError
        The bag cannot be read.
    """
    src = str(path)
    if max_messages < 1:
        raise InputError(f"--max-messages {max_messages}: must be at least 1")
    notes: list[str] = []
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)
        total = int(reader.message_count)
        start = int(reader.start_time) if total else None
        end = int(reader.end_time) - 1 if total else None
        scanned = _inspect(reader, topics, src, max_messages, wanted=lambda t, m: True, notes=notes)
    transforms = _transform_infos(scanned)
    chains = tf_chains(transforms)
    joint_states = []
    for topic in scanned:
        if topic.msgtype == JOINT_STATE and topic.content is not None:
            joints = [s.info(name) for name, s in topic.content.joints.items()]
            joint_states.append(
                JointStateInfo(
                    topic.name,
                    tuple(joints[:MAX_LISTED]),
                    max(len(joints) - MAX_LISTED, 0),
                    topic.content.decoded,
                    topic.scan.complete,
                )
            )
    empty = []
    for topic in scanned:
        content = topic.content
        if content is not None and content.stamped and content.empty_stamps == content.stamped:
            empty.append(topic.name)
            notes.append(
                f"{topic.name}: every header stamp read is zero; read it with --time-source bag"
            )
    infos = [
        TopicInfo(
            t.name,
            t.msgtype,
            t.count,
            t.duration,
            t.rate,
            t.content.decoded if t.content is not None else 0,
        )
        for t in scanned
    ]
    complete = all(t.scan.complete for t in scanned if t.content is not None)
    return BagInfo(
        path=src,
        storage=_storage(Path(path)),
        start=None if start is None else start * 1e-9,
        duration=0.0 if start is None or end is None else (end - start) * 1e-9,
        messages=total,
        topics=tuple(infos[:MAX_LISTED]),
        topics_not_listed=max(len(infos) - MAX_LISTED, 0),
        joint_states=tuple(joint_states),
        transforms=tuple(transforms[:MAX_LISTED]),
        transforms_not_listed=max(len(transforms) - MAX_LISTED, 0),
        chains=tuple(chains[:MAX_CHAINS]),
        chains_not_listed=max(len(chains) - MAX_CHAINS, 0),
        wheels=tuple(_wheel_candidates(scanned)[:MAX_LISTED]),
        odometry=tuple(_odometry_candidates(scanned, transforms)[:MAX_LISTED]),
        truth=tuple(_truth_candidates(scanned, transforms, chains)[:MAX_LISTED]),
        max_messages=max_messages,
        complete=complete,
        notes=tuple(notes),
        empty_stamps=tuple(empty),
    )


def truth_candidates(path: str | Path, *, max_messages: int = 200) -> list[Candidate]:
    """The ground-truth candidates of a bag, likeliest first, from a quick look: pose and
    odometry topics, and the transforms of ``/tf`` and ``/tf_static``, with at most
    ``max_messages`` messages of each looked into (spread over its time span).

    Raises
    ------
    InputError
        The bag cannot be read.
    """
    src = str(path)
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)

        def wanted(topic: str, msgtype: str) -> bool:
            return msgtype in TRUTH_TYPES or topic in (TF_TOPIC, TF_STATIC)

        scanned = _inspect(reader, topics, src, max_messages, wanted=wanted, notes=[])
    transforms = _transform_infos(scanned)
    return _truth_candidates(scanned, transforms, tf_chains(transforms))

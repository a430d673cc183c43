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
- ``left_field`` and ``right_field``: two numbers in the messages of ``wheel_topic``, of
  any type (a vendor's ``my_robot_msgs/msg/WheelEncoders``), named by field paths
  (``left_ticks``, ``wheels.left.position``, ``positions[0]``; at most 8 names, one
  index each). Angles [rad]; or, with ``ticks_per_revolution``, encoder counts, where
  8-, 16- and 32-bit integer fields are unwrapped as above. An integer field without
  ``ticks_per_revolution`` is refused. The type's definition comes from the bag (ROS 1
  bags, MCAP, sqlite3 from rosbag2 Iron on) or from ``.msg`` files in ``msg_dir``; see
  :mod:`umbmark.sources.bag.custom`, which also checks the paths against the definition
  before any message is read (a field that is not there: the message lists the fields
  that are).
- ``odom_topic`` or ``odom_tf`` with ``odom_geometry``: the controller's odometry, turned
  back into wheel rotation (:mod:`umbmark.sources.controller_odometry`).

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
ticks topics always use the bag time, as do custom types without a ``std_msgs/Header
header`` field. Times are seconds (``sec + nanosec * 1e-9``).

Samples are sorted by time; of samples with exactly the same time only the first (in
the bag's order) is kept, and samples with values that are not finite numbers are
dropped. Wheel samples of the two ticks topics arrive at different times: the right
wheel's angle is interpolated linearly onto the left wheel's times, inside the time both
topics cover. Every problem with the bag or the options raises
:class:`umbmark.errors.InputError`, one line naming the bag.

Speed
-----
Joint states, the three pose types and the ``std_msgs`` numbers are read with the
byte-level decoder of :mod:`umbmark.sources.bag.fastpath`, which reads fixed-layout
messages with vectorized numpy views and deserializes only the rest with rosbags; its
docstring gives the measured speed-up and how it is kept equal to rosbags'
deserialization. Custom message types are deserialized by rosbags, message by message,
straight through the typestore, their values collected into one list and turned into an
array once: 10-20 % slower than a bare rosbags loop that reads, deserializes and picks
the fields (300 000 ``my_robot_msgs/WheelEncoders`` messages with a header and two int32
counts, best of 5, rosbags 0.11.9: 1.2 s from sqlite3, 2.0 s from ROS 1, 1.5 s from
MCAP). Opening bags and iterating their raw messages is
:mod:`umbmark.sources.bag.reader`.

Progress
--------
``read_bag(..., progress=callback)`` (or any read inside
:func:`umbmark.sources.progress.reading_progress`) reports ``(messages read, messages to
read)``: the total is the message count the bag's index or metadata gives for each topic
read, a topic read twice (finding the wheel joints) counted twice.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from ...recording import PoseSeries, WheelSeries
from ..controller_odometry import OdometryGeometry, wheels_from_odometry
from ..progress import Progress, Tracker, current_callback, tracking
from . import custom, transforms
from . import reader as bag_reader
from .fastpath import POSITION, VELOCITY, Decoded, LayoutOf, Sample, decode_messages, fast_layout
from .msgtypes import (
    JOINT_STATE,
    POSE_STAMPED,
    TICK_TYPES,
    TRUTH_TYPES,
    JointState,
    Number,
    PoseStamped,
    PoseWithCovarianceStamped,
    Quaternion,
    Stamped,
    Vector,
)

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = ["BagOptions", "bag_topics", "read_bag"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

TF_TOPIC = "/tf"


@dataclass(frozen=True)
class BagOptions:
    """What to read from a bag; see the module docstring for the details.

    Attributes
    ----------
    wheel_topic : str
        ``sensor_msgs/JointState`` topic with the wheel joints.
    left_joint, right_joint : str, tuple of str or None
        The left and right wheel joints in it: a name, several (a tuple, or one string
        separated by commas) whose angles are averaged as ros2_control does for
        ``left_wheel_names``, or None to find them (see the module docstring).
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
    odom_topic : str or None
        Instead of wheel data: the controller's odometry (``nav_msgs/Odometry`` or a
        pose type), turned back into wheel rotation with ``odom_geometry``.
    odom_tf : (str, str) or None
        Instead of wheel data: the controller's odometry as the transform chain
        ``(parent, child)``, for example ``("odom", "base_link")``.
    odom_geometry : OdometryGeometry or None
        The effective radii and separation the controller used; required with
        ``odom_topic`` or ``odom_tf``.
    left_field, right_field : str or None
        Instead of joint states: field paths to each wheel's value in the messages of
        ``wheel_topic``, which may then have any type (``left_ticks``,
        ``wheels.left.position``, ``positions[0]``; both or neither). Angles [rad], or
        encoder counts when ``ticks_per_revolution`` is given.
    msg_dir : Path or None
        A folder of ``.msg`` files defining ``wheel_topic``'s type, for bags that do not
        carry its definition (:mod:`umbmark.sources.bag.custom`); only with the fields.
    """

    wheel_topic: str = "/joint_states"
    left_joint: str | tuple[str, ...] | None = None
    right_joint: str | tuple[str, ...] | None = None
    left_ticks_topic: str | None = None
    right_ticks_topic: str | None = None
    ticks_per_revolution: float | None = None
    truth_topic: str | None = None
    tf_parent: str | None = None
    tf_child: str | None = None
    time_source: Literal["header", "bag"] = "header"
    odom_topic: str | None = None
    odom_tf: tuple[str, str] | None = None
    odom_geometry: OdometryGeometry | None = None
    left_field: str | None = None
    right_field: str | None = None
    msg_dir: Path | None = None

    @property
    def left_joints(self) -> tuple[str, ...]:
        """The left wheel joints asked for (empty: take them from the bag)."""
        return _joint_names(self.left_joint)

    @property
    def right_joints(self) -> tuple[str, ...]:
        """The right wheel joints asked for (empty: take them from the bag)."""
        return _joint_names(self.right_joint)


def _joint_names(value: str | tuple[str, ...] | None) -> tuple[str, ...]:
    if value is None:
        return ()
    names = value.split(",") if isinstance(value, str) else value
    return tuple(name.strip() for name in names if name.strip())


def read_bag(
    path: str | Path, options: BagOptions, *, progress: Progress | None = None
) -> tuple[WheelSeries, PoseSeries | None]:
    """Read the wheel rotation and, if configured, the ground truth from a bag.

    Parameters
    ----------
    path : str or Path
        A ROS 1 ``.bag`` file, a ROS 2 bag folder, or the ``.db3``/``.mcap`` file (or
        ``metadata.yaml``) of one.
    options : BagOptions
        Topics, joints and time source.
    progress : callable, optional
        Called as ``progress(read, total)`` with the messages read so far and the
        messages to read in all (the message counts of the bag's index or metadata; a
        topic read twice counts twice), every
        :data:`~umbmark.sources.progress.REPORT_EVERY` messages and once more with
        ``read == total`` at the end. Default: the callback of the enclosing
        :func:`umbmark.sources.progress.reading_progress` block, if any.

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
    callback = progress if progress is not None else current_callback()
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)
        tracker = None
        if callback is not None:
            tracker = Tracker(callback, _planned(reader, topics, options))
        with tracking(tracker):
            wheels, truth = _read(reader, topics, options, src)
        if tracker is not None:
            tracker.finish()
    return wheels, truth


def _planned(
    reader: AnyReader, topics: dict[str, str], options: BagOptions
) -> list[tuple[str, int]]:
    """The topics :func:`read_bag` reads and their message counts, for its progress."""
    if options.odom_topic is not None:
        wanted = [options.odom_topic]
    elif options.odom_tf is not None:
        wanted = [transforms.TF_TOPIC, transforms.TF_STATIC_TOPIC]
    elif options.left_ticks_topic is not None and options.right_ticks_topic is not None:
        wanted = [options.left_ticks_topic, options.right_ticks_topic]
    else:
        wanted = [options.wheel_topic]
    if options.truth_topic is not None:
        wanted.append(options.truth_topic)
    elif options.tf_parent is not None and options.tf_child is not None:
        wanted += [transforms.TF_TOPIC, transforms.TF_STATIC_TOPIC]
    counts: dict[str, int] = {}
    for conn in reader.connections:
        counts[conn.topic] = counts.get(conn.topic, 0) + bag_reader.message_count([conn])
    return [(topic, counts[topic]) for topic in wanted if topic in topics]


def _read(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str
) -> tuple[WheelSeries, PoseSeries | None]:
    """What :func:`read_bag` returns, from the open bag."""
    if options.odom_topic is not None or options.odom_tf is not None:
        wheels = _read_odometry(reader, topics, options, src)
    elif options.left_field is not None and options.right_field is not None:
        wheels = _read_fields(reader, topics, options, src)
    elif options.left_ticks_topic is not None and options.right_ticks_topic is not None:
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
        header = options.time_source == "header"
        edges = transforms.read_edges(reader, topics, src, header=header)
        time, poses = transforms.chain_poses(edges, options.tf_parent, options.tf_child, src)
        truth = PoseSeries(time=time, poses=poses)
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
    with bag_reader.open_bag(Path(path), src) as reader:
        return bag_reader.topic_types(reader)


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
        if options.left_ticks_topic == options.right_ticks_topic:
            fail(f"the left and right ticks topics are the same: {options.left_ticks_topic}")
    tpr = options.ticks_per_revolution
    if tpr is not None and not (math.isfinite(tpr) and tpr > 0):
        fail(f"ticks_per_revolution must be a positive number, not {tpr!r}")
    _check_fields(options, src)
    for side, given, names in (
        ("left", options.left_joint, options.left_joints),
        ("right", options.right_joint, options.right_joints),
    ):
        if given is not None and not names:
            fail(f"the {side} wheel joint option (--{side}-joint) names no joint: {given!r:.60}")
    left = options.left_joints or DEFAULT_JOINTS[:1]
    right = options.right_joints or DEFAULT_JOINTS[1:]
    both = set(left) & set(right)
    if both and options.left_ticks_topic is None:
        fail(f"the left and right wheel joints are the same: {sorted(both)[0]!r}")
    if (options.odom_topic is not None or options.odom_tf is not None) and (
        options.odom_geometry is None
    ):
        fail(
            "turning odometry back into wheel rotation needs the controller's geometry "
            "(wheel radius and separation)"
        )
    if options.odom_topic is not None and options.odom_tf is not None:
        fail("give the odometry as a topic or as a transform, not both")
    if options.truth_topic is None and (options.tf_parent is None) != (options.tf_child is None):
        fail("a TF ground truth needs both tf_parent and tf_child")
    if options.truth_topic is not None and (
        options.tf_parent is not None or options.tf_child is not None
    ):
        fail(
            "give the ground truth as a topic (--truth-topic) or as a TF pair (--tf-parent, "
            "--tf-child), not both"
        )


def _check_fields(options: BagOptions, src: str) -> None:
    """Refuse field paths that are malformed, or given with other wheel data."""
    if (options.left_field is None) != (options.right_field is None):
        raise InputError("the left and right fields go together: give both or neither", source=src)
    if options.left_field is None or options.right_field is None:
        if options.msg_dir is not None:
            raise InputError(
                "msg_dir (--msg-dir) is for reading wheel data from a custom message type "
                "with left_field and right_field (--left-field, --right-field)",
                source=src,
            )
        return
    other = (
        "ticks topics"
        if options.left_ticks_topic is not None
        else "controller odometry"
        if options.odom_topic is not None or options.odom_tf
        else None
    )
    if other is not None:
        raise InputError(
            f"give the wheels as fields of {options.wheel_topic} or as {other}, not both",
            source=src,
        )
    for what, text in (("left field", options.left_field), ("right field", options.right_field)):
        try:
            custom.parse_path(text, what)
        except InputError as err:
            raise InputError(err.problem, source=src) from None
    if options.left_field.replace(" ", "") == options.right_field.replace(" ", ""):
        raise InputError(
            f"the left and right fields are the same: {options.left_field!r}", source=src
        )


# --- reading a topic and its time ------------------------------------------------------


def _read_topic(
    reader: AnyReader,
    conns: Sequence[Connection],
    msgtype: str,
    topic: str,
    src: str,
    *,
    width: int,
    decode: Callable[[Any], list[Sample]],
    layout_of: LayoutOf | None,
) -> Decoded:
    """Every sample of ``topic``: ``decode`` turns a deserialized message into samples.

    The fast path of :func:`~umbmark.sources.bag.fastpath.decode_messages` reads the
    messages that fit ``layout_of``; the rest are deserialized by rosbags and decoded.

    Raises
    ------
    InputError
        The topic has no messages, or one cannot be read or deserialized.
    """

    def deserialize_and_decode(raw: bytes) -> list[Sample]:
        return decode(bag_reader.deserialize(reader, raw, msgtype, topic, src))

    scan = decode_messages(
        bag_reader.messages(reader, conns, topic, src),
        ros2=bool(reader.is2),
        width=width,
        decode=deserialize_and_decode,
        layout_of=layout_of,
    )
    if scan.messages == 0:
        raise InputError(f"topic {topic} has no messages", source=src)
    return scan


def _time_ns(scan: Decoded, header: bool) -> IntArray:
    """Sample times [ns], shape (k,): header stamps or bag receive times."""
    if header:
        return scan.sec * 1_000_000_000 + scan.nsec
    return scan.bag_ns


def _seconds(time_ns: IntArray) -> FloatArray:
    """Times [s] of ``time_ns`` [ns], shape (k,), as ``sec + nanosec * 1e-9``."""
    sec, nsec = np.divmod(time_ns, 1_000_000_000)
    return np.asarray(sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9)


def _stamp(msg: Stamped) -> tuple[int, int]:
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


#: Joint states inspected to find the wheel joints, at most.
MAX_INSPECTED = 2_000
#: Rotation [rad] over the recording above which a joint counts as moving.
MOVING = 1.0
DEFAULT_JOINTS = ("left_wheel_joint", "right_wheel_joint")


def wheel_joints(
    reader: AnyReader, conns: Sequence[Connection], msgtype: str, topic: str, src: str
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The wheel joints of a joint-states topic, when the options do not name them.

    ``left_wheel_joint`` and ``right_wheel_joint`` if present; else the joints that move
    (turn more than :data:`MOVING` rad over up to :data:`MAX_INSPECTED` messages spread
    over the recording), split by ``left`` and ``right`` in their names: one or more per
    side (a skid-steer's four wheels are averaged per side).

    Raises
    ------
    InputError
        The moving joints do not split into left and right; the message names them.
    """
    total = sum(int(getattr(conn, "msgcount", 0)) for conn in conns)
    stride = max(1, total // MAX_INSPECTED)
    low: dict[str, float] = {}
    high: dict[str, float] = {}
    for k, (_, raw) in enumerate(bag_reader.messages(reader, conns, topic, src)):
        if k % stride:
            continue
        msg: JointState = bag_reader.deserialize(reader, raw, msgtype, topic, src)  # type: ignore[assignment]
        names = list(msg.name)
        if set(DEFAULT_JOINTS) <= set(names):
            return (DEFAULT_JOINTS[0],), (DEFAULT_JOINTS[1],)
        values = msg.position if len(msg.position) == len(names) else ()
        for name, value in zip(names, values, strict=False):
            if math.isfinite(value):
                low[name] = min(low.get(name, value), float(value))
                high[name] = max(high.get(name, value), float(value))
    moving = sorted(name for name in low if high[name] - low[name] > MOVING)
    left = tuple(name for name in moving if "left" in name.lower())
    right = tuple(name for name in moving if "right" in name.lower())
    if left and right and not set(left) & set(right) and len(left) + len(right) == len(moving):
        return left, right
    present = bag_reader.listing(moving) if moving else "none"
    raise InputError(
        f"which joints of {topic} are the wheels? give --left-joint and --right-joint "
        f"(or a controller file with left_wheel_names); joints that move: {present}",
        source=src,
    )


def _read_joint_states(
    reader: AnyReader,
    topics: dict[str, str],
    options: BagOptions,
    src: str,
) -> WheelSeries:
    topic = options.wheel_topic
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (JOINT_STATE,), "wheel joint states", src
    )
    left, right = options.left_joints, options.right_joints
    named = bool(left and right)
    if not named:
        left, right = left or DEFAULT_JOINTS[:1], right or DEFAULT_JOINTS[1:]
    scan, seen = _scan_joints(reader, conns, msgtype, topic, src, left, right)
    if scan.values.shape[0] == 0 and not named:
        found = wheel_joints(reader, conns, msgtype, topic, src)
        left = options.left_joints or found[0]
        right = options.right_joints or found[1]
        scan, seen = _scan_joints(reader, conns, msgtype, topic, src, left, right)
    joints = left + right
    if scan.values.shape[0] == 0:
        missing = [name for name in joints if name not in seen]
        present = bag_reader.listing(sorted(seen)) if seen else "none"
        if missing:
            raise InputError(
                f"no joint {_quoted(missing)} in {topic}; joints present: {present}", source=src
            )
        raise InputError(
            f"the joints {_quoted(joints)} never appear in the same message of {topic}",
            source=src,
        )
    header = options.time_source == "header"
    kinds = np.unique(scan.kind)
    if kinds.size > 1:
        raise InputError(
            f"{topic} mixes messages with wheel positions and messages with only velocities",
            source=src,
        )
    # several wheels per side: their mean, as ros2_control's diff_drive_controller takes
    per_side = np.column_stack(
        [scan.values[:, : len(left)].mean(axis=1), scan.values[:, len(left) :].mean(axis=1)]
    )
    time_ns, time, values = _clean(
        _time_ns(scan, header), per_side, f"topic {topic}", src, header=header
    )
    if kinds[0] == VELOCITY:
        dt = np.diff(time_ns).astype(np.float64) * 1e-9
        steps = 0.5 * (values[1:] + values[:-1]) * dt[:, None]
        values = np.concatenate([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    return WheelSeries(time=time, angles=values)


def _scan_joints(
    reader: AnyReader,
    conns: Sequence[Connection],
    msgtype: str,
    topic: str,
    src: str,
    left: tuple[str, ...],
    right: tuple[str, ...],
) -> tuple[Decoded, set[str]]:
    """The joints' samples, and the names seen in messages without all of them."""
    joints = left + right
    seen: set[str] = set()

    def decode(msg: JointState) -> list[Sample]:
        names = list(msg.name)
        try:
            where = [names.index(joint) for joint in joints]
        except ValueError:
            seen.update(names)
            return []
        sec, nsec = _stamp(msg)
        position, velocity = msg.position, msg.velocity
        if len(position) > max(where):
            return [(sec, nsec, tuple(float(position[i]) for i in where), POSITION)]
        if len(velocity) > max(where):
            return [(sec, nsec, tuple(float(velocity[i]) for i in where), VELOCITY)]
        raise InputError(
            f"a message of {topic} (stamp {sec + nsec * 1e-9:.9f} s) has neither position"
            f" nor velocity for the joints {_quoted(joints)}",
            source=src,
        )

    scan = _read_topic(
        reader,
        conns,
        msgtype,
        topic,
        src,
        width=len(joints),
        decode=decode,
        layout_of=fast_layout(msgtype, joints),
    )
    return scan, seen


def _quoted(names: Sequence[str]) -> str:
    return " and ".join(repr(name) for name in names)


def _read_odometry(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str
) -> WheelSeries:
    """Wheel rotation from the controller's odometry topic or transform chain."""
    assert options.odom_geometry is not None  # _check_options
    if options.odom_topic is not None:
        what = f"odometry {options.odom_topic}"
        series = _read_pose_topic(
            reader, topics, options.odom_topic, options, src, role="controller odometry"
        )
    else:
        assert options.odom_tf is not None
        parent, child = options.odom_tf
        what = f"odometry {parent}->{child}"
        edges = transforms.read_edges(reader, topics, src, header=options.time_source == "header")
        time, poses = transforms.chain_poses(edges, parent, child, src)
        series = PoseSeries(time=time, poses=poses)
    return wheels_from_odometry(series, options.odom_geometry, what, src).wheels


def _read_counts(
    reader: AnyReader, topics: dict[str, str], topic: str, side: str, src: str
) -> tuple[IntArray, FloatArray]:
    """Time [ns] and unwrapped cumulative counts, each shape (k,), of a ticks topic."""
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, tuple(TICK_TYPES), f"{side} wheel ticks", src
    )
    bits = TICK_TYPES[msgtype][1]

    def decode(msg: Number) -> list[Sample]:
        return [(0, 0, (float(msg.data),), POSITION)]

    layout_of = fast_layout(msgtype)
    scan = _read_topic(
        reader, conns, msgtype, topic, src, width=1, decode=decode, layout_of=layout_of
    )
    time_ns, _, counts = _clean(
        _time_ns(scan, False), scan.values, f"topic {topic}", src, header=False
    )
    return time_ns, _unwrap(counts[:, 0], bits)


def _unwrap(counts: FloatArray, bits: int | None) -> FloatArray:
    """Counts of a ``bits``-bit counter that wraps around, shape (k,), made continuous.

    A jump of more than half the counter's range between two samples is taken as a wrap.
    ``bits`` None: the counts are returned as they are.
    """
    if bits is None:
        return counts
    span = float(2**bits)
    step = np.diff(counts)
    step = step - span * (step > span / 2) + span * (step < -span / 2)
    return np.asarray(counts[0] + np.concatenate([[0.0], np.cumsum(step)]))


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


def _read_fields(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str
) -> WheelSeries:
    """Wheel rotation from two fields of the messages of ``wheel_topic``, of any type.

    The type's definition comes from the bag or ``msg_dir``
    (:func:`umbmark.sources.bag.custom.add_definitions`); every message is deserialized
    by rosbags and its two values collected into lists, turned into arrays once. Times
    are ``header.stamp`` if the type has a ``std_msgs/Header header`` and the time source
    is ``"header"``, else the bag time.
    """
    assert options.left_field is not None  # the caller checked
    assert options.right_field is not None
    topic = options.wheel_topic
    if topic in topics and ", " in topics[topic]:
        raise InputError(
            f"topic {topic} has messages of several types ({topics[topic]}); wheel fields "
            "are read from one",
            source=src,
        )
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (topics.get(topic, ""),), "wheel data", src
    )
    custom.add_definitions(reader, msgtype, options.msg_dir, topic, src)
    fielddefs = reader.typestore.fielddefs
    fields = []
    for what, text in (("left field", options.left_field), ("right field", options.right_field)):
        try:
            fields.append(custom.resolve_field(fielddefs, msgtype, text, what, of=topic))
        except InputError as err:
            raise InputError(err.problem, source=src) from None
    left, right = fields
    tpr = options.ticks_per_revolution
    if tpr is None:
        for field in fields:
            if field.integer:
                raise InputError(
                    f"field {field.text} of {msgtype} is an integer ({field.base}): encoder "
                    "counts need ticks_per_revolution (--ticks-per-rev, counts per wheel "
                    "revolution); without it the fields are read as angles [rad]",
                    source=src,
                )
    header = options.time_source == "header" and custom.has_header(fielddefs, msgtype)
    paths = [left.steps, right.steps]
    if header:
        paths += [("header", "stamp", "sec"), ("header", "stamp", "nanosec")]
    row = custom.row_getter(paths)
    store = reader.typestore
    deserialize = store.deserialize_cdr if reader.is2 else store.deserialize_ros1
    rows: list[tuple[Any, ...]] = []
    bag_ns: list[int] = []
    add_row, add_ns = rows.append, bag_ns.append
    for ns, raw in bag_reader.messages(reader, conns, topic, src):
        try:
            msg = deserialize(raw, msgtype)
        except Exception as err:  # malformed message bytes, a definition that does not fit
            raise InputError(
                f"a message of {topic} cannot be decoded as {msgtype}: {bag_reader.one_line(err)}",
                source=src,
            ) from None
        try:
            add_row(row(msg))
        except AttributeError as err:  # a message class unlike its definition
            raise InputError(
                f"a message of {topic} lacks a field of {msgtype}: {bag_reader.one_line(err)}",
                source=src,
            ) from None
        except IndexError:
            raise InputError(
                f"a message of {topic} (bag time {ns * 1e-9:.9f} s) has too few entries "
                f"for the field {_short_field(msg, left, right)}",
                source=src,
            ) from None
        add_ns(ns)
    if not rows:
        raise InputError(f"topic {topic} has no messages", source=src)
    # one conversion; float64 holds the stamps' seconds and nanoseconds exactly
    table = np.array(rows, np.float64).reshape(len(rows), len(paths))
    if header:
        time_ns = table[:, 2].astype(np.int64) * 1_000_000_000 + table[:, 3].astype(np.int64)
    else:
        time_ns = np.array(bag_ns, np.int64)
    _, time, values = _clean(time_ns, table[:, :2], f"topic {topic}", src, header=header)
    if tpr is None:
        return WheelSeries(time=time, angles=values)
    counts = np.column_stack(
        [_unwrap(values[:, 0], left.wrap_bits), _unwrap(values[:, 1], right.wrap_bits)]
    )
    return WheelSeries(time=time, angles=counts * (2.0 * math.pi / tpr))


def _short_field(msg: object, *fields: custom.Field) -> str:
    """The first of ``fields`` that ``msg`` is too short for."""
    for field in fields:
        try:
            custom.getter(field.steps)(msg)
        except IndexError:
            return field.text
    return fields[0].text


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


def _pose_values(p: Vector, q: Quaternion) -> tuple[float, ...]:
    """``x, y`` of ``p`` and the quaternion ``q``'s ``x, y, z, w``."""
    return (float(p.x), float(p.y), float(q.x), float(q.y), float(q.z), float(q.w))


def _read_pose_topic(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    options: BagOptions,
    src: str,
    role: str = "ground truth",
) -> PoseSeries:
    conns, msgtype = bag_reader.topic_connections(reader, topics, topic, TRUTH_TYPES, role, src)

    def decode_pose(msg: PoseStamped) -> list[Sample]:
        sec, nsec = _stamp(msg)
        pose = msg.pose
        return [(sec, nsec, _pose_values(pose.position, pose.orientation), POSITION)]

    def decode_covariance(msg: PoseWithCovarianceStamped) -> list[Sample]:
        sec, nsec = _stamp(msg)
        pose = msg.pose.pose  # nav_msgs/Odometry has the same pose.pose
        return [(sec, nsec, _pose_values(pose.position, pose.orientation), POSITION)]

    decode = decode_pose if msgtype == POSE_STAMPED else decode_covariance

    scan = _read_topic(
        reader,
        conns,
        msgtype,
        topic,
        src,
        width=6,
        decode=decode,
        layout_of=fast_layout(msgtype),
    )
    header = options.time_source == "header"
    return _truth(_time_ns(scan, header), scan.values, f"topic {topic}", src, header=header)

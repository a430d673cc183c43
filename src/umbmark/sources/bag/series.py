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
Joint states, the three pose types and the ``std_msgs`` numbers are read with the
byte-level decoder of :mod:`umbmark.sources.bag.fastpath`, which reads fixed-layout
messages with vectorized numpy views and deserializes only the rest with rosbags; its
docstring gives the measured speed-up and how it is kept equal to rosbags'
deserialization. Opening bags and iterating their raw messages is
:mod:`umbmark.sources.bag.reader`.
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
from . import reader as bag_reader
from .fastpath import POSITION, VELOCITY, Decoded, LayoutOf, Sample, decode_messages, fast_layout
from .msgtypes import (
    JOINT_STATE,
    POSE_STAMPED,
    TF_TYPES,
    TICK_TYPES,
    TRUTH_TYPES,
    JointState,
    Number,
    PoseStamped,
    PoseWithCovarianceStamped,
    Quaternion,
    Stamped,
    TFMessage,
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
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)
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
        elif not (math.isfinite(tpr) and tpr > 0):
            fail(f"ticks_per_revolution must be a positive number, not {tpr!r}")
        if options.left_ticks_topic == options.right_ticks_topic:
            fail(f"the left and right ticks topics are the same: {options.left_ticks_topic}")
    elif options.left_joint == options.right_joint:
        fail(f"the left and right wheel joints are the same: {options.left_joint!r}")
    if options.truth_topic is None and (options.tf_parent is None) != (options.tf_child is None):
        fail("a TF ground truth needs both tf_parent and tf_child")


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
    left, right = options.left_joint, options.right_joint
    seen: set[str] = set()

    def decode(msg: JointState) -> list[Sample]:
        names = list(msg.name)
        try:
            i, j = names.index(left), names.index(right)
        except ValueError:
            seen.update(names)
            return []
        sec, nsec = _stamp(msg)
        position, velocity = msg.position, msg.velocity
        if len(position) > max(i, j):
            return [(sec, nsec, (float(position[i]), float(position[j])), POSITION)]
        if len(velocity) > max(i, j):
            return [(sec, nsec, (float(velocity[i]), float(velocity[j])), VELOCITY)]
        raise InputError(
            f"a message of {topic} (stamp {sec + nsec * 1e-9:.9f} s) has neither position"
            f" nor velocity for the joints {left!r} and {right!r}",
            source=src,
        )

    scan = _read_topic(
        reader,
        conns,
        msgtype,
        topic,
        src,
        width=2,
        decode=decode,
        layout_of=fast_layout(msgtype, (left, right)),
    )
    if scan.values.shape[0] == 0:
        missing = [name for name in (left, right) if name not in seen]
        present = bag_reader.listing(sorted(seen)) if seen else "none"
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
        _time_ns(scan, header), scan.values, f"topic {topic}", src, header=header
    )
    if kinds[0] == VELOCITY:
        dt = np.diff(time_ns).astype(np.float64) * 1e-9
        steps = 0.5 * (values[1:] + values[:-1]) * dt[:, None]
        values = np.concatenate([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    return WheelSeries(time=time, angles=values)


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


def _pose_values(p: Vector, q: Quaternion) -> tuple[float, ...]:
    """``x, y`` of ``p`` and the quaternion ``q``'s ``x, y, z, w``."""
    return (float(p.x), float(p.y), float(q.x), float(q.y), float(q.z), float(q.w))


def _read_pose_topic(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    options: BagOptions,
    src: str,
) -> PoseSeries:
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, TRUTH_TYPES, "ground truth", src
    )

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


def _read_tf(
    reader: AnyReader,
    topics: dict[str, str],
    parent: str,
    child: str,
    options: BagOptions,
    src: str,
) -> PoseSeries:
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, TF_TOPIC, TF_TYPES, "TF ground truth", src
    )
    want = (parent.lstrip("/"), child.lstrip("/"))
    pairs: set[tuple[str, str]] = set()

    def decode(msg: TFMessage) -> list[Sample]:
        samples: list[Sample] = []
        for tf in msg.transforms:
            pair = (tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/"))
            if pair != want:
                pairs.add(pair)
                continue
            sec, nsec = _stamp(tf)
            values = _pose_values(tf.transform.translation, tf.transform.rotation)
            samples.append((sec, nsec, values, POSITION))
        return samples

    scan = _read_topic(
        reader, conns, msgtype, TF_TOPIC, src, width=6, decode=decode, layout_of=None
    )
    if scan.values.shape[0] == 0:
        present = bag_reader.listing([f"{p}->{c}" for p, c in sorted(pairs)]) if pairs else "none"
        raise InputError(
            f"no transform {want[0]}->{want[1]} in {TF_TOPIC}; parent->child pairs"
            f" present: {present}",
            source=src,
        )
    what = f"transform {want[0]}->{want[1]} in {TF_TOPIC}"
    header = options.time_source == "header"
    return _truth(_time_ns(scan, header), scan.values, what, src, header=header)

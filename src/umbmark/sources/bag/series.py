"""ROS bags: wheel rotation and ground truth from ROS 1 and ROS 2 recordings.

Reads ROS 1 bags (``.bag`` files) and ROS 2 bags (a folder with ``metadata.yaml`` and
sqlite3 ``.db3`` or ``.mcap`` storage; the path of the storage file or of
``metadata.yaml`` itself also works and means its folder) through ``rosbags``
(``pip install 'umbmark[ros]'``), and returns a :class:`umbmark.model.recording.WheelSeries`
and, if asked for, a :class:`umbmark.model.recording.PoseSeries` of ground truth.

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
- ``left_wheel_frame`` and ``right_wheel_frame``: the wheels' frames on ``/tf``
  (``base_link -> wheel_left_link`` from ``robot_state_publisher``), their rotation
  about the parent's ``y`` axis (:mod:`umbmark.sources.bag.wheel_tf`).

Ground truth, optional: ``truth_topic`` (``geometry_msgs/PoseStamped``,
``geometry_msgs/PoseWithCovarianceStamped``, ``nav_msgs/Odometry``, Gazebo's
``gazebo_msgs/ModelStates`` with the model ``truth_model``, or the position-only
``geometry_msgs/PointStamped`` and ``sensor_msgs/NavSatFix``:
:mod:`umbmark.sources.bag.references`), else the transform chain ``tf_parent ->
tf_child`` on ``/tf`` (``tf2_msgs/TFMessage``; leading slashes of frame names are
ignored). The pose is ``x, y`` of the position and the yaw of the orientation,
``atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))`` of the normalized quaternion. A ground truth
that is the odometry the wheels are read from is refused
(:mod:`umbmark.sources.bag.independence`).

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
:class:`umbmark.core.errors.InputError`, one line naming the bag.

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
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.core.errors import InputError
from umbmark.core.messages import info
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.sources.bag import custom, independence, references, transforms
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.encoders import read_fields, read_ticks
from umbmark.sources.bag.fastpath import POSITION, VELOCITY, Decoded, Sample, fast_layout
from umbmark.sources.bag.msgtypes import (
    JOINT_STATE,
    MODEL_STATES,
    POSE_STAMPED,
    POSITION_TYPES,
    REFERENCE_TYPES,
    TRUTH_TYPES,
    JointState,
    PoseStamped,
    PoseWithCovarianceStamped,
)
from umbmark.sources.bag.samples import clean as _clean
from umbmark.sources.bag.samples import pose_values as _pose_values
from umbmark.sources.bag.samples import read_topic as _read_topic
from umbmark.sources.bag.samples import stamp as _stamp
from umbmark.sources.bag.samples import time_ns as _time_ns
from umbmark.sources.bag.samples import truth_series as _truth
from umbmark.sources.bag.wheel_tf import read_wheel_transforms
from umbmark.sources.controller_odometry import OdometryGeometry, wheels_from_odometry
from umbmark.sources.progress import Progress, Tracker, current_callback, tracking

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = ["BagOptions", "BagRead", "bag_topics", "read_bag", "read_recording"]

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
        ``geometry_msgs/PoseWithCovarianceStamped``, ``nav_msgs/Odometry``,
        ``gazebo_msgs/ModelStates``, or (positions only) ``geometry_msgs/PointStamped``
        or ``sensor_msgs/NavSatFix``.
    truth_model : str or None
        With a ``gazebo_msgs/ModelStates`` ground truth: the robot's model (default: the
        one model that moves).
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
    left_wheel_frame, right_wheel_frame : str or None
        Instead of joint states: the child frames of the wheels' transforms on ``/tf``
        (both or neither).
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
    truth_model: str | None = None
    left_wheel_frame: str | None = None
    right_wheel_frame: str | None = None

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


@dataclass(frozen=True)
class BagRead:
    """What :func:`read_recording` read.

    Attributes
    ----------
    wheels : WheelSeries
    truth : PoseSeries or None
    notes : tuple of str
        What people should know (a ground truth stamped on another clock, GNSS fixes
        left out, the model read).
    """

    wheels: WheelSeries
    truth: PoseSeries | None
    notes: tuple[str, ...] = ()


def read_bag(
    path: str | Path, options: BagOptions, *, progress: Progress | None = None
) -> tuple[WheelSeries, PoseSeries | None]:
    """Read the wheel rotation and, if configured, the ground truth from a bag.

    :func:`read_recording` without the notes.

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
    read = read_recording(path, options, progress=progress)
    return read.wheels, read.truth


def read_recording(
    path: str | Path, options: BagOptions, *, progress: Progress | None = None
) -> BagRead:
    """Read the wheel rotation, the ground truth if configured, and notes, from a bag.

    The parameters and errors are those of :func:`read_bag`.
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
            read = _read(reader, topics, options, src)
        if tracker is not None:
            tracker.finish()
    return read


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
    elif options.left_wheel_frame is not None:
        wanted = [transforms.TF_TOPIC]
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


def _read(reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str) -> BagRead:
    """What :func:`read_recording` returns, from the open bag."""
    odometry: PoseSeries | None = None
    header = options.time_source == "header"
    if options.odom_topic is not None or options.odom_tf is not None:
        wheels, odometry = _read_odometry(reader, topics, options, src)
    elif options.left_wheel_frame is not None and options.right_wheel_frame is not None:
        wheels = read_wheel_transforms(
            reader, topics, options.left_wheel_frame, options.right_wheel_frame, header, src
        )
    elif options.left_field is not None and options.right_field is not None:
        wheels = read_fields(reader, topics, options, src)
    elif options.left_ticks_topic is not None and options.right_ticks_topic is not None:
        assert options.ticks_per_revolution is not None  # _check_options
        wheels = read_ticks(
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
    notes: list[str] = []
    if options.truth_topic is not None:
        truth = _read_truth_topic(reader, topics, options, src, notes)
    elif options.tf_parent is not None and options.tf_child is not None:
        edges = transforms.read_edges(reader, topics, src, header=header)
        if options.odom_tf is not None:
            independence.check_chain(
                edges, (options.tf_parent, options.tf_child), options.odom_tf, src
            )
        time, poses = transforms.chain_poses(edges, options.tf_parent, options.tf_child, src)
        truth = PoseSeries(time=time, poses=poses)
    if odometry is not None and truth is not None:
        odom = options.odom_topic or " -> ".join(options.odom_tf or ())
        ref = options.truth_topic or f"{options.tf_parent} -> {options.tf_child}"
        what = f"ground truth {ref} and odometry {odom}"
        independence.check_not_reproduced(odometry, truth, what, src)
    return BagRead(wheels, truth, tuple(notes))


def _read_truth_topic(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str, notes: list[str]
) -> PoseSeries:
    """The ground truth of ``truth_topic``, whatever its type; notes go to ``notes``."""
    topic = options.truth_topic
    assert topic is not None
    msgtype = topics.get(topic)
    if options.truth_model is not None and msgtype != MODEL_STATES:
        raise InputError(
            f"--truth-model names a model of a {MODEL_STATES} topic; {topic} "
            + (f"has {msgtype}" if msgtype else "is not in the bag"),
            source=src,
        )
    header = options.time_source == "header"
    if msgtype == MODEL_STATES:
        truth, model = references.read_model_states(reader, topics, topic, options.truth_model, src)
        clock = (
            "; the wheels use their header stamps: if the two clocks differ, give --time-source bag"
            if header
            else ""
        )
        notes.append(
            info(
                f"ground truth: model {model} of {topic}, which has no header: stamped with the "
                f"bag's receive times{clock}"
            )
        )
        return truth
    if msgtype in POSITION_TYPES:
        truth, more = references.read_positions(reader, topics, topic, header, src)
        notes += more
        notes.append(
            info(
                f"ground truth {topic} has positions only: each run's start heading is taken "
                "from the direction of its first metre; estimators that need headings "
                "(heading, endpoints, trajectory) refuse it"
            )
        )
        return truth
    return _read_pose_topic(reader, topics, topic, options, src, allowed=REFERENCE_TYPES)


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
    if options.truth_model is not None and options.truth_topic is None:
        fail("--truth-model names a model of the ground-truth topic: give --truth-topic too")
    if (options.left_wheel_frame is None) != (options.right_wheel_frame is None):
        fail("the left and right wheel frames go together: give both or neither")
    if options.left_wheel_frame is not None:
        other = (
            "ticks topics"
            if options.left_ticks_topic is not None
            else "fields"
            if options.left_field is not None
            else "controller odometry"
            if options.odom_topic is not None or options.odom_tf is not None
            else None
        )
        if other is not None:
            fail(f"give the wheels as wheel frames on /tf or as {other}, not both")
    tf_truth = (
        (options.tf_parent, options.tf_child)
        if options.tf_parent is not None and options.tf_child is not None
        else None
    )
    independence.check_distinct(
        options.truth_topic, tf_truth, options.odom_topic, options.odom_tf, src
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
) -> tuple[WheelSeries, PoseSeries]:
    """Wheel rotation from the controller's odometry topic or transform chain, and that
    odometry."""
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
    return wheels_from_odometry(series, options.odom_geometry, what, src).wheels, series


def _read_pose_topic(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    options: BagOptions,
    src: str,
    role: str = "ground truth",
    allowed: tuple[str, ...] = TRUTH_TYPES,
) -> PoseSeries:
    conns, msgtype = bag_reader.topic_connections(reader, topics, topic, allowed, role, src)

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

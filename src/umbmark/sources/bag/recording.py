"""Reading a bag's recording: wheel rotation, ground truth and notes, as the options say.

Reads ROS 1 bags (``.bag`` files) and ROS 2 bags (a folder with ``metadata.yaml`` and
sqlite3 ``.db3`` or ``.mcap`` storage; the path of the storage file or of
``metadata.yaml`` itself also works and means its folder) through ``rosbags``
(umbmark's ``ros`` extra), and returns a :class:`umbmark.model.recording.WheelSeries`
and, if asked for, a :class:`umbmark.model.recording.PoseSeries` of ground truth.

What is read is set by :class:`umbmark.sources.bag.bag_options.BagOptions` (its module
says what each option reads): the wheels from one of :mod:`umbmark.sources.bag.wheels`,
the ground truth from :mod:`umbmark.sources.bag.truth`, a ground truth that is the
odometry the wheels come from refused (:mod:`umbmark.sources.bag.truth.independence`).

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

from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.core.errors import InputError, option
from umbmark.core.messages import info
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.bag_options import BagOptions, check_options
from umbmark.sources.bag.msgtypes import (
    MODEL_STATES,
    POSITION_TYPES,
    REFERENCE_TYPES,
    TF_STATIC_TOPIC,
    TF_TOPIC,
    unstamped,
)
from umbmark.sources.bag.truth import independence, references, transforms
from umbmark.sources.bag.truth.poses import read_pose_topic
from umbmark.sources.bag.wheels.encoders import read_fields, read_ticks
from umbmark.sources.bag.wheels.joint_states import read_joint_states
from umbmark.sources.bag.wheels.odometry import wheels_from_odometry
from umbmark.sources.bag.wheels.wheel_tf import read_wheel_transforms
from umbmark.sources.progress import Progress, Tracker, current_callback, tracking

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = ["BagRead", "bag_topics", "read_bag", "read_recording"]


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
    path: str | Path,
    options: BagOptions,
    *,
    progress: Progress | None = None,
    window: tuple[int, int] | None = None,
) -> BagRead:
    """Read the wheel rotation, the ground truth if configured, and notes, from a bag.

    The parameters and errors are those of :func:`read_bag`; ``window`` (bag times [ns],
    from and before) reads only that part of the recording
    (:func:`~umbmark.sources.bag.reader.open_bag`).
    """
    src = str(path)
    check_options(options, src)
    tf_truth = (
        (options.tf_parent, options.tf_child)
        if options.tf_parent is not None and options.tf_child is not None
        else None
    )
    independence.check_distinct(
        options.truth_topic, tf_truth, options.odom_topic, options.odom_tf, src
    )
    callback = progress if progress is not None else current_callback()
    with bag_reader.open_bag(Path(path), src, window) as reader:
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
        wanted = [TF_TOPIC, TF_STATIC_TOPIC]
    elif options.left_ticks_topic is not None and options.right_ticks_topic is not None:
        wanted = [options.left_ticks_topic, options.right_ticks_topic]
    elif options.left_wheel_frame is not None:
        wanted = [TF_TOPIC]
    else:
        wanted = [options.wheel_topic]
    if options.truth_topic is not None:
        wanted.append(options.truth_topic)
    elif options.tf_parent is not None and options.tf_child is not None:
        wanted += [TF_TOPIC, TF_STATIC_TOPIC]
    counts: dict[str, int] = {}
    for conn in reader.connections:
        counts[conn.topic] = counts.get(conn.topic, 0) + bag_reader.message_count([conn])
    return [(topic, counts[topic]) for topic in wanted if topic in topics]


def _read(reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str) -> BagRead:
    """What :func:`read_recording` returns, from the open bag."""
    header = options.time_source == "header"
    wheels, odometry = _read_wheels(reader, topics, options, src)
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
    if truth is not None and header and unstamped(topics.get(options.truth_topic or "")):
        stamped = wheels.time
        if stamped[0] > truth.time[-1] or stamped[-1] < truth.time[0]:
            wheels, odometry = _read_wheels(
                reader, topics, replace(options, time_source="bag"), src
            )
            notes.append(
                info(
                    f"ground truth {options.truth_topic} has no header stamps (the bag's "
                    f"receive times) and the wheels' header stamps ({stamped[0]:.3f} to "
                    f"{stamped[-1]:.3f} s, a simulation's clock) do not overlap them: both read "
                    "on the bag's receive clock (--time-source bag, as umbmark info suggests)"
                )
            )
    if odometry is not None and truth is not None:
        odom = options.odom_topic or " -> ".join(options.odom_tf or ())
        ref = options.truth_topic or f"{options.tf_parent} -> {options.tf_child}"
        what = f"ground truth {ref} and odometry {odom}"
        independence.check_not_reproduced(odometry, truth, what, src)
    return BagRead(wheels, truth, tuple(notes))


def _read_wheels(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str
) -> tuple[WheelSeries, PoseSeries | None]:
    """The wheel rotation as the options say, and the controller's odometry where it is
    read from that."""
    odometry: PoseSeries | None = None
    if options.odom_topic is not None or options.odom_tf is not None:
        wheels, odometry = _read_odometry(reader, topics, options, src)
    elif options.left_wheel_frame is not None and options.right_wheel_frame is not None:
        header = options.time_source == "header"
        wheels = read_wheel_transforms(
            reader, topics, options.left_wheel_frame, options.right_wheel_frame, header, src
        )
    elif options.left_field is not None and options.right_field is not None:
        wheels = read_fields(reader, topics, options, src)
    elif options.left_ticks_topic is not None and options.right_ticks_topic is not None:
        assert options.ticks_per_rev is not None  # check_options
        wheels = read_ticks(
            reader,
            topics,
            options.left_ticks_topic,
            options.right_ticks_topic,
            options.ticks_per_rev,
            src,
        )
    else:
        wheels = read_joint_states(reader, topics, options, src)
    return wheels, odometry


def _read_odometry(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str
) -> tuple[WheelSeries, PoseSeries]:
    """Wheel rotation from the controller's odometry topic or transform chain, and that
    odometry."""
    assert options.odom_geometry is not None  # check_options
    header = options.time_source == "header"
    if options.odom_topic is not None:
        what = f"odometry {options.odom_topic}"
        series = read_pose_topic(
            reader, topics, options.odom_topic, header, src, role="controller odometry"
        )
    else:
        assert options.odom_tf is not None
        parent, child = options.odom_tf
        what = f"odometry {parent}->{child}"
        edges = transforms.read_edges(reader, topics, src, header=header)
        time, poses = transforms.chain_poses(edges, parent, child, src)
        series = PoseSeries(time=time, poses=poses)
    return wheels_from_odometry(series, options.odom_geometry, what, src).wheels, series


def _read_truth_topic(
    reader: AnyReader, topics: dict[str, str], options: BagOptions, src: str, notes: list[str]
) -> PoseSeries:
    """The ground truth of ``truth_topic``, whatever its type; notes go to ``notes``."""
    topic = options.truth_topic
    assert topic is not None
    msgtype = topics.get(topic)
    if options.truth_model is not None and msgtype != MODEL_STATES:
        raise InputError(
            f"{option('truth_model')} names a model of a {MODEL_STATES} topic; {topic} "
            + (f"has {msgtype}" if msgtype else "is not in the bag"),
            source=src,
        )
    header = options.time_source == "header"
    if msgtype == MODEL_STATES:
        truth, model = references.read_model_states(reader, topics, topic, options.truth_model, src)
        notes.append(
            info(
                f"ground truth: model {model} of {topic}, which has no header: stamped with the "
                "bag's receive times"
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
    return read_pose_topic(reader, topics, topic, header, src, allowed=REFERENCE_TYPES)


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

"""Poses from pose topics: ``geometry_msgs/PoseStamped``,
``geometry_msgs/PoseWithCovarianceStamped`` and ``nav_msgs/Odometry``.

A ground truth (``--truth-topic``), or the controller's odometry (``--odom-topic``) whose
wheel rotation :mod:`umbmark.sources.bag.wheels.odometry` recovers. Read with the fast
path of :mod:`umbmark.sources.bag.fastpath`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from umbmark.model.recording import PoseSeries
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.fastpath import POSITION, Sample, fast_layout
from umbmark.sources.bag.msgtypes import (
    POSE_STAMPED,
    TRUTH_TYPES,
    PoseStamped,
    PoseWithCovarianceStamped,
)
from umbmark.sources.bag.samples import pose_values, read_topic, stamp, time_ns, truth_series

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = ["read_pose_topic"]


def read_pose_topic(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    header: bool,
    src: str,
    role: str = "ground truth",
    allowed: tuple[str, ...] = TRUTH_TYPES,
) -> PoseSeries:
    """The planar poses of a pose topic: ``x, y`` of the position and the yaw of the
    orientation (:func:`~umbmark.sources.bag.samples.truth_series`).

    Parameters
    ----------
    header : bool
        Stamp the poses with their ``header.stamp``, else with the bag's receive times.
    role : str
        What the topic is for, for messages (``"controller odometry"``).
    allowed : tuple of str
        The message types it may have: ``geometry_msgs/PoseStamped``,
        ``geometry_msgs/PoseWithCovarianceStamped``, ``nav_msgs/Odometry``.

    Raises
    ------
    InputError
        The topic is missing, of another type, or has fewer than 2 usable poses.
    """
    conns, msgtype = bag_reader.topic_connections(reader, topics, topic, allowed, role, src)

    def decode_pose(msg: PoseStamped) -> list[Sample]:
        sec, nsec = stamp(msg)
        pose = msg.pose
        return [(sec, nsec, pose_values(pose.position, pose.orientation), POSITION)]

    def decode_covariance(msg: PoseWithCovarianceStamped) -> list[Sample]:
        sec, nsec = stamp(msg)
        pose = msg.pose.pose  # nav_msgs/Odometry has the same pose.pose
        return [(sec, nsec, pose_values(pose.position, pose.orientation), POSITION)]

    decode = decode_pose if msgtype == POSE_STAMPED else decode_covariance

    scan = read_topic(
        reader,
        conns,
        msgtype,
        topic,
        src,
        width=6,
        decode=decode,
        layout_of=fast_layout(msgtype),
    )
    return truth_series(time_ns(scan, header), scan.values, f"topic {topic}", src, header=header)

"""The ROS message types the bag reader reads, and what it uses of rosbags' message classes.

The names are rosbags' (``sensor_msgs/msg/JointState``, also for ROS 1 bags). The
protocols describe the attributes of rosbags' deserialized messages that the readers of
:mod:`umbmark.sources.bag.series` use; rosbags itself is never imported here.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import NDArray

JOINT_STATE = "sensor_msgs/msg/JointState"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
POSE_COV_STAMPED = "geometry_msgs/msg/PoseWithCovarianceStamped"
ODOMETRY = "nav_msgs/msg/Odometry"
TRUTH_TYPES = (POSE_STAMPED, POSE_COV_STAMPED, ODOMETRY)
TF_TYPES = ("tf2_msgs/msg/TFMessage", "tf/msg/tfMessage")

# std_msgs number types: numpy type code of ``data`` and bits of a counter that wraps
# (None: no wrap).
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


class Time(Protocol):
    """``builtin_interfaces/Time`` (ROS 1 ``time``)."""

    sec: int
    nanosec: int


class Header(Protocol):
    """``std_msgs/Header``."""

    stamp: Time
    frame_id: str


class Stamped(Protocol):
    """Any message with a ``header``."""

    header: Header


class JointState(Stamped, Protocol):
    """``sensor_msgs/JointState``; arrays of shape (n,), ``n = len(name)`` or empty."""

    name: list[str]
    position: NDArray[np.float64]
    velocity: NDArray[np.float64]


class Number(Protocol):
    """A ``std_msgs`` number (``Int32``, ``Float64``, ...)."""

    data: float


class Vector(Protocol):
    """``geometry_msgs/Point`` or ``geometry_msgs/Vector3``."""

    x: float
    y: float
    z: float


class Quaternion(Vector, Protocol):
    """``geometry_msgs/Quaternion``."""

    w: float


class Pose(Protocol):
    """``geometry_msgs/Pose``."""

    position: Vector
    orientation: Quaternion


class PoseStamped(Stamped, Protocol):
    """``geometry_msgs/PoseStamped``."""

    pose: Pose


class PoseWithCovariance(Protocol):
    """``geometry_msgs/PoseWithCovariance``."""

    pose: Pose


class PoseWithCovarianceStamped(Stamped, Protocol):
    """``geometry_msgs/PoseWithCovarianceStamped``, and ``nav_msgs/Odometry``'s pose."""

    pose: PoseWithCovariance


class Transform(Protocol):
    """``geometry_msgs/Transform``."""

    translation: Vector
    rotation: Quaternion


class TransformStamped(Stamped, Protocol):
    """``geometry_msgs/TransformStamped``."""

    child_frame_id: str
    transform: Transform


class TFMessage(Protocol):
    """``tf2_msgs/TFMessage`` (ROS 1 ``tf/tfMessage``)."""

    transforms: list[TransformStamped]

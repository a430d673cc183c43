"""The ROS message types the bags hold, the transform topics, and what the readers use of
rosbags' message classes.

The names are rosbags' (``sensor_msgs/msg/JointState``, also for ROS 1 bags). The
protocols describe the attributes of rosbags' deserialized messages that the readers of
:mod:`umbmark.sources.bag` use; rosbags itself is never imported here.
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
TF_MESSAGE = "tf2_msgs/msg/TFMessage"
#: Transform messages: ROS 2's and ROS 1's, and ROS 1's older ``tf``.
TF_TYPES = (TF_MESSAGE, "tf/msg/tfMessage")
TF_TOPIC = "/tf"
TF_STATIC_TOPIC = "/tf_static"
#: Gazebo's poses of every model: no header, one entry per model.
MODEL_STATES = "gazebo_msgs/msg/ModelStates"
POINT_STAMPED = "geometry_msgs/msg/PointStamped"
NAV_SAT_FIX = "sensor_msgs/msg/NavSatFix"
#: References with positions only (no heading).
POSITION_TYPES = (POINT_STAMPED, NAV_SAT_FIX)
#: Everything a ground truth may be read from.
REFERENCE_TYPES = (*TRUTH_TYPES, MODEL_STATES, *POSITION_TYPES)
#: References without a header: stamped with the bag's receive times, the recording's
#: clock (``umbmark info`` suggests ``--time-source bag`` for them; the reader reads the
#: wheels on that clock too where their header stamps are on another).
UNSTAMPED_REFERENCES = (MODEL_STATES,)


def unstamped(msgtype: str | None) -> bool:
    """Whether a reference of ``msgtype`` has no header stamps (:data:`UNSTAMPED_REFERENCES`)."""
    return msgtype in UNSTAMPED_REFERENCES


STRING = "std_msgs/msg/String"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
IMU = "sensor_msgs/msg/Imu"

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


class Twist(Protocol):
    """``geometry_msgs/Twist``."""

    linear: Vector
    angular: Vector


class ModelStates(Protocol):
    """``gazebo_msgs/ModelStates``: ``name``, ``pose`` and ``twist`` of every model, no
    header."""

    name: list[str]
    pose: list[Pose]
    twist: list[Twist]


class PointStamped(Stamped, Protocol):
    """``geometry_msgs/PointStamped``."""

    point: Vector


class NavSatStatus(Protocol):
    """``sensor_msgs/NavSatStatus``: ``status`` -1 no fix, 0 fix, 1 SBAS, 2 GBAS (RTK)."""

    status: int


class NavSatFix(Stamped, Protocol):
    """``sensor_msgs/NavSatFix``: WGS84 degrees and metres; ``position_covariance`` [m^2]
    shape (9,), east, north, up, row-major."""

    status: NavSatStatus
    latitude: float
    longitude: float
    altitude: float
    position_covariance: NDArray[np.float64]
    position_covariance_type: int


class String(Protocol):
    """``std_msgs/String``."""

    data: str


class LaserScan(Stamped, Protocol):
    """``sensor_msgs/LaserScan``: ``ranges`` [m] shape (beams,), angles [rad]."""

    angle_min: float
    angle_max: float
    angle_increment: float
    time_increment: float
    range_min: float
    range_max: float
    ranges: NDArray[np.float32]


class Imu(Stamped, Protocol):
    """``sensor_msgs/Imu``: rates [rad/s] and accelerations [m/s^2] in ``header.frame_id``;
    each covariance shape (9,), row-major, its first element -1 where the message has no
    such data."""

    orientation: Quaternion
    orientation_covariance: NDArray[np.float64]
    angular_velocity: Vector
    angular_velocity_covariance: NDArray[np.float64]
    linear_acceleration: Vector
    linear_acceleration_covariance: NDArray[np.float64]

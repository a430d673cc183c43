"""The corrected odometry (:class:`~umbmark.monitor.status.CorrectedOdometry`) as
``nav_msgs/Odometry``, and the ``odom -> base`` transform beside it.

In the controller's frames: ``header.frame_id`` and ``child_frame_id`` as the controller's
own odometry names them (:class:`Frames`, taken from its messages; ``odom`` and the base
frame where the wheels come from joint states). Covariances are row-major 6 x 6 over
``(x, y, z, roll, pitch, yaw)``, 36 numbers, as ``nav_msgs/Odometry`` carries them; where
the core gives none that is finite, the controller's own (its latest message's) is kept,
as diff_drive_controller writes its ``pose_covariance_diagonal`` there. The orientation
is the yaw's quaternion ``(0, 0, sin(yaw/2), cos(yaw/2))``.

The layout (:func:`odometry_fields`) needs no ROS; :func:`fill_odometry` and
:func:`fill_transform` put it into the message classes a node hands them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from umbmark.monitor.status import CorrectedOdometry

__all__ = ["Frames", "OdometryFields", "fill_odometry", "fill_transform", "odometry_fields"]


@dataclass(frozen=True)
class Frames:
    """The odometry's frames: ``odom`` (its ``header.frame_id``) and the robot's base
    (its ``child_frame_id``)."""

    odom: str = "odom"
    base: str = "base_link"


@dataclass(frozen=True)
class OdometryFields:
    """What a ``nav_msgs/Odometry`` holds, as plain values.

    Attributes
    ----------
    time : float
        Its stamp [s].
    frames : Frames
    position : (float, float, float)
        [m]; z is 0.
    orientation : (float, float, float, float)
        Quaternion x, y, z, w.
    pose_covariance, twist_covariance : tuple of 36 float
        Row-major over x, y, z, roll, pitch, yaw.
    linear, angular : float
        ``twist.twist.linear.x`` [m/s] and ``angular.z`` [rad/s].
    """

    time: float
    frames: Frames
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    pose_covariance: tuple[float, ...]
    twist_covariance: tuple[float, ...]
    linear: float
    angular: float


def _row_major(matrix: object, fallback: Sequence[float] | None) -> tuple[float, ...]:
    """A 6 x 6 covariance as 36 numbers, row-major; the fallback (36 numbers) where it is
    not a finite 6 x 6 matrix with something on its diagonal, else zeros."""
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape == (6, 6) and bool(np.all(np.isfinite(m))) and bool(np.any(np.diag(m) > 0.0)):
        return tuple(float(v) for v in m.reshape(36))
    if fallback is not None and len(fallback) == 36:
        return tuple(float(v) for v in fallback)
    return (0.0,) * 36


def odometry_fields(
    odometry: CorrectedOdometry,
    frames: Frames,
    pose_fallback: Sequence[float] | None = None,
    twist_fallback: Sequence[float] | None = None,
) -> OdometryFields:
    """The message's fields of ``odometry`` in ``frames``; the controller's covariances
    (``pose_fallback``, ``twist_fallback``: 36 numbers each) where the core's are not."""
    yaw = float(odometry.pose.theta)
    return OdometryFields(
        time=float(odometry.time),
        frames=frames,
        position=(float(odometry.pose.x), float(odometry.pose.y), 0.0),
        orientation=(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)),
        pose_covariance=_row_major(odometry.pose_covariance, pose_fallback),
        twist_covariance=_row_major(odometry.twist_covariance, twist_fallback),
        linear=float(odometry.linear),
        angular=float(odometry.angular),
    )


def fill_odometry(fields: OdometryFields, msg: Any, stamp: Any) -> Any:  # noqa: ANN401
    """``msg`` (a new ``nav_msgs/Odometry``) filled with ``fields``, stamped ``stamp``."""
    msg.header.stamp = stamp
    msg.header.frame_id = fields.frames.odom
    msg.child_frame_id = fields.frames.base
    p, q = msg.pose.pose.position, msg.pose.pose.orientation
    p.x, p.y, p.z = fields.position
    q.x, q.y, q.z, q.w = fields.orientation
    msg.pose.covariance = list(fields.pose_covariance)
    msg.twist.twist.linear.x = fields.linear
    msg.twist.twist.angular.z = fields.angular
    msg.twist.covariance = list(fields.twist_covariance)
    return msg


def fill_transform(fields: OdometryFields, msg: Any, stamp: Any) -> Any:  # noqa: ANN401
    """``msg`` (a new ``geometry_msgs/TransformStamped``): ``odom -> base`` at the pose."""
    msg.header.stamp = stamp
    msg.header.frame_id = fields.frames.odom
    msg.child_frame_id = fields.frames.base
    t, q = msg.transform.translation, msg.transform.rotation
    t.x, t.y, t.z = fields.position
    q.x, q.y, q.z, q.w = fields.orientation
    return msg

"""What a written bag's IMU is: :class:`ImuTrack`, the readings of a ``sensor_msgs/Imu``
topic in the IMU's own frame with its mounting, and the messages that carry it (for
:func:`umbmark.sources.bag.writer.write_bag`).

The messages are as an IMU driver publishes them: ``header.frame_id`` the IMU's frame,
``angular_velocity`` [rad/s] and ``linear_acceleration`` [m/s^2] in it, their covariances
diagonal (the variance of one reading's noise, where known), and no orientation
(``orientation_covariance[0] = -1``, the ROS convention for a field the message does not
give). The mounting, ``base_link -> frame``, goes on ``/tf_static`` beside the laser's.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.sources.bag.msgtypes import IMU

__all__ = ["ImuTrack", "imu_maker"]


@dataclass(frozen=True)
class ImuTrack:
    """An IMU's readings in its own frame, as a bag records them.

    Attributes
    ----------
    time : array, shape (n,)
        Sample times [s] on the recording's clock (the wheels'), increasing.
    rate : array, shape (n, 3)
        Angular rate about the IMU's x, y, z axes [rad/s], as the gyro reads it.
    accel : array, shape (n, 3)
        Specific force along its axes [m/s^2] (about +9.81 on an up-pointing z at rest).
    translation : (float, float, float)
        The IMU frame's origin in ``base_link`` [m].
    rotation : (float, float, float, float)
        Its orientation in ``base_link``, a unit quaternion ``x, y, z, w``.
    rate_variance, accel_variance : float
        The variance of one reading's noise [(rad/s)^2, (m/s^2)^2], written as each axis'
        covariance (0: unknown, as many drivers write).
    frame, topic : str
    """

    time: FloatArray
    rate: FloatArray
    accel: FloatArray
    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    rate_variance: float = 0.0
    accel_variance: float = 0.0
    frame: str = "imu_link"
    topic: str = "/imu"

    def __post_init__(self) -> None:
        n = self.time.shape[0]
        if self.rate.shape != (n, 3) or self.accel.shape != (n, 3):
            raise ValueError(f"an IMU's rates and accelerations must have shape ({n}, 3)")
        if n > 1 and not np.all(np.diff(self.time) > 0):
            raise ValueError("an IMU's sample times must increase")


def imu_maker(
    types: Any,  # noqa: ANN401 (a typestore's types)
    header: Callable[[int, str, str], object],
    track: ImuTrack,
) -> Callable[[int, int], object]:
    """The messages of ``track``: ``make(i, stamp)`` is sample ``i``'s ``sensor_msgs/Imu``
    stamped ``stamp`` [ns]; ``header(stamp, frame, topic)`` makes its header."""
    vector, quaternion = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    no_orientation = np.zeros(9)
    no_orientation[0] = -1.0
    rate_cov = np.diag(np.full(3, track.rate_variance)).ravel()
    accel_cov = np.diag(np.full(3, track.accel_variance)).ravel()
    rate, accel = track.rate, track.accel
    level = quaternion(x=0.0, y=0.0, z=0.0, w=1.0)

    def make(i: int, stamp: int) -> object:
        wx, wy, wz = rate[i].tolist()
        ax, ay, az = accel[i].tolist()
        return types[IMU](
            header=header(stamp, track.frame, track.topic),
            orientation=level,
            orientation_covariance=no_orientation,
            angular_velocity=vector(x=wx, y=wy, z=wz),
            angular_velocity_covariance=rate_cov,
            linear_acceleration=vector(x=ax, y=ay, z=az),
            linear_acceleration_covariance=accel_cov,
        )

    return make

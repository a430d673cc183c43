"""A gyro's readings over time: what every IMU source (a bag's ``sensor_msgs/Imu``, the
simulator) produces and the gyro estimators consume.

The rates are in the robot's base frame (``docs/conventions.md``: x forward, y left, z up,
yaw counter-clockwise positive), put there by the mounting of the IMU's own frame (its
transform, where the reader found one). The readings are as the gyro gave them: scale
error, bias and noise not removed. A gyro's scale and bias follow the convention of
:mod:`umbmark.estimators` (``omega_true = k_g (omega_read - bias)``): ``k_g`` is the
factor that corrects the gyro.

Units: seconds, rad/s, m/s^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray

__all__ = ["GyroSeries"]


@dataclass(frozen=True)
class GyroSeries:
    """A gyro's angular rates over time, in the robot's base frame.

    Attributes
    ----------
    time : array, shape (n,)
        Sample times [s], strictly increasing.
    rate : array, shape (n, 3)
        Angular rate about the base frame's x, y and z axes [rad/s], as read (bias and
        scale error in it); ``rate[:, 2]`` is the yaw rate.
    accel : array, shape (n, 3), or None
        Linear acceleration in the base frame [m/s^2] where the IMU gives it (gravity in
        it: about +9.81 on z at rest on a level floor), else None.
    frame : str
        The IMU's own frame (``imu_link``), for messages.
    source : str
        Where the readings came from (a bag's path and topic), for messages.
    """

    time: FloatArray
    rate: FloatArray
    accel: FloatArray | None = None
    frame: str = "imu_link"
    source: str = ""

    def __post_init__(self) -> None:
        n = self.time.shape[0] if self.time.ndim == 1 else -1
        if n < 0:
            raise ValueError(f"gyro time must be one-dimensional, got shape {self.time.shape}")
        if not np.all(np.isfinite(self.time)):
            raise ValueError("gyro time has values that are not finite numbers")
        if n > 1 and not np.all(np.diff(self.time) > 0):
            raise ValueError("gyro time must increase strictly from sample to sample")
        if self.rate.shape != (n, 3):
            raise ValueError(f"gyro rates must have shape ({n}, 3), got {self.rate.shape}")
        if not np.all(np.isfinite(self.rate)):
            raise ValueError("gyro rates have values that are not finite numbers")
        if self.accel is not None and self.accel.shape != (n, 3):
            raise ValueError(f"accelerations must have shape ({n}, 3), got {self.accel.shape}")

    def __len__(self) -> int:
        return int(self.time.shape[0])

    def yaw_change(self, start: FloatArray, end: FloatArray) -> FloatArray:
        """The yaw rate integrated from each ``start`` to each ``end`` [rad] (the
        trapezoid rule on the samples, linear between them; the bias is in it).

        Parameters
        ----------
        start, end : array, shape (k,)
            Times [s] within ``time[0]`` and ``time[-1]``, ``start <= end``.

        Returns
        -------
        array, shape (k,)
        """
        t, w = self.time, self.rate[:, 2]
        cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])

        def at(x: FloatArray) -> FloatArray:
            i = np.clip(np.searchsorted(t, x, side="right") - 1, 0, len(t) - 2)
            dt = x - t[i]
            slope = (w[i + 1] - w[i]) / (t[i + 1] - t[i])
            return np.asarray(cumulative[i] + w[i] * dt + 0.5 * slope * dt * dt)

        if len(t) < 2:
            raise ValueError("a gyro's yaw change needs at least two readings")
        return at(np.asarray(end, dtype=np.float64)) - at(np.asarray(start, dtype=np.float64))

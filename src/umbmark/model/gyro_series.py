"""A gyro's readings over time: what every IMU source (a bag's ``sensor_msgs/Imu``, the
simulator) produces and the gyro estimators consume.

The rates are in the robot's base frame (``docs/conventions.md``: x forward, y left, z up,
yaw counter-clockwise positive), put there by the mounting of the IMU's own frame (its
transform, where the reader found one). The readings are as the gyro gave them: scale
error, bias and noise not removed. A gyro's scale and bias follow the convention of
:mod:`umbmark.estimators` (``omega_true = k_g (omega_read - bias)``): ``k_g`` is the
factor that corrects the gyro.

What a gyro cannot have read is found here, once, for every source (the bag reader
names it, the intervals the estimator compares leave it out):

- **frozen**: exactly the same three rates for at least :data:`FROZEN` seconds and
  :data:`FROZEN_READINGS` readings (a real gyro's noise changes every reading; a driver
  that hung repeats its last one), :func:`frozen_stretches`;
- **saturated**: one axis held at its largest (or smallest) value for at least
  :data:`SATURATED_RUN` readings in a row, that value at least :data:`MIN_FULL_SCALE` (a
  rate clipped at the gyro's full scale in a fast turn, whatever that full scale is),
  outside frozen stretches, :func:`saturated_stretches`.

Both assume a gyro's noise: readings without any (a simulation with none) repeat
exactly wherever the motion is steady.

Units: seconds, rad/s, m/s^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray, IntArray

__all__ = [
    "FROZEN",
    "FROZEN_READINGS",
    "MIN_FULL_SCALE",
    "SATURATED_RUN",
    "GyroSeries",
    "frozen_stretches",
    "saturated_stretches",
]

#: The same three rates for this long [s] (and :data:`FROZEN_READINGS` readings) is a
#: frozen gyro.
FROZEN = 1.0
FROZEN_READINGS = 10
#: Readings in a row at an axis' extreme that make it saturated ...
SATURATED_RUN = 5
#: ... where that extreme is at least this [rad/s] (29 deg/s; no gyro's full scale is
#: lower).
MIN_FULL_SCALE = 0.5


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


def _runs(mask: BoolArray) -> tuple[IntArray, IntArray]:
    """The runs of True in ``mask`` (shape (n,)): their first indices and the indices
    after their last, each shape (r,)."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def frozen_stretches(time: FloatArray, rates: FloatArray) -> FloatArray:
    """Stretches ``[start, end]`` [s] of exactly the same three rates (the module's
    documentation), shape (k, 2).

    Parameters
    ----------
    time : array, shape (n,)
    rates : array, shape (n, 3)
    """
    if time.size < 2:
        return np.zeros((0, 2))
    same = np.all(rates[1:] == rates[:-1], axis=1)
    first, after = _runs(same)  # pairs i..after-1 equal: readings first..after
    long = (time[after] - time[first] >= FROZEN) & (after - first + 1 >= FROZEN_READINGS)
    return np.column_stack([time[first[long]], time[after[long]]])


def saturated_stretches(
    time: FloatArray, rates: FloatArray, frozen: FloatArray | None = None
) -> FloatArray:
    """Stretches ``[start, end]`` [s] where an axis holds its extreme (the module's
    documentation), outside the ``frozen`` stretches (shape (k, 2); default: found by
    :func:`frozen_stretches`), in time order, shape (m, 2).

    Parameters
    ----------
    time : array, shape (n,)
    rates : array, shape (n, 3)
    """
    if time.size == 0:
        return np.zeros((0, 2))
    frozen = frozen_stretches(time, rates) if frozen is None else frozen
    out: list[tuple[float, float]] = []
    for axis in range(3):
        column = rates[:, axis]
        for extreme in (float(column.max()), float(column.min())):
            if abs(extreme) < MIN_FULL_SCALE:
                continue
            first, after = _runs(column == extreme)
            for a, b in zip(first.tolist(), after.tolist(), strict=True):
                start, end = float(time[a]), float(time[b - 1])
                inside = np.any((frozen[:, 0] <= start) & (frozen[:, 1] >= end))
                if b - a >= SATURATED_RUN and not inside:
                    out.append((start, end))
    return np.array(sorted(out), dtype=np.float64).reshape(-1, 2)

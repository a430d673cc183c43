"""Synchronized motion intervals: what the wheels turned against how a sensor moved.

The input of the simultaneous calibration of odometry and sensor mounting (Censi,
Franchi, Marchionni and Oriolo, IEEE T-RO 2013): for each interval ``k`` of driving, its
duration, the rotation of the left and right wheel over it, and the sensor's own
displacement over it (measured by scan matching), expressed in the sensor frame at the
interval's start. One interval is one row of the reference implementation's ``.tuple``
files (``T``, ``phi_l``, ``phi_r``, ``sm``).

Units: seconds, radians (wheel rotation, sensor yaw), metres. The robot frame follows
``docs/conventions.md``: x forward, y left, yaw counter-clockwise positive.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray

__all__ = ["MotionIntervals"]


@dataclass(frozen=True)
class MotionIntervals:
    """``n`` intervals of driving, wheels against the sensor's measured motion.

    Attributes:
        duration: ``(n,)`` seconds each interval lasts (> 0).
        phi_left: ``(n,)`` rotation of the left wheel over the interval [rad], positive
            when the wheel drives the robot forward.
        phi_right: ``(n,)`` rotation of the right wheel [rad], same sign rule.
        sensor_motion: ``(n, 3)`` the sensor's displacement ``(x, y, yaw)`` over the
            interval in the sensor frame at its start [m, m, rad] (scan matching).
        sensor_covariance: ``(n, 3, 3)`` covariance of ``sensor_motion`` where the
            matcher gives one, else ``None``.
        start_time: ``(n,)`` when each interval starts [s] on the recording's clock, or
            ``None`` (tuple files carry no time).
        source: where the intervals came from (a file or bag path, for messages).
    """

    duration: FloatArray
    phi_left: FloatArray
    phi_right: FloatArray
    sensor_motion: FloatArray
    sensor_covariance: FloatArray | None = None
    start_time: FloatArray | None = None
    source: str = ""

    def __post_init__(self) -> None:
        n = self.duration.shape[0]
        for name in ("duration", "phi_left", "phi_right"):
            if getattr(self, name).shape != (n,):
                raise ValueError(f"MotionIntervals.{name} must have shape ({n},)")
        if self.sensor_motion.shape != (n, 3):
            raise ValueError(f"MotionIntervals.sensor_motion must have shape ({n}, 3)")
        if self.sensor_covariance is not None and self.sensor_covariance.shape != (n, 3, 3):
            raise ValueError(f"MotionIntervals.sensor_covariance must have shape ({n}, 3, 3)")
        if self.start_time is not None and self.start_time.shape != (n,):
            raise ValueError(f"MotionIntervals.start_time must have shape ({n},)")

    def __len__(self) -> int:
        return int(self.duration.shape[0])

    def rows(self, mask: BoolArray) -> MotionIntervals:
        """The intervals ``mask`` (shape (n,), True: kept) picks, in their order."""
        cov, start = self.sensor_covariance, self.start_time
        return MotionIntervals(
            duration=self.duration[mask],
            phi_left=self.phi_left[mask],
            phi_right=self.phi_right[mask],
            sensor_motion=self.sensor_motion[mask],
            sensor_covariance=None if cov is None else cov[mask],
            start_time=None if start is None else start[mask],
            source=self.source,
        )

    @classmethod
    def concatenate(cls, parts: Sequence[MotionIntervals]) -> MotionIntervals:
        """The intervals of ``parts`` one after the other (covariances and start times
        kept only where every part has them; sources joined by ", ")."""
        if not parts:
            raise ValueError("no motion intervals to join")
        covs = [p.sensor_covariance for p in parts]
        starts = [p.start_time for p in parts]
        return cls(
            duration=np.concatenate([p.duration for p in parts]),
            phi_left=np.concatenate([p.phi_left for p in parts]),
            phi_right=np.concatenate([p.phi_right for p in parts]),
            sensor_motion=np.concatenate([p.sensor_motion for p in parts]),
            sensor_covariance=None
            if any(c is None for c in covs)
            else np.concatenate([c for c in covs if c is not None]),
            start_time=None
            if any(t is None for t in starts)
            else np.concatenate([t for t in starts if t is not None]),
            source=", ".join(p.source for p in parts if p.source),
        )

"""Laser scans over time: what a planar laser scanner (``sensor_msgs/LaserScan``) measured.

The input of scan matching (:mod:`umbmark.scans`): one scanner's sweeps, all with the
same beams. Units: seconds, radians, metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray

__all__ = ["LaserMounting", "ScanSeries"]


@dataclass(frozen=True)
class ScanSeries:
    """``n`` sweeps of one planar laser scanner of ``beams`` beams each.

    Attributes:
        times: ``(n,)`` the sweeps' stamps [s], strictly increasing (any spacing).
        ranges: ``(n, beams)`` measured ranges [m]; NaN, inf, or outside
            ``range_min .. range_max`` is no return.
        angle_min: angle of the first beam [rad] in the scanner's frame.
        angle_increment: angle between beams [rad] (negative: the beams run clockwise).
        range_min, range_max: the scanner's valid range [m].
        upside_down: the scanner is mounted upside down (its z axis points down, as TF
            says of a mounting rolled by 180 degrees): its angles run clockwise seen from
            above. The points and motions of :mod:`umbmark.scans` are then given in the
            scanner's frame turned right side up (same x axis, y and yaw mirrored), so that
            they read counter-clockwise like the robot's own frame.
        time_increment: time between two beams [s] (``sensor_msgs/LaserScan``'s): beam
            ``k`` is measured ``k * time_increment`` after the sweep's stamp; 0 (or a sweep
            taken at once) leaves the sweeps as they are, otherwise the matcher undoes the
            scanner's motion during the sweep.
        frame: the scanner's frame (``header.frame_id``), for messages.
        source: where the scans came from (a bag and topic), for messages.
    """

    times: FloatArray
    ranges: FloatArray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    upside_down: bool = False
    time_increment: float = 0.0
    frame: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        n = self.times.shape[0] if self.times.ndim == 1 else -1
        if n < 0:
            raise ValueError("ScanSeries.times must have shape (n,)")
        if self.ranges.ndim != 2 or self.ranges.shape[0] != n:
            raise ValueError(f"ScanSeries.ranges must have shape ({n}, beams)")
        if n > 1 and not np.all(np.diff(self.times) > 0):
            raise ValueError("ScanSeries.times must be strictly increasing")
        if not (math.isfinite(self.angle_increment) and self.angle_increment != 0.0):
            raise ValueError("ScanSeries.angle_increment must be a finite non-zero angle")
        if not (math.isfinite(self.time_increment) and self.time_increment >= 0.0):
            raise ValueError("ScanSeries.time_increment must be a time >= 0")
        if not (0.0 <= self.range_min < self.range_max):
            raise ValueError("ScanSeries needs 0 <= range_min < range_max")

    def __len__(self) -> int:
        return int(self.times.shape[0])

    @property
    def beams(self) -> int:
        """Beams per sweep."""
        return int(self.ranges.shape[1])

    def angles(self) -> FloatArray:
        """The beams' angles [rad], shape ``(beams,)``, in the scanner's frame as mounted."""
        return np.asarray(
            self.angle_min + self.angle_increment * np.arange(self.beams, dtype=np.float64)
        )


@dataclass(frozen=True)
class LaserMounting:
    """A laser's mounting as the robot states it (TF, ``/tf_static``, its URDF): the pose
    of the laser's frame in the robot's base frame.

    Attributes:
        x, y: the laser's origin forward and left of the base frame's [m].
        yaw: the direction of the laser's x axis [rad], ccw from the base's x axis.
        lift: ``(z, roll, pitch)`` [m, rad, rad], the height and tilt the robot states
            (URDF ``rpy``: fixed axes, yaw last); None where only the planar mounting is
            known. The planar scan matching does not see them.
        base, frame: the base frame and the laser's frame (``header.frame_id``).
        source: where it was stated, for people (``TF``, ``/tf_static in BAG``, ...).
    """

    x: float
    y: float
    yaw: float
    lift: tuple[float, float, float] | None = None
    base: str = "base_link"
    frame: str = "laser"
    source: str = ""

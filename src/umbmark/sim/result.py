"""What a simulation returns: the runs' end poses and, on request, their time series."""

from __future__ import annotations

from dataclasses import dataclass

from umbmark.core.arrays import FloatArray, IntArray
from umbmark.core.conventions import Direction
from umbmark.model.run import EndPose, Run

__all__ = ["SimResult", "Trace"]


@dataclass(frozen=True)
class Trace:
    """Time series of a simulation (recorded on request).

    Attributes
    ----------
    time : array, shape (T,)
        Sample times [s], from 0.
    true_pose : array, shape (R, T, 3)
        True ``x, y, theta`` of every run [m, rad].
    counts : array, shape (R, T, 2)
        Cumulative encoder counts ``left, right``.
    odometry_pose : array, shape (R, T, 3)
        The robot's odometry pose [m, rad].
    """

    time: FloatArray
    true_pose: FloatArray
    counts: IntArray
    odometry_pose: FloatArray


@dataclass(frozen=True)
class SimResult:
    """End poses of simulated runs.

    Attributes
    ----------
    directions : tuple of Direction
    true_end, odometry_end : array, shape (R, 3)
        True and odometry end poses ``x, y, theta`` [m, rad], headings unwrapped.
    duration : array, shape (R,)
        Time each run took [s].
    samples_used : array, shape (R,)
        Sampling periods each run took (its last sample, in a trace, is this index).
    samples : int
        Number of sampling periods simulated (for the longest run).
    trace : Trace or None
    """

    directions: tuple[Direction, ...]
    true_end: FloatArray
    odometry_end: FloatArray
    duration: FloatArray
    samples_used: IntArray
    samples: int
    trace: Trace | None = None

    def runs(self, label: str = "sim") -> list[Run]:
        """The simulated runs as :class:`umbmark.model.run.Run` values."""
        return [
            Run(
                direction=d,
                true_end=EndPose(*(float(v) for v in self.true_end[i])),
                odometry_end=EndPose(*(float(v) for v in self.odometry_end[i])),
                label=f"{label} run {i + 1}",
            )
            for i, d in enumerate(self.directions)
        ]

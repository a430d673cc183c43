"""Recorded time series: what every logged source (run logs, OptiOdom, ROS bags) reads.

A source reads a :class:`Recording`: the wheels' rotation over time and, usually, a
ground-truth pose over time, each on its own clock samples. :mod:`umbmark.association`
matches the two in time, :mod:`umbmark.segmentation` splits a recording into runs, and
:mod:`umbmark.logged` turns each run into a :class:`umbmark.model.run.Run` whose ``log`` is a
:class:`RunLog`.

Units: seconds, radians (wheel rotation and heading), metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.model.kinematics import IntegrationMethod, WheelParams, integrate_odometry
from umbmark.options.spec import READ

__all__ = [
    "DEFAULT_MAX_GAP",
    "GAP_FACTOR",
    "MIN_GAP",
    "PoseSeries",
    "Recording",
    "RunLog",
    "WheelSeries",
    "gap_mask",
]


#: Longest stretch [s] without ground truth across which poses are interpolated (the
#: default of ``--max-gap``; :mod:`umbmark.runs.association`).
DEFAULT_MAX_GAP: float = READ["max_gap"].default
#: An interval between samples longer than this many typical sample periods (the
#: median) is a gap (:func:`gap_mask`) ...
GAP_FACTOR = 5.0
#: ... if it is also longer than this [s].
MIN_GAP = 0.1


def gap_mask(time: FloatArray) -> BoolArray:
    """Which intervals of ``time`` (shape (n,), increasing) are gaps, shape (n - 1,): a
    while without a sample (:mod:`umbmark.runs.gaps` says what happens across one)."""
    dt = np.diff(time)
    if dt.size == 0:
        return np.zeros(0, dtype=bool)
    limit = max(GAP_FACTOR * float(np.median(dt)), MIN_GAP)
    return np.asarray(dt > limit)


def _check_time(time: FloatArray, what: str) -> None:
    if time.ndim != 1:
        raise ValueError(f"{what} time must be one-dimensional, got shape {time.shape}")
    if not np.all(np.isfinite(time)):
        raise ValueError(f"{what} time has values that are not finite numbers")
    if time.size > 1 and not np.all(np.diff(time) > 0):
        raise ValueError(f"{what} time must increase strictly from sample to sample")


@dataclass(frozen=True)
class WheelSeries:
    """Wheel rotation over time.

    Attributes
    ----------
    time : array, shape (n,)
        Sample times [s], strictly increasing.
    angles : array, shape (n, 2)
        Cumulative rotation of the left and right wheel [rad] (any origin); forward
        motion increases both.
    """

    time: FloatArray
    angles: FloatArray

    def __post_init__(self) -> None:
        _check_time(self.time, "wheel")
        if self.angles.shape != (self.time.size, 2):
            raise ValueError(
                f"wheel angles must have shape ({self.time.size}, 2), got {self.angles.shape}"
            )
        if not np.all(np.isfinite(self.angles)):
            raise ValueError("wheel angles have values that are not finite numbers")


@dataclass(frozen=True)
class PoseSeries:
    """A planar pose over time (ground truth).

    Attributes
    ----------
    time : array, shape (m,)
        Sample times [s], strictly increasing.
    poses : array, shape (m, 3)
        ``x, y`` [m] and heading ``theta`` [rad], in any fixed frame; headings may be
        wrapped (they are unwrapped on use). NaN headings when ``headings`` is False.
    headings : bool
        Whether the reference measures headings; False for position-only references (a
        GPS fix, a tracked point), whose ``theta`` column is NaN.
    covariance : array, shape (m, 2, 2), or None
        The positions' covariance [m^2] where the reference gives one (a GPS receiver's
        ``position_covariance``, east and north); NaN where a sample has none.
    """

    time: FloatArray
    poses: FloatArray
    headings: bool = True
    covariance: FloatArray | None = None

    def __post_init__(self) -> None:
        _check_time(self.time, "ground-truth")
        if self.poses.shape != (self.time.size, 3):
            raise ValueError(
                f"ground-truth poses must have shape ({self.time.size}, 3), got {self.poses.shape}"
            )
        checked = self.poses if self.headings else self.poses[:, :2]
        if not np.all(np.isfinite(checked)):
            raise ValueError("ground-truth poses have values that are not finite numbers")
        if self.covariance is not None and self.covariance.shape != (self.time.size, 2, 2):
            raise ValueError(
                f"ground-truth covariances must have shape ({self.time.size}, 2, 2), got "
                f"{self.covariance.shape}"
            )


@dataclass(frozen=True)
class Recording:
    """What a source read, not yet split into runs.

    Attributes
    ----------
    name : str
        Its short name (a file's name, ``run-01``): the label of its runs.
    wheels : WheelSeries
    truth : PoseSeries or None
        Ground truth, if the source has it.
    params : WheelParams or None
        Nominal wheel parameters, if the source knows them.
    side_length : float or None
        The square's side [m], if the source knows it.
    path : str or None
        The file it was read from, for messages (``name`` where None).
    wheel_sample : str
        What one wheel sample is, for messages (``"/odom message"``).
    truth_at_stops : bool
        The ground truth was measured only where the robot stood (a self-calibration's
        corner fixes): few wheel samples have one, as intended.
    truth_name : str
        The ground truth, for messages (``"the ground truth /odom"``).
    """

    name: str
    wheels: WheelSeries
    truth: PoseSeries | None = None
    params: WheelParams | None = None
    side_length: float | None = None
    path: str | None = None

    @property
    def where(self) -> str:
        """The recording as messages name it: its file, else its name."""
        return self.path or self.name

    wheel_sample: str = "wheel sample"
    truth_at_stops: bool = False
    truth_name: str = "the ground truth"


@dataclass(frozen=True)
class RunLog:
    """The time series of one run, ready for the estimators.

    Attributes
    ----------
    time : array, shape (n,)
        Seconds from the run's start.
    wheel_angles : array, shape (n, 2)
        Rotation of the left and right wheel since the run's start [rad].
    truth : array, shape (n, 3)
        Ground truth ``x, y, theta`` in the run's start frame (its first row is zero);
        NaN rows where no ground truth matched the wheel sample.
    source : str
        Where it came from.
    start : float
        The absolute time [s] of the run's first sample on the recording's own clock
        (a bag's header or receive times, a run log's CSV time): ``start + time`` are the
        recording's timestamps, for matching with other trajectories of the same
        recording (TUM exports). 0.0 when the source has no clock of its own.
    headings : bool
        Whether the ground truth has headings; False for a position-only reference,
        whose ``theta`` column is NaN throughout.
    """

    time: FloatArray
    wheel_angles: FloatArray
    truth: FloatArray
    source: str = ""
    start: float = 0.0
    headings: bool = True

    @property
    def matched(self) -> NDArray[np.bool_]:
        """Which samples have ground truth (a position, and a heading where the reference
        has headings), shape (n,)."""
        columns = self.truth if self.headings else self.truth[:, :2]
        return np.asarray(np.all(np.isfinite(columns), axis=1))

    def truth_turn(self) -> tuple[float, float, float] | None:
        """The ground truth's first and last matched sample's times [s, the recording's
        clock: ``start + time``] and its heading change between them [rad, unwrapped];
        None without headings or fewer than two matched samples."""
        at = np.flatnonzero(self.matched)
        if not self.headings or at.size < 2:
            return None
        heading = np.unwrap(self.truth[at, 2])
        first, last = float(self.time[at[0]]), float(self.time[at[-1]])
        return self.start + first, self.start + last, float(heading[-1] - heading[0])

    def odometry(self, params: WheelParams, method: IntegrationMethod = "arc") -> FloatArray:
        """Odometry poses, shape (n, 3), from the wheel rotation and ``params``.

        Wheel travel per interval is ``c * D_n / 2 * dphi`` (Eqs. 2.2, 4.33 with
        ``c_m N = (D_n / 2) dphi``). With ``params.spot_wheelbase`` set, each interval
        turns with the scrub model's wheelbase ``b_eff``
        (:meth:`umbmark.model.kinematics.WheelParams.step_wheelbase`).
        """
        dphi = np.diff(self.wheel_angles, axis=0)
        d_left = params.c_left * 0.5 * params.wheel_diameter * dphi[:, 0]
        d_right = params.c_right * 0.5 * params.wheel_diameter * dphi[:, 1]
        wheelbase = params.step_wheelbase(d_left, d_right)
        return integrate_odometry(d_left, d_right, wheelbase, method=method)

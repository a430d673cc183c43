"""Synchronized motion intervals from a scanner's sweeps and the wheels' rotation.

As Censi, Franchi, Marchionni and Oriolo (IEEE T-RO 2013) build their input: the
recording is cut into intervals between two sweeps, and for each the wheels' rotation
over it (their angles interpolated linearly at the two sweeps' stamps) is set against
the scanner's own displacement, measured by matching the second sweep against the first
(:func:`umbmark.scans.icp.match`).

How intervals are chosen (:class:`IntervalOptions`): from a key sweep, the interval ends
at the first sweep at least ``min_interval`` later; the next interval starts there, so
intervals follow each other without overlapping and every sweep is prepared once. An
interval is left out, and counted by its reason in :class:`IntervalReport`, when

- it is longer than ``max_interval`` (a gap in the sweeps),
- the wheels do not cover it (their samples start later or end sooner),
- neither wheel turned more than ``min_rotation`` (standing still: no information),
- the match is degenerate or failed (a corridor, open space, not converged),
- the match disagrees with the guess from the wheels by more than ``max_disagreement``
  (with a guess only: a match that slid along a wall).

The guess: with the nominal geometry (:class:`OdometryGuess`), the wheels' rotation over
the interval is integrated into the robot's motion (an arc between every two wheel
samples) and moved into the scanner's frame by its nominal mounting; without it, the
match starts from no motion, which holds for slow driving and fast sweeps only.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.recording import WheelSeries
from umbmark.model.scans import ScanSeries
from umbmark.scans.icp import DEFAULT_SETTINGS, MatchSettings, match
from umbmark.scans.points import PreparedScan, prepare, series_points

__all__ = [
    "IntervalOptions",
    "IntervalReport",
    "OdometryGuess",
    "compose",
    "intervals_from_scans",
    "invert",
    "match_intervals",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OdometryGuess:
    """The nominal geometry the first guess of every match is computed with.

    Attributes
    ----------
    wheel_radius_left, wheel_radius_right : float
        Nominal wheel radii [m].
    wheelbase : float
        Nominal wheelbase [m].
    laser_pose : tuple of float
        The scanner's nominal pose ``x, y, yaw`` [m, m, rad] in the robot's base frame
        (of its frame right side up, for a scanner mounted upside down).
    """

    wheel_radius_left: float
    wheel_radius_right: float
    wheelbase: float
    laser_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class IntervalOptions:
    """How intervals are chosen and matched (the module's docstring).

    Attributes
    ----------
    min_interval, max_interval : float
        Shortest and longest interval [s].
    min_rotation : float
        Least rotation [rad] of one wheel for an interval to count.
    max_disagreement : tuple of float
        Largest difference between match and guess: translation [m], yaw [rad].
    guess : OdometryGuess or None
    settings : MatchSettings
    """

    min_interval: float = 0.5
    max_interval: float = 1.5
    min_rotation: float = 0.02
    max_disagreement: tuple[float, float] = (0.3, 0.35)
    guess: OdometryGuess | None = None
    settings: MatchSettings = DEFAULT_SETTINGS

    def __post_init__(self) -> None:
        if not (0.0 < self.min_interval <= self.max_interval):
            raise ValueError("IntervalOptions needs 0 < min_interval <= max_interval")


DEFAULT_OPTIONS = IntervalOptions()


@dataclass(frozen=True)
class IntervalReport:
    """What :func:`match_intervals` found.

    Attributes
    ----------
    intervals : MotionIntervals
        The intervals kept.
    left_out : dict of str to int
        Intervals left out, by reason (``"corridor"``, ``"open space"``, ``"not
        converged"``, ``"standing still"``, ``"gap in the scans"``, ``"no wheel data"``,
        ``"far from the wheels' guess"``).
    rms : array, shape (n,)
        Each kept match's residual [m] (root mean square point-to-line distance).
    """

    intervals: MotionIntervals
    left_out: dict[str, int] = field(default_factory=dict)
    rms: FloatArray = field(default_factory=lambda: np.zeros(0))

    @property
    def tried(self) -> int:
        """Intervals considered, kept or not."""
        return len(self.intervals) + sum(self.left_out.values())


def compose(a: FloatArray, b: FloatArray) -> FloatArray:
    """The planar pose ``a (+) b``: ``b`` ``(x, y, yaw)`` given in the frame ``a``."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array(
        [
            a[0] + c * b[0] - s * b[1],
            a[1] + s * b[0] + c * b[1],
            math.remainder(a[2] + b[2], math.tau),
        ]
    )


def invert(a: FloatArray) -> FloatArray:
    """The planar pose ``(-) a``: ``compose(a, invert(a))`` is no motion."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2]])


def _robot_motion(guess: OdometryGuess, angles: FloatArray) -> FloatArray:
    """The robot's motion ``(x, y, yaw)`` over wheel angles ``(k, 2)`` [rad], arcs between
    samples, in its frame at the first sample."""
    d = np.diff(angles, axis=0) * [guess.wheel_radius_left, guess.wheel_radius_right]
    ds = 0.5 * (d[:, 0] + d[:, 1])
    dth = (d[:, 1] - d[:, 0]) / guess.wheelbase
    heading = np.concatenate([[0.0], np.cumsum(dth)])
    mid = heading[:-1] + 0.5 * dth
    chord = ds * np.sinc(dth / (2 * math.pi))  # 2 sin(dth/2)/dth, times ds
    return np.array(
        [float(np.sum(chord * np.cos(mid))), float(np.sum(chord * np.sin(mid))), heading[-1]]
    )


def _wheel_angles(wheels: WheelSeries, t0: float, t1: float) -> FloatArray:
    """Wheel angles ``(k, 2)`` at ``t0``, at every sample inside, and at ``t1``."""
    inner = (wheels.time > t0) & (wheels.time < t1)
    times = np.concatenate([[t0], wheels.time[inner], [t1]])
    return np.column_stack([np.interp(times, wheels.time, wheels.angles[:, i]) for i in range(2)])


def match_intervals(
    scans: ScanSeries, wheels: WheelSeries, options: IntervalOptions = DEFAULT_OPTIONS
) -> IntervalReport:
    """The motion intervals of a recording and what was left out (the module's docstring).

    Parameters
    ----------
    scans : ScanSeries
        The scanner's sweeps (at any rate, regular or not).
    wheels : WheelSeries
        The wheels' cumulative rotation on the same clock.
    options : IntervalOptions
    """
    left_out: Counter[str] = Counter()
    rows: list[tuple[float, float, float, float, FloatArray, FloatArray, float]] = []
    times = scans.times
    mount = None if options.guess is None else np.asarray(options.guess.laser_pose, np.float64)
    prepared: dict[int, PreparedScan] = {}

    def sweep(i: int) -> PreparedScan:
        if i not in prepared:
            prepared.clear()  # only the key sweep is ever needed again
            prepared[i] = prepare(series_points(scans, i))
        return prepared[i]

    i = 0
    n = len(scans)
    while i < n - 1:
        j = int(np.searchsorted(times, times[i] + options.min_interval, side="left"))
        if j >= n:
            break
        t0, t1 = float(times[i]), float(times[j])
        start, i = i, j
        if t1 - t0 > options.max_interval:
            left_out["gap in the scans"] += 1
            continue
        if t0 < wheels.time[0] or t1 > wheels.time[-1]:
            left_out["no wheel data"] += 1
            continue
        angles = _wheel_angles(wheels, t0, t1)
        phi = angles[-1] - angles[0]
        if np.max(np.abs(phi)) < options.min_rotation:
            left_out["standing still"] += 1
            continue
        guess = None
        if options.guess is not None and mount is not None:
            robot = _robot_motion(options.guess, angles)
            guess = compose(compose(invert(mount), robot), mount)
        reference = sweep(start)
        result = match(reference, sweep(j), guess, options.settings)
        if not result.ok:
            left_out[result.status] += 1
            continue
        if guess is not None:
            off = result.pose - guess
            if (
                math.hypot(off[0], off[1]) > options.max_disagreement[0]
                or abs(math.remainder(off[2], math.tau)) > options.max_disagreement[1]
            ):
                left_out["far from the wheels' guess"] += 1
                continue
        rows.append(
            (t0, t1 - t0, float(phi[0]), float(phi[1]), result.pose, result.covariance, result.rms)
        )
    k = len(rows)
    intervals = MotionIntervals(
        duration=np.array([r[1] for r in rows], dtype=np.float64),
        phi_left=np.array([r[2] for r in rows], dtype=np.float64),
        phi_right=np.array([r[3] for r in rows], dtype=np.float64),
        sensor_motion=np.array([r[4] for r in rows], dtype=np.float64).reshape(k, 3),
        sensor_covariance=np.array([r[5] for r in rows], dtype=np.float64).reshape(k, 3, 3),
        start_time=np.array([r[0] for r in rows], dtype=np.float64),
        source=scans.source,
    )
    rms = np.array([r[6] for r in rows], dtype=np.float64)
    return IntervalReport(intervals, dict(left_out), rms)


def intervals_from_scans(
    scans: ScanSeries, wheels: WheelSeries, options: IntervalOptions = DEFAULT_OPTIONS
) -> MotionIntervals:
    """The motion intervals of a recording (:func:`match_intervals` without the counts)."""
    return match_intervals(scans, wheels, options).intervals

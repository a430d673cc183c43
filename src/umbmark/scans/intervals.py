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
match starts from no motion, which holds for slow driving and fast sweeps only (rolling
sweeps, below, are matched a second time from the fitted motion). A guess that loses
most moving intervals (far from it, or not converged from it) is checked against the
sweeps alone: where their own motion per wheel rotation is far from the guess's (a wheel
diameter or wheelbase in another unit), the guess is given up and the intervals are
those matched from the sweeps alone (:attr:`IntervalReport.guess_off` says by how much).

The motion during a sweep: a rotating scanner measures its beams one after the other
(``ScanSeries.time_increment``), so a sweep taken while turning is bent; matched as it
is, the turns come out short by about the sweep's share of a revolution (0.6 % at 10 Hz
and 0.6 rad/s). Each sweep's points are moved into the scanner's frame at its stamp
(:func:`umbmark.scans.points.series_points`) with the scanner's velocity during the
sweep, by the wheels (their angles at every sample, turned into the scanner's motion by
the nominal geometry, :func:`jacobian`); without a guess, by the geometry fitted to a
first matching of the sweeps as they are (:func:`fit_jacobian`), after which every
interval is matched again.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.recording import WheelSeries
from umbmark.model.scans import LaserMounting, ScanSeries
from umbmark.scans.icp import DEFAULT_SETTINGS, MatchSettings, match
from umbmark.scans.points import PreparedScan, prepare, series_points

__all__ = [
    "IntervalOptions",
    "IntervalReport",
    "OdometryGuess",
    "fit_jacobian",
    "intervals_from_scans",
    "jacobian",
    "match_intervals",
]


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

    def __post_init__(self) -> None:
        values = (self.wheel_radius_left, self.wheel_radius_right, self.wheelbase)
        if not all(math.isfinite(v) and v > 0.0 for v in values):
            raise ValueError("OdometryGuess needs wheel radii and a wheelbase > 0 [m]")
        if not all(math.isfinite(v) for v in self.laser_pose):
            raise ValueError("OdometryGuess.laser_pose must be finite")


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
    guess : OdometryGuess or None
        The nominal geometry the matches started from.
    notes : tuple of str
        Where the guess came from, for people.
    stated : LaserMounting or None
        The laser's mounting as the recording states it (``/tf_static``, the robot
        description), where it does.
    guess_off : tuple of float, optional
        Where the guess was given up (:func:`match_intervals`): the scanner's motion per
        wheel rotation as its sweeps alone measure it, over the guess's, driving straight
        (the wheels' mean radius) and turning on the spot (radius over wheelbase); the
        intervals are then those matched from the sweeps alone.
    lost : tuple of int, optional
        With ``guess_off``: the moving intervals the guess's matches lost, of how many.
    """

    intervals: MotionIntervals
    left_out: dict[str, int] = field(default_factory=dict)
    rms: FloatArray = field(default_factory=lambda: np.zeros(0))
    guess: OdometryGuess | None = None
    notes: tuple[str, ...] = ()
    stated: LaserMounting | None = None
    guess_off: tuple[float, float] | None = None
    lost: tuple[int, int] | None = None

    @property
    def tried(self) -> int:
        """Intervals considered, kept or not."""
        return len(self.intervals) + sum(self.left_out.values())


def jacobian(guess: OdometryGuess) -> FloatArray:
    """The scanner's motion per wheel rotation: its twist ``(vx, vy, w)`` [m, m, rad] in its
    own frame is ``J @ (phi_left, phi_right)``, ``J`` shape (3, 2), for the nominal
    geometry (the robot's twist moved into the scanner's frame by its mounting)."""
    rl, rr, b = guess.wheel_radius_left, guess.wheel_radius_right, guess.wheelbase
    lx, ly, lth = guess.laser_pose
    forward, turn = np.array([rl / 2, rr / 2]), np.array([-rl / b, rr / b])
    # at the scanner: v + w x l, turned into its frame
    vx, vy = forward - turn * ly, turn * lx
    c, s = math.cos(lth), math.sin(lth)
    return np.array([c * vx + s * vy, -s * vx + c * vy, turn])


def fit_jacobian(intervals: MotionIntervals) -> FloatArray | None:
    """:func:`jacobian` fitted to matched intervals by least squares (their motions as
    twists, the logarithm of SE(2)); None when they do not determine it (fewer than 6,
    or the wheels never turned against each other)."""
    if len(intervals) < 6:
        return None
    wheels = np.column_stack([intervals.phi_left, intervals.phi_right])
    if np.linalg.cond(wheels) > 1e3:
        return None
    x, y, th = intervals.sensor_motion.T
    half = 0.5 * th
    with np.errstate(invalid="ignore", divide="ignore"):
        a = np.where(np.abs(half) > 1e-9, half / np.tan(half), 1.0)
    twists = np.column_stack([a * x + half * y, -half * x + a * y, th])
    fitted, *_ = np.linalg.lstsq(wheels, twists, rcond=None)
    return np.asarray(fitted.T, dtype=np.float64)


def _laser_path(
    jac: FloatArray, wheels: WheelSeries, t0: float, t1: float
) -> tuple[FloatArray, FloatArray]:
    """The scanner's poses ``(k, 3)`` in its frame at ``t0``, at ``t0``, every wheel sample
    inside and ``t1``, and those times ``(k,)`` [s] from ``t0``: constant twists between
    samples (exact arcs)."""
    inner = (wheels.time > t0) & (wheels.time < t1)
    times = np.concatenate([[t0], wheels.time[inner], [t1]])
    angles = np.column_stack([np.interp(times, wheels.time, wheels.angles[:, i]) for i in (0, 1)])
    xi = np.diff(angles, axis=0) @ jac.T
    w = xi[:, 2]
    heading = np.concatenate([[0.0], np.cumsum(w)])
    mid = heading[:-1] + 0.5 * w
    arc = np.sinc(w / (2 * math.pi))  # sin(w/2) / (w/2)
    dx = arc * (np.cos(mid) * xi[:, 0] - np.sin(mid) * xi[:, 1])
    dy = arc * (np.sin(mid) * xi[:, 0] + np.cos(mid) * xi[:, 1])
    poses = np.column_stack(
        [np.concatenate([[0.0], np.cumsum(dx)]), np.concatenate([[0.0], np.cumsum(dy)]), heading]
    )
    return times - t0, poses


def _path_motion(times: FloatArray, poses: FloatArray) -> Callable[[FloatArray], FloatArray]:
    def motion(tau: FloatArray) -> FloatArray:
        return np.column_stack([np.interp(tau, times, poses[:, i]) for i in range(3)])

    return motion


def match_intervals(
    scans: ScanSeries, wheels: WheelSeries, options: IntervalOptions = DEFAULT_OPTIONS
) -> IntervalReport:
    """The motion intervals of a recording and what was left out (the module's docstring).

    Without a guess, sweeps with a ``time_increment`` are matched twice: once as they
    are, to fit the scanner's motion per wheel rotation (:func:`fit_jacobian`), then
    again with the motion during each sweep undone by it.

    Parameters
    ----------
    scans : ScanSeries
        The scanner's sweeps (at any rate, regular or not).
    wheels : WheelSeries
        The wheels' cumulative rotation on the same clock.
    options : IntervalOptions
    """
    if options.guess is not None:
        guessed = _matched(scans, wheels, options, jacobian(options.guess), check=True)
        return _checked_guess(guessed, scans, wheels, options)
    if scans.time_increment * scans.beams <= 0.0:
        return _matched(scans, wheels, options, None, check=False)
    first = _matched(dataclasses.replace(scans, time_increment=0.0), wheels, options, None)
    jac = fit_jacobian(first.intervals)
    if jac is None:
        return first
    return _matched(scans, wheels, options, jac, check=False)


#: Reasons an interval is left out that say nothing of the guess (no motion, no data).
_NOT_MATCHED = ("standing still", "gap in the scans", "no wheel data")
#: A guess whose matches lose more than this share of the moving intervals (far from the
#: guess, or not converged from it) is checked against the sweeps alone; a right guess
#: loses a few (a match slid along a wall; none on the simulated room's bags) ...
_DOUBTFUL_LOSS = 1.0 / 3.0
#: ... and given up where the sweeps' own motion per wheel rotation differs from it by
#: more than this factor, straight or turning: a wheel diameter or wheelbase in another
#: unit, a radius given for a diameter. The matches then started far from the motion
#: (ten times a leg's length, or a turn's), so most failed and the rest are biased.
_GUESS_FACTOR = 1.5


def _checked_guess(
    guessed: IntervalReport, scans: ScanSeries, wheels: WheelSeries, options: IntervalOptions
) -> IntervalReport:
    """``guessed`` (matched from ``options.guess``), or where it lost most moving intervals
    and the sweeps alone measure a motion per wheel rotation far from the guess's, the
    intervals matched from the sweeps alone, with :attr:`IntervalReport.guess_off`."""
    assert options.guess is not None
    moving = len(guessed.intervals) + sum(
        n for why, n in guessed.left_out.items() if why not in _NOT_MATCHED
    )
    lost = moving - len(guessed.intervals)
    if lost <= _DOUBTFUL_LOSS * moving:
        return guessed
    alone = match_intervals(scans, wheels, dataclasses.replace(options, guess=None))
    fitted = fit_jacobian(alone.intervals)
    if fitted is None:
        return guessed
    nominal = jacobian(options.guess)
    ratios = []
    for row, wheels_turned in ((slice(0, 2), (1.0, 1.0)), (slice(2, 3), (-1.0, 1.0))):
        turned = np.asarray(wheels_turned)
        ratios.append(
            float(np.linalg.norm(fitted[row] @ turned) / np.linalg.norm(nominal[row] @ turned))
        )
    straight, turning = ratios
    if all(1.0 / _GUESS_FACTOR <= r <= _GUESS_FACTOR for r in ratios if math.isfinite(r)):
        return guessed
    return dataclasses.replace(alone, guess_off=(straight, turning), lost=(lost, moving))


def _matched(
    scans: ScanSeries,
    wheels: WheelSeries,
    options: IntervalOptions,
    jac: FloatArray | None,
    *,
    check: bool = False,
) -> IntervalReport:
    """:func:`match_intervals` with the scanner's motion per wheel rotation ``jac`` (the
    first guesses, the motion during the sweeps) or without (no motion); ``check``: leave
    out matches far from the guess."""
    left_out: Counter[str] = Counter()
    rows: list[tuple[float, float, float, float, FloatArray, FloatArray, float]] = []
    times = scans.times
    prepared: dict[int, PreparedScan] = {}
    span = scans.time_increment * scans.beams  # how long a sweep takes [s]

    def sweep(i: int) -> PreparedScan:
        if i not in prepared:
            prepared.clear()  # only the key sweep is ever needed again
            motion = None
            if span > 0.0 and jac is not None:
                t = float(times[i])
                motion = _path_motion(*_laser_path(jac, wheels, t, t + span))
            prepared[i] = prepare(series_points(scans, i, motion))
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
        phi = np.array([np.interp([t0, t1], wheels.time, wheels.angles[:, k]) for k in (0, 1)])
        phi = phi[:, 1] - phi[:, 0]
        if np.max(np.abs(phi)) < options.min_rotation:
            left_out["standing still"] += 1
            continue
        guess = None if jac is None else _laser_path(jac, wheels, t0, t1)[1][-1]
        result = match(sweep(start), sweep(j), guess, options.settings)
        if not result.ok:
            left_out[result.status] += 1
            continue
        if check and guess is not None:
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

"""The robot's motion matched as it arrives, a chunk of :data:`CHUNK_SECONDS` at a time.

The monitor keeps the wheels' angles, the gyro's rates and the laser's sweeps (decimated:
one each ``scan_period``) only until their chunk is made; a chunk is

- the motion intervals of its sweeps against the wheels, matched by
  :func:`umbmark.scans.intervals.match_intervals` (the intervals a bag's or the anywhere
  routine's recording gives, from the same first guess: the controller's geometry and the
  laser's stated mounting), the last sweep kept as the first of the next chunk;
- the wheels and the gyro cut into rests and driving
  (:func:`umbmark.scans.gyro_intervals.gyro_intervals`), and the gyro over the matched
  intervals (:func:`umbmark.scans.gyro_intervals.gyro_reference`);
- the driving it holds (:class:`Driving`).

Intervals whose matched motion disagrees with what the present calibration predicts from
the wheels (:func:`umbmark.estimators.scan_matching.predicted_motion`) by more than
:data:`OUTLIER_SHARE` of the motion plus :data:`OUTLIER_FLOOR` are the wheels and the laser
disagreeing (pushed, lifted, slipping): left out of the chunk, their spans kept
(:attr:`Chunk.disagreed`). A change of the robot (a wheel a percent smaller) moves the
prediction by a small share of the motion only. The chunk's gyro intervals over those
spans are left out too.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.errors import InputError
from umbmark.model.gyro_series import GyroSeries
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.recording import WheelSeries
from umbmark.model.scans import ScanSeries
from umbmark.robot.base import ScanSweep
from umbmark.scans.gyro_intervals import GyroIntervals, GyroReference

__all__ = [
    "CHUNK_SECONDS",
    "OUTLIER_FLOOR",
    "OUTLIER_SHARE",
    "Chunk",
    "ChunkMaker",
    "Driving",
    "join_gyro",
    "join_reference",
]

#: A chunk's length [s] of robot time.
CHUNK_SECONDS = 10.0
#: A chunk is made once the wheels are this far [s] past its end (late sweeps and gyro).
_LAG = 0.3
#: Intervals disagreeing by more than this share of the predicted motion ...
OUTLIER_SHARE = 0.1
#: ... plus this [m, rad] are the wheels and the laser disagreeing.
OUTLIER_FLOOR = (0.02, 0.02)
#: Wheel rotation [rad] under which the robot did not move in a chunk.
_STILL = 0.01


@dataclass(frozen=True)
class Driving:
    """The driving over a span by the wheels (the controller's effective geometry).

    Attributes
    ----------
    travel : float
        The mean of both wheels' distance rolled [m] (turns on the spot included).
    metres : float
        The axle centre's distance driven [m], forward or back.
    left, right : float
        Turned counter-clockwise and clockwise [rad].
    """

    travel: float = 0.0
    metres: float = 0.0
    left: float = 0.0
    right: float = 0.0

    @classmethod
    def of(cls, angles: FloatArray, radii: tuple[float, float], separation: float) -> Driving:
        """From ``(n, 2)`` wheel angles [rad] in time order."""
        if angles.shape[0] < 2:
            return cls()
        d = np.diff(angles, axis=0) * np.asarray(radii)
        turn = (d[:, 1] - d[:, 0]) / separation
        return cls(
            float(np.sum(0.5 * (np.abs(d[:, 0]) + np.abs(d[:, 1])))),
            float(np.sum(np.abs(0.5 * (d[:, 0] + d[:, 1])))),
            float(np.sum(turn[turn > 0])),
            float(-np.sum(turn[turn < 0])),
        )

    def __add__(self, other: Driving) -> Driving:
        return Driving(
            self.travel + other.travel,
            self.metres + other.metres,
            self.left + other.left,
            self.right + other.right,
        )


@dataclass(frozen=True)
class Chunk:
    """One chunk of the robot's motion (the module's notes).

    Attributes
    ----------
    start, end : float
        Its span on the robot's clock [s].
    motion : MotionIntervals or None
        The matched intervals kept (None: no laser, or no sweeps came).
    gyro : GyroIntervals or None
        The wheels against the gyro (None: no gyro).
    reference : GyroReference or None
        The gyro over the matched intervals.
    driving : Driving
    left_out : dict of str to int
        Intervals left out, by reason (the matching's, and ``"wheels and laser
        disagree"``).
    disagreed : tuple of (float, float)
        The spans of the intervals where wheels and laser disagreed.
    """

    start: float
    end: float
    motion: MotionIntervals | None
    gyro: GyroIntervals | None
    reference: GyroReference | None
    driving: Driving
    left_out: dict[str, int] = field(default_factory=dict)
    disagreed: tuple[tuple[float, float], ...] = ()

    @property
    def disagreeing_seconds(self) -> float:
        """How long wheels and laser disagreed in it [s]."""
        return sum(b - a for a, b in self.disagreed)

    @property
    def moved(self) -> bool:
        """Whether the robot drove in it."""
        return self.driving.travel > 0.0


class ChunkMaker:
    """Collects the inputs and makes the chunks (the module's notes).

    Parameters
    ----------
    radii : (float, float)
        The controller's effective wheel radii [m].
    separation : float
        Its effective wheel separation [m].
    scan_period : float
        One sweep kept per this time [s].
    laser : bool
        Whether sweeps are expected (without, chunks are cut by the wheels' time).
    """

    def __init__(
        self, radii: tuple[float, float], separation: float, scan_period: float, laser: bool
    ) -> None:
        self.radii, self.separation = radii, separation
        self.scan_period = scan_period
        self.laser = laser
        #: The present calibration: the six parameters of
        #: :data:`umbmark.estimators.scan_matching.PARAMETERS` the outliers are judged by.
        self.params: FloatArray | None = None
        self.mount = (0.0, 0.0, 0.0)
        self.reset()
        if laser:  # the matching's KD-trees: a second or two to import, taken now rather
            # than in the first chunk, inside a node's callback (its status waiting on it)
            import scipy.spatial  # noqa: F401

    def reset(self) -> None:
        """Forget everything not yet in a chunk (the clock went back, a restart)."""
        self._wheels: list[tuple[float, float, float]] = []
        self._gyro: list[tuple[float, float]] = []
        self._sweeps: list[ScanSweep] = []
        self._start: float | None = None

    def wheels(self, time: float, left: float, right: float) -> None:
        """The wheels' angles [rad] at ``time``."""
        self._wheels.append((time, left, right))
        if self._start is None:
            self._start = time

    def gyro(self, time: float, rate: float) -> None:
        """The gyro's yaw rate [rad/s] at ``time``."""
        self._gyro.append((time, rate))

    def scan(self, sweep: ScanSweep) -> bool:
        """Keep ``sweep`` where it is a scan period after the last kept; whether kept."""
        last = self._sweeps[-1] if self._sweeps else None
        if last is not None and sweep.time - last.time < self.scan_period - 1e-6:
            return False
        if last is not None and (
            sweep.ranges.shape != last.ranges.shape or sweep.angle_min != last.angle_min
        ):
            self._sweeps = []  # the beams changed: start again from this sweep
        self._sweeps.append(sweep)
        return True

    def pending(self) -> Driving:
        """The driving since the last chunk's end, not yet in a chunk."""
        if self._start is None or len(self._wheels) < 2:
            return Driving()
        w = np.asarray(self._wheels, dtype=np.float64)
        return Driving.of(w[w[:, 0] >= self._start - 1e-9, 1:], self.radii, self.separation)

    def make(self) -> Chunk | None:
        """A chunk, where the wheels are far enough past the next one's end; else None."""
        if self._start is None or len(self._wheels) < 2:
            return None
        latest = self._wheels[-1][0]
        end = self._start + CHUNK_SECONDS
        if latest < end + _LAG:
            return None
        inside = [s for s in self._sweeps if s.time <= end]
        if self.laser and len(inside) >= 2:
            end = inside[-1].time
        chunk = self._chunk(self._start, end, inside)
        self._trim(end, inside[-1] if inside else None)
        return chunk

    def _trim(self, end: float, key: ScanSweep | None) -> None:
        """Keep what the next chunk needs: the wheels and gyro from ``end`` on (one sample
        before it), the sweeps from the key sweep on."""
        times = [w[0] for w in self._wheels]
        k = max(int(np.searchsorted(times, end, side="right")) - 1, 0)
        self._wheels = self._wheels[k:]
        self._gyro = [g for g in self._gyro if g[0] >= end - 0.05]
        self._sweeps = [s for s in self._sweeps if key is None or s.time >= key.time]
        self._start = end

    def _chunk(self, start: float, end: float, sweeps: Sequence[ScanSweep]) -> Chunk:
        w = np.asarray(self._wheels, dtype=np.float64)
        within = (w[:, 0] >= start - 1e-9) & (w[:, 0] <= end + 1e-9)
        driving = Driving.of(w[within, 1:], self.radii, self.separation)
        wheels = WheelSeries(time=w[:, 0], angles=w[:, 1:])
        left: Counter[str] = Counter()
        motion: MotionIntervals | None = None
        disagreed: tuple[tuple[float, float], ...] = ()
        if len(sweeps) >= 2 and driving.travel > 0.0:
            motion, disagreed, left = self._matched(sweeps, wheels)
        elif self.laser and driving.travel > 0.0:
            left["no sweeps"] += 1
        gyro, reference = None, None
        if len(self._gyro) >= 2 and within.sum() >= 2:
            gyro, reference = self._gyro_parts(WheelSeries(w[within, 0], w[within, 1:]),
                                               motion, disagreed, left)  # fmt: skip
        return Chunk(start, end, motion, gyro, reference, driving, dict(left), disagreed)

    def _matched(
        self, sweeps: Sequence[ScanSweep], wheels: WheelSeries
    ) -> tuple[MotionIntervals | None, tuple[tuple[float, float], ...], Counter[str]]:
        """The sweeps' intervals against the wheels, those disagreeing left out."""
        from umbmark.scans.intervals import IntervalOptions, OdometryGuess, match_intervals

        first = sweeps[0]
        scans = ScanSeries(
            times=np.array([s.time for s in sweeps], dtype=np.float64),
            ranges=np.array([s.ranges for s in sweeps], dtype=np.float64),
            angle_min=first.angle_min, angle_increment=first.angle_increment,
            range_min=first.range_min, range_max=first.range_max, frame=first.frame,
        )  # fmt: skip
        guess = OdometryGuess(self.radii[0], self.radii[1], self.separation, self.mount)
        options = IntervalOptions(
            min_interval=0.9 * self.scan_period, max_interval=2.5 * self.scan_period, guess=guess
        )
        try:
            report = match_intervals(scans, wheels, options)
        except (ValueError, InputError):
            return None, (), Counter({"not matched": len(sweeps) - 1})
        left = Counter(report.left_out)
        motion = report.intervals
        if len(motion) == 0:
            return None, (), left
        bad = self._disagreeing(motion)
        spans: tuple[tuple[float, float], ...] = ()
        if bad.any():
            assert motion.start_time is not None
            t0 = motion.start_time[bad]
            spans = tuple(zip(t0.tolist(), (t0 + motion.duration[bad]).tolist(), strict=True))
            left["wheels and laser disagree"] += int(bad.sum())
            motion = _rows(motion, ~bad)
        return (motion if len(motion) else None), spans, left

    def _disagreeing(self, motion: MotionIntervals) -> BoolArray:
        """The intervals whose matched motion is far from the present calibration's."""
        from umbmark.estimators.scan_matching import predicted_motion

        params = self.params
        if params is None:
            params = np.array([*self.radii, self.separation, *self.mount])
        predicted = predicted_motion(motion, params)
        off = motion.sensor_motion - predicted
        xy = np.hypot(off[:, 0], off[:, 1])
        yaw = np.abs(np.remainder(off[:, 2] + math.pi, math.tau) - math.pi)
        far_xy = xy > OUTLIER_FLOOR[0] + OUTLIER_SHARE * np.hypot(predicted[:, 0], predicted[:, 1])
        far_yaw = yaw > OUTLIER_FLOOR[1] + OUTLIER_SHARE * np.abs(predicted[:, 2])
        bad: BoolArray = far_xy | far_yaw
        return bad

    def _gyro_parts(
        self,
        wheels: WheelSeries,
        motion: MotionIntervals | None,
        disagreed: tuple[tuple[float, float], ...],
        left: Counter[str],
    ) -> tuple[GyroIntervals | None, GyroReference | None]:
        from umbmark.scans.gyro_intervals import gyro_intervals, gyro_reference

        g = np.asarray(self._gyro, dtype=np.float64)
        rate = np.zeros((g.shape[0], 3))
        rate[:, 2] = g[:, 1]
        series = GyroSeries(time=g[:, 0], rate=rate, source="the gyro")
        try:
            cut = gyro_intervals(wheels, series)
        except (ValueError, InputError):
            return None, None
        keep = np.ones(len(cut), dtype=bool)
        for a, b in disagreed:
            keep &= (cut.end <= a) | (cut.start >= b)
        if not keep.all():
            left["gyro while wheels and laser disagree"] += int((~keep).sum())
            cut = cut.select(keep)
        reference = None
        if motion is not None:
            try:
                reference = gyro_reference(series, motion)
            except (ValueError, InputError):
                reference = None
        return (cut if len(cut) else None), reference


def _rows(motion: MotionIntervals, rows: BoolArray) -> MotionIntervals:
    cov, start = motion.sensor_covariance, motion.start_time
    return MotionIntervals(
        duration=motion.duration[rows],
        phi_left=motion.phi_left[rows],
        phi_right=motion.phi_right[rows],
        sensor_motion=motion.sensor_motion[rows],
        sensor_covariance=None if cov is None else cov[rows],
        start_time=None if start is None else start[rows],
        source=motion.source,
    )


def _joined(parts: Sequence[Any], name: str) -> FloatArray | None:
    """The parts' optional array ``name`` one after the other; None where any lacks it."""
    arrays = [getattr(p, name) for p in parts]
    return None if any(a is None for a in arrays) else np.concatenate(arrays)


def join_gyro(parts: Sequence[GyroIntervals]) -> GyroIntervals | None:
    """The chunks' gyro intervals one after the other, every field kept (the gyro's rate
    changes among them: its delay is fitted from them); None: none."""
    if not parts:
        return None
    left: Counter[str] = Counter()
    for p in parts:
        left.update(p.left_out)
    return GyroIntervals(
        start=np.concatenate([p.start for p in parts]),
        end=np.concatenate([p.end for p in parts]),
        phi_left=np.concatenate([p.phi_left for p in parts]),
        phi_right=np.concatenate([p.phi_right for p in parts]),
        yaw=np.concatenate([p.yaw for p in parts]),
        rotation=np.concatenate([p.rotation for p in parts]),
        rest=np.concatenate([p.rest for p in parts]),
        accel=_joined(parts, "accel"),
        left_out=dict(left),
        source=parts[0].source,
        frame=parts[0].frame,
        rate_change=_joined(parts, "rate_change"),
    )


def join_reference(parts: Sequence[GyroReference]) -> GyroReference | None:
    """The chunks' gyro references one after the other, every field kept (the wheels'
    rotation over each stretch among them: the pairs of the joint fit; the gyro's rate
    changes); None: none."""
    if not parts:
        return None
    motions = [p.motion for p in parts if p.motion is not None]
    left: Counter[str] = Counter()
    for p in parts:
        left.update(p.left_out)
    return GyroReference(
        start=np.concatenate([p.start for p in parts]),
        end=np.concatenate([p.end for p in parts]),
        yaw=np.concatenate([p.yaw for p in parts]),
        variance=np.concatenate([p.variance for p in parts]),
        gyro_yaw=np.concatenate([p.gyro_yaw for p in parts]),
        motion=MotionIntervals.concatenate(motions) if len(motions) == len(parts) else None,
        left_out=dict(left),
        source=parts[0].source,
        phi_left=_joined(parts, "phi_left"),
        phi_right=_joined(parts, "phi_right"),
        rate_change=_joined(parts, "rate_change"),
    )

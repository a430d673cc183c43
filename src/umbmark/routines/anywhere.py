"""The self-calibration anywhere: a short excitation pattern, its wheels against the
laser's own motion (Censi, Franchi, Marchionni and Oriolo, IEEE T-RO 2013).

Where UMBmark needs a 4 x 4 m square of floor and an L-shaped corner, this routine
needs about 2 x 2 m of free floor around the robot and a laser that sees some structure
(walls, furniture) in more than one direction. The robot drives :data:`PATTERN` by its
odometry, with the safety stops of :mod:`umbmark.routines.drive`: turns on the spot both
ways, straights forward and back, arcs to the left and right forward and back, each
ending where it began, so the robot comes back to its start. Meanwhile it records:

- the odometry at every control period, turned back into wheel rotation with the
  parameters the controller runs with
  (:func:`umbmark.sources.bag.wheels.odometry.wheels_from_odometry`: the same inverse
  the bags with odometry and no joint states use); a robot that gives its wheels'
  angles itself (``wheel_angles()``, as the virtual robot does) is read directly;
- every new laser sweep (at most one each ``scan_period``), with its mounting from TF;
- the IMU's readings, where the robot has one (:meth:`Robot.gyro`, fetched every
  :data:`GYRO_PERIOD`), its rates in the base frame: the pattern then begins and ends
  each repetition with a rest of :data:`GYRO_REST` (:data:`GYRO_PATTERN`), over which
  the gyro reads its bias alone.

The recording is cut into motion intervals and scan matched as a bag's would be
(:func:`umbmark.scans.intervals.match_intervals`, the first guess from the nominal
geometry and the mounting), and calibrated by the scan-matching estimator
(:func:`umbmark.calibration.scan.calibrate_intervals`, through :func:`umbmark.calibrate`
on the intervals' tuple file, so that the verdict and the history are the same as for
any calibration); with the gyro, :mod:`umbmark.routines.anywhere_gyro` calibrates it
and the wheels against the laser's motion together, or, without a laser, the wheels
against the gyro alone.

Before anything moves: the robot must have a laser (:func:`check_scene`), and two
sweeps taken standing still must match as a scene with structure (no open space, no
corridor): otherwise the routine is refused with what is missing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, option
from umbmark.model.gyro_series import GyroSeries
from umbmark.model.kinematics import OdometryGeometry
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.model.scans import LaserMounting, ScanSeries
from umbmark.robot.base import (
    ApplyMethod,
    ApplyResult,
    DriveParams,
    ImuSource,
    Pose2D,
    RangeReading,
    Robot,
    ScanSweep,
    StampedPose,
)
from umbmark.routines.drive import DriveLimits, Driver
from umbmark.scans.intervals import IntervalOptions, IntervalReport, OdometryGuess, match_intervals

__all__ = [
    "GYRO_PATTERN",
    "GYRO_REST",
    "PATTERN",
    "Move",
    "PatternRecording",
    "Recorder",
    "check_scene",
    "drive_pattern",
    "first_scan",
    "intervals_note",
    "pattern_intervals",
]

#: How far from its start the pattern takes the robot's centre, at most [m].
PATTERN_REACH = 0.75
#: The shortest motion interval [s]: 1 s at 0.2 m/s or 0.8 rad/s moves the laser enough
#: that a match's error (a millimetre, a few hundredths of a degree) is small beside the
#: motion; halving it doubles the intervals and loses precision (on the virtual robot,
#: the pattern three times, 8 seeds: E_d 2.4e-4 rms at 0.5 s, 1.5e-4 at 1 s).
INTERVAL = 1.0
#: Standing still, the scene must fix the laser's motion this many times more firmly than
#: a match needs (:attr:`umbmark.scans.icp.MatchSettings.min_constraint`): an ordinary
#: room gives over 10 times, a corridor longer than the laser's range about 1 time, and
#: driving sees less than standing.
SCENE_MARGIN = 2.5


@dataclass(frozen=True)
class Move:
    """One move of the pattern.

    Attributes
    ----------
    kind : {"turn", "straight", "arc", "rest"}
    amount : float
        A turn's or an arc's change of heading [rad] (ccw positive); a straight's length
        [m] (negative: backward); a rest's duration [s].
    radius : float
        An arc's radius [m].
    backward : bool
        An arc driven backward (it undoes the forward arc of the same radius).
    """

    kind: Literal["turn", "straight", "arc", "rest"]
    amount: float
    radius: float = 0.0
    backward: bool = False

    def describe(self) -> str:
        """For progress lines: ``turn +120 deg``, ``straight -0.60 m``, ..."""
        if self.kind == "straight":
            return f"straight {self.amount:+.2f} m"
        if self.kind == "rest":
            return f"rest {self.amount:.1f} s"
        way = " backward" if self.backward else ""
        deg = math.degrees(self.amount)
        if self.kind == "turn":
            return f"turn {deg:+.0f} deg"
        return f"arc {deg:+.0f} deg, radius {self.radius:.2f} m{way}"


_THIRD = 2.0 * math.pi / 3.0
#: The excitation: a full turn each way (in thirds), straights forward and back, arcs
#: left and right forward and back (radius 0.4 m, a quarter circle); everything ends
#: where it began. Within :data:`PATTERN_REACH` of the start.
PATTERN: tuple[Move, ...] = (
    *(Move("turn", _THIRD) for _ in range(3)),
    *(Move("turn", -_THIRD) for _ in range(3)),
    Move("straight", 0.6),
    Move("straight", -0.6),
    Move("arc", 0.5 * math.pi, 0.4),
    Move("arc", -0.5 * math.pi, 0.4, backward=True),
    Move("arc", -0.5 * math.pi, 0.4),
    Move("arc", 0.5 * math.pi, 0.4, backward=True),
    Move("turn", 0.5 * math.pi),
    Move("straight", 0.5),
    Move("straight", -0.5),
    Move("turn", -0.5 * math.pi),
)


#: With a gyro: a rest this long [s] begins and ends each repetition of the pattern (the
#: odometry settled first): 2 s less the gyro intervals' margins, 1.6 s of its bias alone.
GYRO_REST = 2.0
#: The pattern a robot with a gyro drives: :data:`PATTERN` between rests.
GYRO_PATTERN: tuple[Move, ...] = (Move("rest", GYRO_REST), *PATTERN)
#: The IMU's readings are fetched from the robot this often [s] of its time (it holds
#: :data:`umbmark.robot.base.IMU_HELD`).
GYRO_PERIOD = 0.5


def _expected_time(moves: tuple[Move, ...], limits: DriveLimits) -> float:
    """The pattern's driving time without stops [s] (ramps counted once per move)."""
    total = 0.0
    for m in moves:
        if m.kind == "rest":
            total += m.amount + limits.settle_time
        elif m.kind == "turn":
            total += abs(m.amount) / limits.turn_rate + limits.turn_rate / limits.turn_acceleration
        else:
            length = abs(m.amount) * (m.radius if m.kind == "arc" else 1.0)
            speed = (
                limits.speed
                if m.kind == "straight"
                else min(limits.speed, limits.turn_rate * m.radius)
            )
            total += length / speed + speed / limits.acceleration
    return total


class Recorder:
    """A :class:`~umbmark.robot.base.Robot` that records what it passes on: after every
    :meth:`wait`, the odometry (each new reading), the wheels' angles where the robot
    gives them, the latest laser sweep (a new one at most each ``scan_period`` [s]), and
    the IMU's readings where it has one (fetched each :data:`GYRO_PERIOD`)."""

    def __init__(self, robot: Robot, scan_period: float = 0.1) -> None:
        self.robot = robot
        self.name = robot.name
        self.scan_period = scan_period
        self.odometry_samples: list[tuple[float, float, float, float]] = []
        self.wheel_samples: list[tuple[float, float, float]] = []
        self.scans: list[ScanSweep] = []
        self.gyro_parts: list[GyroSeries] = []
        self._angles: Callable[[], tuple[float, float, float] | None] | None = getattr(
            robot, "wheel_angles", None
        )
        self._imu = robot.imu()
        self._gyro_asked = -math.inf
        self._gyro_since = robot.now() if self._imu is not None else math.inf

    def gyro_series(self) -> GyroSeries | None:
        """The IMU's readings recorded (None: the robot has no IMU, or none came)."""
        if self._imu is None:
            return None
        self._fetch_gyro()
        parts = [p for p in self.gyro_parts if len(p)]
        if not parts:
            return None
        accel = [p.accel for p in parts]
        return GyroSeries(
            time=np.concatenate([p.time for p in parts]),
            rate=np.concatenate([p.rate for p in parts]),
            accel=None if any(a is None for a in accel) else np.concatenate(accel),  # type: ignore[arg-type]
            frame=parts[0].frame,
            source=f"{self.name}'s IMU on {self._imu.topic}",
        )

    def _fetch_gyro(self) -> None:
        new = self.robot.gyro(self._gyro_since)
        self._gyro_asked = self.robot.now()
        if new is not None and len(new):
            self.gyro_parts.append(new)
            self._gyro_since = float(new.time[-1])

    def sample(self) -> None:
        """Record what is new."""
        odom = self.robot.odometry()
        if odom is not None and (
            not self.odometry_samples or odom.time > self.odometry_samples[-1][0]
        ):
            p = odom.pose
            self.odometry_samples.append((odom.time, p.x, p.y, p.theta))
        if self._angles is not None:
            angles = self._angles()
            if angles is not None and (
                not self.wheel_samples or angles[0] > self.wheel_samples[-1][0]
            ):
                self.wheel_samples.append(angles)
        if self._imu is not None and self.robot.now() - self._gyro_asked >= GYRO_PERIOD:
            self._fetch_gyro()
        last = self.scans[-1].time if self.scans else -math.inf
        if self.robot.now() - last >= self.scan_period - 1e-9:
            scan = self.robot.scan()
            if scan is not None and scan.time > last:
                self.scans.append(scan)

    # --- the Robot interface, passed on -------------------------------------------------

    def now(self) -> float:
        return self.robot.now()

    def wait(self, duration: float) -> None:
        self.robot.wait(duration)
        self.sample()

    def send_velocity(self, linear: float, angular: float) -> None:
        self.robot.send_velocity(linear, angular)

    def odometry(self) -> StampedPose | None:
        return self.robot.odometry()

    def scan(self) -> ScanSweep | None:
        return self.robot.scan()

    def ranges(self) -> RangeReading | None:
        return self.robot.ranges()

    def ground_truth(self) -> StampedPose | None:
        return self.robot.ground_truth()

    def imu(self) -> ImuSource | None:
        return self._imu

    def gyro(self, since: float) -> GyroSeries | None:
        return self.robot.gyro(since)

    def drive_params(self) -> DriveParams:
        return self.robot.drive_params()

    def apply(self, params: DriveParams, method: ApplyMethod) -> ApplyResult:
        return self.robot.apply(params, method)

    def close(self) -> None:
        self.robot.close()


@dataclass(frozen=True)
class PatternRecording:
    """What one drive of the pattern recorded.

    Attributes
    ----------
    scans : ScanSeries or None
        The laser's sweeps (None: the robot has no laser).
    wheels : WheelSeries
        The wheels' cumulative rotation [rad] on the robot's clock.
    params : DriveParams
        The parameters the controller ran with.
    mount : Pose2D
        The laser's mounting as the robot states it (TF): the matching's first guess.
    start, end : Stamped
        The settled odometry before and after.
    stated : LaserMounting or None
        The stated mounting with its height, tilt and frames, for the report.
    gyro : GyroSeries or None
        The IMU's readings, rates in the base frame (None: the robot has no IMU, or they
        cannot be used: ``gyro_trouble``).
    imu : ImuSource or None
        The IMU they came from, with its frame's mounting.
    gyro_trouble : str or None
        Why the IMU's readings are left out (:func:`umbmark.routines.gyro_watch.gyro_trouble`:
        it fell silent or froze while the robot drove); None: they are used, or no IMU.
    """

    scans: ScanSeries | None
    wheels: WheelSeries
    params: DriveParams
    mount: Pose2D
    start: StampedPose
    end: StampedPose
    stated: LaserMounting | None = None
    gyro: GyroSeries | None = None
    imu: ImuSource | None = None
    gyro_trouble: str | None = None


def first_scan(robot: Robot, limits: DriveLimits | None = None) -> ScanSweep | None:
    """The robot's laser sweep now, or after ``stale_scan`` (None: it has no laser)."""
    limits = limits or DriveLimits()
    first = robot.scan()
    if first is None:
        robot.wait(limits.stale_scan)
        first = robot.scan()
    return first


def check_scene(
    robot: Robot, limits: DriveLimits | None = None, first: ScanSweep | None = None
) -> ScanSweep:
    """Refuse, before anything moves, a robot without a laser, a scene where two sweeps
    taken standing still do not match as a scene with structure (open space, a corridor:
    the routine needs walls or furniture in view in more than one direction), or
    something on the pattern's floor. The first sweep (``first``: the one
    :func:`first_scan` took)."""
    from umbmark.scans.icp import DEFAULT_SETTINGS, match
    from umbmark.scans.points import prepare, series_points

    limits = limits or DriveLimits()
    first = first or first_scan(robot, limits)
    if first is None:
        raise InputError(
            "the robot has no laser scan and no IMU: the anywhere routine matches the "
            "laser's sweeps, or turns against the gyro (give the scan topic or the IMU's, "
            f"or use {option('routine', 'umbmark')} with a corner)"
        )
    robot.wait(limits.stale_scan / 2)
    second = robot.scan() or first
    series = _series([first, second] if second.time > first.time else [first, first])
    a = prepare(series_points(series, 0, None))
    b = prepare(series_points(series, len(series) - 1, None))
    result = match(a, b, None)
    status = result.status
    if result.ok and result.constraint < SCENE_MARGIN * DEFAULT_SETTINGS.min_constraint:
        status = "corridor"  # barely fixed standing still: not while driving
    if status != "ok":
        what = {
            "open space": "the laser sees too little structure around the robot (open "
            "space: too few returns on walls or furniture)",
            "corridor": "the laser sees walls in one direction only (a corridor): motion "
            "along them cannot be measured",
        }.get(status, f"two sweeps taken standing still do not match ({status})")
        raise InputError(
            f"{what}; the anywhere routine needs walls or furniture in view in more than "
            "one direction within the laser's range: move the robot, or use "
            f"{option('routine', 'umbmark')} with a corner"
        )
    _free_floor(first, limits)
    return first


def _free_floor(scan: ScanSweep, limits: DriveLimits) -> None:
    """Refuse a return of the laser on the pattern's floor: within :data:`PATTERN_REACH`
    plus the reach of the robot's footprint (:attr:`clearance.Footprint.reach`: the disc
    it sweeps turning) of its centre; the watch then looks at the band of each move."""
    ranges = np.asarray(scan.ranges, dtype=np.float64)
    ok = np.isfinite(ranges) & (ranges >= scan.range_min) & (ranges <= scan.range_max)
    angles = scan.angles()[ok] + scan.mount.theta
    x = scan.mount.x + ranges[ok] * np.cos(angles)
    y = scan.mount.y + ranges[ok] * np.sin(angles)
    reach = PATTERN_REACH + limits.outline.reach
    near = np.hypot(x, y) < reach
    if near.any():
        k = int(np.argmin(np.hypot(x[near], y[near])))
        raise InputError(
            f"something stands within the pattern's floor at x = {float(x[near][k]):.2f} m, "
            f"y = {float(y[near][k]):.2f} m of the robot ({int(near.sum())} laser returns "
            f"within {reach:.2f} m of its centre): clear the floor, or place the robot where "
            f"{2 * reach:.1f} x {2 * reach:.1f} m around it are free"
        )


def _series(scans: list[ScanSweep], source: str = "") -> ScanSeries:
    """Sweeps of one laser as a :class:`ScanSeries` (the same beams and mounting; a
    repeated stamp is dropped)."""
    first = scans[0]
    times: list[float] = []
    ranges: list[np.ndarray] = []
    for s in scans:
        if s.ranges.shape != first.ranges.shape or s.angle_min != first.angle_min:
            raise InputError("the laser's sweeps changed their beams during the routine")
        if times and s.time <= times[-1]:
            continue
        times.append(s.time)
        ranges.append(s.ranges)
    return ScanSeries(
        times=np.asarray(times, dtype=np.float64),
        ranges=np.asarray(ranges, dtype=np.float64).reshape(len(times), -1),
        angle_min=first.angle_min,
        angle_increment=first.angle_increment,
        range_min=first.range_min,
        range_max=first.range_max,
        source=source,
    )


def drive_pattern(
    robot: Robot,
    limits: DriveLimits | None = None,
    progress: Callable[[int, str], None] | None = None,
    moves: tuple[Move, ...] = PATTERN,
    *,
    laser: bool = True,
) -> PatternRecording:
    """Drive ``moves`` by the odometry from where the robot stands (the safety stops of
    :mod:`umbmark.routines.drive`: stale odometry or scans, obstacles in the direction of
    travel, the odometry farther than :data:`PATTERN_REACH` plus ``margin`` from the
    start, more than ``time_factor`` times the expected time), recording the wheels, the
    sweeps (``laser``: the robot has one) and the IMU's readings (where the robot has
    one). ``progress``: called with the move's number (from 1) and its text.

    Raises
    ------
    SafetyError
        After a zero velocity.
    InputError
        The odometry cannot be turned back into wheel rotation, or too few sweeps came.
    """
    limits = limits or DriveLimits()
    recorder = Recorder(robot)
    driver = Driver(recorder, 0.0, Direction.CCW, limits)
    params = robot.drive_params()
    try:
        driver.radius = math.inf
        start = driver.settle()
        driver.origin = start.pose
        driver.radius = PATTERN_REACH + limits.margin
        driver.deadline = robot.now() + limits.time_factor * _expected_time(moves, limits) + 30.0
        for k, move in enumerate(moves, 1):
            if progress is not None:
                progress(k, move.describe())
            here = driver.read()
            if move.kind == "rest":
                driver.settle()
                for _ in range(max(1, round(move.amount / limits.period))):
                    driver.command(0.0, 0.0)
            elif move.kind == "turn":
                driver.turn(here.theta + move.amount)
            elif move.kind == "straight":
                driver.leg(here, abs(move.amount), backward=move.amount < 0)
            else:
                driver.arc(here.theta + move.amount, move.radius, backward=move.backward)
        driver.deadline = math.inf
        end = driver.settle()
    except BaseException:
        robot.send_velocity(0.0, 0.0)
        raise
    return _recording(recorder, params, start, end, laser)


def _recording(
    recorder: Recorder, params: DriveParams, start: StampedPose, end: StampedPose, laser: bool
) -> PatternRecording:
    """The recorder's samples as scans, wheels and the gyro."""
    if laser and len(recorder.scans) < 10:
        raise InputError(
            f"only {len(recorder.scans)} laser sweeps came while driving the pattern: is the "
            "laser publishing?"
        )
    name = recorder.name
    if len(recorder.wheel_samples) >= 2:
        w = np.asarray(recorder.wheel_samples, dtype=np.float64)
        wheels = WheelSeries(time=w[:, 0], angles=w[:, 1:])
    else:
        from umbmark.sources.bag.wheels.odometry import wheels_from_odometry

        o = np.asarray(recorder.odometry_samples, dtype=np.float64).reshape(-1, 4)
        geometry = OdometryGeometry(
            params.wheel_radius * params.left_wheel_radius_multiplier,
            params.wheel_radius * params.right_wheel_radius_multiplier,
            params.wheelbase,
        )
        series = PoseSeries(time=o[:, 0], poses=o[:, 1:])
        wheels = wheels_from_odometry(series, geometry, "the odometry", name).wheels
    gyro, imu, trouble = recorder.gyro_series(), recorder.imu(), None
    if imu is not None:
        from umbmark.routines.gyro_watch import gyro_trouble

        trouble = gyro_trouble(gyro, float(wheels.time[0]), float(wheels.time[-1]), imu.topic)
        gyro = None if trouble is not None else gyro
    if not laser:
        return PatternRecording(None, wheels, params, Pose2D(), start, end, None, gyro, imu,
                                trouble)  # fmt: skip
    first = recorder.scans[0]
    stated = LaserMounting(
        first.mount.x, first.mount.y, first.mount.theta, first.lift,
        first.base or "base_link", first.frame or "laser",
    )  # fmt: skip
    return PatternRecording(
        scans=_series(recorder.scans, f"{name}'s laser"),
        wheels=wheels,
        params=params,
        mount=first.mount,
        start=start,
        end=end,
        stated=stated,
        gyro=gyro,
        imu=imu,
        gyro_trouble=trouble,
    )


def pattern_intervals(recording: PatternRecording) -> IntervalReport:
    """The recording's motion intervals, scan matched from the nominal geometry and the
    stated mounting (:func:`umbmark.scans.intervals.match_intervals`).

    Raises
    ------
    InputError
        No interval could be matched: what the scene lacks (open space, a corridor).
    """
    if recording.scans is None:
        raise InputError("the robot has no laser: no motion intervals can be scan matched")
    p = recording.params
    m = recording.mount
    guess = OdometryGuess(
        p.wheel_radius * p.left_wheel_radius_multiplier,
        p.wheel_radius * p.right_wheel_radius_multiplier,
        p.wheelbase,
        laser_pose=(m.x, m.y, m.theta),
    )
    options = IntervalOptions(min_interval=INTERVAL, max_interval=2.0 * INTERVAL, guess=guess)
    report = match_intervals(recording.scans, recording.wheels, options)
    if len(report.intervals) < 6:
        left = ", ".join(f"{n} {why}" for why, n in sorted(report.left_out.items())) or "none"
        raise InputError(
            f"only {len(report.intervals)} of {report.tried} motion intervals could be "
            f"scan matched (left out: {left}): the laser needs walls or furniture in view "
            "in more than one direction while the robot drives"
        )
    return report


def intervals_note(report: IntervalReport) -> str:
    """One line: the intervals matched, and those left out by reason."""
    left = ", ".join(f"{n} {why}" for why, n in sorted(report.left_out.items()))
    return f"{len(report.intervals)} motion intervals matched of {report.tried}" + (
        f" (left out: {left})" if left else ""
    )

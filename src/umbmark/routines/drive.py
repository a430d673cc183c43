"""Driving one UMBmark run by the robot's own odometry, safely.

A run (Sec. 5 of the paper) is four straight legs of length ``L``, each followed by an
on-the-spot turn of 90 degrees (left for ccw, right for cw; the fourth turn at the end),
all steered by the odometry: the robot believes it drove a perfect square, and its true
return error is what UMBmark measures. So the odometry's own end pose must match the
commanded one closely (:data:`DriveLimits.end_position`, :data:`DriveLimits.end_heading`).

- **Legs** are closed-loop on the odometry: the speed ramps up and down within the
  acceleration limit (``v <= sqrt(2 a d)`` on the way to the corner, a creep speed at the
  last millimetres), the heading is held on the leg's direction and the robot steered back
  onto the line (a heading term and a cross-track term), and the leg ends when the
  odometry reaches the corner.
- **Turns** are on the spot, ramped the same way in angle, to the odometry's heading
  within :data:`DriveLimits.heading_tolerance`.
- Between segments the robot stops completely; after the run it settles (the odometry
  still for :data:`DriveLimits.settle_time`) before anything is measured.

Safety comes first: a zero velocity is sent on any error or interruption and before any
:class:`SafetyError` propagates: odometry older than ``stale_odometry``, a scan older than
``stale_scan``, an obstacle on the robot's path (the band its footprint sweeps,
:mod:`umbmark.routines.clearance`) nearer than the stop distance at the speed driven
(:meth:`DriveLimits.stop_distance`) and than the end of the leg plus the margin, the
odometry jumping (a controller restarted under it), the robot's clock going back or
jumping forward (``clock_jump``), the odometry leaving the square plus ``margin``, or a
run taking more than ``time_factor`` times its expected time. Knows nothing of ROS: it
drives a :class:`~umbmark.robot.base.Robot`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from umbmark.core.bounds import check_range
from umbmark.core.conventions import Direction, wrap_angle
from umbmark.core.errors import SafetyError, option
from umbmark.options.selfcal import OBSTACLE_MARGIN_RANGE, STOP_LATENCY
from umbmark.robot.base import Pose2D, Robot, StampedPose
from umbmark.routines.clearance import Footprint, arc_band, scan_points, straight_band

__all__ = [
    "DriveLimits",
    "DrivenRun",
    "Driver",
    "SafetyError",
    "drive_square",
    "move_to",
    "settle",
    "stop_safely",
]


@dataclass(frozen=True)
class DriveLimits:
    """How the square is driven, and the safety limits (SI units).

    Attributes
    ----------
    speed, acceleration : float
        Cruise speed on the legs [m/s] (the paper: 0.2) and its acceleration limit [m/s^2].
    turn_rate, turn_acceleration : float
        Top turn rate on the spot [rad/s] and its acceleration limit [rad/s^2].
    creep_speed, creep_rate : float
        The slowest speed [m/s] and turn rate [rad/s] when closing in.
    period : float
        Control period [s].
    heading_gain, cross_track_gain : float
        Line following on the legs: turn rate per heading error [1/s] and per metre of
        cross-track error [1/(m s)].
    position_tolerance, heading_tolerance : float
        A leg ends within this of its corner along the leg [m]; a turn within this of its
        heading [rad].
    end_position, end_heading : float
        The odometry's end pose must be this close to the commanded one [m, rad].
    settle_time, still_speed : float
        The robot has settled when the odometry moved less than ``still_speed`` [m/s, and
        rad/s] for ``settle_time`` [s]; odometry still moving ``settle_limit`` [s] after
        the stop stops the routine.
    stale_odometry : float
        Odometry older than this [s] stops the robot.
    stale_scan : float
        A laser whose latest scan is older than this [s] stops the robot on the legs.
    odometry_jump : float
        The odometry moving between two readings by more than this [m] beyond what the
        speed allows (or by more than ten times this in radians beyond the turn rate)
        stops the robot: a controller restarted under it (its odometry reset).
    obstacle_margin, stop_latency : float
        A scan return in the band the footprint sweeps on the rest of the leg (or arc)
        nearer than the stop distance at the speed ``v`` driven (:meth:`stop_distance`:
        ``v^2 / (2 acceleration) + v stop_latency + obstacle_margin``) and than the
        leg's remaining length plus ``obstacle_margin`` stops the robot.
        ``obstacle_margin`` [m] is what is left between the robot's centre and the
        obstacle once stopped; ``stop_latency`` [s] covers the look-ahead period, the
        scan's age and the zero velocity's way to the wheels.
    obstacle_period : float
        The scan ahead is looked at this often [s] on the legs.
    clock_jump : float
        The robot's clock (sim time where ``/clock`` runs) going backwards, or forward by
        more than this [s] between two control steps, stops the robot (a restarted or
        stalled simulation, a clock stepped under a running robot).
    footprint : Footprint, optional
        The robot's outline: the band it sweeps is what the watch looks at
        (:mod:`umbmark.routines.clearance`) [default: :meth:`outline`'s 0.4 m square;
        :func:`umbmark.selfcal` puts the robot's own there, ``robot_width`` else its
        description: :meth:`umbmark.routines.setup.SelfcalSetup.drive_limits`].
    closing_time : float
        Closing in, the speed (turn rate) is at most the remaining distance (angle) over
        this [s]: an approach with this time constant, which a command arriving a few
        periods late (a ROS robot's controller) follows without overshooting; at most
        one period is a dead-beat approach, which such a robot overshoots back and forth.
    margin : float
        The odometry leaving the square by more than this [m] stops the robot.
    time_factor : float
        A run taking more than this times its expected time stops the robot.
    """

    speed: float = 0.2
    acceleration: float = 0.3
    turn_rate: float = 0.8
    turn_acceleration: float = 1.5
    creep_speed: float = 0.01
    creep_rate: float = 0.03
    period: float = 0.02
    heading_gain: float = 3.0
    cross_track_gain: float = 6.0
    position_tolerance: float = 0.0005
    heading_tolerance: float = math.radians(0.02)
    end_position: float = 0.005
    end_heading: float = math.radians(0.1)
    settle_time: float = 0.5
    settle_limit: float = 30.0
    still_speed: float = 0.002
    stale_odometry: float = 0.5
    stale_scan: float = 1.0
    odometry_jump: float = 0.05
    obstacle_margin: float = 0.3
    stop_latency: float = STOP_LATENCY
    obstacle_period: float = 0.25
    clock_jump: float = 5.0
    margin: float = 0.5
    time_factor: float = 2.0
    closing_time: float = 0.2
    footprint: Footprint | None = None

    def __post_init__(self) -> None:
        bounds = {
            "speed": (0.01, 1.0),
            "acceleration": (0.01, 5.0),
            "turn_rate": (0.05, 3.0),
            "turn_acceleration": (0.05, 20.0),
            "period": (0.001, 0.2),
            "margin": (0.05, 5.0),
            "time_factor": (1.2, 10.0),
            "settle_limit": (1.0, 600.0),
            "closing_time": (0.001, 2.0),
            "obstacle_margin": OBSTACLE_MARGIN_RANGE,
            "stop_latency": (0.0, 2.0),
            "clock_jump": (0.05, 60.0),
        }
        for name, (low, high) in bounds.items():
            check_range(option(name), getattr(self, name), (low, high))

    @property
    def outline(self) -> Footprint:
        """The footprint the watch and the checks before moving keep clear: ``footprint``,
        else the default :class:`~umbmark.routines.clearance.Footprint`."""
        return Footprint() if self.footprint is None else self.footprint

    def stop_distance(self, speed: float) -> float:
        """How near [m] an obstacle ahead may come at ``speed`` [m/s] before the robot is
        stopped: the braking distance at the acceleration limit, the way driven during
        the latency, and the margin: ``v^2 / (2 a) + v t_latency + margin``."""
        v = abs(speed)
        return v * v / (2.0 * self.acceleration) + v * self.stop_latency + self.obstacle_margin

    def expected_time(self, side: float) -> float:
        """A run's time without stops or settling [s]: four legs and four turns, each an
        acceleration-limited ramp up, cruise and ramp down."""

        def ramp(distance: float, top: float, acceleration: float) -> float:
            reach = top * top / acceleration  # the distance of ramping up and down
            if distance <= reach:
                return 2.0 * math.sqrt(distance / acceleration)
            return 2.0 * top / acceleration + (distance - reach) / top

        leg = ramp(side, self.speed, self.acceleration)
        turn = ramp(0.5 * math.pi, self.turn_rate, self.turn_acceleration)
        return 4.0 * (leg + turn)


@dataclass(frozen=True)
class DrivenRun:
    """What one run drove, by the odometry.

    Attributes
    ----------
    direction : Direction
    start, end : Stamped
        The odometry's settled pose before and after the run (frame ``odom``).
    commanded_end : Pose2D
        Where the odometry was told to end (the start pose).
    odometry : array, shape (n, 4)
        ``t, x, y, theta`` of every odometry reading during the run.
    """

    direction: Direction
    start: StampedPose
    end: StampedPose
    commanded_end: Pose2D
    odometry: np.ndarray

    @property
    def end_error(self) -> tuple[float, float]:
        """How far the odometry's end is from the commanded end: distance [m], heading
        [rad]."""
        rel = self.end.pose.relative_to(self.commanded_end)
        return math.hypot(rel.x, rel.y), abs(float(wrap_angle(rel.theta)))


#: What the driver reports while it drives: (leg or turn number 1-8, text).
Progress = Callable[[int, str], None]


def stop_safely(robot: Robot, reason: str) -> SafetyError:
    """Send a zero velocity and return the :class:`SafetyError` to raise."""
    robot.send_velocity(0.0, 0.0)
    return SafetyError(reason)


class _Driver:
    """The control loop of one run (state kept between segments)."""

    def __init__(
        self, robot: Robot, side: float, direction: Direction, limits: DriveLimits
    ) -> None:
        self.robot, self.side, self.direction, self.limits = robot, side, direction, limits
        self.samples: list[tuple[float, float, float, float]] = []
        self.linear = 0.0
        self.angular = 0.0
        self.deadline = math.inf
        self.origin = Pose2D()
        #: For moves other than the square: how far from ``origin`` the odometry may go.
        self.radius: float | None = None
        self.clock: float | None = None  # the robot's clock at the last reading

    # --- reading, with the safety checks ------------------------------------------------

    def read(self) -> Pose2D:
        """The odometry now, checked: fresh, inside the square plus the margin."""
        odom = self.robot.odometry()
        now = self.robot.now()
        limits = self.limits
        self._check_clock(now)
        if odom is None or now - odom.time > limits.stale_odometry:
            age = "none" if odom is None else f"{now - odom.time:.2f} s old"
            raise stop_safely(
                self.robot, f"odometry stale ({age}, limit {limits.stale_odometry:g} s)"
            )
        if now > self.deadline:
            raise stop_safely(
                self.robot,
                f"the run takes more than {limits.time_factor:g} times its expected time",
            )
        pose = odom.pose
        if self.samples and self.radius != math.inf:  # settling: an apply may make it jump
            self._check_jump(self.samples[-1], odom.time, pose)
        self.samples.append((odom.time, pose.x, pose.y, pose.theta))
        local = pose.relative_to(self.origin)
        sign = self.direction.turn_sign
        m = limits.margin
        if self.radius is not None:
            inside = math.hypot(local.x, local.y) <= self.radius
        else:
            inside = -m <= local.x <= self.side + m and -m <= sign * local.y <= self.side + m
        if not inside:
            raise stop_safely(
                self.robot,
                f"the odometry left the {'square' if self.radius is None else 'move'} by "
                f"more than {m:g} m (at x = {local.x:.3f} m, y = {local.y:.3f} m of its frame)",
            )
        return pose

    def _check_clock(self, now: float) -> None:
        """Stop when the robot's clock went backwards, or forward by more than the bound,
        since the last reading (one control step)."""
        last, self.clock = self.clock, now
        if last is None:
            return
        if now < last:
            raise stop_safely(
                self.robot,
                f"the robot's clock went back {last - now:.3f} s (from {last:.3f} to "
                f"{now:.3f} s): was the simulation restarted?",
            )
        if now - last > self.limits.clock_jump:
            raise stop_safely(
                self.robot,
                f"the robot's clock jumped {now - last:.2f} s forward in one control step "
                f"(limit {self.limits.clock_jump:g} s): a clock stepped under the robot, or "
                "a simulation or control loop that stalled",
            )

    def _check_jump(
        self, last: tuple[float, float, float, float], time: float, pose: Pose2D
    ) -> None:
        """Stop when the odometry moved farther than the robot can since ``last``."""
        limits = self.limits
        dt = max(time - last[0], limits.period)
        step = math.hypot(pose.x - last[1], pose.y - last[2])
        turn = abs(float(wrap_angle(pose.theta - last[3])))
        if (
            step > 2.0 * limits.speed * dt + limits.odometry_jump
            or turn > 2.0 * limits.turn_rate * dt + 10.0 * limits.odometry_jump
        ):
            raise stop_safely(
                self.robot,
                f"the odometry jumped {step:.3f} m and {math.degrees(turn):.1f} deg in "
                f"{dt:.2f} s: was the controller restarted (its odometry reset)?",
            )

    def check_ahead(
        self,
        remaining: float,
        backward: bool = False,
        heading: float = 0.0,
        radius: float | None = None,
        left: bool = True,
    ) -> None:
        """Stop for a scan return in the band the robot sweeps (:mod:`clearance`) on the
        rest of its leg (straight at ``heading`` [rad, base frame], or on an arc of
        ``radius`` [m] whose centre is on the ``left``), driving ``backward`` or not, and
        for a laser gone silent. A return in the band stops the robot when nearer than
        the stop distance at the speed driven and than ``remaining`` [m] plus the
        margin: one beyond where the robot stops anyway does not."""
        scan = self.robot.scan()
        if scan is None:
            return
        age = self.robot.now() - scan.time
        if age > self.limits.stale_scan:
            raise stop_safely(
                self.robot,
                f"scan stale ({age:.2f} s old, limit {self.limits.stale_scan:g} s): the laser "
                "went silent, and nothing watches for obstacles",
            )
        points = scan_points(scan)
        half = self.limits.outline.half_width
        if radius is None:
            distance = straight_band(points, half, heading, backward)
        else:
            if backward:
                points = points * np.array([-1.0, 1.0])
            distance = arc_band(points, half, radius, left)
        limit = min(self.limits.stop_distance(self.linear), remaining + self.limits.obstacle_margin)
        if distance < limit:
            where = "behind" if backward else "ahead"
            raise stop_safely(
                self.robot,
                f"an obstacle {distance:.2f} m {where} on the robot's path (stop distance "
                f"{limit:.2f} m at {abs(self.linear):.2f} m/s)",
            )

    def command(self, linear: float, angular: float) -> None:
        self.linear, self.angular = linear, angular
        self.robot.send_velocity(linear, angular)
        self.robot.wait(self.limits.period)

    # --- segments -----------------------------------------------------------------------

    def leg(self, start: Pose2D, length: float | None = None, backward: bool = False) -> None:
        """Drive ``length`` [default: the side] metres along ``start``'s heading (or
        ``backward``, against it), on the line, and stop."""
        length = self.side if length is None else length
        lim, dt = self.limits, self.limits.period
        sign = -1.0 if backward else 1.0
        cos_h, sin_h = math.cos(start.theta), math.sin(start.theta)
        scan_every = max(1, round(lim.obstacle_period / dt))
        k = 0
        while True:
            pose = self.read()
            dx, dy = pose.x - start.x, pose.y - start.y
            along = sign * (dx * cos_h + dy * sin_h)
            cross = -dx * sin_h + dy * cos_h
            remaining = length - along
            if remaining <= lim.position_tolerance:
                break
            if k % scan_every == 0:
                self.check_ahead(remaining, backward, float(wrap_angle(start.theta - pose.theta)))
            k += 1
            brake = math.sqrt(2.0 * lim.acceleration * remaining)
            close = remaining / max(dt, lim.closing_time)
            goal = min(lim.speed, brake, close)
            goal = max(goal, min(lim.creep_speed, close))
            step = lim.acceleration * dt
            current = abs(self.linear)  # the speed, forward or backward
            linear = min(max(goal, current - step), current + step)
            heading_error = float(wrap_angle(start.theta - pose.theta))
            angular = lim.heading_gain * heading_error - sign * lim.cross_track_gain * cross
            angular = min(max(angular, -lim.turn_rate), lim.turn_rate)
            self.command(sign * linear, angular)
        self.command(0.0, 0.0)

    def arc(self, heading: float, radius: float, backward: bool = False) -> None:
        """Drive forward (or ``backward``) on a circle of ``radius`` [m] until the odometry
        heading is ``heading`` (its sign of turn: towards it), and stop."""
        lim, dt = self.limits, self.limits.period
        sign = -1.0 if backward else 1.0
        scan_every = max(1, round(lim.obstacle_period / dt))
        k = 0
        while True:
            error = float(wrap_angle(heading - self.read().theta))
            remaining = abs(error) * radius  # along the arc [m]
            if abs(error) <= lim.heading_tolerance:
                break
            if k % scan_every == 0:
                # the centre: left when the heading turns left driving forward
                self.check_ahead(remaining, backward, radius=radius, left=(error > 0) != backward)
            k += 1
            brake = math.sqrt(2.0 * lim.acceleration * remaining)
            close = remaining / max(dt, lim.closing_time)
            goal = min(lim.speed, lim.turn_rate * radius, brake, close)
            goal = max(goal, min(lim.creep_speed, close))
            step = lim.acceleration * dt
            speed = min(max(goal, abs(self.linear) - step), abs(self.linear) + step)
            self.command(sign * speed, math.copysign(speed / radius, error))
        self.command(0.0, 0.0)

    def turn(self, heading: float) -> None:
        """Turn on the spot to the odometry heading ``heading`` and stop."""
        lim, dt = self.limits, self.limits.period
        while True:
            pose = self.read()
            error = float(wrap_angle(heading - pose.theta))
            if abs(error) <= lim.heading_tolerance:
                break
            brake = math.sqrt(2.0 * lim.turn_acceleration * abs(error))
            close = abs(error) / max(dt, lim.closing_time)
            goal = min(lim.turn_rate, brake, close)
            goal = max(goal, min(lim.creep_rate, close))
            step = lim.turn_acceleration * dt
            rate = abs(self.angular) if self.angular * error > 0 else 0.0
            rate = min(max(goal, rate - step), rate + step)
            self.command(0.0, math.copysign(rate, error))
        self.command(0.0, 0.0)

    def settle(self) -> StampedPose:
        """Wait until the odometry has been still for ``settle_time`` and for half the
        readings that takes (a loop stalled on a busy machine reads too few to show the
        stand the run log needs); the settled pose."""
        lim = self.limits
        self.robot.send_velocity(0.0, 0.0)
        still_since = begun = self.robot.now()
        last = self.read()
        last_time = self.robot.now()
        reads, needed = 0, max(2, round(0.5 * lim.settle_time / lim.period))
        while self.robot.now() - still_since < lim.settle_time or reads < needed:
            if self.robot.now() - begun > lim.settle_limit:
                raise stop_safely(
                    self.robot,
                    f"the odometry does not come to rest: it still moves {lim.settle_limit:g} s "
                    "after the robot was told to stop (a wheel slipping, or the controller "
                    "not taking commands)",
                )
            self.robot.send_velocity(0.0, 0.0)
            self.robot.wait(lim.period)
            pose = self.read()
            now = self.robot.now()
            moved = math.hypot(pose.x - last.x, pose.y - last.y)
            turned = abs(float(wrap_angle(pose.theta - last.theta)))
            span = max(now - last_time, 1e-9)
            reads += 1
            if moved / span > lim.still_speed or turned / span > lim.still_speed:
                still_since, reads = now, 0
            last, last_time = pose, now
        odom = self.robot.odometry()
        assert odom is not None  # read() checked it
        return odom


#: The control loop with its safety checks, for moves other than the square (the
#: self-calibration anywhere: :mod:`umbmark.routines.anywhere`).
Driver = _Driver


def drive_square(
    robot: Robot,
    side: float,
    direction: Direction,
    limits: DriveLimits | None = None,
    progress: Progress | None = None,
) -> DrivenRun:
    """Drive one UMBmark run by the odometry: four legs and four on-the-spot turns.

    Parameters
    ----------
    robot : Robot
    side : float
        The square's side ``L`` [m].
    direction : Direction
        ``ccw``: left turns; ``cw``: right turns (both start along the robot's heading).
    limits : DriveLimits, optional
    progress : callable, optional
        Called with the segment number (1-8) and a short text as each segment starts.

    Returns
    -------
    DrivenRun

    Raises
    ------
    SafetyError
        After sending a zero velocity (stale odometry, an obstacle, leaving the square,
        too long).
    """
    limits = limits or DriveLimits()
    driver = _Driver(robot, side, direction, limits)
    try:
        driver.radius = math.inf  # the square's frame is the settled start's
        start = driver.settle()
        driver.origin = start.pose
        driver.radius = None
        driver.deadline = robot.now() + limits.time_factor * limits.expected_time(side)
        heading = start.pose.theta
        corner = start.pose
        turn = direction.turn_sign * 0.5 * math.pi
        for k in range(4):
            if progress is not None:
                progress(2 * k + 1, f"leg {k + 1}")
            driver.leg(corner)
            odom = robot.odometry()
            assert odom is not None
            # The next corner as commanded: the square's corner, not where the leg stopped.
            corner = corner.compose(Pose2D(side, 0.0, 0.0))
            heading += turn
            if progress is not None:
                progress(2 * k + 2, f"turn {k + 1}")
            driver.turn(heading)
            corner = Pose2D(corner.x, corner.y, heading)
        driver.deadline = math.inf
        end = driver.settle()
    except BaseException:
        robot.send_velocity(0.0, 0.0)
        raise
    return DrivenRun(
        direction=direction,
        start=start,
        end=end,
        commanded_end=Pose2D(start.pose.x, start.pose.y, start.pose.theta + 4 * turn),
        odometry=np.asarray(driver.samples, dtype=np.float64),
    )


def settle(robot: Robot, limits: DriveLimits | None = None) -> StampedPose:
    """Stop and wait until the odometry has been still for ``settle_time``."""
    limits = limits or DriveLimits()
    driver = _Driver(robot, 0.0, Direction.CCW, limits)
    driver.radius = math.inf
    try:
        return driver.settle()
    except BaseException:
        robot.send_velocity(0.0, 0.0)
        raise


def move_to(robot: Robot, target: Pose2D, limits: DriveLimits | None = None) -> StampedPose:
    """Drive by the odometry to ``target`` (a pose relative to the robot now): turn to
    face it, drive there, turn to its heading, settle. For short moves, such as back to
    the start between runs (within ``margin`` of the straight line, safety stops as for a
    run).

    Returns
    -------
    Stamped
        The settled odometry.
    """
    limits = limits or DriveLimits()
    distance = math.hypot(target.x, target.y)
    driver = _Driver(robot, distance, Direction.CCW, limits)
    driver.radius = math.inf
    try:
        here = driver.settle().pose
        driver.origin = Pose2D(here.x, here.y, here.theta)
        driver.radius = distance + limits.margin
        driver.deadline = robot.now() + limits.time_factor * (
            2.0 * limits.expected_time(max(distance, 1e-3)) / 4.0 + 10.0
        )
        goal = here.compose(target)
        if distance > limits.end_position:
            facing = here.theta + math.atan2(target.y, target.x)
            driver.turn(facing)
            driver.leg(Pose2D(here.x, here.y, facing), distance)
        driver.turn(goal.theta)
        driver.deadline = math.inf
        return driver.settle()
    except BaseException:
        robot.send_velocity(0.0, 0.0)
        raise

"""One UMBmark pass driven by the robot itself: before each run it returns to the start
(by the corner fix) and takes a fix; it drives the square by its odometry, settles and
takes a fix again. The pass is recorded as a run log (:mod:`umbmark.routines.record`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from umbmark.core.conventions import Direction, wrap_angle
from umbmark.core.errors import option
from umbmark.robot.base import Pose2D, Robot
from umbmark.routines.corner import CornerFix, CornerNotFoundError, expected_pose
from umbmark.routines.drive import DriveLimits, drive_square, move_to, settle
from umbmark.routines.measure import Measure, take_fix
from umbmark.routines.record import MeasuredRun

__all__ = [
    "HOME_ANGLE",
    "HOME_DISTANCE",
    "Home",
    "corner_truth",
    "drive_pass",
    "go_home",
    "strays",
]

#: Back at the start: within this distance [m] and angle [rad] of the first fix.
HOME_DISTANCE = 0.02
HOME_ANGLE = math.radians(1.0)
#: Moves back to the start tried before a run is started from where the robot is.
HOME_MOVES = 3

#: What the routine reports while a pass runs: (run number, direction, what).
PassProgress = Callable[[int, Direction, str], None]


@dataclass
class Home:
    """Where the runs start (the first fix in the corner frame), and the latest fix with
    the odometry at that fix, for the next fix's prior."""

    pose: Pose2D
    fix: CornerFix
    odometry: Pose2D
    #: Every fix taken, with the true pose in the corner frame where the robot knows it
    #: (a virtual robot: :meth:`umbmark.robot.virtual.VirtualRobot.corner_truth`).
    fixes: list[tuple[CornerFix, Pose2D | None]] = field(default_factory=list)

    def reanchor(self, robot: Robot) -> None:
        """The robot has not moved since the last fix, but its odometry may have (new
        parameters make diff_drive_controller's odometry jump): take the odometry now as
        the one at the last fix."""
        self.odometry = settle(robot).pose

    def prior(self, odometry_now: Pose2D) -> Pose2D:
        """Where the robot should be now in the corner frame, by the odometry."""
        return expected_pose(self.fix, self.odometry, odometry_now)


def _fix_here(robot: Robot, how: Measure, home: Home, gate: tuple[float, float]) -> CornerFix:
    odom = settle(robot).pose
    fix = take_fix(robot, how, home.prior(odom), gate)
    home.fix, home.odometry = fix, odom
    home.fixes.append((fix, corner_truth(robot, how)))
    return fix


def corner_truth(robot: Robot, how: Measure) -> Pose2D | None:
    """The robot's true pose in the frame of ``how``'s fixes, if it knows it (a virtual
    robot): the corner frame, or the world frame for fixes by the ground truth."""
    if how.method == "truth":
        pose = getattr(robot, "true_pose", None)
        return pose if isinstance(pose, Pose2D) else None
    truth = getattr(robot, "corner_truth", None)
    return truth() if callable(truth) else None


def go_home(robot: Robot, how: Measure, home: Home, limits: DriveLimits) -> CornerFix:
    """Drive back to the start by the corner fixes (a few short moves by the odometry)
    and return the fix taken there."""
    fix = _fix_here(robot, how, home, (0.5, math.radians(20.0)))
    for _ in range(HOME_MOVES):
        target = home.pose.relative_to(fix.pose)  # the start, seen from the robot
        off = math.hypot(target.x, target.y)
        if off <= HOME_DISTANCE and abs(float(wrap_angle(target.theta))) <= HOME_ANGLE:
            break
        move_to(robot, target, limits)
        fix = _fix_here(robot, how, home, (0.5, math.radians(20.0)))
    return fix


def drive_pass(
    robot: Robot,
    how: Measure,
    side: float,
    runs: int,
    home: Home,
    limits: DriveLimits,
    progress: PassProgress | None = None,
    measured: Callable[[int, Direction, MeasuredRun], None] | None = None,
) -> list[MeasuredRun]:
    """``runs`` cw runs, then ``runs`` ccw runs (Sec. 5), each from the start and measured
    at both ends.

    A run's end fix is gated by a wide prior: the odometry believes the robot came back,
    so the prior is the start, and the return error may be large (up to a fifth of the
    side and 30 degrees are taken). ``measured`` is called with each run as it is
    measured (its number in the pass, 1 to ``2 runs``).
    """
    out: list[MeasuredRun] = []
    order = [Direction.CW] * runs + [Direction.CCW] * runs
    for k, direction in enumerate(order, start=1):
        if progress is not None:
            progress(k, direction, "back to the start")
        start = go_home(robot, how, home, limits)
        if progress is not None:
            progress(k, direction, "driving")
        legs = None
        if progress is not None:

            def legs(_: int, segment: str, k: int = k, direction: Direction = direction) -> None:
                assert progress is not None
                progress(k, direction, f"driving, {segment}")

        run = drive_square(robot, side, direction, limits, progress=legs)
        if progress is not None:
            progress(k, direction, "measuring")
        try:
            end = _fix_here(robot, how, home, (0.2 * side + 0.3, math.radians(30.0)))
        except CornerNotFoundError as exc:
            raise _lost_at_the_end(exc, how, direction, (k - 1) % runs + 1) from None
        out.append(MeasuredRun(run, start, end))
        if measured is not None:
            measured(k, direction, out[-1])
    return out


def _lost_at_the_end(
    exc: CornerNotFoundError, how: Measure, direction: Direction, k: int
) -> CornerNotFoundError:
    """The end fix failed: say which run, and for range sensors (which see the corner only
    near the start) what to do."""
    where = f"at the end of {direction.value} run {k}"
    if how.method != "ranges" or exc.cause != "missing_echo":
        return CornerNotFoundError(exc.cause, f"{exc.problem} ({where})")
    return CornerNotFoundError(
        exc.cause,
        f"{exc.problem} ({where}): the robot stopped too far from its start for three range "
        "sensors, which see both walls only within some 0.3 m and 10 deg of it; measure with "
        f"{option('measure', 'lidar')} (or truth), or make the errors smaller first (a smaller "
        f"square, {option('side_length')})",
    )


def strays(measured: list[MeasuredRun], limits: DriveLimits) -> tuple[str, ...]:
    """A warning for each run whose odometry ended farther from the commanded end than the
    limits (a robot answering commands late, a controller that does not settle)."""
    out = []
    counted: dict[Direction, int] = {}
    for m in measured:
        k = counted[m.run.direction] = counted.get(m.run.direction, 0) + 1
        distance, heading = m.run.end_error
        if distance > limits.end_position or heading > limits.end_heading:
            out.append(
                f"{m.run.direction.value} run {k}: the odometry ended {distance * 1000:.1f} mm "
                f"and {math.degrees(heading):.2f} deg from where it was sent (limits "
                f"{limits.end_position * 1000:g} mm, {math.degrees(limits.end_heading):g} deg): "
                "the run is not the square the benchmark assumes"
            )
    return tuple(out)

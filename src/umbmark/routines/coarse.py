"""The coarse turning check: does the robot turn as far as its odometry believes?

A robot whose odometry overstates or understates its turns by tens of percent
(skid-steer robots run with ``wheel_separation_multiplier`` of 1.5 to 1.9) cannot drive
a square at all by its odometry. Before UMBmark the robot turns on the spot by a quarter
turn (then back), by its odometry, and a fix before and after tells how far it really
turned. The ratio of the odometry's angle to the true one is the wheelbase the odometry
should use over the one it uses: ``wheel_separation_multiplier`` is multiplied by it
when it is off by more than :data:`COARSE_THRESHOLD`.

On-the-spot turns measure the wheelbase of spot turns; UMBmark's ``E_b`` (turns and legs
together) follows in the passes. A quarter turn keeps the true angle unambiguous for any
ratio from 1/2 to 2.

How far the robot really turned comes from the corner: a fix before and after each turn,
taken without a prior. Where the robot has an IMU it comes from the gyro instead (no fix
needed, so the check also runs with range sensors): the robot stands
:data:`COARSE_REST` before and after each turn, the gyro's mean over those rests is its
bias, removed from its integral over the turn. The gyro's scale is taken as 1: a MEMS
gyro's is good to a few percent (``scale_tolerance``, the calibration's
``--gyro-scale-tolerance``), and so is the ratio, which the words say; the UMBmark passes
that follow measure ``E_b`` against the corner. Where the gyro fell silent or froze
over a turn (:func:`umbmark.routines.gyro_watch.gyro_trouble`), the robot turns back and
the check is made by the fixes, the words saying why: nothing is corrected from such a
gyro.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from umbmark.core.conventions import wrap_angle
from umbmark.robot.base import ImuSource, Pose2D, Robot
from umbmark.routines.drive import DriveLimits, move_to, settle
from umbmark.routines.measure import Measure, take_fix

__all__ = ["COARSE_REST", "COARSE_THRESHOLD", "CoarseTurning", "coarse_turning"]

#: A ratio farther than this from 1 is corrected before UMBmark.
COARSE_THRESHOLD = 0.05
#: The turn by the odometry [rad].
COARSE_TURN = 0.5 * math.pi
#: Ratios outside this are refused: no odometry setting explains them.
RATIO_RANGE = (0.5, 2.0)
#: With a gyro: the robot stands this long [s] before and after each turn (its bias).
COARSE_REST = 2.0


@dataclass(frozen=True)
class CoarseTurning:
    """The coarse turning check.

    Attributes
    ----------
    odometry_angle, true_angle : float
        How far the odometry believes the robot turned, and how far it did [rad] (the sum
        of the turn and the turn back, in absolute value).
    ratio : float
        ``odometry_angle / true_angle``: the factor for ``wheel_separation_multiplier``.
    needed : bool
        Whether the ratio is off by more than :data:`COARSE_THRESHOLD`.
    measured_by : {"corner fixes", "imu"}
        What measured the true turns (``imu``: its gyro).
    imu : str or None
        The gyro's IMU (its topic and mounting), where it measured.
    gyro_bias : float or None
        The gyro's bias removed [rad/s] (its mean over the rests).
    rest : float or None
        How long the robot stood for it [s], all rests together.
    scale_tolerance : float or None
        How far the gyro's scale, taken as 1, may be off (a fraction): the ratio's too.
    gyro_left_out : str or None
        Why the robot's IMU did not measure (it fell silent or froze during a turn:
        :func:`umbmark.routines.gyro_watch.gyro_trouble`), the fixes measuring instead.
    """

    odometry_angle: float
    true_angle: float
    ratio: float
    needed: bool
    measured_by: str = "corner fixes"
    imu: str | None = None
    gyro_bias: float | None = None
    rest: float | None = None
    scale_tolerance: float | None = None
    gyro_left_out: str | None = None

    def words(self) -> str:
        """One sentence: how far the robot turned against its odometry, and what was done."""
        done = "corrected" if self.needed else "within 5 %, not corrected"
        how = ""
        if self.gyro_bias is not None and self.scale_tolerance is not None:
            tol = 100.0 * self.scale_tolerance
            how = (
                f" by the gyro ({self.imu}; its bias {math.degrees(self.gyro_bias):.4f} deg/s, "
                f"its mean over {self.rest or 0.0:.1f} s of rest, removed; its scale taken as "
                f"1, known to +-{tol:g} %, so the ratio to +-{tol:g} %)"
            )
        if self.gyro_left_out is not None:
            how = f" by {self.measured_by} (the gyro left out: {self.gyro_left_out})"
        return (
            f"Coarse turning check{how}: the robot turned {math.degrees(self.true_angle):.1f} "
            f"deg while its odometry turned {math.degrees(self.odometry_angle):.1f} deg "
            f"(ratio {self.ratio:.4f}): {done}."
        )

    def to_dict(self) -> dict[str, float | bool | str | None]:
        """JSON-ready (radians, rad/s)."""
        return {
            "odometry_angle": self.odometry_angle,
            "true_angle": self.true_angle,
            "ratio": self.ratio,
            "needed": self.needed,
            "measured_by": self.measured_by,
            "imu": self.imu,
            "gyro_bias": self.gyro_bias,
            "rest": self.rest,
            "scale_tolerance": self.scale_tolerance,
            "gyro_left_out": self.gyro_left_out,
        }


def coarse_turning(
    robot: Robot, how: Measure, limits: DriveLimits, scale_tolerance: float = 0.03
) -> CoarseTurning:
    """Turn a quarter turn left by the odometry and back, measuring the true turns: by
    the gyro where the robot has an IMU (the module's documentation; ``scale_tolerance``:
    how far its scale may be off), else by corner fixes; by the fixes too where the gyro
    fell silent or froze during a turn (the robot turned back first; said in
    :attr:`CoarseTurning.gyro_left_out`).

    The fixes are taken without a prior (the odometry cannot be trusted to predict the
    heading: that is what is checked), so the corner must be the plainest L in view.

    Raises
    ------
    umbmark.routines.corner.CornerNotFoundError
        The corner was not found after a turn.
    ValueError
        A ratio outside 1/2 to 2.
    """
    imu = robot.imu()
    if imu is not None:
        by_gyro = _by_gyro(robot, imu, limits, scale_tolerance)
        if isinstance(by_gyro, CoarseTurning):
            return by_gyro
        return replace(_by_fixes(robot, how, limits), gyro_left_out=by_gyro)
    return _by_fixes(robot, how, limits)


def _by_fixes(robot: Robot, how: Measure, limits: DriveLimits) -> CoarseTurning:
    """The quarter turns measured by fixes taken without a prior."""
    odometry_angle = true_angle = 0.0
    for sign in (1.0, -1.0):
        odom_before = settle(robot, limits).pose
        before = take_fix(robot, how)
        move_to(robot, Pose2D(0.0, 0.0, sign * COARSE_TURN), limits)
        odom_after = settle(robot, limits).pose
        after = take_fix(robot, how)
        odometry_angle += abs(float(wrap_angle(odom_after.theta - odom_before.theta)))
        true_angle += abs(float(wrap_angle(after.pose.theta - before.pose.theta)))
    ratio = _ratio(odometry_angle, true_angle)
    return CoarseTurning(odometry_angle, true_angle, ratio, abs(ratio - 1.0) > COARSE_THRESHOLD)


def _ratio(odometry_angle: float, true_angle: float) -> float:
    """The ratio of the angles turned, refused outside :data:`RATIO_RANGE`."""
    ratio = odometry_angle / true_angle if true_angle > 0 else math.inf
    if not (RATIO_RANGE[0] <= ratio <= RATIO_RANGE[1]):
        raise ValueError(
            f"the robot turned {math.degrees(true_angle):.1f} deg while its odometry "
            f"turned {math.degrees(odometry_angle):.1f} deg (ratio {ratio:.3g}): outside "
            f"{RATIO_RANGE[0]:g} to {RATIO_RANGE[1]:g}; check the wheel_separation and "
            "the wheel radius of the controller"
        )
    return ratio


def _stand(robot: Robot, seconds: float, limits: DriveLimits) -> tuple[float, float]:
    """Stand still for ``seconds`` (a zero velocity each control period): its start and
    end on the robot's clock."""
    start = robot.now()
    while robot.now() - start < seconds:
        robot.send_velocity(0.0, 0.0)
        robot.wait(limits.period)
    return start, robot.now()


def _by_gyro(
    robot: Robot, imu: ImuSource, limits: DriveLimits, scale_tolerance: float
) -> CoarseTurning | str:
    """The quarter turns measured by the gyro, its bias over the rests removed; where it
    fell silent or froze over a turn, the robot turned back to its start heading and the
    line saying so."""
    from umbmark.routines.gyro_watch import gyro_trouble

    odometry_angle = true_angle = 0.0
    biases, rested = [], 0.0
    for sign in (1.0, -1.0):
        odom_before = settle(robot, limits).pose
        before = _stand(robot, COARSE_REST, limits)
        move_to(robot, Pose2D(0.0, 0.0, sign * COARSE_TURN), limits)
        odom_after = settle(robot, limits).pose
        after = _stand(robot, COARSE_REST, limits)
        gyro = robot.gyro(before[0])
        trouble = gyro_trouble(gyro, before[0], after[1], imu.topic)
        if trouble is not None or gyro is None:
            if sign > 0:  # turned left: back to the heading the fixes start from
                move_to(robot, Pose2D(0.0, 0.0, -COARSE_TURN), limits)
            return str(trouble)
        yaw = gyro.rate[:, 2]
        rests = [(gyro.time >= a) & (gyro.time <= b) for a, b in (before, after)]
        bias = float(np.mean(yaw[rests[0] | rests[1]]))
        turned = gyro.yaw_change(np.array([before[1]]), np.array([after[0]]))[0]
        odometry_angle += abs(float(wrap_angle(odom_after.theta - odom_before.theta)))
        true_angle += abs(float(turned) - bias * (after[0] - before[1]))
        biases.append(bias)
        rested += (before[1] - before[0]) + (after[1] - after[0])
    ratio = _ratio(odometry_angle, true_angle)
    return CoarseTurning(
        odometry_angle, true_angle, ratio, abs(ratio - 1.0) > COARSE_THRESHOLD, "imu",
        imu.describe(), float(np.mean(biases)), rested, scale_tolerance,
    )  # fmt: skip

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from umbmark.core.conventions import wrap_angle
from umbmark.robot.base import Pose2D, Robot
from umbmark.routines.drive import DriveLimits, move_to, settle
from umbmark.routines.measure import Measure, take_fix

__all__ = ["COARSE_THRESHOLD", "CoarseTurning", "coarse_turning"]

#: A ratio farther than this from 1 is corrected before UMBmark.
COARSE_THRESHOLD = 0.05
#: The turn by the odometry [rad].
COARSE_TURN = 0.5 * math.pi
#: Ratios outside this are refused: no odometry setting explains them.
RATIO_RANGE = (0.5, 2.0)


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
    """

    odometry_angle: float
    true_angle: float
    ratio: float
    needed: bool

    def words(self) -> str:
        """One sentence: how far the robot turned against its odometry, and what was done."""
        done = "corrected" if self.needed else "within 5 %, not corrected"
        return (
            f"Coarse turning check: the robot turned {math.degrees(self.true_angle):.1f} deg "
            f"while its odometry turned {math.degrees(self.odometry_angle):.1f} deg "
            f"(ratio {self.ratio:.4f}): {done}."
        )

    def to_dict(self) -> dict[str, float | bool]:
        """JSON-ready (radians)."""
        return {
            "odometry_angle": self.odometry_angle,
            "true_angle": self.true_angle,
            "ratio": self.ratio,
            "needed": self.needed,
        }


def coarse_turning(robot: Robot, how: Measure, limits: DriveLimits) -> CoarseTurning:
    """Turn a quarter turn left by the odometry and back, measuring the true turns.

    The fixes are taken without a prior (the odometry cannot be trusted to predict the
    heading: that is what is checked), so the corner must be the plainest L in view.

    Raises
    ------
    umbmark.routines.corner.CornerNotFoundError
        The corner was not found after a turn.
    ValueError
        A ratio outside 1/2 to 2.
    """
    odometry_angle = true_angle = 0.0
    for sign in (1.0, -1.0):
        odom_before = settle(robot, limits).pose
        before = take_fix(robot, how)
        move_to(robot, Pose2D(0.0, 0.0, sign * COARSE_TURN), limits)
        odom_after = settle(robot, limits).pose
        after = take_fix(robot, how)
        odometry_angle += abs(float(wrap_angle(odom_after.theta - odom_before.theta)))
        true_angle += abs(float(wrap_angle(after.pose.theta - before.pose.theta)))
    ratio = odometry_angle / true_angle if true_angle > 0 else math.inf
    if not (RATIO_RANGE[0] <= ratio <= RATIO_RANGE[1]):
        raise ValueError(
            f"the robot turned {math.degrees(true_angle):.1f} deg while its odometry "
            f"turned {math.degrees(odometry_angle):.1f} deg (ratio {ratio:.3g}): outside "
            f"{RATIO_RANGE[0]:g} to {RATIO_RANGE[1]:g}; check the wheel_separation and "
            "the wheel radius of the controller"
        )
    return CoarseTurning(odometry_angle, true_angle, ratio, abs(ratio - 1.0) > COARSE_THRESHOLD)

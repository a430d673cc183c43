"""The square is driven by a robot whose commands arrive late, as a ROS robot's do (the
velocity crosses a topic to a controller updating at 50 Hz, the odometry comes back the
same way): closing in on a leg's end or a turn's heading must not overshoot back and
forth (a dead-beat approach, the remaining distance in one period, does with a delay of
two periods and more)."""

from __future__ import annotations

from collections import deque

import pytest

from umbmark.core.conventions import Direction
from umbmark.robot.base import StampedPose
from umbmark.robot.virtual import VirtualRobot
from umbmark.routines.drive import DriveLimits, drive_square


class LateRobot(VirtualRobot):
    """A virtual robot whose commands take effect ``delay`` periods after they are sent
    and whose odometry is ``odom_delay`` periods old."""

    def __init__(self, delay: int, odom_delay: int = 0) -> None:
        super().__init__(E_d=1.004, E_b=0.97, slip=0.0, seed=1)
        self.delay, self.odom_delay = delay, odom_delay
        self.queue: deque[tuple[float, float]] = deque()
        self.odom_queue: deque[StampedPose] = deque(maxlen=odom_delay + 1)

    def send_velocity(self, linear: float, angular: float) -> None:
        self.queue.append((linear, angular))

    def wait(self, duration: float) -> None:
        for _ in range(round(duration / self.period)):
            if len(self.queue) > self.delay:
                while len(self.queue) > self.delay:
                    linear, angular = self.queue.popleft()
                super().send_velocity(linear, angular)
            self._step()
            self.odom_queue.append(super().odometry())

    def odometry(self) -> StampedPose:
        return self.odom_queue[0] if self.odom_queue else super().odometry()


@pytest.mark.parametrize(("delay", "odom_delay"), [(2, 0), (3, 0), (2, 2)])
def test_a_square_with_late_commands_does_not_overshoot(delay: int, odom_delay: int) -> None:
    """No back-and-forth: the run ends (before the 2x time limit's safety stop), about as
    fast as without delays (four 1 m legs at 0.2 m/s and four quarter turns: 33 s), its
    heading within the limit."""
    robot = LateRobot(delay, odom_delay)
    limits = DriveLimits()
    run = drive_square(robot, 1.0, Direction.CCW, limits)
    assert run.end.time - run.start.time < 40.0
    assert run.end_error[1] <= limits.end_heading


@pytest.mark.parametrize("delay", [2, 3])
def test_late_commands_end_within_the_position_limit(delay: int) -> None:
    run = drive_square(LateRobot(delay), 1.0, Direction.CCW, DriveLimits())
    assert run.end_error[0] <= DriveLimits().end_position

"""The pace of the simulated robot nodes (tests/ros1_robot_node.py, tests/ros2_robot_node.py):
one controller period of robot time every ``period / rate`` wall seconds, and never faster.

A node that fell behind (a busy machine) and then ran its late periods back to back would
move its clock several robot seconds in a fraction of a wall second. The program driving
the robot (umbmark's drive, its command timeout, the monitor) reads that clock and answers
on the wall's: its commands would reach the robot seconds of robot time late, a run would
take far longer than planned in robot time, and its safety deadline would stop it. A late
node starts counting from where it is instead, so its clock slows with the machine.
"""

from __future__ import annotations

import time

#: How far behind [wall periods] the node may be before it stops catching up (jitter).
SLACK_STEPS = 2


class Pace:
    """``wait()`` after each period: sleeps until the next one is due, never catches up."""

    def __init__(self, wall_step: float) -> None:
        self.wall_step = wall_step
        self._due = time.monotonic()

    def wait(self) -> None:
        self._due += self.wall_step
        delay = self._due - time.monotonic()
        if delay > 0.0:
            time.sleep(delay)
        elif delay < -SLACK_STEPS * self.wall_step:  # behind: go on from now
            self._due = time.monotonic()

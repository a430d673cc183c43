"""Checks before anything moves: the odometry is alive, the controller answers, the
sensor the fixes need is there, and the floor of both squares is free.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.robot.base import Robot
from umbmark.routines.drive import DriveLimits
from umbmark.routines.measure import Measure

__all__ = ["ROBOT_RADIUS", "free_floor", "preflight"]

#: Room kept around the squares' lines for the robot's body [m].
ROBOT_RADIUS = 0.3


def free_floor(robot: Robot, side: float) -> str:
    """Whether the laser sees anything on the floor of the two squares (cw to the right,
    ccw to the left, both along the robot's heading), widened by :data:`ROBOT_RADIUS`.

    Raises
    ------
    InputError
        Naming the nearest return in the way, in the robot's frame.
    """
    scan = robot.scan()
    if scan is None:
        return "no laser: the floor of the squares is not checked"
    ranges = np.asarray(scan.ranges, dtype=np.float64)
    ok = np.isfinite(ranges) & (ranges >= scan.range_min) & (ranges <= scan.range_max)
    angles = scan.angles()[ok] + scan.mount.theta
    x = scan.mount.x + ranges[ok] * np.cos(angles)
    y = scan.mount.y + ranges[ok] * np.sin(angles)
    r = ROBOT_RADIUS
    inside = (x > -r) & (x < side + r) & (np.abs(y) < side + r)
    # the squares' area only: the band around the four legs of each square
    legs = (np.abs(y) < r) | (np.abs(x - side) < r) | (np.abs(np.abs(y) - side) < r) | (x < r)
    blocked = inside & legs
    if blocked.any():
        k = int(np.argmin(np.hypot(x[blocked], y[blocked])))
        px, py = float(x[blocked][k]), float(y[blocked][k])
        raise InputError(
            f"something stands on the squares' path at x = {px:.2f} m, y = {py:.2f} m of the "
            f"robot ({int(blocked.sum())} laser returns within {r:g} m of the {side:g} m "
            "squares): clear the floor, or place the robot elsewhere"
        )
    return f"the squares' path is clear as far as the laser sees ({int(ok.sum())} returns)"


def preflight(
    robot: Robot,
    how: Measure,
    side: float,
    limits: DriveLimits,
    say: Callable[[str], None] | None = None,
) -> list[str]:
    """Run the checks; lines saying what each found (each also given to ``say`` as it is
    found). Without a laser, a line says that nothing watches for obstacles.

    Raises
    ------
    InputError
        The first check that failed, with its cause.
    """
    lines = _Lines(say)
    robot.send_velocity(0.0, 0.0)
    robot.wait(2 * limits.period)
    odom = robot.odometry()
    if odom is None:
        raise InputError("no odometry from the robot: is its controller running?")
    age = robot.now() - odom.time
    if age > limits.stale_odometry:
        raise InputError(f"the robot's odometry is {age:.2f} s old: is its controller running?")
    lines.append(f"odometry alive ({age * 1000:.0f} ms old)")
    params = robot.drive_params()
    values = (params.wheel_separation, params.wheel_radius, params.wheel_separation_multiplier)
    if not all(v > 0 and math.isfinite(v) for v in values):
        raise InputError(f"the controller's parameters are not usable: {params}")
    lines.append(
        f"controller answers: wheel_separation {params.wheel_separation:g} m, wheel_radius "
        f"{params.wheel_radius:g} m, multipliers {params.wheel_separation_multiplier:g}, "
        f"{params.left_wheel_radius_multiplier:g}, {params.right_wheel_radius_multiplier:g}"
    )
    velocity_note = getattr(robot, "velocity_note", None)  # a ROS 2 robot's velocity topic
    said = velocity_note() if callable(velocity_note) else None
    if isinstance(said, str):
        lines.append(said)
    sensor = {"lidar": robot.scan, "ranges": robot.ranges, "truth": robot.ground_truth}
    read = sensor.get(how.method)
    if read is not None and read() is None:
        names = {"lidar": "laser scan", "ranges": "range readings", "truth": "ground truth"}
        raise InputError(f"{option('measure', how.method)}: the robot gives no {names[how.method]}")
    if how.method == "lidar":
        lines.append(free_floor(robot, side))
    apply_note = getattr(robot, "apply_note", None)  # a ROS 2 controller manager's way
    note = apply_note() if callable(apply_note) else None
    if isinstance(note, str):
        lines.append(note)
    if how.method != "lidar" and robot.scan() is None:  # lidar: the laser was checked
        lines.append(
            "no laser: nothing watches for obstacles while the robot drives; keep the "
            "squares' floor clear and a hand on the emergency stop"
        )
    else:
        stop = limits.stop_distance(limits.speed)
        lines.append(
            f"the laser watches for obstacles: at {limits.speed:g} m/s the robot stops for "
            f"one {stop:.2f} m ahead or nearer"
        )
    return list(lines)


class _Lines(list[str]):
    """The checks' lines, each said as it is added."""

    def __init__(self, say: Callable[[str], None] | None) -> None:
        super().__init__()
        self.say = say

    def append(self, line: str) -> None:
        super().append(line)
        if self.say is not None:
            self.say(line)

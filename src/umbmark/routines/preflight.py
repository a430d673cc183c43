"""Checks before anything moves: the odometry is alive, the controller answers, the
sensor the fixes need is there, and the floor of both squares is free.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from umbmark.core.bounds import smallest_side
from umbmark.core.errors import InputError, option
from umbmark.options.selfcal import SQUARE_SIDE_RANGE
from umbmark.robot.base import DriveParams, Robot
from umbmark.routines.clearance import path_blocked, scan_points
from umbmark.routines.drive import DriveLimits
from umbmark.routines.measure import Measure

__all__ = ["check_side", "free_floor", "preflight", "square_paths"]


def square_paths(side: float) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """The two squares' vertices [m] in the robot's frame at the start, start first and
    last: ccw (to the left), cw (to the right)."""
    return (
        [(0.0, 0.0), (side, 0.0), (side, side), (0.0, side), (0.0, 0.0)],
        [(0.0, 0.0), (side, 0.0), (side, -side), (0.0, -side), (0.0, 0.0)],
    )


def _blocked(points: np.ndarray, side: float, limits: DriveLimits) -> np.ndarray:
    found = np.zeros(len(points), dtype=bool)
    for path in square_paths(side):
        found |= path_blocked(points, path, limits.outline, limits.obstacle_margin)
    return found


def _advice(points: np.ndarray, side: float, limits: DriveLimits) -> str:
    """What to change so that the squares fit: the robot moved forward or sideways by
    the least that clears the band, or the longest side that fits."""
    ways = []
    for name, (ux, uy) in (("forward", (1.0, 0.0)), ("to the left", (0.0, 1.0))):
        for sign, label in ((1.0, name), (-1.0, "to the right" if uy else "")):
            if not label:
                continue
            for step in np.arange(0.05, 2.0 + 1e-9, 0.05):
                shift = np.array([sign * ux * step, sign * uy * step])
                if not _blocked(points - shift, side, limits).any():
                    ways.append(f"move the robot {step:.2f} m {label}")
                    break
    for shorter in np.arange(side - 0.1, SQUARE_SIDE_RANGE[0] - 1e-9, -0.1):
        if not _blocked(points, float(shorter), limits).any():
            ways.append(f"use {option('side_length', round(float(shorter), 1), 'm')}")
            break
    return "; or ".join(ways) if ways else "clear the floor, or place the robot elsewhere"


def check_side(side: float, params: DriveParams) -> None:
    """Refuse squares of ``side`` [m] that a robot of the controller's ``params`` would
    drive only to have the pass refused: the calibration takes a side not above twice the
    odometry's wheelbase for swapped or mistyped options
    (:func:`umbmark.core.bounds.check_square_geometry`). Checked before moving and before
    every pass (a pass's correction changes the wheelbase multiplier).

    Raises
    ------
    InputError
        Naming the side, the wheelbase it is judged by and the smallest side that works
        (the next 0.1 m above twice the wheelbase).
    """
    wheelbase = params.wheelbase
    limit = smallest_side(wheelbase)
    if side > limit:
        return
    enough = math.floor(limit * 10.0 + 1.0 + 1e-9) / 10.0  # the next 0.1 m strictly above
    multiplier = params.wheel_separation_multiplier
    times = f" times wheel_separation_multiplier {multiplier:g}" if multiplier != 1.0 else ""
    raise InputError(
        f"{option('side_length', side, 'm')} is too short for this robot: the squares' side "
        f"must be more than twice the odometry's wheelbase, {wheelbase:g} m (the controller's "
        f"wheel_separation {params.wheel_separation:g} m{times}), so more than {limit:g} m; "
        "squares this small would be driven and their pass then refused by the calibration, "
        "which takes a wheelbase of half the side or more for swapped or mistyped options: "
        f"the smallest side that works is {option('side_length', enough, 'm')}"
    )


def free_floor(robot: Robot, side: float, limits: DriveLimits | None = None) -> str:
    """Whether the laser sees anything on the two squares' path (cw to the right, ccw to
    the left, both along the robot's heading): the band the robot's footprint sweeps on
    each leg and past its end by the obstacle margin, the disc it sweeps turning at each
    corner, widened by the drift its errors allow (:func:`clearance.path_blocked`). What
    passes here is not stopped for on the way by the watch, which looks at the same band.

    Raises
    ------
    InputError
        Naming the nearest return in the way, in the robot's frame, and what to change:
        move the robot forward or sideways by how much, or a side that fits.
    """
    limits = limits or DriveLimits()
    scan = robot.scan()
    if scan is None:
        return "no laser: the floor of the squares is not checked"
    points = scan_points(scan)
    blocked = _blocked(points, side, limits)
    if blocked.any():
        near = points[blocked]
        k = int(np.argmin(np.hypot(near[:, 0], near[:, 1])))
        px, py = float(near[k, 0]), float(near[k, 1])
        fp = limits.outline
        raise InputError(
            f"something stands on the squares' path at x = {px:.2f} m, y = {py:.2f} m of the "
            f"robot ({int(blocked.sum())} laser returns in the band a {fp.width:g} m wide robot "
            f"sweeps on the {side:g} m squares, its turns and {limits.obstacle_margin:g} m "
            f"past each leg's end): {_advice(points, side, limits)}"
        )
    return f"the squares' path is clear as far as the laser sees ({len(points)} returns)"


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
    check_side(side, params)
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
        lines.append(free_floor(robot, side, limits))
    imu = robot.imu()  # a ROS robot: its frame's mounting found here, before moving
    if imu is not None:
        lines.append(f"gyro: {imu.describe()}")
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
            f"one {stop:.2f} m ahead or nearer on its path ({limits.outline.width:g} m wide "
            "plus room each side)"
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

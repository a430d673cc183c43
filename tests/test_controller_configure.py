"""``VirtualRobot.configure_controller``: ros2_controllers' diff_drive_controller configured
again on new multipliers (``on_configure``), as ``odometry.cpp`` has it on Humble to Kilted
with position feedback. Expected values by hand: the robot drove 1 m straight (0.2 m/s for
5 s, truth equal to the nominal geometry), so each wheel turned 1 m / 0.075 m; the
controller's remembered wheel positions are that rotation times the old radius."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from umbmark.core.errors import InputError
from umbmark.robot.base import DriveParams
from umbmark.robot.virtual import VirtualRobot

SEPARATION, RADIUS = 0.34, 0.075


def _driven() -> VirtualRobot:
    robot = VirtualRobot(E_d=1.0, E_b=1.0, wheelbase=SEPARATION, wheel_diameter=2 * RADIUS)
    for _ in range(250):  # 5 s at 0.2 m/s, a command each period
        robot.send_velocity(0.2, 0.0)
        robot.wait(robot.period)
    robot.send_velocity(0.0, 0.0)
    robot.wait(1.0)  # stopped (the wheels stand: a command of zero)
    return robot


#: The encoder's step at the wheel [m]: 2000 pulses x 20 gear, at 0.075 m.
STEP = 2 * math.pi / 40000 * RADIUS


def test_a_configure_resets_the_pose_and_the_first_update_jumps_by_the_radius_change() -> None:
    """Kept wheel positions (in metres at the old radii): after the configure the pose is
    zero, and one update later it moved by the wheels' travel (1 m) times the change: the
    left wheel +1% -> 10 mm, the right none: 5 mm ahead, turned -0.010 / 0.34 rad."""
    robot = _driven()
    assert robot.odometry().pose.x == pytest.approx(1.0, abs=4 * STEP)
    new = replace(DriveParams(SEPARATION, RADIUS), left_wheel_radius_multiplier=1.01)
    robot.configure_controller(new, loaded=False)
    start = robot.odometry().pose
    assert (start.x, start.y, start.theta) == (0.0, 0.0, 0.0)
    robot.wait(robot.period)
    pose = robot.odometry().pose
    assert pose.theta == pytest.approx(-0.010 / SEPARATION, abs=4 * STEP / SEPARATION)
    assert pose.x == pytest.approx(0.005, abs=4 * STEP)
    assert robot.drive_params() == new


def test_a_controller_just_loaded_jumps_by_the_wheels_whole_travel() -> None:
    """Remembered positions zero: its first update integrates the whole 1 m of each wheel
    at the new radii (left 1.01 m, right 1 m): 1.005 m along an arc turning -0.01 / 0.34."""
    robot = _driven()
    new = replace(DriveParams(SEPARATION, RADIUS), left_wheel_radius_multiplier=1.01)
    robot.configure_controller(new, loaded=True)
    robot.wait(robot.period)
    pose = robot.odometry().pose
    turn = -0.010 / SEPARATION
    chord = 1.005 / turn * 2 * math.sin(turn / 2)  # an exact arc of 1.005 m
    assert pose.theta == pytest.approx(turn, abs=4 * STEP / SEPARATION)
    assert math.hypot(pose.x, pose.y) == pytest.approx(abs(chord), abs=8 * STEP)


def test_a_configure_on_multipliers_that_are_not_positive_is_refused() -> None:
    robot = VirtualRobot()
    bad = replace(DriveParams(SEPARATION, RADIUS), wheel_separation_multiplier=0.0)
    with pytest.raises(InputError, match="wheel_separation_multiplier"):
        robot.configure_controller(bad, loaded=False)

"""What arrives, when: out of order dropped, the clock going back, restarts of the
controller kept out of the wheels' angles, the odometry turned back into wheel rotation."""

from __future__ import annotations

import math

import pytest

from umbmark.monitor.arrivals import CLOCK_BACK, Arrivals, WheelAngles
from umbmark.robot.base import Pose2D


def test_out_of_order_is_dropped_and_counted() -> None:
    a = Arrivals()
    assert a.arrive("wheels", 1.0) == "ok"
    assert a.arrive("wheels", 0.9) == "drop"
    assert a.arrive("wheels", 1.0) == "drop"  # the same stamp again
    assert a.arrive("scan", 0.5) == "ok"  # each input on its own
    assert a.dropped["wheels: out of order"] == 2


def test_the_clock_going_back_is_said_once() -> None:
    a = Arrivals()
    a.arrive("wheels", 100.0)
    a.arrive("scan", 100.0)
    assert a.arrive("wheels", 100.0 - CLOCK_BACK - 1.0) == "back"
    assert a.arrive("scan", 97.0) == "ok"  # the others start again with it
    assert a.arrive("wheels", 96.5) == "ok"


def test_silent_inputs() -> None:
    a = Arrivals()
    a.arrive("wheels", 10.0)
    a.arrive("scan", 10.0)
    a.arrive("wheels", 14.0)
    # the scan fell silent; the gyro never spoke (a robot may have none)
    assert a.silent(14.0, ("wheels", "scan", "imu"), 2.0) == ("scan",)
    assert a.silent(11.0, ("wheels", "scan"), 2.0) == ()
    assert a.silent(17.0, ("odometry", "scan"), 2.0) == ("wheels", "scan")


def test_a_wheel_reset_is_a_break_not_a_jump() -> None:
    w = WheelAngles((0.075, 0.075), 0.34)
    w.from_wheels(0.0, 100.0, 200.0)
    assert w.from_wheels(0.02, 100.1, 200.1)
    assert not w.from_wheels(0.04, 0.0, 0.0)  # the driver restarted: counts from 0
    assert w.breaks == 1
    assert w.from_wheels(0.06, 0.1, 0.1)
    assert w.angles == pytest.approx((0.2, 0.2))


def test_odometry_turned_back_into_wheel_rotation() -> None:
    r, b = 0.075, 0.34
    w = WheelAngles((r, r), b)
    w.from_odometry(0.0, Pose2D())
    assert w.from_odometry(0.1, Pose2D(0.05, 0.0, 0.0))  # 5 cm straight
    assert w.angles == pytest.approx((0.05 / r, 0.05 / r))
    turn = 0.2  # on the spot: each wheel rolls b/2 * turn, opposite ways
    assert w.from_odometry(0.2, Pose2D(0.05, 0.0, turn))
    assert w.angles[0] == pytest.approx((0.05 - 0.5 * b * turn) / r)
    assert w.angles[1] == pytest.approx((0.05 + 0.5 * b * turn) / r)


def test_an_odometry_jump_is_a_restart() -> None:
    w = WheelAngles((0.075, 0.075), 0.34)
    w.from_odometry(0.0, Pose2D(12.0, 3.0, 1.0))
    w.from_odometry(0.02, Pose2D(12.01, 3.0, 1.0))
    before = w.angles
    assert not w.from_odometry(0.04, Pose2D(0.0, 0.0, 0.0))  # the controller restarted
    assert w.breaks == 1
    assert w.angles == before
    assert w.from_odometry(0.06, Pose2D(0.01 * math.cos(0.0), 0.0, 0.0))

"""What to apply from the robot's present state, and its verdict."""

from __future__ import annotations

import pytest

from umbmark.monitor.apply import offer
from umbmark.robot.base import DriveParams


def test_the_multipliers_are_the_robots_own() -> None:
    # A robot whose right wheel is 0.6 % smaller, wheelbase 1 % wider, mean diameter 0.3 %
    # smaller: Eqs. 4.31, 4.32 (times E_s) and 4.26 give the multipliers by hand.
    E_d, E_b, E_s = 0.994, 1.01, 0.997
    got = offer({"E_d": (E_d, 1e-4), "E_b": (E_b, 5e-4), "E_s": (E_s, 5e-4)},
                DriveParams(0.34, 0.075))  # fmt: skip
    assert got is not None
    assert got.verdict.applies
    p = got.params
    assert p.wheel_separation_multiplier == pytest.approx(1.01)
    assert p.left_wheel_radius_multiplier == pytest.approx(2 * 0.997 / 1.994)
    assert p.right_wheel_radius_multiplier == pytest.approx(2 * 0.997 * 0.994 / 1.994)
    assert (p.wheel_separation, p.wheel_radius) == (0.34, 0.075)


def test_an_interval_that_does_not_say_which_way_is_not_applied() -> None:
    got = offer({"E_d": (0.994, 0.01), "E_b": (1.01, 0.05)}, DriveParams(0.34, 0.075))
    assert got is not None
    assert not got.verdict.applies


def test_nothing_without_E_d_and_E_b() -> None:
    assert offer({"E_s": (1.0, 1e-3)}, DriveParams(0.34, 0.075)) is None

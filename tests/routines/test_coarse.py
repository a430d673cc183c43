"""The coarse turning check by the gyro (``routines/coarse.py``) on the virtual robot:
the ratio it finds is the odometry's turn over the gyro's, which reads 1 / k_g of the
true turn, its bias removed: E_b k_g / E_s for turns on the spot (hand derivation:
the odometry turns ``(D/2)(phi_R - phi_L) / b`` where the robot turns ``(D_R phi_R -
D_L phi_L) / (2 E_b b)``, the same wheels' mean diameter ``E_s D`` both ways)."""

from __future__ import annotations

import math

import pytest

from faulty_imu import FaultyImu
from umbmark.robot.virtual import VirtualRobot
from umbmark.routines.coarse import COARSE_REST, coarse_turning
from umbmark.routines.drive import DriveLimits
from umbmark.routines.measure import Measure
from umbmark.sim.imu import ImuSetup

DEG = math.pi / 180.0


@pytest.mark.parametrize(("E_b", "k_g", "needed"), [(0.9, 1.02, True), (1.01, 0.98, False)])
def test_the_gyro_measures_the_turns_with_its_bias_removed(E_b, k_g, needed):
    setup = ImuSetup(gyro_scale=k_g, gyro_bias=0.5 * DEG)
    robot = VirtualRobot(E_d=1.003, E_b=E_b, E_s=1.005, slip=0.0004, seed=2, imu=setup)
    check = coarse_turning(robot, Measure("lidar"), DriveLimits(), scale_tolerance=0.03)
    assert check.measured_by == "imu"
    assert check.ratio == pytest.approx(E_b * k_g / 1.005, abs=0.002)
    assert check.needed is needed
    assert check.gyro_bias == pytest.approx(0.5 * DEG, abs=0.01 * DEG)
    assert check.rest == pytest.approx(4 * COARSE_REST, abs=0.1)
    words = check.words()
    assert "by the gyro (the IMU on /imu" in words
    assert "known to +-3 %" in words
    assert check.to_dict()["measured_by"] == "imu"


@pytest.mark.parametrize(("fault", "said"), [("silent", "fell silent"), ("frozen", "froze")])
def test_a_gyro_failing_over_a_turn_leaves_the_check_to_the_corner_fixes(fault, said):
    """The IMU fails 3 s in (during the first quarter turn, which begins after 2 s of
    rest): the robot turns back and the corner fixes measure, as without an IMU: the
    ratio is E_b / E_s for turns on the spot (the module's derivation, no gyro in it),
    within the fixes' 0.5 %; the gyro's figures are left empty and the words say why."""
    robot = FaultyImu(fault, 3.0, E_d=1.003, E_b=0.9, E_s=1.005, slip=0.0004, seed=2,
                       imu=ImuSetup(gyro_scale=1.02))  # fmt: skip
    check = coarse_turning(robot, Measure("lidar"), DriveLimits(), scale_tolerance=0.03)
    assert check.measured_by == "corner fixes"
    assert check.ratio == pytest.approx(0.9 / 1.005, rel=0.005)
    assert check.needed
    assert check.gyro_bias is None
    assert check.gyro_left_out is not None
    assert f"the IMU on /imu {said}" in check.gyro_left_out
    assert f"(the gyro left out: the IMU on /imu {said}" in check.words()
    assert check.to_dict()["gyro_left_out"] == check.gyro_left_out

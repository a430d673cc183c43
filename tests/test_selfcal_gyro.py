"""The self-calibration with the robot's gyro, end to end on the virtual robot: its truth
is what the robot and its IMU were built with (E_d, E_b, E_s, the gyro's scale k_g and
bias, its mounting), never what the code under test computes.

- with the laser: the gyro calibrated too, within its intervals of the truth and issue
  36's figures (k_g within 0.1 %, the bias within 0.01 deg/s), the wheels as the routine
  promises;
- without a laser: the wheels relative to the gyro, ``E_b k_g / E_s`` within its
  interval, said so in the terminal, the JSON and on the page, and not "apply";
- the IMU given and left out by the command's options.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace
from html import unescape

import numpy as np
import pytest

import umbmark
from umbmark.jobs.selfcal_anywhere import AnywhereReport, selfcal_anywhere
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import ROOM_LASER, room_world
from umbmark.sim.imu import ImuSetup

from helpers import run_cli

DEG = math.pi / 180.0
E_D, E_B, E_S = 1.004, 0.97, 1.01
#: The routine's promises (issue 23), and issue 36's for the gyro.
TOL_E_D, TOL_E_B, TOL_E_S = 5e-4, 0.002, 0.002
TOL_K_G, TOL_BIAS = 1e-3, 0.01 * DEG


def _covers(interval: tuple[float, float] | None, truth: float) -> bool:
    return interval is not None and interval[0] <= truth <= interval[1]


@pytest.mark.slow
def test_with_the_laser_the_gyro_is_calibrated_too() -> None:
    """A gyro that reads 3 % high (k_g 0.97), a bias of 0.5 deg/s that does not walk (so
    that its truth is one number), mounted rolled 1 deg (stated so: its yaw bias is the
    IMU's bias in the base frame)."""
    setup = ImuSetup(gyro_scale=0.97, gyro_bias=0.5 * DEG, gyro_bias_walk=0.0,
                     imu_roll=1.0 * DEG)  # fmt: skip
    robot = VirtualRobot(E_D, E_B, E_S, slip=0.0004, seed=3, world=room_world(),
                         laser_pose=(ROOM_LASER.x, ROOM_LASER.y, ROOM_LASER.theta),
                         imu=setup)  # fmt: skip
    report = umbmark.selfcal(robot, routine="anywhere", verify=False)
    assert isinstance(report, AnywhereReport)
    gyro = report.calibration.gyro
    assert gyro is not None
    assert gyro.reference == "scan matching"
    raw = robot.imu_readings(-math.inf)
    assert raw is not None
    yaw_bias = float((setup.rotation @ raw.bias[-1])[2])
    assert _covers(gyro.interval("k_g"), 0.97), gyro.interval("k_g")
    assert abs(gyro.values["k_g"] - 0.97) < TOL_K_G * 0.97
    # within 3 standard errors (this seed: -2.5; seeds 1, 2, 4, 5: within 0.6) and
    # issue 36's 0.01 deg/s (this seed: 0.0026 deg/s)
    error = gyro.values["bias"] - yaw_bias
    assert abs(error) < 3.0 * gyro.standard_errors["bias"], error
    assert abs(error) < TOL_BIAS
    est = report.calibration.report.estimate
    assert est.method == "gyro"
    assert abs(est.E_d - E_D) < TOL_E_D
    assert abs(est.E_b - E_B) < TOL_E_B
    assert est.E_s is not None
    assert abs(est.E_s - E_S) < TOL_E_S
    assert report.laser
    assert report.imu is not None
    assert "/imu" in report.imu
    data = report.to_dict()
    assert data["calibrated_against"].startswith("the laser's scan matching and the gyro")
    assert data["gyro_calibration"]["values"]["k_g"] == gyro.values["k_g"]
    assert report.calibration.report.verdict.applies
    assert any("gyro: the IMU on /imu" in c for c in report.checks)


@pytest.mark.slow
def test_without_a_laser_the_wheels_are_relative_to_the_gyro(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """``selfcal --sim --sim-no-laser --routine anywhere``: E_d (free of the gyro's scale)
    and E_b k_g / E_s (the command's IMU: k_g 1.02) within their intervals of the truth;
    the terminal, the JSON and the page say it, and the verdict is not "apply"."""
    k_g = 1.02  # --sim-gyro-scale's default
    args = ["selfcal", "--sim", "--routine", "anywhere", "--sim-no-laser", "--sim-E-s",
            str(E_S)]  # fmt: skip
    proc = run_cli(*args, "--out", str(tmp_path / "j"), "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    gyro = data["gyro_calibration"]
    assert data["laser"] is False
    assert gyro["reference"] == "no reference"
    assert "the gyro alone" in data["calibrated_against"]
    low, high = gyro["intervals_95"]["E_d"]
    assert low < E_D < high
    assert abs(gyro["values"]["E_d"] - E_D) < TOL_E_D
    product = E_B * k_g / E_S  # what wheels and gyro alone identify
    low, high = gyro["intervals_95"]["E_b_k_g"]
    assert low < product < high, (low, high, product)
    assert "k_g" not in gyro["values"]
    assert gyro["relative_to_gyro"] == ["E_b"]
    # at best with care: E_b k_g's interval, widened by the 3 % tolerance, holds 1
    assert data["verdict"]["level"] == "care"
    assert any("gyro alone" in w for w in data["warnings"])
    text = run_cli(*args, "--out", str(tmp_path / "t"))
    assert text.returncode == 0, text.stderr
    assert "no laser: the wheels are calibrated against the gyro alone" in text.stderr
    assert "warning: calibrated against the gyro alone (no laser)" in text.stderr
    assert re.search(r"E_b k_g = 0\.97\d+ (?:±|\+-) 0\.000\d+: the wheelbase relative to the gyro",
                     text.stdout), text.stdout  # fmt: skip
    page = unescape((tmp_path / "t" / "report.html").read_text(encoding="utf-8"))
    gyro_section = page.split('<section id="imu">', 1)[1].split("</section>", 1)[0]
    assert "the gyro alone (no laser)" in gyro_section
    assert "E_b k_g" in gyro_section
    assert "no laser" in gyro_section
    assert "The robot has no laser: no mounting was fitted." in page


@pytest.mark.slow
def test_the_imu_options_of_the_virtual_robot_are_checked(tmp_path) -> None:  # type: ignore[no-untyped-def]
    proc = run_cli("selfcal", "--sim", "--sim-gyro-scale", "3", cwd=tmp_path)
    assert proc.returncode == 2
    assert "--sim-gyro-scale" in proc.stderr
    assert "Traceback" not in proc.stderr
    proc = run_cli("selfcal", "--sim", "--no-imu", "--imu-topic", "/imu", cwd=tmp_path)
    assert proc.returncode == 2
    assert "--imu-topic and --no-imu" in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_the_robots_imu_as_connect_makes_it() -> None:
    from umbmark.robot.connect import connect

    with_imu = connect("sim", imu=ImuSetup(gyro_scale=0.98), room=True)
    assert with_imu.imu() is not None
    assert with_imu.scan() is not None
    bare = connect("sim", laser=False)
    assert bare.imu() is None
    assert bare.scan() is None
    np.testing.assert_allclose(with_imu.imu().mounting.rotation, np.eye(3))  # type: ignore[union-attr]


@pytest.mark.slow
@pytest.mark.parametrize(("fault", "said"), [("silent", "fell silent"), ("frozen", "froze")])
def test_a_gyro_failing_mid_pattern_is_left_out_for_the_laser(fault, said) -> None:  # type: ignore[no-untyped-def]
    """The IMU's driver fails 20 s into the pattern (driven once): the routine goes on with
    the laser's scan matching alone, warned, the gyro's figures absent; E_d and E_b are
    the laser's (within the routine's promise of the truth), not bent by a dead gyro."""
    from faulty_imu import FaultyImu

    robot = FaultyImu(fault, 20.0, E_d=E_D, E_b=E_B, E_s=E_S, slip=0.0004, seed=3,
                      world=room_world(), imu=ImuSetup(gyro_scale=0.97),
                      laser_pose=(ROOM_LASER.x, ROOM_LASER.y, ROOM_LASER.theta))  # fmt: skip
    report = selfcal_anywhere(robot, verify=False, repeats=1)
    assert isinstance(report, AnywhereReport)
    assert report.calibration.gyro is None
    est = report.calibration.report.estimate
    assert est.method == "scan-matching"
    assert abs(est.E_d - E_D) < TOL_E_D
    assert abs(est.E_b - E_B) < TOL_E_B
    warned = [w for w in report.calibration.report.warnings if f"the IMU on /imu {said}" in w]
    assert len(warned) == 1
    assert "the gyro is left out" in warned[0]
    data = report.to_dict()
    assert data["gyro_calibration"] is None
    assert data["calibrated_against"].startswith("the laser's scan matching alone")


@pytest.mark.slow
def test_without_a_laser_a_gyro_falling_silent_is_refused(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """No laser, and the IMU silent from 20 s into the pattern: nothing else measured the
    turns, so one line (the routine's InputError: exit 2 on the command line), nothing
    calibrated, nothing recorded."""
    from faulty_imu import FaultyImu
    from umbmark.core.errors import InputError
    from umbmark.robot.world import corner_world

    robot = FaultyImu("silent", 20.0, E_d=E_D, E_b=E_B, seed=3, imu=ImuSetup(),
                      world=replace(corner_world(), lidar=None))  # fmt: skip
    with pytest.raises(InputError) as caught:
        selfcal_anywhere(robot, verify=False, repeats=1, out=tmp_path / "o")
    line = str(caught.value)
    # silent from 20 s of the robot's clock: the drive began after the robot settled
    found = re.search(
        r"the IMU on /imu fell silent (\d+\.\d) s into the (\d+\.\d) s the robot", line
    )
    assert found is not None, line
    assert 17.0 < float(found[1]) < 20.0 < float(found[2])
    assert "nothing calibrated, nothing applied" in line
    assert "\n" not in line
    assert robot.drive_params().wheel_separation_multiplier == 1.0

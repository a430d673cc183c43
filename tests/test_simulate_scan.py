"""``umbmark simulate --bag X --scan``: a 2D laser in the simulated bag (issue 30, item 10),
calibrated by ``calibrate X --scan-topic /scan`` with no other option: the nominal wheels
and the laser's mounting from the bag's robot description, the truth from the simulation's
options (E_d 1.002 and E_b 1.01, many standard errors from 1), the mounting the one the
simulator put the laser at (0.1 m ahead of the axle)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import umbmark

from helpers import cli_error, cli_json, run_cli

pytest.importorskip("rosbags")

E_D, E_B = 1.002, 1.01
SIM = {"E_d": E_D, "E_b": E_B, "side_length": 1.0, "runs": 2, "seed": 3, "dt": 0.02}


def _check(data: dict) -> None:  # type: ignore[type-arg]
    se = data["standard_errors"]
    for key, truth in (("E_d", E_D), ("E_b", E_B), ("E_s", 1.0)):
        assert abs(data[key] - truth) < 4 * se[key], (key, data[key], se[key])
    # an uncalibrated answer (1) is many standard errors off
    assert 8 * se["E_d"] < E_D - 1
    assert 8 * se["E_b"] < E_B - 1
    x, y, yaw = data["laser_pose"]
    assert abs(x - 0.1) < 0.003  # [m]
    assert abs(y) < 0.003
    assert abs(yaw) < math.radians(0.3)
    assert data["nominal"] == {"wheelbase": 0.34, "wheel_diameter": 0.15}


@pytest.mark.slow
def test_a_simulated_bag_with_a_laser_calibrates_by_scan_matching(tmp_path: Path) -> None:
    bag = tmp_path / "room"
    umbmark.simulate(**SIM, bag=bag, bag_storage="mcap", scan=True)
    report = umbmark.calibrate(bag, scan_topic="/scan")
    _check(report.to_dict())
    assert any("from the bag's robot description" in note for note in report.notes)
    assert any("from /tf_static in base_link: laser at x = 0.1000 m" in n for n in report.notes)


@pytest.mark.slow
def test_the_commands_as_the_docs_show_them(tmp_path: Path) -> None:
    bag = tmp_path / "room.bag"
    args = ["--E-d", "1.002", "--E-b", "1.01", "-L", "1", "--runs", "2", "--seed", "3"]
    proc = run_cli("simulate", *args, "--dt", "0.02", "--bag", str(bag), "--scan")
    assert proc.returncode == 0, proc.stderr
    _check(cli_json("calibrate", str(bag), "--scan-topic", "/scan"))
    info = run_cli("info", str(bag)).stdout
    assert "--scan-topic /scan" in info
    # without --bag there is nothing to put a laser into
    assert "--scan writes a laser into --bag" in cli_error("simulate", *args, "--scan")

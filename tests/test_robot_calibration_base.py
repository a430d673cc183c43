"""The reimplementation of ROS robot_calibration's base calibration
(``tools/robot_calibration_base.py``) holds to its source, and umbmark's gyro estimator
finds the truth on the same simulated spins (the table of ``docs/estimators.md``)."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from helpers import ROOT

sys.path.insert(0, str(ROOT / "tools"))

import robot_calibration_base as rc


def test_the_formula_is_printcalibrationdatas():
    # by hand: (6.3 - 6) / 6 = 0.05 and (-6.3 + 6) / -6 = 0.05; (6.3 - 6.6) / 6.6 and
    # (-6.3 + 6.0) / -6.0 average to (-0.0454545 + 0.05) / 2 = 0.00227273
    track, gyro = rc.base_calibration([6.3, -6.3], [6.0, -6.0], [6.6, -6.0], 0.34, 0.001221729)
    assert track == pytest.approx(0.34 * 1.05, rel=1e-12)
    assert gyro == pytest.approx(0.001221729 * (1 + (-0.3 / 6.6 + 0.05) / 2), rel=1e-12)


def test_the_wall_angle_is_the_robots_turn_from_the_wall():
    # a wall 2 m ahead, the robot turned 0.1 rad counter-clockwise from it: the beam at
    # angle a meets it at 2 / cos(a + 0.1); the line's slope in (sin(a) r, cos(a) r) is
    # tan(0.1)
    beams = np.linspace(-0.6, 0.6, 241)
    assert rc.wall_angle(2.0 / np.cos(beams + 0.1), beams) == pytest.approx(0.1, abs=1e-12)


def test_on_the_spins_umbmark_finds_the_truth():
    for row in rc.compare():
        assert abs(row["ours_E_b_k_g"] - row["E_b_k_g"]) < 4 * row["ours_E_b_k_g_se"]
        assert abs(row["ours_E_b"] - row["E_b"]) < 4 * row["ours_E_b_se"]
        assert abs(row["ours_k_g"] / row["k_g"] - 1) < 1e-3
        assert math.isfinite(row["rc_E_b"])
        assert math.isfinite(row["rc_k_g"])

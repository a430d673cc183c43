"""The corrected odometry: the wheels integrated with the present calibration."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.monitor.corrected import Integrator, WheelCalibration


def test_a_straight_and_a_turn_with_the_calibration() -> None:
    cal = WheelCalibration(0.075, 0.076, 0.35, 1e-5, 1e-5, 1e-4)
    odo = Integrator(cal)
    assert odo.odometry() is None
    odo.update(0.0, (0.0, 0.0))
    phi = 1.0 / 0.0755  # both wheels the same rotation: an arc of the radii's difference
    odo.update(1.0, (phi, phi))
    turn = (0.076 - 0.075) * phi / 0.35
    travel = 0.5 * (0.075 + 0.076) * phi
    got = odo.odometry()
    assert got is not None
    assert got.pose.theta == pytest.approx(turn)
    chord = travel * math.sin(turn / 2) / (turn / 2)
    assert got.pose.x == pytest.approx(chord * math.cos(turn / 2))
    assert got.pose.y == pytest.approx(chord * math.sin(turn / 2))
    assert got.linear == pytest.approx(travel)
    cov = got.pose_covariance
    assert cov.shape == (6, 6)
    assert np.allclose(cov, cov.T)
    assert cov[0, 0] > 0
    assert cov[5, 5] > 0
    assert np.all(np.linalg.eigvalsh(cov) >= -1e-15)

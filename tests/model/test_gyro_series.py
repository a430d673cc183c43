"""A gyro's readings: shapes checked, and the yaw rate integrated over intervals exactly
for rates linear between samples (closed forms by hand)."""

from __future__ import annotations

import numpy as np
import pytest

from umbmark.model.gyro_series import GyroSeries


def test_the_yaw_change_of_a_constant_and_a_ramp_is_their_integral():
    t = np.linspace(0.0, 10.0, 101)
    rate = np.zeros((101, 3))
    rate[:, 2] = 0.5 + 0.1 * t  # a ramp: integral 0.5 (b - a) + 0.05 (b^2 - a^2)
    gyro = GyroSeries(t, rate)
    start, end = np.array([0.0, 1.234, 9.5]), np.array([10.0, 5.678, 9.5])
    expected = 0.5 * (end - start) + 0.05 * (end**2 - start**2)
    np.testing.assert_allclose(gyro.yaw_change(start, end), expected, rtol=1e-12, atol=1e-15)


def test_bad_shapes_and_times_are_refused():
    t = np.arange(3.0)
    with pytest.raises(ValueError, match="shape"):
        GyroSeries(t, np.zeros((3, 2)))
    with pytest.raises(ValueError, match="increase strictly"):
        GyroSeries(np.array([0.0, 1.0, 1.0]), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="not finite"):
        GyroSeries(t, np.array([[0.0, 0.0, np.nan]] * 3))
    with pytest.raises(ValueError, match="accelerations"):
        GyroSeries(t, np.zeros((3, 3)), accel=np.zeros((2, 3)))

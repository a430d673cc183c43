"""Kinematics against closed forms: Eq. 2.1, Eqs. 2.2/4.33, straight line, rotation, arc."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.model.kinematics import WheelParams, integrate_odometry, wheel_displacements

METHODS = ("arc", "midpoint", "segment")


def test_conversion_factor_is_eq_2_1():
    # c_m = pi D_n / (n C_e): a 150 mm wheel, 1000-pulse encoder on a 20:1 gear.
    params = WheelParams(
        wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=1000, gear_ratio=20
    )
    assert params.conversion_factor == pytest.approx(math.pi * 0.15 / 20_000)
    # OptiOdom robot: D = 84 mm, 64 pulses per motor turn, 43.7:1 gear.
    optiodom = WheelParams(0.2, 0.084, encoder_resolution=64, gear_ratio=43.7)
    assert optiodom.conversion_factor == pytest.approx(9.4356e-5, rel=1e-4)


def test_wheel_displacements_apply_correction_factors_eq_4_33():
    params = WheelParams(0.34, 0.1, encoder_resolution=100, c_left=0.99, c_right=1.01)
    c_m = math.pi * 0.1 / 100
    left, right = wheel_displacements([10, -20], [30, 40], params)
    np.testing.assert_allclose(left, [0.99 * c_m * 10, -0.99 * c_m * 20])
    np.testing.assert_allclose(right, [1.01 * c_m * 30, 1.01 * c_m * 40])


@pytest.mark.parametrize("method", METHODS)
def test_straight_line(method):
    poses = integrate_odometry(np.full(50, 0.02), np.full(50, 0.02), 0.3, method=method)
    np.testing.assert_allclose(poses[-1], [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(poses[:, 0], np.linspace(0, 1.0, 51), atol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_pure_rotation_stays_in_place(method):
    # Wheels travel +-u: the heading changes by 2u / b per interval, the centre stays.
    u, b, n = 0.001, 0.25, 400
    poses = integrate_odometry(np.full(n, -u), np.full(n, u), b, method=method)
    np.testing.assert_allclose(poses[-1, :2], [0.0, 0.0], atol=1e-15)
    assert poses[-1, 2] == pytest.approx(n * 2 * u / b)


def _arc_increments(radius: float, b: float, total_angle: float, n: int):
    step = total_angle / n
    return np.full(n, (radius - b / 2) * step), np.full(n, (radius + b / 2) * step)


def test_arc_method_is_exact_on_a_constant_curvature_arc_for_any_step():
    # Centre on a circle of radius R about (0, R): x = R sin(phi), y = R (1 - cos(phi)).
    radius, b, phi = 2.0, 0.4, 2.5
    for n in (1, 3, 1000):
        left, right = _arc_increments(radius, b, phi, n)
        end = integrate_odometry(left, right, b, method="arc")[-1]
        np.testing.assert_allclose(
            end, [radius * math.sin(phi), radius * (1 - math.cos(phi)), phi], atol=1e-12
        )


@pytest.mark.parametrize(("method", "order"), [("midpoint", 2), ("segment", 1)])
def test_straight_segment_updates_converge_at_their_order(method, order):
    radius, b, phi = 2.0, 0.4, 2.5
    truth = np.array([radius * math.sin(phi), radius * (1 - math.cos(phi))])
    errs = []
    for n in (100, 200):
        left, right = _arc_increments(radius, b, phi, n)
        errs.append(
            np.linalg.norm(integrate_odometry(left, right, b, method=method)[-1, :2] - truth)
        )
    assert errs[0] / errs[1] == pytest.approx(2**order, rel=0.05)


def test_segment_method_is_borenstein_1996_update():
    # theta_i = theta_{i-1} + dtheta_i; x_i = x_{i-1} + ds_i cos(theta_i), by hand.
    left = [0.10, 0.05, 0.12]
    right = [0.12, 0.09, 0.08]
    b = 0.5
    x = y = th = 0.0
    for dl, dr in zip(left, right, strict=True):
        th += (dr - dl) / b
        x += (dr + dl) / 2 * math.cos(th)
        y += (dr + dl) / 2 * math.sin(th)
    end = integrate_odometry(left, right, b, method="segment")[-1]
    np.testing.assert_allclose(end, [x, y, th], atol=1e-15)


def test_batch_dimensions_pass_through_and_match_single_runs():
    rng = np.random.default_rng(3)
    left = rng.uniform(0, 0.01, (3, 4, 60))
    right = rng.uniform(0, 0.01, (3, 4, 60))
    poses = integrate_odometry(left, right, 0.3)
    assert poses.shape == (3, 4, 61, 3)
    np.testing.assert_allclose(poses[2, 1], integrate_odometry(left[2, 1], right[2, 1], 0.3))


def test_initial_pose_rotates_the_path():
    poses = integrate_odometry([0.5], [0.5], 0.3, initial_pose=[1.0, 2.0, math.pi / 2])
    np.testing.assert_allclose(poses[-1], [1.0, 2.5, math.pi / 2], atol=1e-12)


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="wheelbase"):
        integrate_odometry([0.1], [0.1], 0.0)
    with pytest.raises(ValueError, match="shape"):
        integrate_odometry([0.1, 0.2], [0.1], 0.3)
    with pytest.raises(ValueError, match="method"):
        integrate_odometry([0.1], [0.1], 0.3, method="euler")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="wheel diameter must be > 0"):
        WheelParams(wheelbase=0.3, wheel_diameter=-0.1)

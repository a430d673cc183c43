"""Every frame, sign and unit convention of paper-notes.md, pinned by a test of its own."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.core.conventions import Direction, angle_to_rad, length_to_m, wrap_angle
from umbmark.estimators.base import SquareTest
from umbmark.estimators.dispatch import estimate_errors
from umbmark.estimators.paper import paper_estimate
from umbmark.model.kinematics import integrate_odometry
from umbmark.model.run import EndPose, Run
from umbmark.returns.clusters import umbmark_benchmark

from helpers import runs_around, turtle_square

L, B = 4.0, 0.34


def _runs_from_turtle(turn_deg: float, leg_turn_deg: float) -> list[Run]:
    runs = []
    for direction in ("cw", "ccw"):
        x, y, heading = turtle_square(turn_deg, leg_turn_deg, L, direction, steps=2000)
        odo_heading = (1 if direction == "ccw" else -1) * 2 * math.pi
        for dx in (-0.01, 0.01):  # two runs, symmetric about the true end
            runs.append(
                Run(
                    Direction(direction),
                    EndPose(x + dx, y, heading),
                    EndPose(0.0, 0.0, odo_heading),
                )
            )
    return runs


def test_heading_is_counter_clockwise_positive_and_y_points_left():
    # Right wheel travels farther: the robot turns left (ccw), its heading grows, and it
    # drifts towards +y, the robot's left.
    poses = integrate_odometry(np.full(100, 0.010), np.full(100, 0.011), wheelbase=0.34)
    assert poses[-1, 2] > 0
    assert poses[-1, 1] > 0


def test_x_points_along_the_first_leg():
    poses = integrate_odometry(np.full(10, 0.1), np.full(10, 0.1), wheelbase=0.34)
    np.testing.assert_allclose(poses[-1], [1.0, 0.0, 0.0], atol=1e-12)


def test_ccw_run_turns_left_and_cw_run_turns_right():
    # An error-free square: ccw ends with heading +2 pi, cw with -2 pi.
    assert turtle_square(90, 0, L, "ccw", steps=10)[2] == pytest.approx(2 * math.pi)
    assert turtle_square(90, 0, L, "cw", steps=10)[2] == pytest.approx(-2 * math.pi)
    assert Direction.CCW.turn_sign == 1
    assert Direction.CW.turn_sign == -1
    assert Direction.from_heading_change(6.2) is Direction.CCW
    assert Direction.from_heading_change(-6.2) is Direction.CW


def test_return_error_is_absolute_minus_calculated():
    run = Run(Direction.CW, EndPose(0.30, -0.10, 0.05), EndPose(0.10, 0.20, 0.02))
    assert run.return_error == pytest.approx((0.20, -0.30))
    assert run.heading_error == pytest.approx(0.03)


def test_heading_error_is_wrapped_so_a_full_turn_is_no_error():
    # Absolute heading measured in (-pi, pi], odometry unwrapped after a ccw loop.
    run = Run(Direction.CCW, EndPose(0, 0, -0.01), EndPose(0, 0, 2 * math.pi + 0.01))
    assert run.heading_error == pytest.approx(-0.02)


def test_under_turning_robot_gives_positive_alpha_and_E_b_above_one():
    # Turns 89 deg for every commanded 90 deg: the paper's Fig. 7 (Type A, E_b > 1).
    est = paper_estimate(umbmark_benchmark(_runs_from_turtle(89.0, 0.0)), SquareTest(L, B))
    assert est.alpha > 0
    assert est.E_b > 1
    assert est.alpha == pytest.approx(math.radians(1.0), rel=0.05)


def test_legs_curving_left_give_positive_beta_and_E_d_above_one():
    # Each leg bends 0.5 deg to the left: right wheel larger, D_R / D_L > 1 (Fig. 8).
    est = paper_estimate(umbmark_benchmark(_runs_from_turtle(90.0, 0.5)), SquareTest(L, B))
    assert est.beta > 0
    assert est.E_d > 1
    assert est.beta == pytest.approx(math.radians(0.5), rel=0.05)


def test_heading_method_uses_the_same_signs():
    runs = _runs_from_turtle(89.0, 0.5)
    est = estimate_errors("heading", umbmark_benchmark(runs), runs, SquareTest(L, B))
    assert est.alpha == pytest.approx(math.radians(1.0), rel=1e-6)
    assert est.beta == pytest.approx(math.radians(0.5), rel=1e-6)


def test_units_convert_to_si():
    assert length_to_m(1234.0, "mm") == pytest.approx(1.234)
    assert length_to_m(12.0, "cm") == pytest.approx(0.12)
    assert angle_to_rad(180.0, "deg") == pytest.approx(math.pi)
    with pytest.raises(ValueError, match="unknown length unit"):
        length_to_m(1.0, "ft")


@pytest.mark.parametrize(
    ("angle", "wrapped"), [(0.0, 0.0), (2 * math.pi + 0.1, 0.1), (-math.pi - 0.1, math.pi - 0.1)]
)
def test_wrap_angle_lands_in_minus_pi_to_pi(angle, wrapped):
    assert wrap_angle(angle) == pytest.approx(wrapped)


@pytest.mark.parametrize(
    ("label", "direction"),
    [
        ("cw", Direction.CW),
        (" CCW ", Direction.CCW),
        ("Clockwise", Direction.CW),
        ("counter-clockwise", Direction.CCW),
    ],
)
def test_direction_labels_in_any_case(label, direction):
    assert Direction.parse(label) is direction


def test_unknown_direction_label_is_refused():
    with pytest.raises(ValueError, match="neither cw nor ccw"):
        Direction.parse("left")


def test_runs_helper_centres_are_exact():
    rows = runs_around({"cw": (0.1, -0.2), "ccw": (0.3, 0.4)}, spread=0.05)
    cw = np.array([r[1:3] for r in rows if r[0] == "cw"])
    np.testing.assert_allclose(cw.mean(axis=0), [0.1, -0.2], atol=1e-15)


@pytest.mark.slow
def test_tracked_point_off_the_axle_adds_rotated_offset_to_return_errors(tmp_path):
    """A marker at d in the robot frame: eps_marker = eps_axle + (R(dtheta) - I) d, with
    dtheta the run's true heading change; --truth-offset d takes it away."""
    import umbmark
    from umbmark.model.kinematics import WheelParams
    from umbmark.sim.robot import SimRobot

    from helpers import session_log, simulated_session

    odo = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
    robot = SimRobot.with_errors(odo, E_d=1.004, E_b=1.02)
    session = simulated_session(robot, ["cw", "cw", "ccw", "ccw"], side=1.0, rest=2.0)
    axle = session[2]
    d = (0.25, -0.08)
    # the marker's pose, by hand: the axle's position plus d turned by the heading
    c, s = np.cos(axle[:, 2]), np.sin(axle[:, 2])
    marker = np.column_stack(
        [axle[:, 0] + c * d[0] - s * d[1], axle[:, 1] + s * d[0] + c * d[1], axle[:, 2]]
    )
    at_axle = umbmark.calibrate(session_log(tmp_path / "axle", session, axle))
    at_marker = umbmark.calibrate(session_log(tmp_path / "marker", session, marker))
    for run_axle, run_marker in zip(at_axle.runs, at_marker.runs, strict=True):
        dtheta = run_axle.true_end.theta
        bias = (
            (math.cos(dtheta) - 1.0) * d[0] - math.sin(dtheta) * d[1],
            math.sin(dtheta) * d[0] + (math.cos(dtheta) - 1.0) * d[1],
        )
        eps_axle, eps_marker = run_axle.return_error, run_marker.return_error
        # the run log keeps micrometres
        assert eps_marker[0] - eps_axle[0] == pytest.approx(bias[0], abs=3e-6)
        assert eps_marker[1] - eps_axle[1] == pytest.approx(bias[1], abs=3e-6)
        assert abs(bias[0]) + abs(bias[1]) > 1e-3  # the bias is there to see
    moved = umbmark.calibrate(tmp_path / "marker", truth_offset=d)
    for run_axle, run_moved in zip(at_axle.runs, moved.runs, strict=True):
        assert run_moved.return_error == pytest.approx(run_axle.return_error, abs=3e-6)
    assert moved.estimate.E_b == pytest.approx(at_axle.estimate.E_b, abs=1e-5)
    assert abs(at_marker.estimate.E_b - at_axle.estimate.E_b) > 1e-4

"""Controller parameter files as the controllers read them, and overlays they will read.

What the controllers do is taken from their sources: ros2_controllers'
``diff_drive_controller`` (parameters ``left_wheel_names``, ``open_loop``, the three
multipliers) and ROS 1's ``diff_drive_controller`` (``wheel_radius_multiplier``, when set,
used for both wheels instead of the left and right ones).
"""

from __future__ import annotations

import math

import pytest
import yaml

import umbmark
from umbmark.sources.params.reader import read_controller_params

from helpers import linear_cgs, runs_around


def _file(tmp_path, text: str, name: str = "controllers.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _runs(table):
    rows = runs_around(linear_cgs(math.radians(-1.0), math.radians(0.5), 4.0), 0.02)
    return table(rows)


def test_ros1_wheel_radius_multiplier_takes_precedence(tmp_path):
    path = _file(
        tmp_path,
        "husky_velocity_controller:\n  type: diff_drive_controller/DiffDriveController\n"
        "  wheel_separation: 0.555\n  wheel_radius: 0.1651\n  wheel_radius_multiplier: 1.02\n"
        "  left_wheel_radius_multiplier: 0.9\n  left_wheel: [front_left_wheel, rear_left_wheel]\n"
        "  right_wheel: [front_right_wheel, rear_right_wheel]\n",
    )
    params = read_controller_params(path)
    assert params.ros2 is False
    assert params.left_wheel_radius_multiplier == 1.02  # not 0.9: ROS 1 ignores it
    assert params.right_wheel_radius_multiplier == 1.02
    assert params.radius_multiplier == 1.02
    assert params.left_joints == ("front_left_wheel", "rear_left_wheel")


def test_ros1_overlay_says_to_delete_wheel_radius_multiplier(tmp_path, table):
    path = _file(
        tmp_path,
        "husky_velocity_controller:\n  wheel_separation: 0.34\n  wheel_radius_multiplier: 1.02\n",
    )
    report = umbmark.calibrate(_runs(table), side_length=4, current_params=path)
    text = report.ros1_yaml()
    assert "Delete wheel_radius_multiplier (1.02)" in text
    # A ROS 1 controller reads its parameters when it is loaded: no ROS 2 "configure".
    assert "on configure" not in text
    assert "reads these when it is loaded: load them (rosparam load)" in text
    assert "reads these on configure" in report.overlay_yaml()  # the ROS 2 overlay
    values = yaml.safe_load(text)["husky_velocity_controller"]
    # The new left and right multipliers include the 1.02 that was active.
    est = report.estimate
    assert values["left_wheel_radius_multiplier"] == pytest.approx(
        1.02 * 2 / (est.E_d + 1), rel=1e-9
    )


@pytest.mark.parametrize(
    ("text", "keys"),
    [
        ("diff_cont:\n  ros__parameters:\n    wheel_separation: 0.34\n", ["diff_cont"]),
        (
            "robot1:\n  diff_cont:\n    ros__parameters:\n      wheel_separation: 0.34\n",
            ["robot1", "diff_cont"],
        ),
        (
            "/robot1/diff_cont:\n  ros__parameters:\n    wheel_separation: 0.34\n",
            ["/robot1/diff_cont"],
        ),
        ("/**:\n  ros__parameters:\n    wheel_separation: 0.34\n", ["/**"]),
    ],
)
def test_the_overlay_is_keyed_as_the_users_file(tmp_path, table, text, keys):
    path = _file(tmp_path, text)
    report = umbmark.calibrate(_runs(table), side_length=4, current_params=path)
    overlay = yaml.safe_load(report.overlay_yaml())
    node = overlay
    for key in keys:
        assert list(node) == [key]
        node = node[key]
    assert set(node["ros__parameters"]) == {
        "wheel_separation_multiplier",
        "left_wheel_radius_multiplier",
        "right_wheel_radius_multiplier",
    }


def test_a_namespaced_controller_is_named_by_its_path_or_its_name(tmp_path):
    path = _file(
        tmp_path,
        "robot1:\n  diff_cont:\n    ros__parameters:\n      wheel_separation: 0.4\n"
        "robot2:\n  other_cont:\n    ros__parameters:\n      wheel_separation: 0.5\n",
    )
    assert read_controller_params(path, "other_cont").key_path == ("robot2", "other_cont")
    assert read_controller_params(path, "/robot1/diff_cont").wheel_separation == 0.4


def test_open_loop_is_read_and_said(tmp_path, table):
    path = _file(
        tmp_path,
        "diff_drive_base_controller:\n  ros__parameters:\n    wheel_separation: 0.34\n"
        "    open_loop: true\n    left_wheel_names: [left_wheel_joint]\n"
        "    right_wheel_names: [right_wheel_joint]\n",
    )
    params = read_controller_params(path)
    assert params.open_loop is True
    report = umbmark.calibrate(_runs(table), side_length=4, current_params=path)
    assert "open_loop is true" in report.overlay_yaml()


@pytest.mark.slow
def test_skid_steer_multiplier_is_calibrated_on_top_of_its_large_value(tmp_path):
    """A skid-steer turns as if its wheels were 1.3-2 times the track apart; ros2_control
    models that with wheel_separation_multiplier. Track 0.5 m, multiplier 1.6 active (0.8 m
    effective), true effective wheelbase 0.85 m: the new multiplier is 1.6 * 0.85 / 0.8."""
    from umbmark.model.kinematics import WheelParams
    from umbmark.sim.robot import SimRobot

    from helpers import session_log, simulated_session

    active = WheelParams(wheelbase=0.8, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
    robot = SimRobot.with_errors(active, E_d=1.002, E_b=0.85 / 0.8)
    session = simulated_session(robot, ["cw", "cw", "ccw", "ccw"], side=2.0, rest=2.0)
    log = session_log(tmp_path / "skid", session, session[2], wheelbase=0.8, side=2.0)
    params = _file(
        tmp_path,
        "diff_drive_base_controller:\n  ros__parameters:\n    wheel_separation: 0.5\n"
        "    wheel_separation_multiplier: 1.6\n    wheel_radius: 0.075\n",
    )
    report = umbmark.calibrate(log, current_params=params)
    overlay = yaml.safe_load(report.overlay_yaml())
    values = overlay["diff_drive_base_controller"]["ros__parameters"]
    assert values["wheel_separation_multiplier"] == pytest.approx(1.6 * 0.85 / 0.8, abs=1e-3)
    assert report.calibration.wheelbase_corrected == pytest.approx(0.85, abs=1e-3)

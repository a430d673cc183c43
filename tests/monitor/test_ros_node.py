"""What the monitor's ROS 1 and ROS 2 nodes share, without ROS: the command line split
from ROS's arguments, ROS parameters to options by their specs, joint states to wheel
angles, an IMU's rates into the base frame, and the loop's silence, faults and applying
(fed by the recording core of tests/monitor_recording_core.py: what it is fed is
counted; the monitor's own figures are the real core's tests')."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.monitor.ros_node import (
    NODE_OPTIONS,
    NodeOptions,
    base_yaw_rate,
    node_options,
    parameter_values,
    split_ros_args,
    wheel_angles,
)
from umbmark.options.spec import READ
from umbmark.robot.base import Pose2D
from umbmark.robot.ros_common import Mount

SPECS = (*NODE_OPTIONS, READ["scan_topic"], READ["controller"])


def test_ros_arguments_are_taken_out_of_the_command_line() -> None:
    argv = ["--ros2", "--corrected-odom", "/c", "--ros-args", "-p", "stale_after:=5",
            "--params-file", "f.yaml", "--", "--apply", "at-rest", "_robot:=r2",
            "__name:=umbmark_monitor", "scan:=/front"]  # fmt: skip
    split = split_ros_args(argv)
    assert split.own == ("--ros2", "--corrected-odom", "/c", "--apply", "at-rest")
    assert split.ros2 == ("-p", "stale_after:=5", "--params-file", "f.yaml")
    assert split.ros1 == ("_robot:=r2", "__name:=umbmark_monitor", "scan:=/front")
    assert split_ros_args(["--ros-args", "-r", "__ns:=/r1"]).ros2 == ("-r", "__ns:=/r1")


def test_parameters_become_options_by_their_specs() -> None:
    """A YAML integer for a number option is a float; ``"true"`` (ROS 1's ``_x:=true``
    comes typed, a launch file's text may not) a flag; texts stay texts."""
    got = parameter_values(
        {"stale_after": 5, "corrected_tf": "true", "apply": "at-rest", "scan_topic": "/front",
         "use_sim_time": True, "diagnostic_updater.period": 1.0},
        SPECS, "its ROS parameters",
    )  # fmt: skip
    assert got == {"stale_after": 5.0, "corrected_tf": True, "apply": "at-rest",
                   "scan_topic": "/front"}  # fmt: skip
    assert isinstance(got["stale_after"], float)


@pytest.mark.parametrize(
    ("params", "said"),
    [
        ({"stale_aftr": 5}, "no such option; its parameters are apply, base_frame"),
        ({"apply": "sometimes"}, "sometimes"),
        ({"stale_after": "soon"}, "give a number"),
        ({"stale_after": -1.0}, "stale.after must be > 0"),
        ({"stale_after": 601.0}, "at most 600"),
        ({"corrected_tf": 3}, "give true or false"),
        ({"robot": [1, 2]}, "give a text"),
    ],
)
def test_a_wrong_parameter_is_one_line(params: dict[str, object], said: str) -> None:
    with pytest.raises(InputError, match=said) as err:
        parameter_values(params, SPECS, "f.yaml")
    assert "\n" not in str(err.value)


def test_node_options_from_values_and_defaults() -> None:
    o = node_options({"corrected_odom": "/c", "apply": "at-rest", "left_joint": "a,b",
                      "right_joint": "c", "imu_topic": "", "laser_mount": "0.1,0,180"},
                     robot="r9")  # fmt: skip
    assert (o.corrected_odom, o.apply, o.robot, o.imu_topic) == ("/c", "at-rest", "r9", None)
    assert (o.left_joints, o.right_joints, o.scan_topic) == (("a", "b"), ("c",), "/scan")
    assert o.laser_mount == Pose2D(0.1, 0.0, math.pi)
    assert node_options({}) == NodeOptions(robot="robot")


def test_wheel_angles_from_joint_states() -> None:
    assert wheel_angles(["left_wheel_joint", "right_wheel_joint"], [1.0, 2.0]) == (1.0, 2.0)
    assert wheel_angles(["caster", "wheel_left", "wheel_right"], [9.0, 1.5, -0.5]) == (1.5, -0.5)
    four = ["fl", "rl", "fr", "rr"]
    assert wheel_angles(four, [1.0, 3.0, 4.0, 8.0], ("fl", "rl"), ("fr", "rr")) == (2.0, 6.0)
    assert wheel_angles(["arm_joint"], [0.3]) is None  # another joint_states publisher
    assert wheel_angles(["left_wheel_joint", "right_wheel_joint"], [1.0]) is None
    assert wheel_angles(["left_wheel_joint", "right_wheel_joint"], [1.0, math.nan]) is None


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


@pytest.mark.parametrize(
    ("roll", "pitch"), [(0.0, 0.0), (math.pi, 0.0), (0.0, math.pi / 2), (0.3, -0.2)]
)
def test_the_imus_rates_in_the_base_frame(roll: float, pitch: float) -> None:
    """The base frame's z rate is the z row of the IMU's rotation (URDF rpy: Rz Ry Rx)
    times its rates, built here from the three elementary rotations."""
    w = np.array([0.2, -0.1, 0.7])
    expected = float((_rotation(roll, pitch, 1.1) @ w)[2])
    mount = Mount(Pose2D(0.0, 0.0, 1.1), upside_down=abs(roll) > 1.0, lift=(0.1, roll, pitch))
    assert base_yaw_rate(tuple(w), mount) == pytest.approx(expected, abs=1e-12)
    assert base_yaw_rate(tuple(w), None) == 0.7

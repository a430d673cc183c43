"""The monitor's ROS 2 node against a real ROS 2 graph (slow): tests/ros2_robot_node.py in
the warehouse (``--world warehouse``) at 8x sim time, driven on ordinary missions by
tests/mission_driver.py, /diagnostics read as they arrive by tests/diagnostics_probe.py,
every process in ``.venv-ros2`` on a private domain (test_ros2.ros2_env) and ended by its
PID.

- The wiring, with the recording core (tests/monitor_node_dev.py: the node's plumbing, its
  options as ``--ros-args -p``): 1 Hz, the status name, the robot as hardware_id, STALE
  naming /scan while the laser is muted, the corrected odometry in the controller's
  frames, SIGTERM exit 0.
- With the real core, started as a user would (``umbmark monitor --ros2``): a wheel
  changed and the laser knocked mid-run, against the robot node's truth file
  (tests/test_monitor_ros.py has the ROS 1 twin).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from monitor_graph import (
    DEV,
    END_AT,
    KNOCK_AT,
    WHEEL_AT,
    check_changes,
    check_wiring,
    run_changes,
    run_wiring,
)
from test_ros2 import PYTHON, ROOT, T0, Robot2, ros2_env

#: ``umbmark monitor --ros2`` as a user starts it, and the recording core's node.
COMMAND = (str(PYTHON), "-m", "umbmark", "monitor", "--ros2")
RECORDING = (str(PYTHON), str(DEV))
#: The robot's speed-up for that run: the monitor takes 10x a robot's message rates at
#: 10x (rclpy's callbacks in one thread: 500 joint states, 500 odometries and 100 sweeps a
#: wall second), which on two shared cores lost a sixth of the joint states (gaps up to
#: 4 s); at 4x it keeps up.
CHANGES_RATE = "4"


def _env(tmp: Path) -> dict[str, str]:
    env = ros2_env(tmp)
    env["PYTHONPATH"] = f"{ROOT / 'src'}{os.pathsep}{ROOT / 'tests'}"
    return env


@pytest.mark.slow
@pytest.mark.parametrize("core", ["recording", "umbmark"])
def test_ros2_monitor_wiring_on_missions(tmp_path: Path, core: str) -> None:
    """As tests/test_monitor_ros.py's ROS 1 wiring test, on ROS 2, the options as ROS
    parameters (``--ros-args -p``)."""
    env = _env(tmp_path)
    robot = Robot2(env, "--world", "warehouse")
    options = ("stale_after:=1.0", "robot:=r7", "corrected_odom:=/odom_corrected")
    argv = [*(RECORDING if core == "recording" else COMMAND), "--ros-args"]
    argv += [word for option in options for word in ("-p", option)]
    try:
        run = run_wiring(str(PYTHON), "--ros2", env, tmp_path, argv, core == "recording")
    finally:
        robot.close()
    check_wiring(run)


@pytest.mark.slow
def test_ros2_monitor_flags_a_wheel_changed_and_a_laser_knocked(tmp_path: Path) -> None:
    """``umbmark monitor --ros2`` beside the robot on missions, a wheel changed and the
    laser knocked mid-run: as tests/test_monitor_ros.py's ROS 1 twin."""
    env = _env(tmp_path)
    truth = tmp_path / "truth.json"
    events = ("--change-wheel-at", str(WHEEL_AT), "--knock-laser-at", str(KNOCK_AT))
    robot = Robot2(env, "--world", "warehouse", "--rate", CHANGES_RATE, "--no-imu",
                   "--joint-states", *events, "--truth", str(truth))  # fmt: skip
    argv = [*COMMAND, "--ros-args", "-p", "robot:=r7", "-p", "imu_topic:=none"]
    try:
        run = run_changes(str(PYTHON), "--ros2", env, tmp_path, argv, truth, T0 + END_AT, 600.0)
    finally:
        robot.close()
    check_changes(run, truth)

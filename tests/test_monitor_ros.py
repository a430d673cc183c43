"""The monitor's nodes against real ROS graphs (slow).

- ROS 1 (a master on a free port and tests/ros1_robot_node.py at 8x sim time, ended by
  their PIDs: test_ros1.RosGraph): the node with the recording core
  (tests/monitor_node_dev.py, the node's plumbing only) publishes /diagnostics as the
  probe receives them, STALE naming /odom while the robot's odometry is muted, OK again
  once it returns; SIGTERM ends it with one line and exit 0.
- On warehouse missions (``--world warehouse``, tests/mission_driver.py driving; the
  statuses read as they arrive by tests/diagnostics_probe.py; tests/monitor_graph.py):
  the wiring with the recording core, and the same with ``umbmark monitor --ros1``; the
  real core against the robot's truth file, a wheel changed and the laser knocked
  mid-run (tests/robot_node_events.py).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from monitor_graph import (
    END_AT,
    KNOCK_AT,
    WHEEL_AT,
    check_changes,
    check_wiring,
    run_changes,
    run_wiring,
)
from test_ros1 import T0, RosGraph

ROOT = Path(__file__).resolve().parents[1]
DEV = Path(__file__).with_name("monitor_node_dev.py")

PROBE1 = r"""
import json, sys, time, rospy
from diagnostic_msgs.msg import DiagnosticArray
from std_msgs.msg import String
rospy.init_node("monitor_probe", disable_signals=True)
seen = []
rospy.Subscriber("/diagnostics", DiagnosticArray, lambda m: seen.append(m.status[0]))
control = rospy.Publisher("/sim/control", String, queue_size=10, latch=True)
def until(level, limit):
    start = len(seen); deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        for s in seen[start:]:
            if s.level == level:
                return {"level": s.level, "name": s.name, "hw": s.hardware_id,
                        "values": dict((v.key, v.value) for v in s.values), "message": s.message}
        time.sleep(0.05)
    return None
ok = until(0, 30)
control.publish(String("mute_odom"))
stale = until(3, 20)
control.publish(String("unmute_odom"))
back = until(0, 20)
print(json.dumps({"ok": ok, "stale": stale, "back": back}))
"""


@pytest.mark.slow
def test_ros1_monitor_stale_while_the_odometry_is_silent_and_on_again(tmp_path: Path) -> None:
    g = RosGraph(tmp_path)
    env = {**g.env, "PYTHONPATH": str(ROOT / "src")}
    monitor = subprocess.Popen(
        [sys.executable, str(DEV), "ros1=1", "_stale_after:=1.0", "_robot:=r7"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        probe = subprocess.run([sys.executable, "-c", PROBE1], env=env, capture_output=True,
                               text=True, timeout=120, check=False)  # fmt: skip
        assert probe.returncode == 0, probe.stderr[-2000:]
        got = json.loads(probe.stdout.strip().splitlines()[-1])
        monitor.send_signal(signal.SIGTERM)
        out, err = monitor.communicate(timeout=20)
    finally:
        if monitor.poll() is None:
            monitor.kill()
            monitor.communicate()
        g.close()
    assert monitor.returncode == 0, err[-2000:]
    assert "Traceback" not in err
    assert got["ok"]["name"] == "umbmark_monitor: odometry"
    assert got["ok"]["hw"] == "r7"
    assert got["stale"]["values"]["stale topics"] == "/odom"
    assert got["stale"]["message"].startswith("silent: /odom")
    assert got["back"] is not None
    assert "stale topics" not in got["back"]["values"]
    lines = out.strip().splitlines()
    assert lines[-1].startswith("umbmark_monitor stopped (SIGTERM) after")
    assert "umbmark_monitor: /odom back: going on" in lines


def _graph(tmp: Path, *node_args: str) -> tuple[RosGraph, dict[str, str]]:
    g = RosGraph(tmp, "--world", "warehouse", *node_args)
    return g, {**g.env, "PYTHONPATH": f"{ROOT / 'src'}{os.pathsep}{ROOT / 'tests'}"}


#: ``umbmark monitor --ros1`` as a user starts it, and the recording core's node.
COMMAND = (sys.executable, "-m", "umbmark", "monitor", "--ros1")
RECORDING = (sys.executable, str(DEV), "ros1=1")


@pytest.mark.slow
@pytest.mark.parametrize("core", ["recording", "umbmark"])
def test_ros1_monitor_wiring_on_missions(tmp_path: Path, core: str) -> None:
    """The node beside the robot driven on warehouse missions by tests/mission_driver.py
    (the recording core, and ``umbmark monitor --ros1`` as a user starts it): /diagnostics
    once a wall second, named and the robot its hardware_id (the laser's sweeps reaching
    the recording core); STALE naming /scan while the laser is muted, on again after; the
    corrected odometry in the controller's frames, moving; SIGTERM: one line, exit 0. The
    driver kept the robot clear of every rack and wall."""
    g, env = _graph(tmp_path)
    argv = [*(RECORDING if core == "recording" else COMMAND), "_stale_after:=1.0",
            "_robot:=r7", "_corrected_odom:=/odom_corrected"]  # fmt: skip
    try:
        run = run_wiring(sys.executable, "--ros1", env, tmp_path, argv, core == "recording")
    finally:
        g.close()
    check_wiring(run)


@pytest.mark.slow
def test_ros1_monitor_flags_a_wheel_changed_and_a_laser_knocked(tmp_path: Path) -> None:
    """``umbmark monitor --ros1`` beside the robot on missions: its right wheel 0.6 %
    larger at 240 s (E_d 1.004 -> 1.010), its laser turned 2 degrees at 600 s (/tf_static
    keeping the stated mounting): OK with nothing flagged before; each flagged within the
    core's stated distance after it, its size the truth's (tests/robot_node_events.py)."""
    truth = tmp_path / "truth.json"
    events = ("--change-wheel-at", str(WHEEL_AT), "--knock-laser-at", str(KNOCK_AT))
    g, env = _graph(tmp_path, "--rate", "10", "--no-imu", "--joint-states", *events,
                    "--truth", str(truth))  # fmt: skip
    argv = [*COMMAND, "_robot:=r7", "_imu_topic:=none"]
    try:
        run = run_changes(sys.executable, "--ros1", env, tmp_path, argv, truth, T0 + END_AT, 600.0)
    finally:
        g.close()
    check_changes(run, truth)

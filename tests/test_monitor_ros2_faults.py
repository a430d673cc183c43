"""The monitor's faults over a real ROS 2 graph (slow; docs/monitor.md, "What it does",
items 6 and 8): ``umbmark monitor --ros2`` beside tests/ros2_robot_node.py in the
warehouse at 4x sim time, driven on missions by tests/mission_driver.py, /diagnostics read
as they arrive by tests/diagnostics_probe.py, which also sends the robot node's faults on
/sim/control (tests/robot_node_faults.py); every process on a private domain and ended by
its PID.

- The clock going back: a simulation reset as Gazebo's (``reset_clock``).
- The controller restarted (``restart_controller``: deactivated, configured, activated,
  its odometry from zero), the wheels taken from its odometry.
- The monitor killed (SIGKILL) and started again on the same ``--history``.
- ``--apply at-rest`` after a wheel changed, against the robot node's controller.

Each figure is judged against the robot node's truth (``--truth``), within 4 of its
standard errors (twice its 95 % half-width: a run over a ROS graph is a new draw each time).
"""

from __future__ import annotations

import itertools
import json
import math
import os
import signal
import subprocess
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from monitor_graph import Probe, Process, changes, start_driver, start_probe
from test_ros2 import LASER_X, NODE, PYTHON, ROOT, T0, ros2_env

#: ``umbmark monitor --ros2`` as a user starts it, its robot ``r7``, no IMU.
COMMAND = (str(PYTHON), "-m", "umbmark", "monitor", "--ros2")
#: The robot's speed-up (tests/test_monitor_ros2.py's CHANGES_RATE: the monitor keeps up).
RATE = "4"
#: The window's figures against the truth: within this many 95 % half-widths (4 standard
#: errors).
HALF_WIDTHS = 2.0


def _env(tmp: Path) -> dict[str, str]:
    env = ros2_env(tmp)
    env["PYTHONPATH"] = f"{ROOT / 'src'}{os.pathsep}{ROOT / 'tests'}"
    return env


@dataclass
class Stack:
    """The robot node, the driver, the monitor(s) and the probe of one test."""

    env: dict[str, str]
    tmp: Path
    robot: Process
    driver: Process
    probe: Probe
    monitors: list[Process] = field(default_factory=list)
    robot_final: dict[str, Any] = field(default_factory=dict)
    stopped: list[Process] = field(default_factory=list)

    def stop(self, monitor: Process, sig: int = signal.SIGTERM) -> None:
        """``monitor`` stopped by ``sig``."""
        self.stopped.append(monitor)
        monitor.stop(sig)

    def monitor(self, *parameters: str) -> Process:
        """``umbmark monitor --ros2`` with ``-p`` each of ``parameters`` (robot r7, no IMU)."""
        argv = [*COMMAND, "--ros-args"]
        for p in ("robot:=r7", "imu_topic:=none", *parameters):
            argv += ["-p", p]
        n = len(self.monitors)
        proc = Process(argv, self.env, self.tmp / f"monitor{n}.stderr")
        self.monitors.append(proc)
        return proc

    def rows(self, after: int = 0) -> list[dict[str, Any]]:
        return self.probe.rows()[after:]

    def until(
        self, test: Callable[[dict[str, Any]], bool], timeout: float, after: int = 0
    ) -> dict[str, Any] | None:
        """The first status after the first ``after`` that passes ``test`` (None after
        ``timeout`` wall seconds); a monitor that ended meanwhile fails the test."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for row in self.rows(after):
                if test(row):
                    return row
            ended = [
                m for m in self.monitors if m not in self.stopped and m.proc.poll() is not None
            ]
            assert not ended, self._why("a monitor ended")
            time.sleep(0.2)
        return None

    def until_stamp(self, stamp: float, timeout: float, after: int = 0) -> dict[str, Any]:
        """The first status after the first ``after`` stamped past ROS time ``stamp``."""
        row = self.until(lambda r: r["stamp"] > stamp, timeout, after=after)
        assert row is not None, self._why(f"no status stamped past {stamp} s")
        return row

    def _why(self, what: str) -> str:
        tails = [m.stderr()[-1500:] for m in self.monitors]
        said = [m.lines[-5:] for m in self.monitors]
        return f"{what}; the monitors' stderr: {tails}; their last lines: {said}"


@contextmanager
def stack(tmp: Path, robot_args: Sequence[str], driver_args: Sequence[str] = (),
          odom: str | None = None) -> Iterator[Stack]:  # fmt: skip
    """The robot node (``--world warehouse`` at :data:`RATE`, ``robot_args``), the driver
    and the probe; at the end every monitor stopped (SIGTERM), then the probe, the driver
    and the robot (SIGINT: its ``final``)."""
    env = _env(tmp)
    argv = [str(PYTHON), str(NODE), "--world", "warehouse", "--rate", RATE,
            "--laser-x", str(LASER_X), *robot_args]  # fmt: skip
    robot = Process(argv, env, tmp / "robot.stderr")
    procs = [robot]
    monitors: list[Process] = []
    try:
        if robot.wait_line(lambda line: line == "ready", 60.0) is None:
            raise AssertionError(f"the robot node did not come up: {robot.stderr()[-2000:]}")
        procs.append(driver := start_driver(str(PYTHON), "--ros2", env, tmp, *driver_args))
        extra = ("--odom", odom) if odom else ()
        procs.append(probe := start_probe(str(PYTHON), "--ros2", env, tmp, *extra))
        s = Stack(env, tmp, robot, driver, probe, monitors)
        try:
            yield s
        finally:  # what the probe saw, for a failure's reader
            (tmp / "statuses.jsonl").write_text("".join(json.dumps(r) + "\n" for r in s.rows()))
        for m in monitors:
            m.stop(signal.SIGTERM)
        probe.stop()
        driver.stop(signal.SIGTERM)
        robot.stop(signal.SIGINT)
        line = robot.wait_line(lambda line: line.startswith("final "), 5.0)
        assert line is not None, robot.stderr()[-2000:]
        s.robot_final = json.loads(line[len("final ") :])
    finally:
        for proc in [*monitors, *reversed(procs)]:
            proc.stop()


def _value(row: dict[str, Any], key: str) -> float:
    return float(row["values"][key].split()[0])


def _figure(row: dict[str, Any], name: str) -> tuple[float, float] | None:
    """A figure's value and 95 % half-width on a status, None where not determined."""
    said = row["values"][name]
    if said.startswith("not determined"):
        return None
    words = said.split()
    return float(words[0]), float(words[2])


def _no_change(rows: Sequence[dict[str, Any]]) -> None:
    said = [r["message"] for r in rows if changes(r)]
    assert not said, said[:3]


def _clean(proc: Process) -> None:
    """Exit 0 on SIGTERM, no traceback."""
    assert proc.proc.returncode == 0, proc.stderr()[-2000:]
    assert "Traceback" not in proc.stderr(), proc.stderr()[-2000:]


def _history(path: Path) -> dict[str, Any]:
    """``umbmark history r7 --history FILE --json`` (and as people read it: its drift
    line the same)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    said = []
    for json_out in ((), ("--json",)):
        argv = [str(PYTHON), "-m", "umbmark", "history", "r7", "--history", str(path), *json_out]
        out = subprocess.run(argv, capture_output=True, text=True, timeout=120, env=env,
                             check=False)  # fmt: skip
        assert out.returncode == 0, out.stderr[-2000:]
        said.append(out.stdout)
    data: dict[str, Any] = json.loads(said[1])
    assert data["drift"] is None or data["drift"] in said[0], (data["drift"], said[0][-500:])
    return data


def _stretches(path: Path) -> list[Any]:
    """The monitor's stretches in the history, oldest first (robot r7)."""
    from umbmark.store.history import History
    from umbmark.store.monitor_stretches import read_stretches

    return read_stretches(History(path, read_only=True), "r7", 1000)


def _within_truth(row: dict[str, Any], truth: dict[str, float]) -> None:
    """The window's E_d, E_b, E_s on a status within :data:`HALF_WIDTHS` of the truth."""
    for name in ("E_d", "E_b", "E_s"):
        said = _figure(row, name)
        assert said is not None, (name, row["values"][name])
        value, half = said
        assert abs(value - truth[name]) <= HALF_WIDTHS * half, (name, value, half, truth[name])


# --- 1. the clock going back ---------------------------------------------------------------

#: The reset [s of simulated time since the start], and how long the run goes on after.
RESET_AT, AFTER_RESET = 150.0, 150.0


@pytest.mark.slow
def test_ros2_monitor_a_simulation_reset_restarts_the_window(tmp_path: Path) -> None:
    """/clock back to the start and the robot at its start, as Gazebo's reset (the
    controller not told: ros2_controllers' master moves its odometry by the wheels' jump
    back to 0): no traceback, no change flagged, the window started again (metres
    observed falling back, then growing), OK statuses after it; the history's stretches
    in order."""
    history = tmp_path / "history.sqlite3"
    with stack(tmp_path, ("--no-imu", "--joint-states", "--distro", "rolling")) as s:
        monitor = s.monitor(f"history:={history}")
        before = s.until_stamp(T0 + RESET_AT, 240.0)
        reset_mark = len(s.rows())
        s.probe.control("reset_clock")
        back = s.until(lambda r: r["stamp"] < T0 + RESET_AT - 10.0, 30.0, after=reset_mark)
        assert back is not None, "the clock did not go back"
        back_mark = s.rows().index(back)
        s.until_stamp(T0 + AFTER_RESET, 240.0, after=back_mark)
        s.stop(monitor)
    _clean(monitor)
    rows = s.rows()
    assert s.robot_final["resets"], s.robot_final
    assert len(rows[:reset_mark]) >= 20
    observed = [_value(r, "metres observed [m]") for r in rows[:reset_mark]]
    assert max(observed) > 15.0, observed
    after = rows[back_mark:]
    assert len(after) >= 20
    assert {r["level"] for r in after} == {0}, [r["message"] for r in after if r["level"]][:3]
    _no_change(rows)
    after_metres = [_value(r, "metres observed [m]") for r in after]
    assert after_metres[0] < observed[-1] - 10.0, (observed[-1], after_metres[:5])
    assert max(after_metres) > 15.0, after_metres  # filling again
    odometers = [_value(r, "odometer [m]") for r in rows]
    assert all(b >= a - 1e-6 for a, b in itertools.pairwise(odometers)), "the odometer went back"
    assert before["stamp"] > T0 + RESET_AT
    report = _history(history)  # listed by their times: recorded in the same order
    ids = [c["id"] for c in report["calibrations"]]
    assert len(ids) >= 3, report
    assert ids == sorted(ids), [(c["id"], c["time"]) for c in report["calibrations"]]
    if report["drift"] is not None:
        assert report["drift"].startswith("no drift"), report["drift"]


# --- 2. the controller restarted ------------------------------------------------------------

#: The restart [s of simulated time since the start], and the run's end.
RESTART_AT, RESTART_END = 150.0, 450.0


@pytest.mark.slow
def test_ros2_monitor_a_controller_restart_starts_a_new_stretch(tmp_path: Path) -> None:
    """The controller deactivated, configured and activated again mid-run (its odometry
    from zero), the monitor's wheels from that odometry: no change flagged, the figures
    the truth's, no stretch across the restart and one after it, the corrected odometry
    going on without the jump."""
    history, truth = tmp_path / "history.sqlite3", tmp_path / "truth.json"
    with stack(tmp_path, ("--no-imu", "--truth", str(truth)), odom="/odom_corrected") as s:
        monitor = s.monitor(f"history:={history}", "corrected_odom:=/odom_corrected")
        s.until_stamp(T0 + RESTART_AT, 240.0)
        s.probe.control("restart_controller")
        last = s.until_stamp(T0 + RESTART_END, 240.0)
        s.stop(monitor)
    _clean(monitor)
    rows = [r for r in s.rows() if r["level"] != 3]
    assert {r["level"] for r in rows} == {0}, [r["message"] for r in rows if r["level"]][:3]
    _no_change(rows)
    restart = s.robot_final["controller_restarts"]
    assert len(restart) == 1, restart
    assert "after" in restart[0], restart
    at = T0 + restart[0]["time"]
    bx, by, _ = restart[0]["before"]
    ax, ay, _ = restart[0]["after"]
    assert math.hypot(bx - ax, by - ay) > 3.0, restart  # the controller's odometry jumped
    start = json.loads(truth.read_text())["start"]
    _within_truth(last, start)
    stretches = _stretches(history)
    spans = [(st.time, st.time + st.wall_end - st.wall_start) for st in stretches]
    assert not [sp for sp in spans if sp[0] < at < sp[1]], (at, spans)
    assert [sp for sp in spans if sp[0] > at], (at, spans)  # a new stretch after it
    odoms = s.probe.rows("odom")
    near = [o for o in odoms if abs(o["stamp"] - at) < 20.0]
    assert len(near) >= 10, len(near)
    steps = [math.hypot(b["x"] - a["x"], b["y"] - a["y"]) / max(b["stamp"] - a["stamp"], 1e-3)
             for a, b in itertools.pairwise(near)]  # fmt: skip
    assert max(steps) < 1.0, steps  # m/s: the robot's pace, no jump


# --- 3. the monitor killed and started again ------------------------------------------------

#: The kill [s of simulated time since the start], and the run's end.
KILL_AT, KILL_END = 240.0, 420.0


@pytest.mark.slow
def test_ros2_monitor_killed_and_started_again_takes_its_course_up(tmp_path: Path) -> None:
    """The monitor killed (SIGKILL) mid-run and started again on the same history: the
    second takes its course and odometer up (its first odometer at least the first's
    last), flags nothing from the restart; ``umbmark history`` shows one course."""
    history = tmp_path / "history.sqlite3"
    with stack(tmp_path, ("--no-imu", "--joint-states")) as s:
        first = s.monitor(f"history:={history}")
        s.until_stamp(T0 + KILL_AT, 240.0)
        s.stop(first, signal.SIGKILL)
        kill_mark = len(s.rows())
        recorded = len(_stretches(history))
        second = s.monitor(f"history:={history}")
        s.until_stamp(T0 + KILL_END, 240.0, after=kill_mark)
        s.stop(second)
    assert first.proc.returncode == -signal.SIGKILL
    _clean(second)
    rows = s.rows()
    before, after = rows[:kill_mark], rows[kill_mark:]
    assert recorded >= 2, recorded
    last = _value(before[-1], "odometer [m]")
    started = [_value(r, "odometer [m]") for r in after[:5]]
    assert min(started) >= last, (last, started)
    _no_change(rows)
    assert {r["level"] for r in after if r["level"] != 3} == {0}
    stretches = _stretches(history)
    assert len(stretches) > recorded, (recorded, len(stretches))
    report = _history(history)
    assert len(report["calibrations"]) >= 3
    assert report["drift"] is not None
    assert report["drift"].startswith("no drift"), report["drift"]
    odometers = [st.odometer for st in stretches]
    assert odometers == sorted(odometers), odometers


# --- 4. applying at rest -------------------------------------------------------------------

#: The wheel changed [s of simulated time since the start], and how long to wait for the
#: apply [s of wall time]: confirmed within FLAGGED_WITHIN (120 m) of driving after it, at
#: 0.28 m/s on the whole with these rests, 670 s of simulated time at most, 170 s at 4x.
APPLY_WHEEL_AT, APPLY_WAIT = 240.0, 300.0
#: The driver's rest between missions [s] and the monitor's rest before applying [s].
REST, REST_TIME = 20.0, 4.0
#: How long the run goes on after the apply [s of simulated time].
DRIVE_ON = 40.0
#: The controller's multipliers (diff_drive_controller's names).
MULTIPLIERS = ("left_wheel_radius_multiplier", "right_wheel_radius_multiplier",
               "wheel_separation_multiplier")  # fmt: skip


def _multipliers(truth: dict[str, float]) -> dict[str, float]:
    """What the controller should hold for the robot's truth, by hand from
    docs/conventions.md: ``E_d = D_R / D_L`` and ``E_s = (D_R + D_L) / (2 D_n)`` give
    ``D_L = 2 E_s D_n / (1 + E_d)`` and ``D_R = E_d D_L``; each radius multiplier is the
    true diameter over the nominal one, the separation's ``E_b``."""
    d_left = 2.0 * truth["E_s"] / (1.0 + truth["E_d"])
    return {
        "left_wheel_radius_multiplier": d_left,
        "right_wheel_radius_multiplier": truth["E_d"] * d_left,
        "wheel_separation_multiplier": truth["E_b"],
    }


@pytest.mark.slow
def test_ros2_monitor_applies_a_wheel_change_at_rest(tmp_path: Path) -> None:
    """``--apply at-rest --reload`` after the right wheel changed: the multipliers set on
    the controller (set_parameters, then a configure by the manager) while the robot
    stood, never while it moved, within the change's interval of the truth; ``applied``
    on /diagnostics and on the terminal, and in the history."""
    history, truth_file = tmp_path / "history.sqlite3", tmp_path / "truth.json"
    robot = ("--no-imu", "--joint-states", "--change-wheel-at", str(APPLY_WHEEL_AT),
             "--truth", str(truth_file))  # fmt: skip
    with stack(tmp_path, robot, ("--rest", str(REST))) as s:
        monitor = s.monitor(f"history:={history}", "apply:=at-rest", "reload:=true",
                            f"rest_time:={REST_TIME}")  # fmt: skip
        applied = s.until(lambda r: "applied" in r["values"], APPLY_WAIT)
        assert applied is not None, s._why("nothing applied")
        mark = s.rows().index(applied)
        on = s.until_stamp(applied["stamp"] + DRIVE_ON, 120.0, after=mark)  # driving on
        s.stop(monitor)
    _clean(monitor)
    truth = json.loads(truth_file.read_text())
    (wheel,) = [e for e in truth["events"] if e["kind"] == "wheel"]
    rows = s.rows()
    found = [(r, c) for r in rows for c in changes(r) if c["confirmed"] and c["figure"] == "E_d"]
    assert found, "the wheel change was not confirmed"
    row, change = found[0]
    assert row["stamp"] > wheel["time"]
    assert row["stamp"] <= applied["stamp"]
    sets = s.robot_final["parameter_sets"]
    assert sets, s.robot_final
    for one in sets:
        assert one["linear"] < 1e-6, one  # never while moving
        assert one["angular"] < 1e-6, one
        assert T0 + one["time"] >= row["stamp"] - 5.0, (one, row["stamp"])
    values = {k: v for one in sets for k, v in one["values"].items() if k in MULTIPLIERS}
    assert set(values) == set(MULTIPLIERS), sets
    assert s.robot_final["configured"] == {**s.robot_final["configured"], **values}
    expected = _multipliers(wheel["after"])
    # E_d is their ratio: the change's interval holds it
    ratio = values["right_wheel_radius_multiplier"] / values["left_wheel_radius_multiplier"]
    e_d = expected["right_wheel_radius_multiplier"] / expected["left_wheel_radius_multiplier"]
    assert abs(ratio - e_d) <= change["half"], (ratio, e_d, change)
    for name in MULTIPLIERS:  # E_s and E_b within the window's intervals, as said then
        figure = "E_b" if name == "wheel_separation_multiplier" else "E_s"
        said = _figure(applied, figure)
        assert said is not None
        assert abs(values[name] - expected[name]) <= HALF_WIDTHS * said[1] + change["half"], (
            name, values[name], expected[name], said)  # fmt: skip
    after = rows[mark:]
    assert {r["level"] for r in after} == {0}, [r["message"] for r in after if r["level"]][:3]
    assert not [c for r in after for c in changes(r) if c["confirmed"]]  # nothing new
    moved = _value(on, "odometer [m]") - _value(applied, "odometer [m]")
    assert moved > 3.0, moved  # the controller back, the robot driven on
    lines = monitor.lines
    assert [line for line in lines if line.startswith("umbmark_monitor: applied (")], lines[-10:]
    assert "set_parameters" in applied["values"]["applied"], applied["values"]["applied"]
    report = _history(history)
    marked = [c for c in report["calibrations"] if c["applied"]]
    assert len(marked) == 1, report["calibrations"][-3:]
    new = marked[0]["new"]
    for name in MULTIPLIERS:
        assert math.isclose(new[name], values[name], rel_tol=1e-9), (name, new, values)

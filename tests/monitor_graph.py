"""The processes of the monitor's ROS tests (tests/test_monitor_ros.py,
tests/test_monitor_ros2.py), each ended by its PID: the mission driver
(tests/mission_driver.py), the monitor node, and the diagnostics probe
(tests/diagnostics_probe.py) whose lines are collected as they arrive.
"""

from __future__ import annotations

import itertools
import json
import math
import re
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
DRIVER = HERE / "mission_driver.py"
DIAGNOSTICS_PROBE = HERE / "diagnostics_probe.py"
DEV = HERE / "monitor_node_dev.py"
#: The core's stated distance: a change confirmed within this much driving after it [m]
#: (docs/monitor.md): the stretch it falls in and the two after (3 x 20 m) where each
#: determines the figures; on warehouse missions without an IMU about 30 % of 20 m
#: stretches turn too little to (their condition over the limit), each adding 20 m:
#: measured 60-84 m over ROS and 35-104 m on the simulated robot, bounded at 6 stretches.
FLAGGED_WITHIN = 120.0
#: The robot's wheel changed and its laser knocked [s of simulated time], and when the
#: run ends (the ROS 1 and ROS 2 change tests'): the core's window filled (50 m) and its
#: course begun before the first; each given :data:`FLAGGED_WITHIN` after it and more,
#: the knock after the wheel's confirmation: these missions drive 0.33 m/s on the whole
#: (their rests, turns and shelf stops in it; 196 m in 600 s), so 360 s are about 120 m
#: and 420 s about 139 m.
WHEEL_AT, KNOCK_AT, END_AT = 240.0, 600.0, 1020.0
#: A change as the monitor's message says it: ``E_d changed by +0.006 +- 0.0004 since
#: 482.0 s, 41 m ago`` (``beyond the tolerance`` before ``by`` where it is).
CHANGE = re.compile(
    r"(?P<figure>\w+) changed(?P<beyond> beyond the tolerance)? by (?P<size>[-+0-9.eE]+) "
    r"\+- (?P<half>[0-9.eE+-]+) since (?P<since>[0-9.eE+-]+) s, (?P<ago>[0-9.]+) m ago"
    r"(?P<pending> \(to be confirmed)?"
)


class Process:
    """A subprocess whose stdout lines are kept as they come; ended by its PID."""

    def __init__(self, argv: Sequence[str], env: dict[str, str], stderr: Path) -> None:
        self.stderr_path = stderr
        with stderr.open("w") as err:
            self.proc = subprocess.Popen(
                list(argv), env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                stderr=err, text=True,
            )  # fmt: skip
        self.lines: list[str] = []
        self._new = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._new:
                self.lines.append(line.rstrip("\n"))
                self._new.notify_all()
        with self._new:
            self._new.notify_all()

    def wait_line(self, test: Callable[[str], bool], timeout: float) -> str | None:
        """The first line (from the start) ``test`` passes, waiting up to ``timeout``."""
        deadline = time.monotonic() + timeout
        with self._new:
            while True:
                for line in self.lines:
                    if test(line):
                        return line
                left = deadline - time.monotonic()
                if left <= 0 or (self.proc.poll() is not None and not self._reader.is_alive()):
                    return None
                self._new.wait(min(left, 0.5))

    def stderr(self) -> str:
        return self.stderr_path.read_text(errors="replace")

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 20.0) -> int:
        """``sig`` sent, its exit waited for (killed after ``timeout``); its exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(5.0)
        for stream in (self.proc.stdin, self.proc.stdout):
            if stream is not None:
                stream.close()
        return self.proc.returncode


class Probe(Process):
    """tests/diagnostics_probe.py: the statuses (and odometry) as JSON rows."""

    def rows(self, kind: str = "status") -> list[dict[str, Any]]:
        out = []
        for line in list(self.lines):
            if line.startswith("{"):
                row = json.loads(line)
                if row.get("kind") == kind:
                    out.append(row)
        return out

    def until(
        self, test: Callable[[dict[str, Any]], bool], timeout: float, after: int = 0
    ) -> dict[str, Any] | None:
        """The first status after the first ``after`` that passes ``test``."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.proc.poll() is None:
            for row in self.rows()[after:]:
                if test(row):
                    return row
            time.sleep(0.1)
        return None

    def control(self, word: str) -> None:
        """``word`` on /sim/control."""
        assert self.proc.stdin is not None
        self.proc.stdin.write(f"control {word}\n")
        self.proc.stdin.flush()


def start_probe(python: str, side: str, env: dict[str, str], tmp: Path, *args: str) -> Probe:
    probe = Probe([python, str(DIAGNOSTICS_PROBE), side, *args], env, tmp / "probe.stderr")
    if probe.wait_line(lambda line: '"ready"' in line, 60.0) is None:
        probe.stop()
        raise AssertionError(f"the diagnostics probe did not come up: {probe.stderr()[-2000:]}")
    return probe


def start_driver(python: str, side: str, env: dict[str, str], tmp: Path, *args: str) -> Process:
    driver = Process([python, str(DRIVER), side, *args], env, tmp / "driver.stderr")
    if driver.wait_line(lambda line: line == "ready", 60.0) is None:
        driver.stop()
        raise AssertionError(f"the mission driver did not come up: {driver.stderr()[-2000:]}")
    return driver


def driver_final(driver: Process) -> dict[str, Any]:
    """What the driver printed at its end (call after :meth:`Process.stop`)."""
    line = driver.wait_line(lambda line: line.startswith("final "), 5.0)
    assert line is not None, driver.stderr()[-2000:]
    out: dict[str, Any] = json.loads(line[len("final ") :])
    return out


def wall_periods(rows: Sequence[dict[str, Any]]) -> list[float]:
    """The wall time between consecutive statuses [s]."""
    walls = [r["wall"] for r in rows]
    return [b - a for a, b in itertools.pairwise(walls)]


def clearance(path: Sequence[Sequence[float]], robot_radius: float = 0.3) -> float:
    """The true path's least distance [m] to the warehouse's walls and racks, less the
    robot's radius (its base 0.45 m x 0.38 m, centred 5 cm behind the axle: 0.3 m)."""
    import numpy as np

    from umbmark.robot.warehouse import warehouse_world
    from umbmark.sim.missions import Warehouse

    world = warehouse_world(Warehouse())
    return world.clearance(np.asarray(path, dtype=np.float64)) - robot_radius


def odometer_at(rows: Sequence[dict[str, Any]], stamp: float) -> float:
    """The monitor's odometer [m] at ROS time ``stamp``: its last status before it."""
    before = [r for r in rows if r["stamp"] <= stamp and "odometer [m]" in r["values"]]
    return float(before[-1]["values"]["odometer [m]"]) if before else math.nan


def changes(row: dict[str, Any]) -> list[dict[str, Any]]:
    """The changes a status's message says, each its figure, size, half-width, since [s],
    metres ago, whether confirmed and beyond the tolerance."""
    out = []
    for m in CHANGE.finditer(row["message"]):
        out.append({
            "figure": m["figure"], "size": float(m["size"]), "half": float(m["half"]),
            "since": float(m["since"]), "ago": float(m["ago"]),
            "confirmed": m["pending"] is None, "beyond": m["beyond"] is not None,
        })  # fmt: skip
    return out


# --- the runs the ROS 1 and ROS 2 tests share -------------------------------------------


@dataclass
class Run:
    """What one run of the monitor beside the driven robot gave."""

    code: int
    lines: list[str]
    stderr: str
    rows: list[dict[str, Any]]
    odoms: list[dict[str, Any]] = field(default_factory=list)
    final: dict[str, Any] = field(default_factory=dict)
    marks: dict[str, int] = field(default_factory=dict)


def run_wiring(
    python: str, side: str, env: dict[str, str], tmp: Path, monitor_argv: Sequence[str],
    recording: bool,
) -> Run:  # fmt: skip
    """The driver, the monitor (``monitor_argv``: its options, its robot ``r7``, the
    corrected odometry on ``/odom_corrected``, stale after 1 s) and the probe: a few OK
    statuses, the laser muted until STALE, unmuted until OK; SIGTERM."""
    procs: list[Process] = []
    marks: dict[str, int] = {}
    try:
        procs.append(driver := start_driver(python, side, env, tmp))
        procs.append(monitor := Process(monitor_argv, env, tmp / "monitor.stderr"))
        procs.append(probe := start_probe(python, side, env, tmp, "--odom", "/odom_corrected"))
        fed = (lambda r: "scan 0," not in r["message"]) if recording else (lambda r: True)
        ok = probe.until(lambda r: r["level"] == 0 and fed(r), 90.0)
        assert ok is not None, monitor.stderr()[-2000:]
        marks["ok"] = len(probe.rows())
        assert probe.until(lambda r: True, 10.0, after=marks["ok"] + 3) is not None
        probe.control("mute_scan")
        marks["muted"] = len(probe.rows())
        stale = probe.until(lambda r: r["level"] == 3, 20.0, after=marks["muted"])
        probe.control("unmute_scan")
        assert stale is not None, "no STALE status while the laser was muted"
        marks["stale"] = probe.rows().index(stale)
        back = probe.until(lambda r: r["level"] == 0, 20.0, after=marks["stale"])
        marks["back"] = -1 if back is None else probe.rows().index(back)
        code = monitor.stop(signal.SIGTERM)
        odoms = probe.rows("odom")
        probe.stop()
        driver.stop(signal.SIGTERM)
        final = driver_final(driver)
    finally:
        for proc in procs:
            proc.stop()
    return Run(code, monitor.lines, monitor.stderr(), probe.rows(), odoms, final, marks)


def check_wiring(run: Run) -> None:
    """What :func:`run_wiring` must have seen."""
    assert run.code == 0, run.stderr[-2000:]
    assert "Traceback" not in run.stderr
    assert run.lines[-1].startswith("umbmark_monitor stopped (SIGTERM) after")
    rows = run.rows
    assert {r["name"] for r in rows} == {"umbmark_monitor: odometry"}
    assert {r["hardware_id"] for r in rows} == {"r7"}
    ok = run.marks["ok"]
    periods = wall_periods(rows[ok : ok + 4])
    assert all(0.7 < p < 1.3 for p in periods), periods  # 1 Hz of the wall clock
    stale = rows[run.marks["stale"]]
    assert stale["values"]["stale topics"] == "/scan"
    assert run.marks["back"] > 0, "not OK again once the laser spoke"
    assert "stale topics" not in rows[run.marks["back"]]["values"]
    odoms = run.odoms
    assert {(o["frame"], o["child"]) for o in odoms} == {("odom", "base_link")}
    assert max(math.hypot(o["x"] - odoms[0]["x"], o["y"] - odoms[0]["y"]) for o in odoms) > 1.0
    assert run.final["segments"] >= 3
    assert clearance(run.final["path"]) > 0.5  # on the aisles: racks 1.1 m from their centre


def run_changes(
    python: str, side: str, env: dict[str, str], tmp: Path, monitor_argv: Sequence[str],
    truth: Path, until: float, wall_limit: float,
) -> Run:  # fmt: skip
    """The driver, the monitor and the probe until a status stamped after ROS time
    ``until`` [s] (or ``wall_limit`` wall seconds); SIGTERM."""
    procs: list[Process] = []
    try:
        procs.append(driver := start_driver(python, side, env, tmp))
        procs.append(monitor := Process(monitor_argv, env, tmp / "monitor.stderr"))
        procs.append(probe := start_probe(python, side, env, tmp))
        probe.until(lambda r: r["stamp"] > until, wall_limit)
        code = monitor.stop(signal.SIGTERM)
        probe.stop()
        driver.stop(signal.SIGTERM)
        final = driver_final(driver)
    finally:
        for proc in procs:
            proc.stop()
    assert truth.exists()
    return Run(code, monitor.lines, monitor.stderr(), probe.rows(), final=final)


def _first_confirmed(
    rows: Sequence[dict[str, Any]], figure: str, after: float
) -> tuple[dict[str, Any], dict[str, Any]] | None:
    for row in rows:
        if row["stamp"] <= after:
            continue
        for change in changes(row):
            if change["figure"] == figure and change["confirmed"]:
                return row, change
    return None


def check_changes(run: Run, truth_file: Path) -> None:
    """Against the robot node's truth: OK with nothing flagged before the wheel change; a
    change of E_d, WARN, within :data:`FLAGGED_WITHIN` metres of driving after it, its
    size the truth's within its interval, since the stretch it fell in; the laser's knock
    a change of laser_yaw, as close after it."""
    assert run.code == 0, run.stderr[-2000:]
    assert "Traceback" not in run.stderr
    truth = json.loads(truth_file.read_text())
    events = {e["kind"]: e for e in truth["events"]}
    assert set(events) == {"wheel", "laser"}, truth
    wheel, knock = events["wheel"], events["laser"]
    rows = [r for r in run.rows if r["level"] != 3]  # STALE: the first seconds' silence
    before = [r for r in rows if r["stamp"] < wheel["time"]]
    assert len(before) >= 10
    assert {r["level"] for r in before} == {0}, [r["message"] for r in before if r["level"]]
    assert not [c for r in before for c in changes(r) if c["confirmed"]]
    found = _first_confirmed(rows, "E_d", wheel["time"])
    assert found is not None, "the wheel change was not flagged"
    row, change = found
    at = odometer_at(rows, wheel["time"])
    odometer = float(row["values"]["odometer [m]"])
    print(f"E_d confirmed {odometer - at:.0f} m after the wheel was changed")  # -rP shows it
    assert odometer - at < FLAGGED_WITHIN, (odometer, at)
    assert row["level"] == 1  # WARN: 0.006 / 0.34 m = 0.018 rad/m, within the tolerance
    size = wheel["after"]["E_d"] - wheel["before"]["E_d"]
    assert abs(change["size"] - size) <= change["half"], (change, size)
    assert odometer - change["ago"] > at - 25.0  # since the stretch it fell in
    yaw = _first_confirmed(rows, "laser_yaw", knock["time"])
    assert yaw is not None, "the laser's knock was not flagged"
    row, change = yaw
    at = odometer_at(rows, knock["time"])
    print(f"laser_yaw confirmed {float(row['values']['odometer [m]']) - at:.0f} m after the knock")
    assert float(row["values"]["odometer [m]"]) - at < FLAGGED_WITHIN
    turned = knock["after"]["yaw"] - knock["before"]["yaw"]
    assert abs(change["size"] - turned) <= max(change["half"], 0.003), (change, turned)
    assert row["level"] in (1, 2)

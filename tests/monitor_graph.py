"""The processes of the monitor's ROS tests (tests/test_monitor_ros.py,
tests/test_monitor_ros2.py), each ended by its PID: the mission driver
(tests/mission_driver.py), the monitor node, and the diagnostics probe
(tests/diagnostics_probe.py) whose lines are collected as they arrive.
"""

from __future__ import annotations

import json
import math
import re
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
DRIVER = HERE / "mission_driver.py"
DIAGNOSTICS_PROBE = HERE / "diagnostics_probe.py"
DEV = HERE / "monitor_node_dev.py"
#: The core's stated distance: a change confirmed within this much driving after it [m]
#: (the stretch it falls in and the two after: 3 x 20 m; docs/monitor.md).
FLAGGED_WITHIN = 60.0
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
    return [b - a for a, b in zip(walls, walls[1:], strict=False)]


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

"""The self-calibration routine on the virtual robot: how much faster than real time it
runs, and where its wall time goes.

One run of :func:`umbmark.selfcal` (the robot of ``umbmark selfcal --sim``: E_d 1.004,
E_b 0.97, slip 0.0004 m^0.5; 4 m squares, five runs each way, fixes by the laser) on a
:class:`~umbmark.robot.virtual.VirtualRobot` whose methods are timed as the routine calls
them. Printed side by side, from the same run:

- the robot's simulated time against the wall time (the real-time factor: a real robot
  needs the simulated time);
- the wall time's shares: stepping the robot's physics (``wait``), simulated laser scans
  (``scan``), and the rest (the driving controller, the corner fits, the calibrations, the
  files).

Run: python benchmarks/bench_selfcal.py [--runs 5] [--side-length 4]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from umbmark.jobs.selfcal import selfcal
from umbmark.robot.virtual import VirtualRobot


class TimedRobot(VirtualRobot):
    """The virtual robot, with the wall time spent in each of its methods summed."""

    spent: dict[str, float]

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.spent = {}

    def _timed(self, name: str, call: Callable[[], Any]) -> Any:
        start = time.perf_counter()
        try:
            return call()
        finally:
            self.spent[name] = self.spent.get(name, 0.0) + time.perf_counter() - start

    def wait(self, duration: float) -> None:
        self._timed("wait", lambda: super(TimedRobot, self).wait(duration))

    def scan(self):  # type: ignore[no-untyped-def]
        return self._timed("scan", lambda: super(TimedRobot, self).scan())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--side-length", type=float, default=4.0)
    args = parser.parse_args()
    robot = TimedRobot(E_d=1.004, E_b=0.97, slip=0.0004, seed=1)  # as `selfcal --sim`
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        report = selfcal(
            robot, out=Path(folder) / "out", runs=args.runs, side_length=args.side_length
        )
        wall = time.perf_counter() - start
    simulated = robot.now()
    before, after = report.e_max_syst_before, report.e_max_syst_after
    print(f"passes driven: {len(report.passes)} ({args.runs} runs each way, "
          f"{args.side_length:g} m squares)")  # fmt: skip
    if before is not None and after is not None:
        print(f"E_max,syst: {before * 1000:.1f} mm -> {after * 1000:.1f} mm")
    print(f"simulated robot time: {simulated:8.1f} s")
    print(f"wall time:            {wall:8.1f} s")
    print(f"real-time factor:     {simulated / wall:8.1f}x faster than the real robot")
    physics, scans = robot.spent.get("wait", 0.0), robot.spent.get("scan", 0.0)
    rest = wall - physics - scans
    for name, seconds in (("robot physics", physics), ("laser scans", scans), ("rest", rest)):
        print(f"  {name:<14} {seconds:7.2f} s  {100 * seconds / wall:5.1f} % of the wall time")


if __name__ == "__main__":
    main()

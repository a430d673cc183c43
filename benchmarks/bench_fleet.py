"""The fleet on its engine: throughput on 1 and 2 local workers, memory per recording
against its length, and what a fleet of 100 robots x 8 hours a day needs.

A simulated fleet (``umbmark simulate --fleet``: wheels and a laser, ordinary missions) is
calibrated by :func:`umbmark.fleet` twice in one run, into fresh histories: on a local
Dask cluster of 1 worker, then of 2 (separate processes). Printed side by side:

- recordings per second and robot-hours of recording per second on each, and their ratio
  (the speed-up of the second worker);
- the peak memory of one process calibrating one recording
  (:func:`umbmark.fleets.outcome.calibrate_recording`, alone in a fresh process) against
  the recording's length (5, 20 and 60 minutes: one window of
  :data:`umbmark.scans.bag.WINDOW`, 5 minutes, then 4 and 12 of them, read one at a
  time): its growth per minute between the two longer ones;
- the worker-hours a fleet of 100 robots recording 8 hours a day needs, from the robot-
  hours per worker-hour measured on 1 worker (at the laser's rate and scene simulated
  here: 5 Hz sweeps of 360 beams).

Run: python benchmarks/bench_fleet.py [--robots 3] [--days 4] [--minutes 2]
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import umbmark
from umbmark.scans.bag import WINDOW

# The peak is this process's own memory's high-water mark (VmHWM, Linux): getrusage's
# ru_maxrss is kept across exec, so in a child it holds the parent's peak too (here the
# simulation's) when that was larger.
_PEAK = """
import json, sys
from umbmark.fleets.outcome import RecordingTask, calibrate_recording
out = calibrate_recording(RecordingTask(sys.argv[1]))
with open("/proc/self/status") as status:
    kib = next(int(line.split()[1]) for line in status if line.startswith("VmHWM:"))
print(json.dumps({"peak": kib / 1024.0, "method": out.method, "reason": out.reason}))
"""


def _fleet_rate(folder: Path, workers: int, scratch: Path) -> tuple[float, int, float]:
    """Seconds, recordings and robot-hours of one fleet run on ``workers`` workers."""
    history = scratch / f"h{workers}.sqlite3"
    start = time.perf_counter()
    report = umbmark.fleet(str(folder), robot_from="{robot}/{date}/*", history=history,
                           workers=workers)  # fmt: skip
    seconds = time.perf_counter() - start
    hours = sum(o.hours for o in report.done)
    return seconds, len(report.done), hours


def _peak_memory(recording: str) -> float:
    proc = subprocess.run([sys.executable, "-c", _PEAK, recording], capture_output=True,
                          text=True, check=True)  # fmt: skip
    data = json.loads(proc.stdout)
    if data["method"] is None:
        raise SystemExit(f"{recording} was not calibrated: {data['reason']}")
    return float(data["peak"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=3)
    parser.add_argument("--days", type=int, default=4)
    parser.add_argument("--minutes", type=float, default=2.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        folder = scratch / "fleet"
        umbmark.simulate_fleet(folder, fleet=args.robots, days=args.days, minutes=args.minutes)
        rates = {w: _fleet_rate(folder, w, scratch) for w in (1, 2)}
        print(f"fleet of {args.robots} robots x {args.days} days, {args.minutes:g} min each:")
        for w, (seconds, n, hours) in rates.items():
            print(f"  {w} worker(s): {seconds:6.1f} s, {n / seconds:6.3f} recordings/s, "
                  f"{hours / seconds:7.4f} robot-hours/s")  # fmt: skip
        one, two = rates[1], rates[2]
        print(f"  speed-up of the second worker: {one[0] / two[0]:.2f}x")
        lengths = []
        for minutes in (5.0, 20.0, 60.0):
            single = scratch / f"len{minutes:g}"
            umbmark.simulate_fleet(single, fleet=1, days=1, minutes=minutes, seed=7)
            path = next(single.glob("robot01/*/drive"))
            lengths.append((minutes, _peak_memory(str(path))))
            shutil.rmtree(single)
        print("peak memory of one process calibrating one recording:")
        for minutes, peak in lengths:
            print(f"  {minutes:4.1f} min: {peak:7.1f} MiB")
        beyond = (lengths[2][1] - lengths[1][1]) / (lengths[2][0] - lengths[1][0])
        span = f"{lengths[1][0]:g} to {lengths[2][0]:g} minutes ({WINDOW / 60:g}-minute windows)"
        print(f"  growth from {span}: {beyond:.3f} MiB per minute of recording "
              f"({beyond * 480:.0f} MiB more for 8 hours)")  # fmt: skip
        per_worker_hour = one[2] / one[0] * 3600.0  # robot-hours per worker-hour
        need = 100 * 8.0 / per_worker_hour
        print(f"100 robots x 8 h a day: {need:.1f} worker-hours a day at "
              f"{per_worker_hour:.0f} robot-hours per worker-hour (1 worker)")  # fmt: skip


if __name__ == "__main__":
    main()

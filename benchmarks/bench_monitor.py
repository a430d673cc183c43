"""The monitor's core over a simulated shift: its CPU per hour of robot time and its
memory against the time run, and a steady robot's flags.

The simulated warehouse robot (:mod:`umbmark.monitor.simulated`: ordinary missions, 10 Hz
laser, 50 Hz wheels, 200 Hz gyro, no change) feeds :class:`umbmark.monitor.core.Monitor`
for ``--hours`` of robot time (8 by default: a shift). Only the time spent inside the
core's calls (``time.process_time`` around each, the status asked once a second as a
node does) is the monitor's CPU; the simulation's own time is printed beside it. The
goals: at most 10 % of one core (360 s of CPU per hour of robot time) and a flat memory
under 200 MiB (the process's resident set, ``/proc/self/status`` VmRSS, the simulator's
arrays in it, printed every simulated hour with the core's own: its window, stretch and
course).

A steady robot must not be flagged: every change the monitor confirms is a false flag
(printed), and every stretch's figure against its course's present value (its z score
in its standard errors, scaled by the course's own scatter, the Birge ratio) is summed up,
with what a Gaussian of that scatter gives per robot-week of driving round the clock.
``OMP_NUM_THREADS=1`` and friends are set before numpy loads: one core's figures.

    PYTHONPATH=src python benchmarks/bench_monitor.py            # 8 h
    PYTHONPATH=src python benchmarks/bench_monitor.py --hours 0.2  # CI
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from umbmark.calibration.changes import Z_CHANGE  # noqa: E402
from umbmark.monitor.core import Monitor  # noqa: E402
from umbmark.monitor.setup import MonitorSetup  # noqa: E402
from umbmark.monitor.simulated import NOMINAL, SimRobotSetup, feed, messages  # noqa: E402
from umbmark.robot.base import DriveParams, Pose2D  # noqa: E402

#: Hours of driving in a robot-week, round the clock.
WEEK_HOURS = 7 * 24.0


def _rss_mib() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return math.nan


def _core_mib(core: Monitor) -> float:
    """What the core holds in arrays: its window's and stretch's chunks [MiB]."""
    total = 0
    for chunk in [c for _, c in core.window] + core.stretch:
        for part in (chunk.motion, chunk.gyro, chunk.reference):
            if part is None:
                continue
            for value in vars(part).values():
                if isinstance(value, np.ndarray):
                    total += value.nbytes
    points = sum(len(p) for p in core.course.points.values())
    return (total + 100 * points) / 2**20


def _steady_z(core: Monitor) -> tuple[int, float, float]:
    """The stretches' figures against their course: how many, the largest |z| and its
    rms (each in its standard errors times the course's Birge ratio)."""
    zs = []
    for name, series in core.course.points.items():
        change = core.course.change(name)
        if change is None or len(series) < 3:
            continue
        for p in series:
            zs.append((p.value - change.value) / (change.birge * math.hypot(p.se, change.se)))
    z = np.array(zs)
    if z.size == 0:
        return 0, math.nan, math.nan
    return int(z.size), float(np.max(np.abs(z))), float(np.sqrt(np.mean(z**2)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=8.0, help="robot time [h]")
    parser.add_argument("--seed", type=int, default=3)
    args = parser.parse_args()
    setup = MonitorSetup("bench", DriveParams(NOMINAL[0], 0.5 * NOMINAL[1]), Pose2D(0.1, 0, 0),
                         inputs=("wheels", "scan", "imu"))  # fmt: skip
    core = Monitor(setup)
    sim = SimRobotSetup(seed=args.seed)
    cpu, next_status, next_hour = 0.0, 0.0, 3600.0
    counts = {"wheels": 0, "scan": 0, "imu": 0}
    start_cpu, start_wall = time.process_time(), time.monotonic()
    print(
        f"monitor core over {args.hours:g} h of robot time (10 Hz laser, 50 Hz wheels, 200 Hz gyro)"
    )
    print(" robot h   core CPU s   CPU s per h   share of a core   RSS MiB   core MiB   wall s")
    seconds = 3600.0 * args.hours
    flagged: list[str] = []
    for message, _ in messages(sim, seconds):
        if message.time > seconds:
            break
        counts[message.kind] += 1
        t0 = time.process_time()
        feed(core, message)
        if message.time >= next_status:
            next_status = math.floor(message.time) + 1.0
            status = core.status(message.time)
            for c in status.changes:
                line = f"{c.figure} at {c.since:.0f} s ({'confirmed' if c.confirmed else 'latest'})"
                if c.confirmed and line not in flagged:
                    flagged.append(line)
        cpu += time.process_time() - t0
        if message.time >= next_hour:
            hours = message.time / 3600.0
            wall = time.monotonic() - start_wall
            rate = cpu / hours
            print(f"{hours:8.2f}   {cpu:10.1f}   {rate:11.1f}   {rate / 36:14.2f} %"
                  f"   {_rss_mib():7.0f}   {_core_mib(core):8.2f}   {wall:6.0f}")  # fmt: skip
            next_hour += 3600.0
    if next_hour - 3600.0 < seconds - 1.0:  # the last part of an hour
        hours = seconds / 3600.0
        print(
            f"{hours:8.2f}   {cpu:10.1f}   {cpu / hours:11.1f}   {cpu / hours / 36:14.2f} %"
            f"   {_rss_mib():7.0f}   {_core_mib(core):8.2f}   {time.monotonic() - start_wall:6.0f}"
        )
    total = time.process_time() - start_cpu
    print(f"messages: {counts}; the simulation's own CPU {total - cpu:.0f} s beside the core's "
          f"{cpu:.1f} s")  # fmt: skip
    print(f"odometer {core.odometer:.0f} m, {core.stretches} stretches, outliers {core.outliers}, "
          f"left out {dict(core.left_out)}")  # fmt: skip
    n, zmax, zrms = _steady_z(core)
    print(f"steady robot: {len(flagged)} false flags (confirmed changes): {flagged or 'none'}")
    if n:
        per_stretch = math.erfc(Z_CHANGE / (zrms * math.sqrt(2.0)))  # one figure off
        stretches_week = core.stretches / args.hours * WEEK_HOURS
        figures = len(core.course.points)
        # a confirmed false flag needs two stretches in a row off the course, together
        week = per_stretch**2 * stretches_week * figures
        print(f"stretch figures against their course: {n}, |z| largest {zmax:.2f}, rms {zrms:.2f}; "
              f"a Gaussian of that rms: {per_stretch:.1e} of stretches off by {Z_CHANGE:g} "
              f"sigma, {week:.1e} confirmed false flags per robot-week ({stretches_week:.0f} "
              f"stretches of {figures} figures)")  # fmt: skip


if __name__ == "__main__":
    main()

"""A steady simulated robot's false flags on the monitor: every figure's per-stretch scatter
against its stated standard errors, and the false flags per robot-week that gives.

The simulated warehouse robot (:mod:`umbmark.monitor.simulated`, no change) feeds the core
(:class:`umbmark.monitor.core.Monitor`) for ``--hours`` of robot time, once per seed. Every
change it confirms is a false flag (printed: the direct count). Each stretch's figure is
then set against its own course (the seed's weighted mean: what the change model compares
it with) in its standard errors, ``z``; pooled over the seeds, per figure: how many, their
root mean square with its 95 % interval (chi-square), the largest, how many beyond 3, 4
and 5, and the correlation of one stretch's ``z`` with the next's.

A confirmed flag needs two stretches in a row off the course by more than ``Z_CHANGE``
(5) standard errors each (:mod:`umbmark.calibration.changes`: the second confirms the
first; the course's Birge ratio, at least 1, and its own error only widen the test), so
per figure and stretch it happens with at most ``p^2``, ``p`` the chance of one stretch
off by 5 (stretches hold no data in common: independent). The flags per robot-week (168
hours of driving) are at most ``stretches a week x sum over figures of p^2``, with ``p``

- from a Gaussian of the measured rms at the top of its 95 % interval;
- without a model: the 95 % upper Poisson bound of the count beyond 5, over the count;

and the change model itself (:class:`umbmark.monitor.course.Course`, the monitor's, every
path of it: steps hidden in the course too) run on series of each figure's measured ``z``
drawn again at random (bootstrap: their tails as measured), ``--weeks`` robot-weeks,
judged every :data:`EVERY` stretches. The gyro's bias is followed, not flagged
(:data:`umbmark.calibration.changes.FOLLOWED`): shown, not counted.

    PYTHONPATH=src python tools/monitor_false_flags.py --hours 6 --seeds 4
    PYTHONPATH=src python tools/monitor_false_flags.py --hours 3 --seeds 2 --no-imu
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import itertools  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from umbmark.calibration.changes import FOLLOWED, Z_CHANGE  # noqa: E402
from umbmark.monitor.core import Monitor  # noqa: E402
from umbmark.monitor.course import Course, StretchPoint  # noqa: E402
from umbmark.monitor.setup import MonitorSetup  # noqa: E402
from umbmark.monitor.simulated import NOMINAL, SimRobotSetup, feed, messages  # noqa: E402
from umbmark.robot.base import DriveParams, Pose2D  # noqa: E402

WEEK_HOURS = 168.0
#: The bootstrap's change model is judged every this many stretches (a step, once found,
#: stays on the course: it is not missed between).
EVERY = 10


def run(seed: int, hours: float, walk: float, imu: bool = True) -> tuple[Monitor, list[str]]:
    """The core over a steady robot (``imu``: with its gyro); the changes it confirmed."""
    sim = SimRobotSetup(seed=seed, gyro_bias_walk=walk, imu_rate=200.0 if imu else 0.0)
    inputs = ("wheels", "scan", "imu") if imu else ("wheels", "scan")
    setup = MonitorSetup("steady", DriveParams(NOMINAL[0], 0.5 * NOMINAL[1]),
                         Pose2D(*sim.stated), inputs=inputs)  # fmt: skip
    core = Monitor(setup)
    seconds = 3600.0 * hours
    for message, _ in messages(sim, seconds):
        if message.time > seconds:
            break
        feed(core, message)
    flags = [f"seed {seed}: {c.figure} at {c.since_metres:.0f} m" for c in core.changes()
             if c.confirmed]  # fmt: skip
    return core, flags


def z_scores(core: Monitor) -> dict[str, list[float]]:
    """Each figure's stretches against their weighted mean, in standard errors."""
    out: dict[str, list[float]] = {}
    for name, series in core.course.points.items():
        v = np.array([p.value for p in series])
        s = np.array([p.se for p in series])
        mean = float(np.sum(v / s**2) / np.sum(1.0 / s**2))
        out[name] = list((v - mean) / s)
    return out


def bootstrap_flags(z: np.ndarray, stretches: int, rng: np.random.Generator) -> int:
    """The change model's confirmed flags on ``stretches`` of ``z`` drawn again."""
    course = Course()
    drawn = rng.choice(z, size=stretches, replace=True)
    seen: set[float] = set()
    for k, value in enumerate(drawn.tolist()):
        course.add("f", StretchPoint(value, 1.0, 65.0 * k, 20.0 * k, 65.0 * k))
        if k % EVERY == EVERY - 1 or k == stretches - 1:
            _, found = course.found("f", 0.02, 0.34)
            if found is not None and found.confirmed:
                seen.add(found.since_metres)
    return len(seen)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=6.0, help="robot time per seed [h]")
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--weeks", type=float, default=5.0, help="bootstrap robot-weeks")
    parser.add_argument("--bias-walk", type=float, default=0.0,
                        help="the gyro bias's random walk [deg/s/sqrt(s)]")  # fmt: skip
    parser.add_argument("--no-imu", action="store_true", help="the robot has no gyro")
    args = parser.parse_args()
    walk = math.radians(args.bias_walk)
    pooled: dict[str, list[float]] = {}
    lagged: dict[str, list[tuple[float, float]]] = {}
    flags: list[str] = []
    stretches, cpu = 0, time.process_time()
    for seed in range(1, args.seeds + 1):
        core, found = run(seed, args.hours, walk, imu=not args.no_imu)
        flags += found
        stretches += core.stretches
        for name, z in z_scores(core).items():
            pooled.setdefault(name, []).extend(z)
            lagged.setdefault(name, []).extend(itertools.pairwise(z))
    hours = args.hours * args.seeds
    week = stretches / hours * WEEK_HOURS
    print(f"steady robot: {hours:g} h of robot time over {args.seeds} seeds, {stretches} "
          f"stretches ({time.process_time() - cpu:.0f} s of CPU); bias walk "
          f"{args.bias_walk:g} deg/s/sqrt(s){'; no IMU' if args.no_imu else ''}")  # fmt: skip
    print(f"confirmed false flags: {len(flags)} {flags or ''}")
    print("figure       n    rms z [95 %]          max |z|  >3  >4  >5  lag-1 corr")
    gauss = free = 0.0
    counted: dict[str, np.ndarray] = {}
    for name, values in pooled.items():
        z = np.array(values)
        n = z.size
        rms = float(np.sqrt(np.mean(z**2)))
        low = rms * math.sqrt(stats.chi2.ppf(0.025, n) / n)
        high = rms * math.sqrt(stats.chi2.ppf(0.975, n) / n)
        beyond = [int(np.sum(np.abs(z) > c)) for c in (3, 4, Z_CHANGE)]
        pairs = np.array(lagged[name])
        corr = float(np.corrcoef(pairs[:, 0], pairs[:, 1])[0, 1]) if len(pairs) > 2 else math.nan
        note = "  (followed, not flagged)" if name in FOLLOWED else ""
        print(f"{name:10s} {n:5d}  {rms:5.2f} [{low:4.2f}, {high:4.2f}]   {np.max(np.abs(z)):7.2f}"
              f"  {beyond[0]:3d} {beyond[1]:3d} {beyond[2]:3d}  {corr:+.3f}{note}")  # fmt: skip
        if name in FOLLOWED:
            continue
        counted[name] = z
        gauss += math.erfc(Z_CHANGE / (high * math.sqrt(2.0))) ** 2
        free += (0.5 * stats.chi2.ppf(0.95, 2 * (beyond[2] + 1)) / n) ** 2
    print(f"stretches per robot-week: {week:.0f}; {len(counted)} figures flagged")
    print(f"false flags per robot-week at most: {week * gauss:.1e} (a Gaussian of each rms at "
          f"its 95 % top), {week * free:.2f} (no model: the 95 % Poisson bound of the counts "
          f"beyond {Z_CHANGE:g})")  # fmt: skip
    rng = np.random.default_rng(7)
    total, per = 0, max(1, round(week * args.weeks))
    for z in counted.values():
        total += bootstrap_flags(z, per, rng)
    upper = 0.5 * stats.chi2.ppf(0.95, 2 * (total + 1)) / args.weeks
    print(f"the change model on the measured z drawn again ({args.weeks:g} robot-weeks of "
          f"{len(counted)} figures, judged every {EVERY} stretches): {total} confirmed flags, "
          f"{total / args.weeks:.2f} per robot-week (95 % upper {upper:.2f})")  # fmt: skip


if __name__ == "__main__":
    main()

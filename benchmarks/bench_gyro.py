"""The gyro estimator's time and memory against the recording's length, on one core.

Recordings of 10, 30 and 60 minutes of the tests' closed-form robot with a gyro
(``tests/gyro_sim.py``: straights, spins both ways and arcs with rests, a 200 Hz gyro with a
wandering bias, 50 Hz wheels), simulated first and not timed. Timed, best of three:

- ``cut``: :func:`umbmark.scans.gyro_intervals.gyro_intervals`, the recording cut into
  rests and driving and the gyro integrated over each;
- ``fit``: :func:`umbmark.estimators.gyro.fit_gyro` on those intervals, without a
  reference, and with a heading reference every second (``fit + reference``).

Memory: the peak of what numpy and Python allocate during cut and fit
(``tracemalloc``), beside the recording's own size in memory. ``OMP_NUM_THREADS=1`` and
friends are set before numpy loads, so that the figures are one core's. The goal: an hour
of 200 Hz IMU and 50 Hz wheels in under 10 s.

    PYTHONPATH=src python benchmarks/bench_gyro.py
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import sys  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from gyro_sim import Truth, heading_reference, mixed_program, record  # noqa: E402
from umbmark.estimators.gyro import fit_gyro  # noqa: E402
from umbmark.model.kinematics import WheelParams  # noqa: E402
from umbmark.scans.gyro_intervals import (  # noqa: E402
    HeadingReference,
    gyro_intervals,
    gyro_reference,
)

from _timing import best_of  # noqa: E402

GOAL = 10.0  # seconds for an hour


def main() -> None:
    truth = Truth()
    active = WheelParams(truth.nominal_wheelbase, truth.nominal_diameter)
    print(
        "| length [min] | gyro / wheel samples | intervals | cut [s] | fit [s] "
        "| fit + reference [s] | cut + fit per hour [s] | of the goal | peak memory [MB] "
        "| recording [MB] |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for minutes in (10, 30, 60):
        rec = record(mixed_program(minutes), truth, seed=1)
        g, w = rec.gyro, rec.wheels
        size = g.time.nbytes + g.rate.nbytes + (g.accel.nbytes if g.accel is not None else 0)
        size += w.time.nbytes + w.angles.nbytes
        cut, iv = best_of(lambda rec=rec: gyro_intervals(rec.wheels, rec.gyro))
        fit, cal = best_of(lambda iv=iv: fit_gyro(iv, active))
        start, end, yaw = heading_reference(rec)
        ref = gyro_reference(rec.gyro, HeadingReference(start, end, yaw))
        joint, _ = best_of(lambda iv=iv, ref=ref: fit_gyro(iv, active, reference=ref))
        tracemalloc.start()
        fit_gyro(gyro_intervals(rec.wheels, rec.gyro), active)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        per_hour = (cut + fit) * 3600.0 / float(w.time[-1])
        assert np.isfinite(cal.values["E_d"])
        print(
            f"| {w.time[-1] / 60:.1f} | {len(g)} / {w.time.size} | {len(iv)} | {cut:.3f} "
            f"| {fit:.3f} "
            f"| {joint:.3f} | {per_hour:.2f} | {per_hour / GOAL:.3f} | {peak / 1e6:.0f} "
            f"| {size / 1e6:.0f} |"
        )


if __name__ == "__main__":
    main()

"""The closed-loop virtual robot: one vectorized pass over many runs against a plain loop.

Both simulate the same noise-free model (tests/reference_sim.py is the per-sample loop the
vectorized engine is tested against) on 4 x 4 m UMBmark squares; the script prints runs
per second and odometry samples per second of each, and their ratio, for several batch
sizes.

Run: python benchmarks/bench_simulator.py [--runs 10 100 1000 4000] [--loop-runs 4]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.sim.engine import simulate
from umbmark.sim.paths import square
from umbmark.sim.robot import LABMATE, SimRobot

from _timing import best_of

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from reference_sim import simulate_run_loop


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, nargs="+", default=[10, 100, 1000, 4000])
    parser.add_argument("--loop-runs", type=int, default=4)
    args = parser.parse_args()
    robot = SimRobot.with_errors(LABMATE, E_d=1.00084, E_b=336.17 / 340.0)
    path = square(4.0)

    loop_dirs = [Direction.CW, Direction.CCW] * (args.loop_runs // 2)
    t_loop, loop = best_of(lambda: [simulate_run_loop(robot, path, d) for d in loop_dirs], 1)
    loop_samples = sum(s for _, _, s in loop)
    loop_runs_s = len(loop_dirs) / t_loop
    loop_samples_s = loop_samples / t_loop
    print("closed-loop UMBmark square (4 x 4 m, dt = 10 ms), noise-free LabMate")
    print(f"  plain loop: {loop_runs_s:9.1f} runs/s {loop_samples_s / 1e6:8.3f} M samples/s")
    for n in args.runs:
        dirs = [Direction.CW, Direction.CCW] * (n // 2)
        t_vec, result = best_of(lambda dirs=dirs: simulate(robot, path, dirs), 1)
        runs_s = len(dirs) / t_vec
        samples_s = float(np.sum(result.samples_used)) / t_vec
        print(
            f"  vectorized, {len(dirs):5d} runs: {runs_s:9.1f} runs/s "
            f"{samples_s / 1e6:8.3f} M samples/s   ratio {runs_s / loop_runs_s:6.1f}x"
        )
    # Same model: the loop's end poses match the vectorized ones.
    check = simulate(robot, path, loop_dirs[:2])
    diff = max(float(np.abs(check.true_end[i] - np.array(loop[i][0])).max()) for i in range(2))
    print(f"  largest end-pose difference, loop vs vectorized: {diff:.2e} m")


if __name__ == "__main__":
    main()

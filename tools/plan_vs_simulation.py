"""How ``umbmark plan``'s closed forms compare with the slip simulator of ``umbmark study``.

For each cell (square side L, wheelbase b), simulates N robots built as the study builds
them (slip 0.0004 m^0.5, E_d within +-2 %, E_b within +-5 %) driving 5 + 5 squares,
estimates E_d and E_b with the default (exact) estimator, and prints the pooled per-axis
scatter of the return errors, then the ratio of the estimates' actual spread (SD of
estimate - truth) to what ``umbmark.plan`` predicts from that scatter, with the ``slip``
model (the default: x and y correlated) and the ``tape`` model (independent x and y)
side by side, and the ratio of the benchmark's root-mean-square SEM to the planned one.
The sample SD of N trials has a relative standard error of about 1/sqrt(2N). Run:

    python tools/plan_vs_simulation.py [N [L b [L b ...]]]

(default: N = 2000 for the cells L = 1 m b = 0.2 m, 4 m 0.34 m, 0.75 m 0.2 m).
"""

from __future__ import annotations

import math
import sys

import numpy as np

import umbmark
from umbmark.estimators.base import SquareTest
from umbmark.estimators.exact import exact_components
from umbmark.model.kinematics import WheelParams
from umbmark.sim.experiments import umbmark_trials
from umbmark.sim.robot import NoiseModel, SimRobot

SLIP = 0.0004
RUNS = 5


def cell(side: float, wheelbase: float, count: int, seed: int) -> str:
    """One line: the cell, its scatter and the ratios actual / planned."""
    rng = np.random.default_rng(seed)
    odometry = WheelParams(
        wheelbase=wheelbase,
        wheel_diameter=0.15 * wheelbase / 0.34,
        encoder_resolution=2000,
        gear_ratio=20.0,
    )
    E_d = 1 + rng.uniform(-0.02, 0.02, count)
    E_b = 1 + rng.uniform(-0.05, 0.05, count)
    robots = [
        SimRobot.with_errors(odometry, E_d=d, E_b=e, noise=NoiseModel(slip=SLIP))
        for d, e in zip(E_d, E_b, strict=True)
    ]
    test = SquareTest(side, wheelbase)
    errors, squares, sems = [], [], []
    for trial in umbmark_trials(robots, side, RUNS, rng=rng):
        bench = trial.benchmark
        estimate = exact_components(np.concatenate([bench.cw.cg, bench.ccw.cg]), test)
        robot = trial.robot
        errors.append((estimate["E_d"] - robot.E_d, estimate["E_b"] - robot.wheelbase / wheelbase))
        squares.append(sum(float(np.sum((c.errors - c.cg) ** 2)) for c in bench.clusters))
        sems.append(bench.sem)
    spread = np.std(np.array(errors), axis=0, ddof=1)
    sigma = math.sqrt(sum(squares) / (count * 4 * (RUNS - 1)))
    rms_sem = math.sqrt(float(np.mean(np.square(sems))))
    slip, tape = (
        umbmark.plan(scatter=sigma, wheelbase=wheelbase, side_length=side, runs=RUNS, noise=noise)
        for noise in ("slip", "tape")
    )
    return (
        f"L = {side:4.2f} m  b = {wheelbase:4.2f} m  N = {count}  scatter {sigma * 1000:6.2f} mm"
        f"  | E_d {spread[0] / slip.se_E_d:.3f} {spread[0] / tape.se_E_d:.3f}"
        f"  | E_b {spread[1] / slip.se_E_b:.3f} {spread[1] / tape.se_E_b:.3f}"
        f"  | SEM {rms_sem / slip.sem:.3f}  | slip {slip.slip / SLIP if slip.slip else 0:.3f}"
    )


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    numbers = [float(v) for v in sys.argv[2:]]
    cells = list(zip(numbers[::2], numbers[1::2], strict=True)) or [
        (1.0, 0.2),
        (4.0, 0.34),
        (0.75, 0.2),
    ]
    print(f"actual / planned spread (slip model, tape model), SD's relative SE "
          f"{1 / math.sqrt(2 * count) * 100:.1f} %; SEM and slip: actual / planned")  # fmt: skip
    for k, (side, wheelbase) in enumerate(cells):
        print(cell(side, wheelbase, count, seed=3 + k), flush=True)


if __name__ == "__main__":
    main()

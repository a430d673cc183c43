"""How ``umbmark plan``'s closed form compares with the slip simulator.

Simulates N robots (slip 0.0004, E_d within ±0.5 %, E_b within ±2 %) driving 5 + 5
squares of side L with wheelbase b, calibrates each with the default (exact) estimator,
and prints the pooled per-axis scatter of the return errors and the ratios of the
estimates' actual spread to what ``umbmark.plan`` predicts from that scatter. Run:
python tools/plan_vs_simulation.py [L b N]   (default 1.0 0.2 200)
"""

from __future__ import annotations

import sys

import numpy as np

import umbmark
from umbmark.kinematics import WheelParams
from umbmark.sim.experiments import calibrate_robot, umbmark_trials
from umbmark.sim.robot import NoiseModel, VirtualRobot


def main() -> None:
    side, wheelbase, count = 1.0, 0.2, 200
    if len(sys.argv) == 4:
        side, wheelbase, count = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
    runs = 5
    rng = np.random.default_rng(3)
    odometry = WheelParams(
        wheelbase=wheelbase,
        wheel_diameter=0.15 * wheelbase / 0.34,
        encoder_resolution=2000,
        gear_ratio=20.0,
    )
    E_d = 1 + rng.uniform(-0.005, 0.005, count)
    E_b = 1 + rng.uniform(-0.02, 0.02, count)
    robots = [
        VirtualRobot.with_errors(odometry, E_d=d, E_b=e, noise=NoiseModel(slip=0.0004))
        for d, e in zip(E_d, E_b, strict=True)
    ]
    errors, scatter = [], []
    for trial in umbmark_trials(robots, side, runs, rng=rng):
        estimate = calibrate_robot(trial, side, "exact")[0].estimate
        robot = trial.robot
        errors.append((estimate.E_d - robot.E_d, estimate.E_b - robot.wheelbase / wheelbase))
        deviations = np.vstack([c.errors - c.cg for c in trial.benchmark.clusters])
        scatter.append(np.sum(deviations**2) / (2 * (deviations.shape[0] - 2)))
    spread = np.std(np.array(errors), axis=0, ddof=1)
    sigma = float(np.sqrt(np.mean(scatter)))
    plan = umbmark.plan(scatter=sigma, wheelbase=wheelbase, side_length=side, runs=runs)
    print(f"L = {side} m, b = {wheelbase} m, {count} robots: scatter {sigma * 1000:.2f} mm/axis")
    print(f"actual / planned spread: E_d {spread[0] / plan.se_E_d:.2f}, "
          f"E_b {spread[1] / plan.se_E_b:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()

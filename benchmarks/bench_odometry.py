"""Odometry integration: umbmark's vectorized integrator against per-sample Python loops.

Both integrate the same wheel increments with the same model (exact arcs) and return every
pose. Two loops are timed, because "a plain loop" is written two ways in practice:

- a tuned loop: Python floats, the math module, a list of tuples turned into an array;
- an indexing loop: the usual script, reading and writing numpy arrays sample by sample.

Run: python benchmarks/bench_odometry.py [--samples N]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from umbmark.model.kinematics import integrate_odometry

from _timing import best_of


def tuned_loop(d_left: np.ndarray, d_right: np.ndarray, b: float) -> np.ndarray:
    x = y = th = 0.0
    out = [(0.0, 0.0, 0.0)]
    for left, right in zip(d_left.tolist(), d_right.tolist(), strict=True):
        ds = 0.5 * (right + left)
        dth = (right - left) / b
        half = 0.5 * dth
        chord = ds if half == 0.0 else ds * math.sin(half) / half
        x += chord * math.cos(th + half)
        y += chord * math.sin(th + half)
        th += dth
        out.append((x, y, th))
    return np.array(out)


def indexing_loop(d_left: np.ndarray, d_right: np.ndarray, b: float) -> np.ndarray:
    poses = np.zeros((len(d_left) + 1, 3))
    for i in range(len(d_left)):
        ds = (d_right[i] + d_left[i]) / 2
        dth = (d_right[i] - d_left[i]) / b
        x, y, th = poses[i]
        chord = ds if dth == 0 else ds * np.sin(dth / 2) / (dth / 2)
        poses[i + 1] = (
            x + chord * np.cos(th + dth / 2),
            y + chord * np.sin(th + dth / 2),
            th + dth,
        )
    return poses


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1_000_000, help="samples to integrate")
    parser.add_argument("--runs", type=int, default=10, help="runs (rows) they are split into")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    shape = (args.runs, args.samples // args.runs)
    d_left = rng.uniform(0.0, 0.002, shape)
    d_right = d_left + rng.normal(0.0, 1e-4, shape)
    b = 0.34

    t_vec, poses = best_of(lambda: integrate_odometry(d_left, d_right, b))
    n = d_left.size
    # The loops are slow: time them on a tenth of the runs and compare per sample.
    k = max(1, args.runs // 10)
    t_tuned, tuned = best_of(
        lambda: [tuned_loop(d_left[i], d_right[i], b) for i in range(k)], repeat=1
    )
    t_index, indexed = best_of(
        lambda: [indexing_loop(d_left[i], d_right[i], b) for i in range(k)], repeat=1
    )
    m = k * shape[1]
    worst = max(float(np.abs(poses[i] - tuned[i]).max()) for i in range(k))
    worst = max(worst, *(float(np.abs(poses[i] - indexed[i]).max()) for i in range(k)))
    rate_vec, rate_tuned, rate_index = n / t_vec, m / t_tuned, m / t_index
    print(f"odometry integration, exact arcs, {args.runs} runs x {shape[1]} samples")
    print(f"  vectorized (umbmark)  {rate_vec / 1e6:8.2f} M samples/s")
    print(
        f"  tuned Python loop     {rate_tuned / 1e6:8.3f} M samples/s   "
        f"ratio {rate_vec / rate_tuned:6.1f}x"
    )
    print(
        f"  indexing loop         {rate_index / 1e6:8.3f} M samples/s   "
        f"ratio {rate_vec / rate_index:6.1f}x"
    )
    print(f"  largest difference between them: {worst:.2e} m")


if __name__ == "__main__":
    main()

"""Robots with large systematic errors: does ``umbmark calibrate`` take their runs tables?

Virtual robots drive the bi-directional square test (5 + 5 runs, 4 m square, b = 0.34 m,
the default slip), steering by their own odometry; each one's runs table (metres) is
calibrated as a user would, ``umbmark.calibrate(table, side_length=4, wheelbase=0.34)``.
Counted: the tables whose return errors exceed the side, those refused (and whether the
refusal blames a unit), and for those taken how far the exact inversion's ``E_d`` and
``E_b`` are from the truth.

The robots' ``E_d`` and ``E_b`` are drawn from normal distributions about 1 (standard
deviations ``--sd-d``, ``--sd-b``), kept where ``|E_d - 1| <= 5 %`` and
``|E_b - 1| <= 10 %``; ``--uniform`` draws them uniformly within those bounds instead.

Run: python tools/large_errors.py [--robots 600] [--seed 1] [--uniform]
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

import umbmark

SIDE, WHEELBASE = 4.0, 0.34
E_D_BOUND, E_B_BOUND = 0.05, 0.10


def draw(rng: np.random.Generator, args: argparse.Namespace) -> tuple[float, float]:
    """One robot's ``E_d``, ``E_b`` within the bounds."""
    while True:
        if args.uniform:
            e_d = 1.0 + rng.uniform(-E_D_BOUND, E_D_BOUND)
            e_b = 1.0 + rng.uniform(-E_B_BOUND, E_B_BOUND)
        else:
            e_d, e_b = 1.0 + rng.normal(0.0, args.sd_d), 1.0 + rng.normal(0.0, args.sd_b)
        if abs(e_d - 1.0) <= E_D_BOUND and abs(e_b - 1.0) <= E_B_BOUND:
            return float(e_d), float(e_b)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=600)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--sd-d", type=float, default=0.015)
    parser.add_argument("--sd-b", type=float, default=0.04)
    parser.add_argument("--uniform", action="store_true")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    beyond = refused = unit_blamed = 0
    misses: list[tuple[float, float]] = []
    examples: list[str] = []
    with tempfile.TemporaryDirectory() as folder:
        table = Path(folder) / "runs.csv"
        for k in range(args.robots):
            e_d, e_b = draw(rng, args)
            sim = umbmark.simulate(E_d=e_d, E_b=e_b, seed=args.seed * 100_000 + k)
            sim.write(output=table)
            worst = max(math.hypot(*run.return_error) for run in sim.runs)
            beyond += worst > SIDE
            try:
                report = umbmark.calibrate(table, side_length=SIDE, wheelbase=WHEELBASE)
            except umbmark.InputError as exc:
                refused += 1
                blamed = "--unit" in str(exc)
                unit_blamed += blamed
                if len(examples) < 3:
                    examples.append(f"E_d {e_d:.4f}, E_b {e_b:.4f}: {exc}")
                continue
            misses.append((report.estimate.E_d - e_d, report.estimate.E_b - e_b))
    taken = len(misses)
    print(
        f"{args.robots} robots ({'uniform' if args.uniform else 'normal'} E_d, E_b), "
        f"{beyond} with a return error beyond the {SIDE:g} m side"
    )
    print(f"refused: {refused} ({unit_blamed} blaming a unit); taken: {taken}")
    if misses:
        miss = np.abs(np.array(misses))
        print(
            f"taken: |E_d - truth| median {np.median(miss[:, 0]):.2e}, max "
            f"{miss[:, 0].max():.2e}; |E_b - truth| median {np.median(miss[:, 1]):.2e}, "
            f"max {miss[:, 1].max():.2e}"
        )
    for line in examples:
        print("  " + line)


if __name__ == "__main__":
    main()

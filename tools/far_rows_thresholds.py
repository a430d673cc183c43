"""How often Gaussian runs tables have a row :func:`umbmark.estimators.rows.far_rows`
names: the false alarms behind its thresholds (``FAR``, ``TYPO``).

Tables like the bundled one (cw centre (69, 57) mm, ccw (228, -206) mm, odometry ends at
the start, numbers typed to 0.1 mm) with Gaussian runs about the centres: ``n`` runs a
direction, standard deviations ``sx``, ``sy`` [mm] in x and y, the ccw cluster ``ratio``
times wider. Printed for each setting: the 99.9th percentile and the largest of the
tables' farthest row (in robust standard deviations), the share of tables with a row
beyond ``FAR``, and with a row named at all.

Run: python tools/far_rows_thresholds.py [--tables 20000] [--seed 7]
"""

from __future__ import annotations

import argparse

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.estimators.rows import FAR, far_rows, judge_rows
from umbmark.model.run import EndPose, Run

SETTINGS = [  # n, sx, sy, ratio
    (3, 20, 20, 1), (5, 20, 20, 1), (10, 20, 20, 1), (20, 20, 20, 1),
    (5, 15, 30, 1), (5, 15, 30, 2), (10, 15, 30, 2), (3, 15, 30, 2),
]  # fmt: skip
CENTRES = {Direction.CW: (69.0, 57.0), Direction.CCW: (228.0, -206.0)}


def table(rng: np.random.Generator, n: int, sx: float, sy: float, ratio: float) -> list[Run]:
    """One table's runs [m]."""
    runs = []
    for direction, (cx, cy) in CENTRES.items():
        wide = ratio if direction is Direction.CCW else 1.0
        for _ in range(n):
            x = round(cx + rng.normal() * sx * wide, 1) / 1000.0
            y = round(cy + rng.normal() * sy * wide, 1) / 1000.0
            label = f"row {len(runs) + 2}"
            runs.append(Run(direction, EndPose(x, y, None), EndPose(0.0, 0.0, None), label))
    return runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tables", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    print("n  sx  sy  ratio   99.9 %  largest  beyond FAR  named")
    for n, sx, sy, ratio in SETTINGS:
        farthest, named = [], 0
        for _ in range(args.tables):
            runs = table(rng, n, sx, sy, ratio)
            judged = judge_rows(runs)
            assert judged is not None
            farthest.append(max(judged.sigmas(run) for run in runs))
            named += bool(far_rows(runs, "mm"))
        far = np.asarray(farthest)
        print(
            f"{n:<2} {sx:>3} {sy:>3} {ratio:>5} {np.percentile(far, 99.9):>8.1f} "
            f"{far.max():>8.1f} {np.mean(far >= FAR):>11.5f} {named / args.tables:>6.5f}"
        )


if __name__ == "__main__":
    main()

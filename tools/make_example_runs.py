"""Regenerate ``src/umbmark/data/labmate_runs_mm.csv``, the bundled example runs table.

A virtual LabMate (b = 340 mm) with the errors of the paper's Fig. 11 drives 5 cw and 5 ccw
runs around a 4 x 4 m square with the paper's ~25 mm scatter (umbmark's simulator); the
end points are written in millimetres, rounded to 0.1 mm, as a tape-measure user would.

Run: python tools/make_example_runs.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from umbmark.core.atomic import atomic_write_text
from umbmark.sim.experiments import umbmark_trials
from umbmark.sim.reproduce import FIG11_E_B, FIG11_E_D, PAPER_NOISE
from umbmark.sim.robot import LABMATE, SimRobot

SEED = 1996
TARGET = Path(__file__).resolve().parents[1] / "src" / "umbmark" / "data" / "labmate_runs_mm.csv"


def main() -> None:
    robot = SimRobot.with_errors(LABMATE, E_d=FIG11_E_D, E_b=FIG11_E_B, noise=PAPER_NOISE)
    (trial,) = umbmark_trials([robot], 4.0, rng=np.random.default_rng(SEED))
    lines = [
        "# UMBmark example: 5 cw and 5 ccw runs around a 4 x 4 m square, lengths in mm.",
        "# A virtual LabMate (b = 340 mm) with the errors of the paper's Fig. 11",
        f"# (E_d = {FIG11_E_D}, E_b = 336.17/340 = {FIG11_E_B:.6f}) and ~25 mm scatter,",
        f"# simulated by umbmark (tools/make_example_runs.py, seed {SEED}).",
        "# Calibrate: umbmark calibrate FILE --side-length 4 --wheelbase 0.34 --unit mm",
        "direction,x_abs,y_abs,x_odo,y_odo",
    ]
    for run in trial.runs:
        t, o = run.true_end, run.odometry_end
        cells = [f"{round(1000 * v, 1) + 0.0:.1f}" for v in (t.x, t.y, o.x, o.y)]
        lines.append(",".join([run.direction.value, *cells]))
    atomic_write_text(TARGET, "\n".join(lines) + "\n")
    print(f"wrote {TARGET}")


if __name__ == "__main__":
    main()

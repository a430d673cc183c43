"""The scrub model calibrated on squares and replayed on circles: identified or not.

For each pool of OptiOdom sessions: what its runs hold (straight legs, arcs, turns on the
spot), the inflation ``k`` of the scrub model's wheelbase (``umbmark.estimators.motions``:
identified when k <= 3), and the mean end-position error [mm] of the six circle sessions
of day 2506 replayed with each calibration: ``trajectory``, ``trajectory-scrub`` as
``umbmark calibrate`` gives it (one wheelbase where the scrub term is not identified),
and the scrub model fitted anyway (what ``trajectory-scrub`` gave before it checked).
With ``--auto``, what ``calibrate --method auto`` picks for the squares with the
straights and spot turns of day 2506 (about half a minute).

Run: python tools/scrub_identification.py [--data ../shared/data/optiodom] [--auto]
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import numpy as np

import umbmark
from umbmark.calibration.active import read_runs
from umbmark.estimators.motions import motion_coverage
from umbmark.estimators.trajectory_fit import fit_trajectories
from umbmark.model.kinematics import WheelParams
from umbmark.model.runs import end_errors
from umbmark.runs.load import LoadOptions, load_runs
from umbmark.runs.options import ReadOptions

POOLS = {
    "square 2042": ["square/230620202042"],
    "square 0029": ["square/231220200029"],
    "both squares": ["square/230620202042", "square/231220200029"],
    "straights+spot 2506 (ivanjko)": [f"ivanjko/2506202016{s}" for s in ("18", "36", "55")]
    + ["ivanjko/250620201738"],
    "squares + ivanjko": ["square/230620202042", "square/231220200029"]
    + [f"ivanjko/2506202016{s}" for s in ("18", "36", "55")]
    + ["ivanjko/250620201738"],
    "square 2042 + circle 2104": ["square/230620202042", "circular/250620202104"],
}


def circles_error(root: Path, params_for: object) -> float:
    """Mean end-position error [mm] of the circle sessions, each replayed with
    ``params_for(nominal)``."""
    errors = []
    for session in sorted((root / "circular").iterdir()):
        loaded = load_runs(session, "optiodom", LoadOptions())
        assert loaded.params is not None
        params = params_for(loaded.params)  # type: ignore[operator]
        errors.append(np.mean(end_errors([run.reintegrated(params) for run in loaded.runs])))
    return 1000.0 * float(np.mean(errors))


def row(root: Path, name: str, sessions: Sequence[str]) -> None:
    paths = [root / s for s in sessions]
    read = read_runs(paths, ReadOptions.of({}), force=True)
    assert read.params is not None
    logs = [run.log for run in read.runs if run.log is not None]
    cover = motion_coverage(logs, read.params)
    cells = [f"{name:32s}", f"{', '.join(cover.held):>20s}", f"{cover.inflation:8.1f}"]
    for method in ("trajectory", "trajectory-scrub"):
        report = umbmark.calibrate(*paths, method=method, force=True)
        width = 12 if method == "trajectory" else 10
        cells.append(f"{circles_error(root, report.new_params().applied_to):{width}.1f}")
    try:
        fit = fit_trajectories(logs, read.params, model="scrub", check_coverage=False)

        def scrub(nominal: WheelParams) -> WheelParams:
            return fit.params(nominal)

        cells.append(f"{circles_error(root, scrub):14.1f}")
    except ValueError as exc:
        cells.append(f"  refused: {str(exc)[:60]}")
    print("".join(cells))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(__file__).resolve().parents[2] / "shared" / "data" / "optiodom"
    parser.add_argument("--data", type=Path, default=default)
    parser.add_argument("--auto", action="store_true", help="also run calibrate --method auto")
    args = parser.parse_args()
    print("Mean end-position error of the 6 circle sessions of day 2506 replayed [mm]")
    print(
        f"{'calibrated on':32s}{'holds':>20s}{'k':>8s}{'trajectory':>12s}"
        f"{'scrub now':>10s}{'scrub forced':>14s}"
    )
    for name, sessions in POOLS.items():
        row(args.data, name, sessions)
    if args.auto:
        paths = [args.data / s for s in POOLS["squares + ivanjko"]]
        report = umbmark.calibrate(*paths, method="auto", force=True)
        error = circles_error(args.data, report.new_params().applied_to)
        print(f"\nauto on squares + ivanjko: {report.estimate.method}, circles {error:.1f} mm")
        print(report.notes[-1])


if __name__ == "__main__":
    main()

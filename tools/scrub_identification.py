"""Where the scrub model is identified, and what it predicts: OptiOdom sessions replayed.

1. (default) For each pool of OptiOdom sessions: what its runs hold (straight legs, arcs,
   turns on the spot), whether ``trajectory-scrub`` fitted its two wheelbases (else it
   gave the single wheelbase, with the reason), and the mean end-position error [mm] of
   the six circle sessions of day 2506 replayed with ``trajectory`` and with
   ``trajectory-scrub`` as ``umbmark calibrate`` gives them.
2. ``--loso``: leave one session out on pools that mix circles with squares or straights
   with turns on the spot, about 9 % of the turning on the spot in the folds that hold a
   spot session out: ``trajectory-scrub`` calibrated on the other sessions, the held-out
   one replayed; mean end-position error [mm] per held-out session and over the pool
   (``--single``: the same for ``trajectory``). The folds run in parallel (``--jobs``).
3. ``--auto``: what ``calibrate --method auto`` picks for the squares with the straights
   and spot turns of day 2506 (about half a minute).

The tool uses only ``umbmark.calibrate`` and ``umbmark.replay``, so that it runs on any
version: to compare with the rule before issue 21 (the turning-share spread, commit
8f0b291), run it with that version's ``src`` first on ``PYTHONPATH``.

Run: python tools/scrub_identification.py [--data ../shared/data/optiodom] [--loso]
     [--single] [--auto] [--jobs 2]
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import umbmark
from umbmark.estimators.motions import motion_coverage
from umbmark.runs.active import read_runs
from umbmark.runs.read_options import ReadOptions

CIRCLES_2506 = [f"circular/25062020{s}" for s in ("2104", "2119", "2236", "2251", "2317", "2345")]
SPOT_2506 = [f"ivanjko/2506202016{s}" for s in ("18", "36", "55")] + ["ivanjko/250620201738"]
SQUARES = ["square/230620202042", "square/231220200029"]

POOLS = {
    "square 2042": SQUARES[:1],
    "square 0029": SQUARES[1:],
    "both squares": SQUARES,
    "straights+spot 2506 (ivanjko)": SPOT_2506,
    "squares + ivanjko": SQUARES + SPOT_2506,
    "square 2042 + circle 2104": [SQUARES[0], "circular/250620202104"],
}
#: Pools left one session out: circles with two sessions of spot turns (day 2506 alone;
#: the circles with the two squares), and the whole day 2506 (a third of the turning on
#: the spot in every fold).
LOSO = {
    "day 2506: 6 circle sessions + spot sessions 1618, 1636": CIRCLES_2506 + SPOT_2506[:2],
    "6 circle sessions of 2506 + squares 2042, 0029": CIRCLES_2506 + SQUARES,
    "day 2506: 6 circle + 4 spot sessions": CIRCLES_2506 + SPOT_2506,
}


def circles_error(root: Path, report: umbmark.CalibrationReport) -> float:
    """Mean end-position error [mm] of the circle sessions of day 2506 replayed with
    ``report``, the mean of the sessions' means."""
    errors = [umbmark.replay(root / s, report, force=True).mean_end_error for s in CIRCLES_2506]
    return 1000.0 * float(np.mean(errors))


def scrub_state(report: umbmark.CalibrationReport) -> str:
    """``b_arc/b_spot`` [mm] where ``trajectory-scrub`` fitted both, else ``one b``."""
    fit = report.model_fit
    if fit is None or fit.spot_wheelbase is None:
        return "one b"
    return f"{1000 * fit.wheelbase:.1f}/{1000 * fit.spot_wheelbase:.1f}"


def row(root: Path, name: str, sessions: Sequence[str]) -> None:
    paths = [root / s for s in sessions]
    read = read_runs(paths, ReadOptions.of({}), force=True)
    assert read.params is not None
    logs = [run.log for run in read.runs if run.log is not None]
    cells = [f"{name:32s}", f"{', '.join(motion_coverage(logs, read.params).held):>20s}"]
    single = umbmark.calibrate(*paths, method="trajectory", force=True)
    scrub = umbmark.calibrate(*paths, method="trajectory-scrub", force=True)
    cells += [f"{scrub_state(scrub):>14s}", f"{circles_error(root, single):12.1f}"]
    cells.append(f"{circles_error(root, scrub):10.1f}")
    print("".join(cells), flush=True)


def fold(root: Path, pool: Sequence[str], held: str, method: str) -> tuple[float, str]:
    """Calibrate ``method`` on ``pool`` without ``held``; the held-out session's mean
    end-position error [mm] and :func:`scrub_state`."""
    paths = [root / s for s in pool if s != held]
    report = umbmark.calibrate(*paths, method=method, force=True)
    error = umbmark.replay(root / held, report, force=True).mean_end_error
    return 1000.0 * error, scrub_state(report)


def leave_one_out(root: Path, methods: Sequence[str], jobs: int) -> None:
    print(
        "Leave one session out: mean end-position error of the held-out session [mm] "
        f"(umbmark from {Path(umbmark.__file__).parent})"
    )
    with ProcessPoolExecutor(jobs) as pool_of_workers:
        for name, pool in LOSO.items():
            print(f"\n{name}")
            print(f"{'held out':24s}" + "".join(f"{m:>18s}{'b_arc/b_spot':>14s}" for m in methods))
            work = {
                (held, m): pool_of_workers.submit(fold, root, pool, held, m)
                for held in pool
                for m in methods
            }
            table = []
            for held in pool:
                results = [work[held, m].result() for m in methods]
                table.append([error for error, _ in results])
                cells = "".join(f"{error:18.1f}{state:>14s}" for error, state in results)
                print(f"{held:24s}{cells}", flush=True)
            mean = np.mean(table, axis=0)
            print(f"{'mean':24s}" + "".join(f"{e:18.1f}{'':14s}" for e in mean))
            spot = [t for t, held in zip(table, pool, strict=True) if "circular" not in held]
            spread = np.min(spot, axis=0), np.max(spot, axis=0)
            print(
                f"{'spot sessions held out':24s}"
                + "".join(f"{lo:11.1f} to{hi:5.1f}{'':14s}" for lo, hi in zip(*spread, strict=True))
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(__file__).resolve().parents[2] / "shared" / "data" / "optiodom"
    parser.add_argument("--data", type=Path, default=default)
    parser.add_argument("--loso", action="store_true", help="leave one session out instead")
    parser.add_argument("--single", action="store_true", help="--loso: trajectory as well")
    parser.add_argument("--jobs", type=int, default=2, help="--loso: folds in parallel")
    parser.add_argument("--auto", action="store_true", help="also run calibrate --method auto")
    args = parser.parse_args()
    if args.loso:
        methods = ["trajectory-scrub", "trajectory"] if args.single else ["trajectory-scrub"]
        leave_one_out(args.data, methods, args.jobs)
        return
    print("Mean end-position error of the 6 circle sessions of day 2506 replayed [mm]")
    print(
        f"{'calibrated on':32s}{'holds':>20s}{'b_arc/b_spot':>14s}{'trajectory':>12s}{'scrub':>10s}"
    )
    for name, sessions in POOLS.items():
        row(args.data, name, sessions)
    if args.auto:
        paths = [args.data / s for s in POOLS["squares + ivanjko"]]
        report = umbmark.calibrate(*paths, method="auto", force=True)
        error = circles_error(args.data, report)
        print(f"\nauto on squares + ivanjko: {report.estimate.method}, circles {error:.1f} mm")
        print(report.notes[-1])


if __name__ == "__main__":
    main()

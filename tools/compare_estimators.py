"""Compare the estimators on the real OptiOdom sessions by replay.

Every estimator calibrates on each session it can use (the square-test estimators need the
square sessions; endpoints and trajectory take any), and every calibration is
replayed on every session: the mean end-pose error of the runs [mm], against the nominal
parameters' error. Run: python tools/compare_estimators.py [--data ../shared/data/optiodom]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import umbmark

SESSIONS = ("square/230620202042", "square/231220200029", "circular/250620202104")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(__file__).resolve().parents[2] / "shared" / "data" / "optiodom"
    parser.add_argument("--data", type=Path, default=default)
    args = parser.parse_args()

    def replay(calibration: umbmark.CalibrationReport | None) -> str:
        errors = [umbmark.replay(args.data / s, calibration) for s in SESSIONS]
        return "".join(f"{1000 * r.mean_end_error:9.1f}" for r in errors)

    names = [s.split("/")[0][:6] + " " + s.split("/")[1][-4:] for s in SESSIONS]
    print("mean end-pose error on replay [mm]; columns: " + ", ".join(names))
    print(f"{'nominal parameters':42s}" + replay(None))
    for source in SESSIONS:
        square = source.startswith("square")
        logged = ["endpoints", "trajectory"]
        for method in ["paper", "exact", "heading", "endpose", *logged] if square else logged:
            report = umbmark.calibrate(args.data / source, method=method)
            print(f"{f'{method} from {source}':42s}" + replay(report))


if __name__ == "__main__":
    main()

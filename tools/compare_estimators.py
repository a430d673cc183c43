"""Compare the estimators on the real OptiOdom sessions by replay.

Every estimator calibrates on each session it can use (the paper's, exact and heading
methods need the square sessions; the trajectory fit takes any), and every calibration is
replayed on every session: the mean end-pose error of the runs [mm], against the nominal
parameters' error. Run: python tools/compare_estimators.py [--data ../shared/data/optiodom]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from umbmark.benchmark import umbmark_benchmark
from umbmark.calibration import ActiveParams, Calibration
from umbmark.estimators import SquareTest, estimate_errors
from umbmark.estimators.trajectory import trajectory_estimate
from umbmark.kinematics import WheelParams
from umbmark.logged import end_errors, reintegrate
from umbmark.sources.load import Loaded, LoadOptions, load_runs

SESSIONS = ("square/230620202042", "square/231220200029", "circular/250620202104")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(__file__).resolve().parents[2] / "shared" / "data" / "optiodom"
    parser.add_argument("--data", type=Path, default=default)
    parser.add_argument("--window", type=float, default=1.0, help="trajectory window [s]")
    args = parser.parse_args()
    loaded: dict[str, Loaded] = {
        s: load_runs(args.data / s, "optiodom", LoadOptions()) for s in SESSIONS
    }

    def replay(params: WheelParams) -> list[float]:
        return [
            1000 * float(end_errors(reintegrate(loaded[s].runs, params)).mean()) for s in SESSIONS
        ]

    names = [s.split("/")[0][:6] + " " + s.split("/")[1][-4:] for s in SESSIONS]
    print("mean end-pose error on replay [mm]; columns: " + ", ".join(names))
    nominal = loaded[SESSIONS[0]].params
    assert nominal is not None
    print(f"{'nominal parameters':42s}" + "".join(f"{e:9.1f}" for e in replay(nominal)))
    for source in SESSIONS:
        data = loaded[source]
        params = data.params
        assert params is not None
        active = ActiveParams(
            wheelbase=params.wheelbase,
            c_left=params.c_left,
            c_right=params.c_right,
            wheel_diameter=params.wheel_diameter,
        )
        methods = (
            ["paper", "exact", "heading", "trajectory"] if data.side_length else ["trajectory"]
        )
        for method in methods:
            if method == "trajectory":
                logs = [r.log for r in data.runs if r.log is not None]
                estimate, _ = trajectory_estimate(logs, params, data.side_length, args.window)
            else:
                assert data.side_length is not None
                bench = umbmark_benchmark(data.runs)
                test = SquareTest(data.side_length, params.wheelbase)
                estimate = estimate_errors(method, bench, data.runs, test)  # type: ignore[arg-type]
            cal = Calibration(estimate, active)
            new = params.with_corrections(
                c_left=cal.new_c_left, c_right=cal.new_c_right, wheelbase=cal.wheelbase_corrected
            )
            label = f"{method} from {source}"
            print(f"{label:42s}" + "".join(f"{e:9.1f}" for e in replay(new)))


if __name__ == "__main__":
    main()

"""The trajectory fit on the real OptiOdom sessions: replays, leave-one-out, time offsets.

1. Replays (as tools/compare_estimators.py): each calibration is replayed on the squares
   and the circles; mean end-pose error of the runs [mm]. The paper's method against the
   trajectory fit (one wheelbase, "diff") and its scrub model (a wheelbase for arcs and
   one for spot turns, replayed with both), each with the run's start pose fitted (the
   default) or taken from the ground truth.
2. Leave one session out on day 2506 (circles; straights with spot turns): fit on the
   other nine sessions, replay the one left out.
3. What the fit finds on every session alone: wheel diameters, wheelbase(s), the time
   offset between wheels and ground truth, with their standard errors, and whether the
   session identifies the scrub model's turn-rate term (it holds arcs and turns on the
   spot; "both turns"). The scrub model is fitted even where it is not identified, to
   show what it would find.

Run: python tools/trajectory_on_real_data.py [--data ../shared/data/optiodom] [--no-loo]
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

import umbmark
from umbmark.estimators.motions import MotionCoverage, motion_coverage
from umbmark.estimators.trajectory_fit import TrajectoryFit, fit_trajectories
from umbmark.estimators.trajectory_model import StartPose, TrajectoryModel
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run, end_errors
from umbmark.runs.load import LoadOptions, load_runs

REPLAYED = ("square/230620202042", "square/231220200029", "circular/250620202104")
#: Turns nominal parameters into the parameters of a calibration.
Apply = Callable[[WheelParams], WheelParams]


class Sessions:
    """The sessions' runs, read once, with their nominal parameters."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.names = sorted(f"{p.parent.name}/{p.name}" for p in root.glob("*/*") if p.is_dir())
        self._runs: dict[str, tuple[list[Run], WheelParams]] = {}

    def runs(self, name: str) -> tuple[list[Run], WheelParams]:
        if name not in self._runs:
            loaded = load_runs(self.root / name, "optiodom", LoadOptions())
            assert loaded.params is not None
            self._runs[name] = (loaded.runs, loaded.params)
        return self._runs[name]

    def fit(
        self,
        names: Sequence[str],
        model: TrajectoryModel = "diff",
        start_pose: StartPose = "fitted",
    ) -> TrajectoryFit:
        logs = [run.log for name in names for run in self.runs(name)[0] if run.log]
        # The scrub model is fitted even where the runs do not identify its turn-rate term
        # (check_coverage=False): this tool studies what it would find.
        return fit_trajectories(
            logs,
            self.runs(names[0])[1],
            model=model,
            start_pose=start_pose,
            check_coverage=False,
        )

    def coverage(self, name: str) -> MotionCoverage:
        """What the session's runs hold."""
        runs, params = self.runs(name)
        return motion_coverage([run.log for run in runs if run.log], params)

    def replay(self, name: str, apply: Apply) -> float:
        """Mean end-position error [mm] of session ``name`` replayed with ``apply``."""
        runs, nominal = self.runs(name)
        params = apply(nominal)
        return 1000.0 * float(np.mean(end_errors([run.reintegrated(params) for run in runs])))


def short(name: str) -> str:
    """``square 2042`` for ``square/230620202042``."""
    kind, session = name.split("/")
    return f"{kind[:6]} {session[-4:]}"


def replay_table(sessions: Sessions) -> None:
    print("1. Mean end-pose error on replay [mm]")
    print(f"{'calibrated with':52s}" + "".join(f"{short(s):>13s}" for s in REPLAYED))

    def row(label: str, apply: Apply) -> None:
        print(f"{label:52s}" + "".join(f"{sessions.replay(s, apply):13.1f}" for s in REPLAYED))

    row("nominal parameters", lambda nominal: nominal)
    for source in REPLAYED:
        if source.startswith("square"):
            calibrated = umbmark.calibrate(sessions.root / source).new_params()
            row(f"paper, from {short(source)}", calibrated.applied_to)
        for model in ("diff", "scrub"):
            for start_pose in ("fitted", "truth"):
                label = f"trajectory {model}, start {start_pose}, from {short(source)}"
                try:
                    fit = sessions.fit([source], model, start_pose)
                except ValueError as exc:
                    print(f"{label:52s}refused: {exc}")
                    continue
                row(label, fit.params)
        cover = sessions.coverage(source)
        problem = cover.scrub_problem()
        print(
            f"  {short(source)}: scrub term {'may be identified' if problem is None else problem}"
        )
    print()


def leave_one_out(sessions: Sessions) -> None:
    day = [s for s in sessions.names if "/2506" in s]
    print(f"2. Day 2506, leave one session out ({len(day)} sessions): error on the left-out [mm]")
    header = f"{'left out':18s}{'nominal':>9s}"
    variants: list[tuple[TrajectoryModel, StartPose]] = [
        ("diff", "fitted"),
        ("scrub", "fitted"),
        ("diff", "truth"),
        ("scrub", "truth"),
    ]
    print(header + "".join(f"{m + '/' + p:>14s}" for m, p in variants))
    table = []
    for name in day:
        others = [s for s in day if s != name]
        errors = [sessions.replay(name, lambda n: n)]
        errors += [sessions.replay(name, sessions.fit(others, m, p).params) for m, p in variants]
        table.append(errors)
        print(f"{short(name):18s}{errors[0]:9.1f}" + "".join(f"{e:14.1f}" for e in errors[1:]))
    mean = np.mean(table, axis=0)
    print(f"{'mean':18s}{mean[0]:9.1f}" + "".join(f"{e:14.1f}" for e in mean[1:]))
    print()


def per_session(sessions: Sessions) -> None:
    print("3. Each session alone (start pose fitted): +- one standard error")
    print(
        f"{'session':16s}{'runs':>5s}{'D_L [mm]':>16s}{'D_R [mm]':>16s}{'b [mm]':>16s}"
        f"{'b_arc [mm]':>16s}{'b_spot [mm]':>16s}{'offset [ms]':>14s}{'both turns':>11s}"
    )
    for name in sessions.names:
        diff = sessions.fit([name])
        se = diff.standard_errors

        def pm(value: float, error: float, width: int = 16, digits: int = 2) -> str:
            return f"{value:.{digits}f}+-{error:.{digits}f}".rjust(width)

        try:
            scrub = sessions.fit([name], "scrub")
            se_s = scrub.standard_errors
            assert scrub.spot_wheelbase is not None
            scrub_cells = pm(1000 * scrub.wheelbase, 1000 * se_s["wheelbase"]) + pm(
                1000 * scrub.spot_wheelbase, 1000 * se_s["spot_wheelbase"]
            )
        except ValueError:  # the scrub model's lengths are not pinned at all
            scrub_cells = f"{'-':>16s}{'-':>16s}"
        print(
            f"{short(name):16s}{diff.runs:5d}"
            + pm(2000 * diff.r_left, 2000 * se["r_left"], digits=3)
            + pm(2000 * diff.r_right, 2000 * se["r_right"], digits=3)
            + pm(1000 * diff.wheelbase, 1000 * se["wheelbase"])
            + scrub_cells
            + pm(1000 * diff.time_offset, 1000 * se["time_offset"], 14, 1)
            + f"{'yes' if sessions.coverage(name).holds_both_turns else 'no':>11s}"
        )
    print("both turns: whether the session holds arcs and turns on the spot; without, the")
    print("scrub model's turn-rate term is not identified by the session")
    print("(umbmark.estimators.motions), and b_arc or b_spot extrapolates.")
    print()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(__file__).resolve().parents[2] / "shared" / "data" / "optiodom"
    parser.add_argument("--data", type=Path, default=default)
    parser.add_argument("--no-loo", action="store_true", help="skip the leave-one-out part")
    args = parser.parse_args()
    sessions = Sessions(args.data)
    replay_table(sessions)
    if not args.no_loo:
        leave_one_out(sessions)
    per_session(sessions)


if __name__ == "__main__":
    main()

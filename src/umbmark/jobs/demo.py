"""The demo job: UMBmark before, calibration, UMBmark after, on a virtual LabMate (Sec. 5).

The robot has b = 340 mm, the errors of the paper's Fig. 11 (b 340.00 -> 336.17 mm,
D_R/D_L = 1.00084) and wheel slip giving the paper's ~25 mm scatter. It drives 5 cw and
5 ccw runs around a 4 x 4 m square steering by its own odometry, is calibrated from them,
and drives them again.
"""

from __future__ import annotations

import operator
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText
from umbmark.core.messages import join_names
from umbmark.estimators.base import SquareTest
from umbmark.estimators.registry import DEFAULT, SQUARE
from umbmark.options.simulate import DEMO_RUNS, SEED
from umbmark.outputs.calibration import CalibrationReport
from umbmark.returns.clusters import sem_verdict
from umbmark.sim.experiments import Trial
from umbmark.sim.robot import SimRobot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["DemoReport", "demo"]

#: The files the demo writes into its folder.
DEMO_FILES = {
    "runs_before": "runs_before.csv",
    "runs_after": "runs_after.csv",
    "result": "result.json",
    "overlay": "overlay.yaml",
    "plot": "clusters.png",
}


@dataclass(frozen=True, repr=False)
class DemoReport(JsonText):
    """The demo's robot, its test before and after calibration, and the calibration.

    Attributes
    ----------
    robot : SimRobot
        The uncalibrated robot (true errors ``robot.E_d``, :attr:`true_E_b`).
    before, after : Trial
        The bi-directional square tests before and after the correction.
    report : CalibrationReport
        The calibration from the test before.
    seed : int
    files : dict of str to Path
        What was written (empty without a folder).
    """

    robot: SimRobot
    before: Trial
    after: Trial
    report: CalibrationReport
    seed: int
    files: dict[str, Path]

    def __repr__(self) -> str:
        return (
            f"DemoReport(e_max_before={self.before.benchmark.e_max_syst:.6g} m, "
            f"e_max_after={self.after.benchmark.e_max_syst:.6g} m, seed={self.seed})"
        )

    @property
    def true_E_b(self) -> float:
        """The robot's true ``b_actual / b``."""
        return self.robot.wheelbase / self.robot.odometry.wheelbase

    @property
    def improvement(self) -> float:
        """``E_max,syst`` before over after."""
        return self.before.benchmark.e_max_syst / self.after.benchmark.e_max_syst

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres): what ``demo --json`` prints."""
        cal = self.report.calibration
        est = cal.estimate
        b0, b1 = self.before.benchmark, self.after.benchmark
        return {
            "true_E_d": self.robot.E_d,
            "true_E_b": self.true_E_b,
            "E_d": est.E_d,
            "E_b": est.E_b,
            "method": est.method,
            "e_max_before": b0.e_max_syst,
            "e_max_after": b1.e_max_syst,
            "improvement": self.improvement,
            "sem_after": b1.sem,
            "second_pass_recommended_after": b1.second_pass_recommended,
            "verdict_after": sem_verdict(b1),
            "wheelbase_corrected": cal.wheelbase_corrected,
            "c_L": cal.new_c_left,
            "c_R": cal.new_c_right,
            "seed": self.seed,
            "files": {k: str(v) for k, v in self.files.items()},
            "warnings": list(est.warnings),
        }

    def figure(self) -> Figure:
        """Before and after, side by side (the view of Fig. 11)."""
        from umbmark.outputs.plotting import cluster_figure

        cal = self.report.calibration
        odo = self.robot.odometry
        return cluster_figure(
            [
                (
                    self.before.benchmark,
                    f"before: b = {odo.wheelbase * 1000:.2f} mm, D_R/D_L = 1.00000",
                ),
                (
                    self.after.benchmark,
                    f"after: b = {cal.wheelbase_corrected * 1000:.2f} mm, "
                    f"D_R/D_L = {cal.new_c_right / cal.new_c_left:.5f}",
                ),
            ],
            title="Virtual LabMate, 4 x 4 m bi-directional square (cf. Fig. 11)",
        )


def demo(
    *,
    out: str | os.PathLike[str] | None = None,
    seed: int = SEED.default,
    method: str = DEFAULT.name,
    runs: int = DEMO_RUNS.default,
    force: bool = False,
    progress: Callable[[float], None] | None = None,
) -> DemoReport:
    """UMBmark before, calibration, UMBmark after, on a virtual LabMate.

    What ``umbmark demo`` does. Unlike the command, which writes into ``umbmark-demo/``
    (``umbmark-demo-2/``, ... when an earlier demo left files there), the function writes
    files only when given a folder.

    Parameters
    ----------
    out : path, optional
        Folder for the runs tables, the result, the overlay and the plot.
    seed : int
        Seed of the non-systematic errors, 0 to 2**63 - 1.
    method : {"paper", "exact", "heading", "endpose"}
        Estimator to calibrate with.
    runs : int
        Runs in each direction, 2 to :data:`umbmark.options.simulate.MAX_RUNS` (1000).
    force : bool
        Replace the files of ``out`` (:data:`DEMO_FILES`) that exist.
    progress : callable, optional
        Called with the fraction done (0 to 1).

    Raises
    ------
    InputError
        For an option out of range, a folder that cannot be written, or one holding a
        file the demo writes (without ``force``).
    """
    from umbmark.core.atomic import atomic_write_text
    from umbmark.outputs.plotting import save_figure
    from umbmark.sim.experiments import calibrate_robot, umbmark_trials
    from umbmark.sim.reproduce import FIG11_E_B, FIG11_E_D, PAPER_NOISE, SIDE
    from umbmark.sim.robot import LABMATE
    from umbmark.sources.runs_table.writer import write_runs_table

    for spec, value in ((DEMO_RUNS, runs), (SEED, seed)):
        spec.check(value)
    runs, seed = operator.index(runs), operator.index(seed)
    if method not in SQUARE:
        raise InputError(
            f"{option('method', repr(method))}: the demo calibrates from end points: use "
            f"{join_names(SQUARE, 'or')}"
        )
    folder = None if out is None else Path(out)
    if folder is not None:
        from umbmark.outputs.files import check_folder_output, check_new_file

        check_folder_output(folder)  # before anything is computed or written
        for name in DEMO_FILES.values():
            if not force:
                check_new_file(folder / name)

    def stage(start: float) -> Callable[[float], None] | None:
        return None if progress is None else (lambda f: progress(start + 0.5 * f))

    robot = SimRobot.with_errors(LABMATE, E_d=FIG11_E_D, E_b=FIG11_E_B, noise=PAPER_NOISE)
    rng = np.random.default_rng(seed)
    (before,) = umbmark_trials([robot], SIDE, runs, rng=rng, progress=stage(0.0))
    calibration, calibrated = calibrate_robot(before, SIDE, method)
    (after,) = umbmark_trials([calibrated], SIDE, runs, rng=rng, progress=stage(0.5))

    files = {} if folder is None else {k: folder / v for k, v in DEMO_FILES.items()}
    report = CalibrationReport(
        sources=(str(files.get("runs_before", "demo runs before")),),
        format="table",
        runs=tuple(before.runs),
        benchmark=before.benchmark,
        test=SquareTest(SIDE, LABMATE.wheelbase),
        calibration=calibration,
    )
    result = DemoReport(
        robot=robot, before=before, after=after, report=report, seed=seed, files=files
    )
    if folder is not None:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"cannot be made ({exc.strerror or exc})", source=folder) from None
        note = (
            f"umbmark demo, seed {seed}: virtual LabMate, true E_d = {robot.E_d:.6f}, "
            f"E_b = {result.true_E_b:.6f}"
        )
        write_runs_table(files["runs_before"], before.runs, comment=note + "; before calibration")
        write_runs_table(files["runs_after"], after.runs, comment=note + "; after calibration")
        atomic_write_text(files["result"], report.to_json())
        atomic_write_text(files["overlay"], report.overlay_yaml())
        save_figure(result.figure(), files["plot"])
    return result

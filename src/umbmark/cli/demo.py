"""``umbmark demo``: the whole method on a virtual LabMate, before and after."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .common import Estimator, progress_bar, reports_input_errors, warn

__all__ = ["demo"]


@reports_input_errors
def demo(
    json_out: Annotated[
        bool, typer.Option("--json", help="Print one JSON object instead.")
    ] = False,
    out: Annotated[
        Path,
        typer.Option("--out", help="Folder for the plots, runs tables, result and overlay."),
    ] = Path("umbmark-demo"),
    seed: Annotated[int, typer.Option("--seed", help="Seed of the non-systematic errors.")] = 1,
    method: Annotated[
        Estimator, typer.Option("--method", "-m", help="Estimator to calibrate with.")
    ] = Estimator.paper,
    runs: Annotated[int, typer.Option("--runs", "-n", help="Runs in each direction.")] = 5,
) -> None:
    """UMBmark before, calibration, UMBmark after, on a virtual LabMate (Sec. 5).

    The robot has b = 340 mm, the errors of the paper's Fig. 11 (b 340.00 -> 336.17 mm,
    D_R/D_L = 1.00084) and wheel slip giving the paper's ~25 mm scatter. It drives 5 cw
    and 5 ccw runs around a 4 x 4 m square steering by its own odometry, is calibrated
    from them, and drives them again. Prints E_max,syst before and after and writes the
    Fig. 6 / Fig. 11 style plots into --out.
    """
    import json

    import numpy as np
    from rich.console import Console

    from ..errors import InputError
    from ..estimators import METHODS, SquareTest
    from ..io.atomic import atomic_write_text
    from ..io.ros_params import ros2_control_overlay
    from ..io.runs_table import write_runs_table
    from ..plotting import cluster_figure, save_figure
    from ..result import CalibrationReport
    from ..sim.experiments import calibrate_robot, umbmark_trials
    from ..sim.reproduce import FIG11_E_B, FIG11_E_D, PAPER_NOISE, SIDE
    from ..sim.robot import LABMATE, VirtualRobot
    from .calibrate import provenance
    from .render import render_report

    if runs < 2:
        raise InputError(f"--runs must be at least 2, got {runs}")
    if method.value not in METHODS:
        raise InputError("the demo calibrates from end points: use paper, exact or heading")
    if out.exists() and not out.is_dir():
        raise InputError("exists and is not a folder", source=out)
    robot = VirtualRobot.with_errors(LABMATE, E_d=FIG11_E_D, E_b=FIG11_E_B, noise=PAPER_NOISE)
    rng = np.random.default_rng(seed)
    with progress_bar("UMBmark before calibration") as progress:
        (before,) = umbmark_trials([robot], SIDE, runs, rng=rng, progress=progress)
    calibration, calibrated = calibrate_robot(before, SIDE, method.value)
    with progress_bar("UMBmark after calibration") as progress:
        (after,) = umbmark_trials([calibrated], SIDE, runs, rng=rng, progress=progress)

    out.mkdir(parents=True, exist_ok=True)
    files = {
        "runs_before": out / "runs_before.csv",
        "runs_after": out / "runs_after.csv",
        "result": out / "result.json",
        "overlay": out / "overlay.yaml",
        "plot": out / "clusters.png",
    }
    report = CalibrationReport(
        source=str(files["runs_before"]),
        runs=before.runs,
        benchmark=before.benchmark,
        test=SquareTest(SIDE, LABMATE.wheelbase),
        calibration=calibration,
    )
    note = (
        f"umbmark demo, seed {seed}: virtual LabMate, true E_d = {robot.E_d:.6f}, "
        f"E_b = {FIG11_E_B:.6f}"
    )
    write_runs_table(files["runs_before"], before.runs, comment=note + "; before calibration")
    write_runs_table(files["runs_after"], after.runs, comment=note + "; after calibration")
    report.write_json(files["result"])
    overlay = ros2_control_overlay(calibration, provenance(report))
    atomic_write_text(files["overlay"], overlay)
    b0, b1 = before.benchmark, after.benchmark
    fig = cluster_figure(
        [
            (b0, f"before: b = {LABMATE.wheelbase * 1000:.2f} mm, D_R/D_L = 1.00000"),
            (
                b1,
                f"after: b = {calibration.wheelbase_corrected * 1000:.2f} mm, "
                f"D_R/D_L = {calibration.new_c_right / calibration.new_c_left:.5f}",
            ),
        ],
        title="Virtual LabMate, 4 x 4 m bi-directional square (cf. Fig. 11)",
    )
    save_figure(fig, files["plot"])

    est = calibration.estimate
    summary = {
        "true_E_d": robot.E_d,
        "true_E_b": FIG11_E_B,
        "E_d": est.E_d,
        "E_b": est.E_b,
        "method": est.method,
        "e_max_before": b0.e_max_syst,
        "e_max_after": b1.e_max_syst,
        "improvement": b0.e_max_syst / b1.e_max_syst,
        "sem_after": b1.sem,
        "second_pass_recommended_after": b1.second_pass_recommended,
        "wheelbase_corrected": calibration.wheelbase_corrected,
        "c_L": calibration.new_c_left,
        "c_R": calibration.new_c_right,
        "seed": seed,
        "files": {k: str(v) for k, v in files.items()},
        "warnings": list(est.warnings),
    }
    for message in est.warnings:
        warn(message)
    if json_out:
        typer.echo(json.dumps(summary, indent=2))
        return

    console = Console()
    console.print(
        "Virtual LabMate (b = 340 mm, D = 150 mm) with the errors of the paper's Fig. 11: "
        f"true E_d = {robot.E_d:.5f}, E_b = {FIG11_E_B:.5f}; {runs} cw + {runs} ccw runs on a "
        f"4 x 4 m square, steering by its own odometry, ~25 mm scatter (seed {seed}).\n",
        highlight=False,
    )
    render_report(report, console, yaml_text=None)
    console.print(
        f"\nEstimated E_d = {est.E_d:.6f} (true {robot.E_d:.6f}), "
        f"E_b = {est.E_b:.6f} (true {FIG11_E_B:.6f}).",
        highlight=False,
    )
    console.print(
        f"[bold]E_max,syst before: {b0.e_max_syst * 1000:.1f} mm, after: "
        f"{b1.e_max_syst * 1000:.1f} mm: {b0.e_max_syst / b1.e_max_syst:.1f}-fold "
        "improvement[/bold] (the paper's LabMate: 317 mm -> 21 mm, 15-fold).",
        highlight=False,
    )
    verdict = (
        f"After calibration E_max,syst {'>' if b1.second_pass_recommended else '<='} "
        f"3 x SEM = {b1.second_pass_threshold * 1000:.1f} mm: "
        + (
            "a second pass could still help."
            if b1.second_pass_recommended
            else "what remains is the runs' scatter."
        )
    )
    console.print(verdict, highlight=False)
    console.print(f"\nWrote {', '.join(str(p) for p in files.values())}.", highlight=False)
    console.print(
        f"Calibrate the same runs yourself: umbmark calibrate {files['runs_before']} "
        "--side-length 4 --wheelbase 0.34",
        highlight=False,
    )

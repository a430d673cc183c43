"""``umbmark demo``: parse the options, call :func:`umbmark.demo`, render."""

from __future__ import annotations

from pathlib import Path

import click

from umbmark.cli.click_options import Command, force_option, option, spec_option
from umbmark.estimators.registry import DEFAULT, SQUARE
from umbmark.options.simulate import DEMO_RUNS, SEED
from umbmark.options.spec import OUTPUTS

__all__ = ["DEMO_FOLDER", "demo"]

#: Where ``umbmark demo`` writes when not told (not part of the repository: .gitignore).
DEMO_FOLDER = "umbmark-demo"


@click.command(cls=Command)
@option("--json", "json_out", section=OUTPUTS, is_flag=True, help="Print one JSON object instead.")
@option(
    "--out",
    section=OUTPUTS,
    type=click.Path(file_okay=False),
    default=None,
    help=f"Folder for the plots, runs tables, result and overlay [default: {DEMO_FOLDER}, or "
    f"{DEMO_FOLDER}-2, -3, ... when an earlier demo left files there].",
)
@force_option()
@spec_option(SEED, section="Options", help="Seed of the non-systematic errors (0 to 2^63-1).")
@option(
    "--method",
    "-m",
    section="Options",
    type=click.Choice(SQUARE),
    default=DEFAULT.name,
    show_default=True,
    help="Estimator to calibrate with.",
)
@spec_option(DEMO_RUNS)
def demo(json_out: bool, out: str | None, seed: int, method: str, runs: int, force: bool) -> None:
    """UMBmark before, calibration, UMBmark after, on a virtual LabMate (Sec. 5).

    The robot has b = 340 mm, the errors of the paper's Fig. 11 (b 340.00 -> 336.17 mm,
    D_R/D_L = 1.00084) and wheel slip giving the paper's ~25 mm scatter. It drives 5 cw
    and 5 ccw runs around a 4 x 4 m square steering by its own odometry, is calibrated
    from them, and drives them again. Prints E_max,syst before and after and writes the
    Fig. 6 / Fig. 11 style plots into --out.
    """
    from umbmark import demo as run_demo
    from umbmark.cli.common import console, progress_bar, warn, wrote
    from umbmark.cli.render import render_calibration
    from umbmark.outputs.files import fresh_folder
    from umbmark.returns.clusters import sem_verdict

    with progress_bar("UMBmark before and after calibration") as progress:
        result = run_demo(
            out=fresh_folder(DEMO_FOLDER) if out is None else Path(out),
            seed=seed,
            method=method,
            runs=runs,
            force=force,
            progress=progress,
        )
    for message in result.report.warnings:
        warn(message)
    wrote(result.files.values())
    if json_out:
        click.echo(result.to_json(), nl=False)
        return
    est = result.report.estimate
    b0, b1 = result.before.benchmark, result.after.benchmark
    screen = console()
    screen.print(
        "Virtual LabMate (b = 340 mm, D = 150 mm) with the errors of the paper's Fig. 11: "
        f"true E_d = {result.robot.E_d:.5f}, E_b = {result.true_E_b:.5f}; {runs} cw + {runs} "
        "ccw runs on a 4 x 4 m square, steering by its own odometry, ~25 mm scatter "
        f"(seed {seed}).\n"
    )
    render_calibration(result.report, screen, overlay=False)
    screen.print(
        f"\nEstimated E_d = {est.E_d:.6f} (true {result.robot.E_d:.6f}), "
        f"E_b = {est.E_b:.6f} (true {result.true_E_b:.6f})."
    )
    screen.print(
        f"[bold]E_max,syst before: {b0.e_max_syst * 1000:.1f} mm, after: "
        f"{b1.e_max_syst * 1000:.1f} mm: {result.improvement:.1f}-fold improvement[/bold] "
        "(the paper's LabMate: 317 mm -> 21 mm, 15-fold)."
    )
    screen.print(f"After calibration: {sem_verdict(b1)}")
    screen.print(
        f"Calibrate the same runs yourself: umbmark calibrate {result.files['runs_before']} "
        "--side-length 4 --wheelbase 0.34"
    )

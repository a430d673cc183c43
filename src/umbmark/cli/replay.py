"""``umbmark replay``: parse the options, call :func:`umbmark.replay`, render."""

from __future__ import annotations

import math
from typing import Any

import click

from umbmark.cli.click_options import (
    Command,
    apply,
    force_option,
    option,
    override_option,
    source_options,
    tum_time_option,
)
from umbmark.options.spec import OUTPUTS, PARAMETERS

__all__ = ["replay"]


@click.command(cls=Command, no_args_is_help=True)
@click.argument("source", type=click.Path())
@apply(
    [
        option(
            "--params",
            "-p",
            section=PARAMETERS,
            type=click.Path(dir_okay=False),
            help="Calibration result (calibrate -o result.json) to replay with; without it, "
            "only the source's nominal parameters are replayed.",
        ),
        override_option(
            "Replay --params (or take --current-params) even when it is a result for "
            "another nominal wheelbase or wheel diameter than the source's own (more than "
            "1 % apart).",
            section=PARAMETERS,
        ),
    ]
)
@source_options()
@apply(
    [
        option("--json", "json_out", section=OUTPUTS, is_flag=True, help="Print one JSON object."),
        option(
            "--tum",
            section=OUTPUTS,
            type=click.Path(),
            help="Write TUM trajectories of every run (ground truth, nominal, calibrated).",
        ),
        tum_time_option(),
        option(
            "--plot",
            section=OUTPUTS,
            type=click.Path(),
            help="Draw every run's true path and odometry paths to a .png, .svg or .pdf file.",
        ),
        force_option(),
    ]
)
def replay(source: str, json_out: bool, **options: Any) -> None:
    """Replay recorded runs: integrate their wheel data again and compare with the truth.

    SOURCE: a run log, an OptiOdom session or a ROS bag. Each run's end-pose error
    (odometry end against ground truth) and whole-trajectory RMSE (odometry against ground
    truth over every matched sample) are computed with the source's nominal parameters
    and, with --params, with a calibration result. Use it to check a calibration on runs
    that were not used to compute it: calibrate on one session, replay another (a circle,
    another day).
    """
    from umbmark import replay as run_replay
    from umbmark.cli.common import console, note, warn, wrote
    from umbmark.cli.render import row, table
    from umbmark.runs.association import summarize

    report = run_replay(source, **options)
    for line in report.notes:
        note(line)
    for message in report.warnings:
        warn(message)
    wrote(options[key] for key in ("plot", "tum") if options[key])
    if json_out:
        click.echo(report.to_json(), nl=False)
        return

    out = console()
    sets = report.parameter_sets
    columns = ["run", "dir"]
    for name in sets:
        columns += [f"{name}\nend [mm]", f"{name}\nheading [deg]", f"{name}\nRMSE [mm]"]
    gyro = report.gyro_heading_errors
    columns += [f"gyro {name}\nheading [deg]" for name in gyro]
    grid = table(
        f"Replay of {report.source}: odometry against ground truth",
        columns,
        left=("run", "dir"),
    )
    for i, run in enumerate(report.runs):
        cells = [run.label, run.direction.value]
        for name in sets:
            h = report.heading_errors[name][i]
            cells += [
                f"{1000 * report.end_errors[name][i]:.1f}",
                "" if h is None else f"{math.degrees(h):+.2f}",
                f"{1000 * report.rmse[name][i]:.1f}",
            ]
        cells += [
            "" if (g := gyro[name][i]) is None else f"{math.degrees(g):+.2f}" for name in gyro
        ]
        row(grid, *cells)
    cells = ["mean", ""]
    for name in sets:
        cells += [
            f"{1000 * report.end_errors[name].mean():.1f}",
            "",
            f"{1000 * report.rmse[name].mean():.1f}",
        ]
    cells += [""] * len(gyro)
    row(grid, *cells, bold=True)
    out.print(grid)
    for name, p in sets.items():
        out.print(
            f"{name}: b = {1000 * p.wheelbase:.2f} mm, D_L = {1000 * p.diameter_left:.3f} mm, "
            f"D_R = {1000 * p.diameter_right:.3f} mm"
        )
    for line in summarize(list(report.associations)):
        out.print(line)
    if gyro:
        out.print(
            "gyro heading: each run's true heading change less the gyro's, as read and "
            "corrected by the calibration's scale and bias (omega = k_g (omega_read - bias))"
            if "calibrated" in gyro
            else "gyro heading: each run's true heading change less the gyro's, as read (the "
            "calibration replayed holds no gyro's scale and bias)"
        )

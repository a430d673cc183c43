"""``umbmark plan``: parse the options, call :func:`umbmark.plan`, render."""

from __future__ import annotations

from typing import Any

import click

from .options import OUTPUTS, TEST, Command, apply, option

__all__ = ["plan"]


@click.command(cls=Command)
@apply(
    [
        option("--scatter", section=TEST, type=float, required=True,
               help="Standard deviation of the return error per axis [m] (a previous "
               "calibration's spread; the paper's runs: about 0.01)."),
        option("--wheelbase", "-b", section=TEST, type=float, default=0.34, show_default=True,
               help="Wheelbase [m]."),
        option("--side-length", "-L", section=TEST, type=float,
               help="Side of the square [m]: with --runs, predict instead of recommend."),
        option("--runs", section=TEST, type=int, help="Runs per direction."),
        option("--floor", section=TEST, type=float,
               help="Side of the free floor [m]: recommend the largest square that fits."),
        option("--margin", section=TEST, type=float, default=0.6, show_default=True,
               help="Room the robot and the start area need beyond the square [m]."),
        option("--target-E-d", "target_E_d", section=TEST, type=float,
               help="Standard error of E_d wanted."),
        option("--target-E-b", "target_E_b", section=TEST, type=float,
               help="Standard error of E_b wanted."),
        option("--target-e-max", section=TEST, type=float,
               help="E_max,syst [m] to reach: 3 x SEM must stay below it."),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print one JSON object (metres, radians)."),
    ]
)  # fmt: skip
def plan(json_out: bool, **options: Any) -> None:
    """How large a square and how many runs: the standard errors a UMBmark test gives.

    Give --side-length and --runs to predict the standard errors of E_d and E_b and the
    3 x SEM threshold; give --floor and a target (--target-E-d, --target-E-b,
    --target-e-max) to be recommended the square and the runs per direction.
    """
    from .. import plan as run_plan
    from .common import console, warn

    report = run_plan(**options)
    for note in report.notes:
        warn(note)
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    verb = "Recommended" if report.recommended else "Planned"
    out = console()
    out.print(
        f"{verb}: square side L = {report.side_length:.2f} m, {report.runs} runs cw + "
        f"{report.runs} ccw (wheelbase {report.wheelbase:.3f} m, scatter "
        f"{report.scatter * 1000:.1f} mm per axis)"
    )
    out.print(f"  se(E_d)  = {report.se_E_d:.2e}   (E_d's standard error, dimensionless)")
    out.print(f"  se(E_b)  = {report.se_E_b:.2e}   (E_b's standard error, dimensionless)")
    out.print(f"  se(alpha) = se(beta) = {report.se_alpha * 1e3:.3f} mrad")
    out.print(
        f"  SEM of a cluster {report.sem * 1000:.1f} mm; another pass is worth it while "
        f"E_max,syst > 3 x SEM = {report.threshold * 1000:.1f} mm"
    )

"""``umbmark plan``: parse the options, call :func:`umbmark.plan`, render."""

from __future__ import annotations

from typing import Any

import click

from umbmark.cli.click_options import Command, apply, option
from umbmark.options.spec import OUTPUTS, TEST

__all__ = ["plan"]


@click.command(cls=Command)
@apply(
    [
        option("--scatter", section=TEST, type=float,
               help="Standard deviation of the return error per axis [m], as measured (a "
               "previous calibration's spread; the paper's runs: about 0.01)."),
        option("--from", "previous", section=TEST, type=click.Path(dir_okay=False),
               help="A previous calibrate --json result: its scatter (std_cw, std_ccw), "
               "the side it was measured on and its wheelbase."),
        option("--noise", section=TEST, type=click.Choice(["slip", "tape"]), default="slip",
               show_default=True,
               help="slip: scatter driven by the path (x and y correlated, growing with "
               "the side); tape: a reading error only (independent, the same on any side)."),
        option("--scatter-side", section=TEST, type=float,
               help="Side of the square the scatter was measured on [m] (default: the "
               "planned side; --from: the result's)."),
        option("--reading-error", section=TEST, type=float, default=0.0, show_default=True,
               help="slip: the part of the scatter per axis [m] that is a reading or "
               "placement error (independent in x and y, the same on any side)."),
        option("--wheelbase", "-b", section=TEST, type=float,
               help="Wheelbase [m] (default: the --from result's, else 0.34)."),
        option("--side-length", "-L", section=TEST, type=float,
               help="Side of the square [m]: with --runs, predict instead of recommend."),
        option("--runs", section=TEST, type=int, help="Runs per direction."),
        option("--floor", section=TEST, type=float,
               help="Side of the free floor [m]: recommend the square that fits."),
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
    --target-e-max) to be recommended the square and the runs per direction. The scatter
    comes from --scatter or from a previous result (--from).
    """
    from umbmark import plan as run_plan
    from umbmark.cli.common import console, note, warn

    report = run_plan(**options)
    for line in report.notes:
        note(line)
    for message in report.warnings:
        warn(message)
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
    if report.slip is not None:
        out.print(
            f"  noise model slip: x-y correlation {report.correlation:.2f}, wheel slip "
            f"{report.slip * 1e3:.3f} mm/sqrt(m), reading error "
            f"{report.reading_error * 1000:.1f} mm per axis"
        )
    else:
        out.print("  noise model tape: x and y scatter independent")
    from umbmark.cli.render import table
    from umbmark.outputs.components import ANGLE_UNIT, to_shown

    rows = [
        ("se(E_d), E_d's standard error", f"{report.se_E_d:.2e}", "1"),
        ("se(E_b), E_b's standard error", f"{report.se_E_b:.2e}", "1"),
        ("se(alpha) = se(beta)", f"{to_shown(report.se_alpha, ANGLE_UNIT):.4f}", ANGLE_UNIT),
        ("SEM of a cluster", f"{report.sem * 1000:.1f}", "mm"),
        (
            "3 x SEM: another pass while E_max,syst exceeds it",
            f"{report.threshold * 1000:.1f}",
            "mm",
        ),
    ]
    out.print(table("Expected accuracy", ("", "value", "unit"), rows, left=("", "unit")))

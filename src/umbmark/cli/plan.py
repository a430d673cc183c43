"""``umbmark plan``: parse the options, call :func:`umbmark.plan`, render."""

from __future__ import annotations

from typing import Any

import click

from umbmark.cli.click_options import Command, apply, option, spec_option
from umbmark.options.plan import PLAN_OPTIONS
from umbmark.options.spec import OUTPUTS

__all__ = ["plan"]


@click.command(cls=Command)
@apply(
    [
        *(spec_option(spec) for spec in PLAN_OPTIONS),
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

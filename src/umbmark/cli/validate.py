"""``umbmark validate``: parse the options, call :func:`umbmark.validate`, render."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from umbmark.cli.click_options import (
    Command,
    apply,
    option,
    override_option,
    source_options,
    spec_option,
)
from umbmark.estimators.registry import RUNS
from umbmark.options.spec import OUTPUTS, SIDE_LENGTH, TEST

__all__ = ["validate"]


@click.command(cls=Command, no_args_is_help=True)
@click.argument("sources", nargs=-1, required=True, type=click.Path())
@apply(
    [
        option(
            "--methods",
            section=TEST,
            help=f"Estimators to compare, comma-separated [default: all: {', '.join(RUNS)}].",
        ),
        spec_option(SIDE_LENGTH, help="Side of squares [m]."),
        override_option(
            "Take --current-params even when it is a result for another nominal "
            "wheelbase or wheel diameter than the sources' own (more than 1 % apart).",
            section=TEST,
        ),
    ]
)
@source_options()
@option("--json", "json_out", section=OUTPUTS, is_flag=True, help="Print one JSON object.")
def validate(sources: tuple[str, ...], json_out: bool, methods: str | None, **options: Any) -> None:
    """Which estimator predicts this robot best? Held-out replay on its own recordings.

    SOURCES: recorded runs (run logs, OptiOdom sessions, ROS bags). Each source is held
    out in turn (with one source: each run), the rest calibrated with every estimator,
    and the held-out runs replayed with each calibration. Prints the mean end-position
    error of the held-out runs [mm] per estimator and recommends the lowest; calibrate
    --method auto uses it. The figures speak only for the kinds of motion held out
    (straight legs, arcs, turns on the spot): the output says which.
    """
    from umbmark import validate as run_validation
    from umbmark.cli.common import console, note, progress_bar, warn
    from umbmark.cli.render import row, table

    chosen = None if methods is None else [m.strip() for m in methods.split(",") if m.strip()]
    with progress_bar("validating") as progress:
        report = run_validation(*sources, methods=chosen, progress=progress, **options)
    for line in report.notes:
        note(line)
    for message in report.warnings:
        warn(message)
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    grid = table(
        f"Held-out end error [mm], {report.scheme}",
        ["held out", *(f"{candidate} [mm]" for candidate in report.candidates)],
    )
    for fold in report.folds:
        cells = [f"{Path(fold.held_out).name} ({fold.runs} runs)"]
        cells += [
            "-" if fold.errors[c] is None else f"{1000 * (fold.errors[c] or 0.0):.1f}"
            for c in report.candidates
        ]
        row(grid, *cells)
    means = [report.mean_error(c) for c in report.candidates]
    row(grid, "mean", *("-" if m is None else f"{1000 * m:.2f}" for m in means), bold=True)
    out = console()
    out.print(grid)
    out.print(f"What these figures cover: {report.coverage}.", soft_wrap=True)
    best = report.recommended
    if best is None:
        out.print("No estimator predicts the held-out runs better than the nominal parameters.")
    else:
        out.print(
            f"Recommended: {best} ({1000 * (report.mean_error(best) or 0.0):.2f} mm held out, "
            f"nominal {1000 * (report.mean_error('nominal') or 0.0):.2f} mm); "
            f"calibrate with --method {best} (or --method auto)."
        )

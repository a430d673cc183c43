"""``umbmark study``: parse the options, call :func:`umbmark.study`, render."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import click

from umbmark.cli.click_options import Command, apply, option, spec_option
from umbmark.estimators.registry import SQUARE
from umbmark.options.simulate import ROBOTS, STUDY_OPTIONS
from umbmark.options.spec import OUTPUTS

if TYPE_CHECKING:
    from umbmark.jobs.study import CellResult

__all__ = ["study"]


@click.command(cls=Command)
@option("--methods", section=ROBOTS, default=",".join(("truth", *SQUARE)),
        show_default=True, help="Estimators to compare; truth: calibrated with the true "
        "parameters, the ceiling.")  # fmt: skip
@apply([spec_option(spec) for spec in STUDY_OPTIONS])
@option("--json", "json_out", section=OUTPUTS, is_flag=True, help="Print one JSON object.")
def study(json_out: bool, methods: str, **options: Any) -> None:
    """Compare the estimators by Monte Carlo on virtual robots with known errors.

    Every robot drives the bi-directional square test, is calibrated by each estimator,
    drives it again (pass 1), is calibrated again and drives it a third time (pass 2).
    Prints per grid cell and estimator the share of robots at the noise floor after one
    and two passes (E_max,syst <= 3 x SEM), the share refused, the coverage of the 95 %
    intervals of E_d and E_b, the noise-free bias [ppm], the spread of the first pass's
    E_d and E_b about the truth [ppm] (what umbmark plan predicts) and the runs' scatter
    per axis [mm] (what plan --scatter takes).
    """
    from umbmark import study as run_study
    from umbmark.cli.common import console, progress_bar
    from umbmark.cli.render import print_table

    chosen = [m.strip() for m in methods.split(",") if m.strip()]
    with progress_bar("study") as progress:
        report = run_study(methods=chosen, progress=progress, **options)
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    columns = ("slip [m^0.5]", "L [m]", "runs", "b [m]", "method", "floor 1 pass [%]",
               "floor 2 passes [%]", "refused [%]", "95 % cover E_d [%]",
               "95 % cover E_b [%]", "bias E_d [ppm]", "bias E_b [ppm]",
               "spread E_d [ppm]", "spread E_b [ppm]", "scatter [mm]")  # fmt: skip
    title = (
        f"{report.trials} robots per cell, E_d in 1 ± {report.E_d_spread:g}, E_b in 1 ± "
        f"{report.E_b_spread:g}; shares in %, noise-free bias in ppm"
    )

    def pct(value: float) -> str:
        return "-" if not math.isfinite(value) else f"{100 * value:.1f}"

    def ppm(value: float) -> str:
        return "-" if not math.isfinite(value) else f"{value:+.1f}"

    def size(value: float) -> str:
        return "-" if not math.isfinite(value) else f"{value:.1f}"

    def cells(r: CellResult) -> tuple[str, ...]:
        return (
            f"{r.cell.slip:g}", f"{r.cell.side_length:g}", str(r.cell.runs),
            f"{r.cell.wheelbase:g}", r.method, pct(r.floor_after_one), pct(r.floor_after_two),
            pct(r.refused), pct(r.coverage_E_d), pct(r.coverage_E_b), ppm(r.bias_E_d_ppm),
            ppm(r.bias_E_b_ppm), size(1e6 * r.spread_E_d), size(1e6 * r.spread_E_b),
            size(1e3 * r.scatter),
        )  # fmt: skip

    rows = [cells(r) for r in report.results]
    # On a narrow terminal the columns go into several tables, each with the grid cell
    # and the method: no number is ever cut.
    print_table(console(), title, columns, rows, keys=5, left=("method",))

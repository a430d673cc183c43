"""``umbmark report``: parse the options, call :func:`umbmark.report`, render."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Any

import click

from umbmark.cli.calibrate import calibrate as _calibrate_command
from umbmark.cli.click_options import Command, apply, option, source_options
from umbmark.cli.common import command_line
from umbmark.options.spec import OUTPUTS

if TYPE_CHECKING:
    from umbmark.returns.clusters import Benchmark

__all__ = ["report"]

#: The square-test options of ``calibrate``, shared (not copied): same flags, same help.
_SHARED = ("side_length", "wheelbase", "method", "fit_truth_offset", "override_verdict", "force")


@click.command(cls=Command, no_args_is_help=True)
@click.argument("sources", nargs=-1, required=True, type=click.Path())
@source_options(wheelbase=False)
@apply(
    [
        option(
            "--output",
            "-o",
            section=OUTPUTS,
            type=click.Path(),
            required=True,
            help="The page to write (.html): one self-contained file, no network needed.",
        ),
        option(
            "--validate",
            section=OUTPUTS,
            is_flag=True,
            help="Add umbmark validate of the last pass (held-out replay of its recorded "
            "runs) to the page.",
        ),
        option(
            "--json",
            "json_out",
            section=OUTPUTS,
            is_flag=True,
            help="Print one JSON object (metres, radians) instead of the summary.",
        ),
    ]
)
def report(sources: tuple[str, ...], json_out: bool, **options: Any) -> None:
    """UMBmark passes on one robot as one self-contained HTML page.

    SOURCES: one per pass, in the order driven (runs tables, run-log folders, OptiOdom
    sessions or ROS bags): pass 1 the runs before any correction, pass 2 the runs driven
    after applying pass 1's correction, and so on. Each pass is calibrated as umbmark
    calibrate does; from pass 2 on, the previous pass's new c_L, c_R and
    wheel_separation_multiplier are taken as active during its runs. The page: the
    verdict (E_max,syst of every pass, the 3 x SEM rule), the Fig. 6 view of every pass
    in one figure (one pass of recorded runs: also its runs replayed with the new
    parameters, marked as a prediction), the per-pass and per-run tables, the estimates
    with 95 % intervals (alpha and beta in degrees), the figures of the fit, the overlay
    to copy and the provenance.
    """
    from umbmark import report as run_report
    from umbmark.cli.common import console, note, warn, wrote
    from umbmark.cli.render import table

    page = run_report(*sources, command=command_line(sys.argv), **options)
    many = len(page.passes) > 1
    for k, one in enumerate(page.passes, 1):
        for message in one.notes:
            note(f"pass {k}: {message}" if many else message)
        for message in one.warnings:
            warn(f"pass {k}: {message}" if many else message)
    wrote([options["output"]])
    if json_out:
        click.echo(page.to_json(), nl=False)
        return
    out = console()
    last = page.last.verdict
    out.print((f"Pass {len(page.passes)}, the last: " if many else "") + last.line(), markup=False)

    def line(name: str, source: str, bench: Benchmark, verdict: str) -> list[str]:
        return [
            name,
            source,
            f"{bench.cw.n} / {bench.ccw.n}",
            f"{bench.e_max_syst * 1000:.1f}",
            f"{bench.second_pass_threshold * 1000:.1f}",
            "yes" if bench.second_pass_recommended else "no",
            verdict,
        ]

    rows = [
        line(f"pass {k}", one.source, one.benchmark, one.verdict.words)
        for k, one in enumerate(page.passes, 1)
        if one.benchmark is not None  # report() refuses passes without one
    ]
    if page.predicted is not None:
        rows.append(
            line("predicted after", "pass 1 replayed with the new parameters",
                 page.predicted.benchmark, "")
        )  # fmt: skip
    head = ["", "source", "runs cw / ccw", "E_max,syst [mm]", "3 x SEM [mm]", "another pass",
            "correction"]  # fmt: skip
    out.print(table("UMBmark passes", head, rows, left={"", "source", "correction"}))


# The square test's options are calibrate's own, listed first as there.
report.params[1:1] = [p for p in _calibrate_command.params if p.name in _SHARED]

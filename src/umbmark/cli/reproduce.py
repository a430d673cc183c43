"""``umbmark reproduce``: parse the options, call the library's experiments, render."""

from __future__ import annotations

import math

import click

from umbmark.cli.click_options import Command, apply, force_option, option, spec_option
from umbmark.options.reproduce import REPRODUCE, TABLE1_OPTIONS
from umbmark.options.spec import OUTPUTS

__all__ = ["reproduce"]


@click.group(no_args_is_help=True)
def reproduce() -> None:
    """Reproduce the paper's experiments on virtual robots (Table I, Fig. 4)."""


@reproduce.command("table1", cls=Command)
@option("--json", "json_out", section=OUTPUTS, is_flag=True, help="Print one JSON object instead.")
@apply([spec_option(spec) for spec in TABLE1_OPTIONS])
def table1(json_out: bool, seeds: int, seed: int, tape_thickness: float | None) -> None:
    """Table I: eight experiments, E_max,syst before and after the correction.

    Experiment 1 is the robot of Fig. 11; 2 and 6 the same robot under other loads; 3-5
    share one test before and one correction; in 7 tape enlarges the right wheel, in 8 the
    left. A second pass is made wherever the 3 x SEM rule asks for one. Figures are means
    over the seeds, with their standard deviation.
    """
    from umbmark import reproduce_table1
    from umbmark.cli.common import console, progress_bar
    from umbmark.cli.render import row, table

    thickness = None if tape_thickness is None else tape_thickness / 1000.0
    with progress_bar(f"Table I, {seeds} seed(s)") as progress:
        report = reproduce_table1(
            seeds=seeds, seed=seed, tape_thickness=thickness, progress=progress
        )
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    grid = table(
        f"Table I on a virtual LabMate: E_max,syst [mm], mean ± sd over {seeds} seeds",
        ["#", "paper [mm]", "before [mm]", "after [mm]", "2nd pass", "final [mm]", "gain"],
        left=(),
    )
    for result in report.rows:
        st = result.stats()
        e = result.experiment
        cells = (
            str(e.number),
            f"{e.paper_before_mm:.0f} -> {e.paper_after_mm:.0f}",
            f"{1000 * st['e_max_before']:.0f} ± {1000 * st['e_max_before_sd']:.0f}",
            f"{1000 * st['e_max_after']:.0f} ± {1000 * st['e_max_after_sd']:.0f}",
            f"{100 * st['second_pass_share']:.0f} %",
            f"{1000 * st['e_max_final']:.0f} ± {1000 * st['e_max_final_sd']:.0f}",
            f"{st['improvement']:.0f}x",
        )
        row(grid, *cells)
    out = console()
    out.print(grid)
    for result in report.rows:
        e = result.experiment
        out.print(
            f"  {e.number}: {e.comment or 'as 3'}; true E_d = {e.E_d:.5f}, E_b = {e.E_b:.5f}"
            + (f", E_s = {e.E_s:.5f}" if e.E_s != 1.0 else "")
        )
    out.print(
        "after: after the first pass; 2nd pass: share of seeds whose E_max,syst after it "
        "exceeded 3 x SEM, so that a second pass was made; final: after that pass. "
        "The paper: 10- to 22-fold."
    )


@reproduce.command(
    "fig4",
    cls=Command,
    short_help="Fig. 4: the uni-directional trap of tuning the wheelbase alone.",
)
@option("--json", "json_out", section=OUTPUTS, is_flag=True, help="Print one JSON object instead.")
@spec_option(REPRODUCE["plot"])
@force_option()
@spec_option(REPRODUCE["leg_bend"])
def fig4(json_out: bool, plot: str | None, leg_bend: float, force: bool) -> None:
    """Fig. 4: the uni-directional trap.

    A robot with unequal wheels (legs bend left) is "calibrated" by tuning only the
    wheelbase until its cw squares come home. Its cw result then looks excellent and its
    ccw result is bad: the bi-directional test exposes what the uni-directional one hid.
    """
    from umbmark import reproduce_fig4
    from umbmark.cli.common import console, progress_bar, wrote
    from umbmark.cli.render import row, table

    with progress_bar("Fig. 4: tuning the wheelbase on cw runs") as progress:
        report = reproduce_fig4(
            leg_bend=math.radians(leg_bend), plot=plot, force=force, progress=progress
        )
    wrote([plot] if plot else [])
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    robot = report.result.robot
    grid = table(
        f"Fig. 4 on a virtual robot whose legs bend {leg_bend:g} deg left "
        f"(E_d = {robot.E_d:.5f}, E_b = 1), noise-free",
        ["stage", "wheelbase [mm]", "cw return error [mm]", "ccw return error [mm]"],
    )
    for s in report.result.stages:
        row(
            grid,
            s.name,
            f"{s.wheelbase * 1000:.2f}",
            f"{s.r_cw * 1000:.1f}",
            f"{s.r_ccw * 1000:.1f}",
        )
    out = console()
    out.print(grid)
    out.print(
        "Tuning b on cw runs alone makes the robot over-turn just enough to make up for its "
        "curved legs: cw comes home, ccw errors add up. UMBmark's two directions separate "
        "the two errors and fix both."
    )

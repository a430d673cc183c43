"""``umbmark reproduce``: the paper's experiments on virtual robots."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .common import check_figure_path, progress_bar, reports_input_errors

__all__ = ["reproduce_app"]

reproduce_app = typer.Typer(
    help="Reproduce the paper's experiments on virtual robots (Table I, Fig. 4).",
    no_args_is_help=True,
    rich_markup_mode=None,  # help texts say "[m]" and "[s]": no markup
)


@reproduce_app.command("table1")
@reports_input_errors
def table1(
    json_out: Annotated[
        bool, typer.Option("--json", help="Print one JSON object instead.")
    ] = False,
    seeds: Annotated[
        int, typer.Option("--seeds", help="Repetitions of every experiment (random seeds).")
    ] = 10,
    seed: Annotated[int, typer.Option("--seed", help="Base seed.")] = 1,
    tape_thickness: Annotated[
        float | None,
        typer.Option(
            "--tape-thickness",
            help="Model the tape of experiments 7 and 8 by its physical thickness [mm] "
            "(for example 0.15) instead of sizing it by the paper's figures before correction.",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Table I: eight experiments, E_max,syst before and after the correction.

    Experiment 1 is the robot of Fig. 11; 2 and 6 the same robot under other loads; 3-5
    share one test before and one correction; in 7 tape enlarges the right wheel, in 8 the
    left. A second pass is made wherever the 3 x SEM rule asks for one. Figures are means
    over the seeds, with their standard deviation.
    """
    import json

    from rich import box
    from rich.console import Console
    from rich.table import Table
    from rich.text import Text

    from ..errors import InputError
    from ..sim.reproduce import EXPERIMENTS, with_tape
    from ..sim.reproduce import table1 as run_table1

    if seeds < 1:
        raise InputError(f"--seeds must be at least 1, got {seeds}")
    experiments = EXPERIMENTS
    if tape_thickness is not None:
        if not 0 < tape_thickness <= 1:
            raise InputError(f"--tape-thickness {tape_thickness:g} mm: give 0 to 1 mm")
        experiments = with_tape(tape_thickness / 1000.0)
    with progress_bar(f"Table I, {seeds} seed(s)") as progress:
        rows = run_table1(seeds=seeds, seed=seed, progress=progress, experiments=experiments)
    if json_out:
        typer.echo(json.dumps({"rows": [r.to_dict() for r in rows]}, indent=2))
        return
    table = Table(
        title=Text(f"Table I on a virtual LabMate: E_max,syst [mm], mean ± sd over {seeds} seeds"),
        title_justify="left",
        box=box.SIMPLE_HEAD,
    )
    for name in ("#", "paper", "before", "after", "2nd pass", "final", "gain"):
        table.add_column(Text(name), justify="right")
    for row in rows:
        st = row.stats()
        e = row.experiment
        cells = (
            str(e.number),
            f"{e.paper_before_mm:.0f} -> {e.paper_after_mm:.0f}",
            f"{1000 * st['e_max_before']:.0f} ± {1000 * st['e_max_before_sd']:.0f}",
            f"{1000 * st['e_max_after']:.0f} ± {1000 * st['e_max_after_sd']:.0f}",
            f"{100 * st['second_pass_share']:.0f} %",
            f"{1000 * st['e_max_final']:.0f} ± {1000 * st['e_max_final_sd']:.0f}",
            f"{st['improvement']:.0f}x",
        )
        table.add_row(*(Text(c) for c in cells))
    console = Console()
    console.print(table)
    for row in rows:
        e = row.experiment
        console.print(
            f"  {e.number}: {e.comment or 'as 3'}; true E_d = {e.E_d:.5f}, E_b = {e.E_b:.5f}"
            + (f", E_s = {e.E_s:.5f}" if e.E_s != 1.0 else ""),
            highlight=False,
        )
    console.print(
        "after: after the first pass; 2nd pass: share of seeds whose E_max,syst after it "
        "exceeded 3 x SEM, so that a second pass was made; final: after that pass. "
        "The paper: 10- to 22-fold.",
        highlight=False,
    )


@reproduce_app.command("fig4")
@reports_input_errors
def fig4(
    json_out: Annotated[
        bool, typer.Option("--json", help="Print one JSON object instead.")
    ] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Draw the paths of the tuned robot (Figs. 4 and 5) to this file.",
            show_default=False,
        ),
    ] = None,
    leg_bend: Annotated[
        float, typer.Option("--leg-bend", help="How much each leg bends left [deg].")
    ] = 1.0,
) -> None:
    """Fig. 4: the uni-directional trap.

    A robot with unequal wheels (legs bend left) is "calibrated" by tuning only the
    wheelbase until its cw squares come home. Its cw result then looks excellent and its
    ccw result is bad: the bi-directional test exposes what the uni-directional one hid.
    """
    import json

    from rich.console import Console
    from rich.table import Table
    from rich.text import Text

    from ..errors import InputError
    from ..plotting import save_figure, trajectory_figure
    from ..sim.reproduce import fig4 as run_fig4

    if not 0 < abs(leg_bend) <= 10:
        raise InputError(f"--leg-bend {leg_bend:g} deg: give a bend between 0 and 10 deg")
    check_figure_path("--plot", plot)
    with progress_bar("Fig. 4: tuning the wheelbase on cw runs") as progress:
        result = run_fig4(leg_bend_deg=leg_bend, progress=progress)
    if plot is not None:
        tuned = result.stages[1]
        fig = trajectory_figure(
            [(t, d) for t, d in zip(result.tuned_traces, ("cw", "ccw"), strict=True)],
            title=f"Wheelbase tuned on cw runs only (b = {tuned.wheelbase * 1000:.1f} mm): "
            "cw comes home, ccw does not (cf. Figs. 4, 5)",
        )
        save_figure(fig, plot)
    stages = [
        {
            "stage": s.name,
            "wheelbase": s.wheelbase,
            "cw_return_error": list(s.cw),
            "ccw_return_error": list(s.ccw),
            "r_cw": s.r_cw,
            "r_ccw": s.r_ccw,
        }
        for s in result.stages
    ]
    if json_out:
        payload = {"true_E_d": result.robot.E_d, "leg_bend_deg": leg_bend, "stages": stages}
        typer.echo(json.dumps(payload, indent=2))
        return
    table = Table(
        title=Text(
            f"Fig. 4 on a virtual robot whose legs bend {leg_bend:g} deg left "
            f"(E_d = {result.robot.E_d:.5f}, E_b = 1), noise-free"
        ),
        title_justify="left",
    )
    for name in ("stage", "wheelbase [mm]", "cw return error [mm]", "ccw return error [mm]"):
        table.add_column(Text(name), justify="left" if name == "stage" else "right")
    for s in result.stages:
        table.add_row(
            Text(s.name),
            Text(f"{s.wheelbase * 1000:.2f}"),
            Text(f"{s.r_cw * 1000:.1f}"),
            Text(f"{s.r_ccw * 1000:.1f}"),
        )
    console = Console()
    console.print(table)
    console.print(
        "Tuning b on cw runs alone makes the robot over-turn just enough to make up for its "
        "curved legs: cw comes home, ccw errors add up. UMBmark's two directions separate "
        "the two errors and fix both.",
        highlight=False,
    )
    if plot is not None:
        console.print(f"wrote {plot}", highlight=False)

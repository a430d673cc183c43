"""The paper's experiments on virtual robots, as jobs: Table I and the trap of Fig. 4.

The experiments themselves are :mod:`umbmark.sim.reproduce`; these functions check the
options and return reports that serialize (``reproduce table1 --json``, ``reproduce fig4
--json``) and draw.
"""

from __future__ import annotations

import math
import operator
import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from umbmark.core.bounds import option_float
from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText
from umbmark.options.reproduce import MAX_LEG_BEND, MAX_TAPE_THICKNESS, REPRODUCE
from umbmark.options.simulate import SEED
from umbmark.outputs.files import OutputPlan
from umbmark.sim.reproduce import Fig4Result, Table1Row

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["Fig4Report", "Table1Report", "reproduce_fig4", "reproduce_table1"]


@dataclass(frozen=True)
class Table1Report(JsonText):
    """Table I on virtual robots: one row per experiment, statistics over the seeds."""

    rows: tuple[Table1Row, ...]
    seeds: int

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres): what ``reproduce table1 --json`` prints."""
        return {"rows": [row.to_dict() for row in self.rows]}


@dataclass(frozen=True)
class Fig4Report(JsonText):
    """The uni-directional trap: a robot with curved legs tuned on cw runs only."""

    result: Fig4Result
    leg_bend: float

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres, radians): what ``reproduce fig4 --json`` prints."""
        return {
            "true_E_d": self.result.robot.E_d,
            "leg_bend": self.leg_bend,
            "stages": [
                {
                    "stage": s.name,
                    "wheelbase": s.wheelbase,
                    "cw_return_error": list(s.cw),
                    "ccw_return_error": list(s.ccw),
                    "r_cw": s.r_cw,
                    "r_ccw": s.r_ccw,
                }
                for s in self.result.stages
            ],
        }

    def figure(self) -> Figure:
        """The tuned robot's cw and ccw paths (the view of Figs. 4 and 5)."""
        from umbmark.outputs.plotting import trajectory_figure

        tuned = self.result.stages[1]
        return trajectory_figure(
            [(t, d) for t, d in zip(self.result.tuned_traces, ("cw", "ccw"), strict=True)],
            title=f"Wheelbase tuned on cw runs only (b = {tuned.wheelbase * 1000:.1f} mm): "
            "cw comes home, ccw does not (cf. Figs. 4, 5)",
        )


def reproduce_table1(
    *,
    seeds: int = REPRODUCE["seeds"].default,
    seed: int = SEED.default,
    tape_thickness: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> Table1Report:
    """Table I: eight experiments, E_max,syst before and after the correction.

    Parameters
    ----------
    seeds : int
        Repetitions of every experiment (random seeds), 1 to :data:`MAX_SEEDS`.
    seed : int
        Base seed, 0 to 2**63 - 1.
    tape_thickness : float, optional
        Model the tape of experiments 7 and 8 by its physical thickness [m] (the
        command's ``--tape-thickness`` is in mm) instead of sizing it by the paper's
        figures before correction.
    progress : callable, optional
        Called with the fraction done.
    """
    from umbmark.sim.reproduce import EXPERIMENTS, table1, with_tape

    REPRODUCE["seeds"].check(seeds)
    seeds = operator.index(seeds)
    SEED.check(seed)
    seed = operator.index(seed)
    experiments = EXPERIMENTS
    if tape_thickness is not None:
        tape_thickness = option_float(option("tape_thickness"), tape_thickness)
        if not 0 < tape_thickness <= MAX_TAPE_THICKNESS:
            raise InputError(
                f"{option('tape_thickness', tape_thickness * 1000, 'mm')}: give more than 0 and "
                f"at most {MAX_TAPE_THICKNESS * 1000:g} mm (thicker tape makes return errors near "
                "the square's side, beyond what the method corrects)"
            )
        experiments = with_tape(tape_thickness)
    rows = table1(seeds=seeds, seed=seed, progress=progress, experiments=experiments)
    return Table1Report(rows=tuple(rows), seeds=seeds)


def reproduce_fig4(
    *,
    leg_bend: float = math.radians(REPRODUCE["leg_bend"].default),
    plot: str | os.PathLike[str] | None = None,
    force: bool = False,
    progress: Callable[[float], None] | None = None,
) -> Fig4Report:
    """Fig. 4: tune only the wheelbase on cw runs, then look at ccw runs too.

    Parameters
    ----------
    leg_bend : float
        How much each leg bends left [rad] (the command's ``--leg-bend`` is in degrees).
    plot : path, optional
        Draw the tuned robot's paths (:meth:`Fig4Report.figure`) to a .png, .svg or .pdf.
    force : bool
        Replace ``plot`` if it exists.
    progress : callable, optional
        Called with the fraction done.
    """
    from umbmark.sim.reproduce import fig4

    leg_bend = option_float(option("leg_bend"), leg_bend)
    if not (math.isfinite(leg_bend) and 0 < abs(leg_bend) <= math.radians(MAX_LEG_BEND)):
        raise InputError(
            f"{option('leg_bend', math.degrees(leg_bend), 'deg')}: give a bend between 0 and "
            f"{MAX_LEG_BEND:g} deg"
        )
    plan = OutputPlan.of(force=force, plot=plot)
    result = fig4(leg_bend_deg=math.degrees(leg_bend), progress=progress)
    report = Fig4Report(result=result, leg_bend=leg_bend)
    if plan.plot is not None:
        from umbmark.outputs.plotting import save_figure

        save_figure(report.figure(), plan.plot)
    return report

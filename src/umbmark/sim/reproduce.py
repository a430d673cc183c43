"""The paper's experiments on virtual robots: Table I and the uni-directional trap of Fig. 4.

Table I (Sec. 5) lists eight experiments with a LabMate: UMBmark before and after the
correction. The robot of experiment 1 is the one of Fig. 11, whose errors follow from the
figure's numbers (b 340.00 -> 336.17 mm, D_R/D_L 1.00084). Experiments 2 and 6 are the same
robot under other loads (the paper blames load distribution for larger errors; here the
effective wheelbase moves), chosen so that the errors before correction match the table's;
experiments 3, 4 and 5 share one uncalibrated test and one correction, as in the paper, and
differ only in the test after it; in 7 masking tape enlarges the right wheel and in 8 the
left, by the amounts that give the table's figures before correction (an effective 0.02 to
0.04 mm per loop: tape squeezed under a loaded tyre). Every experiment is repeated over
several random seeds of the non-systematic errors; a second pass is made wherever the
3 x SEM rule asks for one.

Sized by the paper's figures before correction, experiment 7's errors stay within reach of
the small-angle formulas, and its first pass rarely leaves more than 3 x SEM: the paper's
66 mm after the first pass is more than geometry and scatter explain. Tape of its full
thickness (:func:`with_tape`, ``--tape-thickness`` on the command line) does reproduce the
second pass, at the price of errors before correction well above the paper's.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.model.systematic import E_b_from_alpha
from umbmark.sim.engine import simulate
from umbmark.sim.experiments import Trial, calibrate_robot, umbmark_trials
from umbmark.sim.paths import square
from umbmark.sim.result import Trace
from umbmark.sim.robot import LABMATE, ControlConfig, NoiseModel, SimRobot

__all__ = [
    "FIG11_E_B",
    "FIG11_E_D",
    "PAPER_NOISE",
    "Fig4Result",
    "Table1Row",
    "TableExperiment",
    "fig4",
    "table1",
    "with_tape",
]

#: The LabMate of Fig. 11: b 340.00 -> 336.17 mm, D_R/D_L 1.00000 -> 1.00084.
FIG11_E_B = 336.17 / 340.00
FIG11_E_D = 1.00084
#: Wheel slip that gives about the paper's 25 mm spread per cluster on a 4 x 4 m square.
PAPER_NOISE = NoiseModel(slip=0.0004)
SIDE = 4.0


@dataclass(frozen=True)
class TableExperiment:
    """One line of Table I: a robot and what the paper measured with the real one."""

    number: int
    E_d: float
    E_b: float
    paper_before_mm: float
    paper_after_mm: float
    comment: str
    shares_before_with: int | None = None
    E_s: float = 1.0

    def robot(self, noise: NoiseModel) -> SimRobot:
        """The virtual robot of this experiment."""
        return SimRobot.with_errors(LABMATE, self.E_d, self.E_b, self.E_s, noise)


def _E_b_for(before_mm: float, E_d: float = FIG11_E_D) -> float:
    """The E_b that gives ``before_mm`` of E_max,syst together with ``E_d`` (first order)."""
    b = LABMATE.wheelbase
    beta = 2.0 * SIDE / b * (E_d - 1.0) / (E_d + 1.0)  # first order; b ~ b_actual
    # ccw dominates for alpha < 0 < beta: E_max = 2 sqrt(2) L |alpha - beta|.
    alpha = beta - before_mm / 1000.0 / (2.0 * math.sqrt(2.0) * SIDE)
    return float(E_b_from_alpha(alpha))


def _E_d_for(before_mm: float, E_b: float = FIG11_E_B) -> float:
    """The E_d that gives ``before_mm`` of E_max,syst together with ``E_b`` (first order)."""
    alpha = 0.5 * math.pi * (1.0 - 1.0 / E_b)
    # Take the root whose beta moves least from the Fig. 11 robot's.
    beta = min(
        (alpha + s * before_mm / 1000.0 / (2.0 * math.sqrt(2.0) * SIDE) for s in (1, -1)),
        key=lambda bb: abs(bb - 0.0099),
    )
    k = beta * LABMATE.wheelbase * E_b / (2.0 * SIDE)
    return (1.0 + k) / (1.0 - k)


def with_tape(thickness: float) -> tuple[TableExperiment, ...]:
    """Table I with experiments 7 and 8 made by tape of a physical ``thickness`` [m].

    Each loop adds twice the thickness to the diameter of its wheel (three loops on the
    right wheel, five on the left), which raises the average diameter too (``E_s``). Tape
    of its full thickness makes much larger errors than the paper's figures before
    correction imply: enough to need a second pass (experiment 7's story).
    """
    base_left = 2.0 * LABMATE.wheel_diameter / (FIG11_E_D + 1.0)
    base_right = FIG11_E_D * base_left
    out = []
    for e in EXPERIMENTS:
        if e.number not in (7, 8):
            out.append(e)
            continue
        left = base_left + (10.0 * thickness if e.number == 8 else 0.0)
        right = base_right + (6.0 * thickness if e.number == 7 else 0.0)
        out.append(
            replace(
                e,
                E_d=right / left,
                E_s=0.5 * (left + right) / LABMATE.wheel_diameter,
                E_b=FIG11_E_B,
                comment=e.comment + f", {thickness * 1000:g} mm each",
            )
        )
    return tuple(out)


EXPERIMENTS: tuple[TableExperiment, ...] = (
    TableExperiment(1, FIG11_E_D, FIG11_E_B, 317, 21, "the robot of Fig. 11"),
    TableExperiment(2, FIG11_E_D, _E_b_for(349), 349, 32, "another load"),
    TableExperiment(3, FIG11_E_D, _E_b_for(310), 310, 31, "3-5: one test before, one correction"),
    TableExperiment(4, FIG11_E_D, _E_b_for(310), 310, 14, "", shares_before_with=3),
    TableExperiment(5, FIG11_E_D, _E_b_for(310), 310, 26, "", shares_before_with=3),
    TableExperiment(6, FIG11_E_D, _E_b_for(403), 403, 35, "another load"),
    TableExperiment(7, _E_d_for(423), FIG11_E_B, 423, 20, "tape on the right wheel (3 loops)"),
    TableExperiment(8, _E_d_for(232), FIG11_E_B, 232, 12, "tape on the left wheel (5 loops)"),
)


@dataclass(frozen=True)
class Table1Row:
    """Result of one experiment over all seeds (lengths in metres)."""

    experiment: TableExperiment
    before: np.ndarray
    after_first: np.ndarray
    second_pass: np.ndarray
    final: np.ndarray
    E_d_estimates: np.ndarray = field(repr=False)
    E_b_estimates: np.ndarray = field(repr=False)

    @property
    def improvement(self) -> float:
        """Mean E_max,syst before over mean E_max,syst at the end."""
        return float(np.mean(self.before) / np.mean(self.final))

    def stats(self) -> dict[str, float]:
        """Means and standard deviations over the seeds [m]."""

        def sd(values: np.ndarray) -> float:
            return float(np.std(values, ddof=1)) if len(values) > 1 else 0.0

        return {
            "e_max_before": float(np.mean(self.before)),
            "e_max_before_sd": sd(self.before),
            "e_max_after": float(np.mean(self.after_first)),
            "e_max_after_sd": sd(self.after_first),
            "second_pass_share": float(np.mean(self.second_pass)),
            "e_max_final": float(np.mean(self.final)),
            "e_max_final_sd": sd(self.final),
            "improvement": self.improvement,
            "E_d_estimate": float(np.mean(self.E_d_estimates)),
            "E_b_estimate": float(np.mean(self.E_b_estimates)),
        }

    def to_dict(self) -> dict[str, object]:
        """JSON-ready figures (metres)."""
        e = self.experiment
        return {
            "experiment": e.number,
            "comment": e.comment,
            "true_E_d": e.E_d,
            "true_E_b": e.E_b,
            "true_E_s": e.E_s,
            "paper_before": e.paper_before_mm / 1000.0,
            "paper_after": e.paper_after_mm / 1000.0,
            **self.stats(),
            "seeds": len(self.before),
        }


def table1(
    seeds: int = 10,
    seed: int = 1,
    noise: NoiseModel = PAPER_NOISE,
    control: ControlConfig | None = None,
    progress: Callable[[float], None] | None = None,
    experiments: Sequence[TableExperiment] = EXPERIMENTS,
) -> list[Table1Row]:
    """Run the eight experiments of Table I, each over ``seeds`` replicates.

    Three vectorized passes: every test before correction, every test after the first
    correction, and the second passes that the 3 x SEM rule asks for.
    """
    rng = np.random.default_rng(seed)
    owners = [e for e in experiments if e.shares_before_with is None]
    robots = {e.number: e.robot(noise) for e in owners}

    def stage(start: float, weight: float) -> Callable[[float], None] | None:
        if progress is None:
            return None
        report = progress
        return lambda f: report(start + weight * f)

    keys = [(e.number, s) for e in owners for s in range(seeds)]
    before = dict(
        zip(
            keys,
            umbmark_trials(
                [robots[n] for n, _ in keys],
                SIDE,
                rng=rng,
                control=control,
                progress=stage(0.0, 0.4),
            ),
            strict=True,
        )
    )
    first: dict[tuple[int, int], tuple[float, float, SimRobot]] = {}
    for (n, s), trial in before.items():
        cal, robot = calibrate_robot(trial, SIDE)
        first[(n, s)] = (cal.estimate.E_d, cal.estimate.E_b, robot)

    def owner(e: TableExperiment) -> int:
        return e.shares_before_with or e.number

    by_number = {e.number: e for e in experiments}
    after_keys = [(e.number, s) for e in experiments for s in range(seeds)]
    after_robots = [first[(owner(by_number[n]), s)][2] for n, s in after_keys]
    after = dict(
        zip(
            after_keys,
            umbmark_trials(after_robots, SIDE, rng=rng, control=control, progress=stage(0.4, 0.4)),
            strict=True,
        )
    )
    again = [k for k, t in after.items() if t.benchmark.second_pass_recommended]
    second: dict[tuple[int, int], Trial] = {}
    if again:
        robots2 = [calibrate_robot(after[k], SIDE)[1] for k in again]
        second = dict(
            zip(
                again,
                umbmark_trials(robots2, SIDE, rng=rng, control=control, progress=stage(0.8, 0.2)),
                strict=True,
            )
        )
    if progress is not None:
        progress(1.0)

    rows = []
    for e in experiments:
        ks = [(e.number, s) for s in range(seeds)]
        b = np.array([before[(owner(e), s)].benchmark.e_max_syst for s in range(seeds)])
        a = np.array([after[k].benchmark.e_max_syst for k in ks])
        done = np.array([k in second for k in ks])
        final = np.array(
            [
                second[k].benchmark.e_max_syst if k in second else after[k].benchmark.e_max_syst
                for k in ks
            ]
        )
        rows.append(
            Table1Row(
                experiment=e,
                before=b,
                after_first=a,
                second_pass=done,
                final=final,
                E_d_estimates=np.array([first[(owner(e), s)][0] for s in range(seeds)]),
                E_b_estimates=np.array([first[(owner(e), s)][1] for s in range(seeds)]),
            )
        )
    return rows


@dataclass(frozen=True)
class Fig4Stage:
    """One stage of the Fig. 4 story: return-error centres [m] of each direction."""

    name: str
    wheelbase: float
    cw: tuple[float, float]
    ccw: tuple[float, float]

    @property
    def r_cw(self) -> float:
        """Distance of the cw return error from the origin [m]."""
        return math.hypot(*self.cw)

    @property
    def r_ccw(self) -> float:
        """Distance of the ccw return error from the origin [m]."""
        return math.hypot(*self.ccw)


@dataclass(frozen=True)
class Fig4Result:
    """The uni-directional trap (Figs. 3-5), noise-free."""

    robot: SimRobot
    stages: tuple[Fig4Stage, ...]
    tuned_traces: tuple[Trace, Trace]


def fig4(
    leg_bend_deg: float = 1.0,
    control: ControlConfig | None = None,
    progress: Callable[[float], None] | None = None,
) -> Fig4Result:
    """Tune only the wheelbase on cw runs, then look at ccw runs too.

    The robot's legs each bend ``leg_bend_deg`` to the left (unequal wheels, ``E_b = 1``).
    An experimenter who only runs cw squares enlarges ``b`` until the cw runs come home:
    the larger turns make up for the curved legs (Fig. 4). The ccw runs, where the two
    errors add up instead, expose it (Fig. 5); UMBmark's correction fixes both.
    """
    b = LABMATE.wheelbase
    beta = math.radians(leg_bend_deg)
    k = beta * b / (2.0 * SIDE)
    robot = SimRobot.with_errors(LABMATE, E_d=(1 + k) / (1 - k), E_b=1.0)
    path = square(SIDE)

    def both(r: SimRobot) -> tuple[np.ndarray, np.ndarray]:
        res = simulate(r, path, [Direction.CW, Direction.CCW], control)
        err = res.true_end[:, :2] - res.odometry_end[:, :2]
        return err[0], err[1]

    def sweep(centre: float, span: float) -> float:
        candidates = centre * (1.0 + np.linspace(-span, span, 41))
        fleet = [robot.calibrated(1.0, 1.0, float(c)) for c in candidates]
        res = simulate(fleet, path, [Direction.CW] * len(fleet), control)
        err = np.hypot(*(res.true_end[:, :2] - res.odometry_end[:, :2]).T)
        return float(candidates[int(np.argmin(err))])

    cw0, ccw0 = both(robot)
    if progress is not None:
        progress(0.2)
    tuned_b = sweep(sweep(b, 0.08), 0.004)
    if progress is not None:
        progress(0.6)
    tuned = robot.calibrated(1.0, 1.0, tuned_b)
    cw1, ccw1 = both(tuned)
    trial = umbmark_trials([tuned], SIDE, runs_per_direction=2, control=control)[0]
    _, fixed = calibrate_robot(trial, SIDE)
    cw2, ccw2 = both(fixed)
    traced = simulate(tuned, path, [Direction.CW, Direction.CCW], control, record=True)
    assert traced.trace is not None
    trace = traced.trace
    if progress is not None:
        progress(1.0)

    def pair(v: np.ndarray) -> tuple[float, float]:
        return float(v[0]), float(v[1])

    return Fig4Result(
        robot=robot,
        stages=(
            Fig4Stage("uncalibrated", b, pair(cw0), pair(ccw0)),
            Fig4Stage("wheelbase tuned on cw runs only", tuned_b, pair(cw1), pair(ccw1)),
            Fig4Stage(
                "UMBmark correction of the tuned robot",
                fixed.odometry.wheelbase,
                pair(cw2),
                pair(ccw2),
            ),
        ),
        tuned_traces=(_one(trace, 0), _one(trace, 1)),
    )


def _one(trace: Trace, i: int) -> Trace:
    return Trace(
        time=trace.time,
        true_pose=trace.true_pose[i : i + 1],
        counts=trace.counts[i : i + 1],
        odometry_pose=trace.odometry_pose[i : i + 1],
    )

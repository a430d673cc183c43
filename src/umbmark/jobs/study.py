"""The study job: estimators compared by Monte Carlo on virtual robots with known errors.

For every cell of a grid (scatter, square side, runs per direction, wheelbase) and every
trial, a virtual robot draws ``E_d`` and ``E_b`` uniformly within the given spreads and
drives the bi-directional square test, steering by its own odometry (the closed-loop
simulator of :mod:`umbmark.sim`). Each estimator calibrates it; the calibrated robot
drives the test again (pass 1), is calibrated again, and drives it a third time (pass 2).
Per cell and estimator the study reports:

- the share of trials at the noise floor after one and after two passes
  (``E_max,syst <= 3 SEM``, Sec. 5's rule), and the share the estimator refused;
- the coverage of its 95 % intervals of ``E_d`` and ``E_b`` (the truth inside them);
- its noise-free bias [ppm]: the same robots driven without slip (encoder quantization
  and the controller only).

Trials run in chunks, each with its own seed from one ``SeedSequence``, so the result
does not depend on how many processes share the work.
"""

from __future__ import annotations

import itertools
import math
import multiprocessing
import operator
import os
import signal
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.calibration.compose import Calibration
from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText
from umbmark.estimators.registry import SQUARE
from umbmark.options.simulate import (
    MAX_GRID_VALUES,
    MAX_ROBOTS,
    MAX_TRIALS,
    STUDY,
    STUDY_OPTIONS,
)

if TYPE_CHECKING:
    from umbmark.returns.clusters import Benchmark
    from umbmark.sim.experiments import Trial
    from umbmark.sim.robot import SimRobot

__all__ = [
    "MAX_GRID_VALUES",
    "MAX_ROBOTS",
    "MAX_TRIALS",
    "Cell",
    "CellResult",
    "StudyReport",
    "study",
]

#: Trials simulated together in one vectorized pass (and given one seed).
CHUNK = 125
#: The reference "estimator": the robot calibrated with its true parameters.
TRUTH = "truth"


@dataclass(frozen=True)
class Cell:
    """One point of the study's grid.

    Attributes
    ----------
    slip : float
        Wheel slip [m^0.5] (``0.0004`` gives the paper's ~25 mm scatter on a 4 m square).
    side_length : float
        Square side [m].
    runs : int
        Runs per direction.
    wheelbase : float
        Nominal wheelbase [m].
    """

    slip: float
    side_length: float
    runs: int
    wheelbase: float


@dataclass(frozen=True)
class CellResult:
    """One estimator in one cell, over all trials (shares in 0..1, biases in ppm).

    ``spread_E_d`` and ``spread_E_b`` are the sample standard deviations of the first
    pass's estimates about the robots' true values (what ``umbmark plan`` predicts as
    ``se_E_d``, ``se_E_b``); ``scatter`` [m] is the runs' standard deviation per axis about
    their clusters' centres, pooled over the trials (what ``plan --scatter`` takes).
    """

    cell: Cell
    method: str
    trials: int
    refused: float
    floor_after_one: float
    floor_after_two: float
    coverage_E_d: float
    coverage_E_b: float
    bias_E_d_ppm: float
    bias_E_b_ppm: float
    worst_bias_E_d_ppm: float
    worst_bias_E_b_ppm: float
    spread_E_d: float = math.nan
    spread_E_b: float = math.nan
    scatter: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready figures (None where no trial gave one)."""
        return {
            k: None if isinstance(v, float) and not math.isfinite(v) else v
            for k, v in {
                "slip": self.cell.slip,
                "side_length": self.cell.side_length,
                "runs_per_direction": self.cell.runs,
                "wheelbase": self.cell.wheelbase,
                "method": self.method,
                "trials": self.trials,
                "refused": self.refused,
                "floor_after_one_pass": self.floor_after_one,
                "floor_after_two_passes": self.floor_after_two,
                "coverage_95_E_d": self.coverage_E_d,
                "coverage_95_E_b": self.coverage_E_b,
                "noise_free_bias_E_d_ppm": self.bias_E_d_ppm,
                "noise_free_bias_E_b_ppm": self.bias_E_b_ppm,
                "noise_free_worst_E_d_ppm": self.worst_bias_E_d_ppm,
                "noise_free_worst_E_b_ppm": self.worst_bias_E_b_ppm,
                "spread_E_d": self.spread_E_d,
                "spread_E_b": self.spread_E_b,
                "scatter": self.scatter,
            }.items()
        }


@dataclass(frozen=True, repr=False)
class StudyReport(JsonText):
    """The study's settings and one :class:`CellResult` per cell and estimator."""

    E_d_spread: float
    E_b_spread: float
    trials: int
    seed: int
    results: tuple[CellResult, ...]

    def __repr__(self) -> str:
        return (
            f"StudyReport(cells={len({r.cell for r in self.results})}, "
            f"methods={sorted({r.method for r in self.results})}, trials={self.trials})"
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary: what ``study --json`` prints."""
        return {
            "E_d_spread": self.E_d_spread,
            "E_b_spread": self.E_b_spread,
            "trials_per_cell": self.trials,
            "seed": self.seed,
            "results": [r.to_dict() for r in self.results],
        }


@dataclass(frozen=True)
class _Chunk:
    cell: Cell
    methods: tuple[str, ...]
    trials: int
    E_d_spread: float
    E_b_spread: float
    seed: np.random.SeedSequence


@dataclass(frozen=True)
class _Outcome:
    """Per trial and method: refused, floor after 1 and 2 passes, covered E_d, E_b,
    noise-free errors of E_d and E_b, errors of E_d and E_b of the first pass (NaN where
    refused), the runs' pooled variance per axis about their centres [m^2]."""

    method: str
    values: np.ndarray  # (trials, 10)


def study(
    *,
    methods: Sequence[str] = SQUARE,
    trials: int = STUDY["trials"].default,
    E_d_spread: float = STUDY["E_d_spread"].default,
    E_b_spread: float = STUDY["E_b_spread"].default,
    slip: Sequence[float] = STUDY["slip"].default,
    side_length: Sequence[float] = STUDY["side_length"].default,
    runs: Sequence[int] = STUDY["runs"].default,
    wheelbase: Sequence[float] = STUDY["wheelbase"].default,
    seed: int = STUDY["seed"].default,
    workers: int | None = STUDY["workers"].default,
    progress: Callable[[float], None] | None = None,
) -> StudyReport:
    """Compare estimators by Monte Carlo (see the module's documentation).

    Parameters
    ----------
    methods : sequence of str
        Estimators of square tests (``paper``, ``exact``, ``heading``, ``endpose``), and
        ``truth``: the robot calibrated with its true parameters, the ceiling.
    trials : int
        Trials per grid cell, 1 to :data:`MAX_TRIALS`; trials times grid cells at most
        :data:`MAX_ROBOTS`.
    E_d_spread, E_b_spread : float
        The robots' ``E_d`` and ``E_b`` are drawn uniformly from ``1 +- spread``.
    slip, side_length, runs, wheelbase : sequences
        The grid: wheel slip [m^0.5], square side [m], runs per direction, wheelbase [m];
        at most :data:`MAX_GRID_VALUES` values each.
    seed : int
        Seed of the whole study, 0 to 2**63 - 1.
    workers : int, optional
        Processes, 1 to 64 (default: the machine's cores). On ``KeyboardInterrupt``
        they are terminated before it propagates.
    progress : callable, optional
        Called with the fraction done.

    Raises
    ------
    InputError
        For options out of range.
    """
    for name in methods:
        if name not in (*SQUARE, TRUTH):
            raise InputError(
                f"{option('methods', repr(name))}: use some of {', '.join(SQUARE)}, {TRUTH}"
            )
    if not methods:
        raise InputError(f"{option('methods')}: name at least one estimator")
    values = {
        "trials": trials,
        "E_d_spread": E_d_spread,
        "E_b_spread": E_b_spread,
        "slip": slip,
        "side_length": side_length,
        "runs": runs,
        "wheelbase": wheelbase,
        "seed": seed,
        "workers": workers,
    }
    for spec in STUDY_OPTIONS:
        spec.check(values[spec.name])
    trials, seed = operator.index(trials), operator.index(seed)
    E_d_spread, E_b_spread = float(E_d_spread), float(E_b_spread)
    slip, side_length = [float(v) for v in slip], [float(v) for v in side_length]
    wheelbase = [float(v) for v in wheelbase]
    cell_count = len(slip) * len(side_length) * len(runs) * len(wheelbase)
    if trials * cell_count > MAX_ROBOTS:
        raise InputError(
            f"{option('trials', trials)} in {cell_count} grid cells are {trials * cell_count} "
            f"robots: at most {MAX_ROBOTS} in all"
        )

    cells = [Cell(*c) for c in itertools.product(slip, side_length, runs, wheelbase)]
    seeds = iter(np.random.SeedSequence(seed).spawn(len(cells) * math.ceil(trials / CHUNK)))
    chunks = [
        _Chunk(
            cell, tuple(methods), min(CHUNK, trials - start), E_d_spread, E_b_spread, next(seeds)
        )
        for cell in cells
        for start in range(0, trials, CHUNK)
    ]
    outcomes = _run_all(chunks, workers, progress)
    results = []
    for cell in cells:
        for method in methods:
            parts = [
                o.values
                for chunk, per_chunk in zip(chunks, outcomes, strict=True)
                if chunk.cell == cell
                for o in per_chunk
                if o.method == method
            ]
            results.append(_summarize(cell, method, np.vstack(parts)))
    return StudyReport(
        E_d_spread=E_d_spread,
        E_b_spread=E_b_spread,
        trials=trials,
        seed=seed,
        results=tuple(results),
    )


def _run_all(
    chunks: Sequence[_Chunk], workers: int | None, progress: Callable[[float], None] | None
) -> list[list[_Outcome]]:
    """Every chunk's outcomes, in the chunks' order, on ``workers`` processes.

    An exception here (``KeyboardInterrupt`` of a Ctrl-C included) terminates the
    worker processes and waits for them before it propagates: nothing keeps running.
    """
    count = min(workers or os.cpu_count() or 1, len(chunks))
    if count == 1:
        out = []
        for k, chunk in enumerate(chunks):
            out.append(_run_chunk(chunk))
            if progress is not None:
                progress((k + 1) / len(chunks))
        return out
    # fork where there is one: works from notebooks and stdin, where spawn cannot re-import.
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    results: list[list[_Outcome] | None] = [None] * len(chunks)
    pool = context.Pool(count, initializer=_ignore_interrupts)
    try:
        work = pool.imap_unordered(_run_numbered, enumerate(chunks))
        for done, (k, outcome) in enumerate(work, start=1):
            results[k] = outcome
            if progress is not None:
                progress(done / len(chunks))
        pool.close()
    finally:
        pool.terminate()  # a no-op for workers that are done; stops the others at once
        pool.join()
    return [r for r in results if r is not None]


def _ignore_interrupts() -> None:
    """In a worker: leave Ctrl-C to the parent, which terminates the workers (a Ctrl-C
    on a terminal reaches every process of the group, and each would print a traceback)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run_numbered(item: tuple[int, _Chunk]) -> tuple[int, list[_Outcome]]:
    """:func:`_run_chunk` of a numbered chunk, keeping its number."""
    return item[0], _run_chunk(item[1])


def _run_chunk(chunk: _Chunk) -> list[_Outcome]:
    """Every trial of a chunk, every method: three tests each, simulated in batches."""
    from umbmark.model.kinematics import WheelParams
    from umbmark.sim.experiments import calibrate_robot, umbmark_trials
    from umbmark.sim.robot import NoiseModel, SimRobot

    rng = np.random.default_rng(chunk.seed)
    cell = chunk.cell
    odometry = WheelParams(
        wheelbase=cell.wheelbase,
        wheel_diameter=0.15 * cell.wheelbase / 0.34,
        encoder_resolution=2000,
        gear_ratio=20.0,
    )
    E_d = 1.0 + rng.uniform(-chunk.E_d_spread, chunk.E_d_spread, chunk.trials)
    E_b = 1.0 + rng.uniform(-chunk.E_b_spread, chunk.E_b_spread, chunk.trials)
    noise = NoiseModel(slip=cell.slip)
    robots = [
        SimRobot.with_errors(odometry, E_d=d, E_b=b, noise=noise)
        for d, b in zip(E_d, E_b, strict=True)
    ]
    quiet = [SimRobot.with_errors(odometry, E_d=d, E_b=b) for d, b in zip(E_d, E_b, strict=True)]
    L, n = cell.side_length, cell.runs
    before = umbmark_trials(robots, L, n, rng=rng)
    noise_free = umbmark_trials(quiet, L, n)

    def calibrate(trial: Trial, method: str) -> tuple[Any, SimRobot] | None:
        if method == TRUTH:
            return _truth(trial)
        try:
            return calibrate_robot(trial, L, method)  # type: ignore[arg-type]
        except ValueError:
            return None

    outcomes = []
    for method in chunk.methods:
        values = np.full((chunk.trials, _COLUMNS), np.nan)
        values[:, 1:3] = 0.0  # a refused robot stays uncalibrated: not at the floor
        values[:, 9] = [_pooled_variance(t.benchmark) for t in before]
        first = [calibrate(t, method) for t in before]
        ok = [k for k, c in enumerate(first) if c is not None]
        values[:, 0] = [c is None for c in first]
        for k in ok:
            calibration = first[k]
            assert calibration is not None
            estimate = calibration[0].estimate
            truth = before[k].robot
            true_E_b = truth.wheelbase / truth.odometry.wheelbase
            values[k, 7] = estimate.E_d - truth.E_d
            values[k, 8] = estimate.E_b - true_E_b
            for col, name, true in ((3, "E_d", truth.E_d), (4, "E_b", true_E_b)):
                interval = estimate.interval(name)
                if interval is not None:
                    values[k, col] = interval[0] <= true <= interval[1]
        after_one = umbmark_trials([first[k][1] for k in ok], L, n, rng=rng)  # type: ignore[index]
        second = [calibrate(t, method) for t in after_one]
        after_two_robots = [
            c[1] if c is not None else t.robot for c, t in zip(second, after_one, strict=True)
        ]
        after_two = umbmark_trials(after_two_robots, L, n, rng=rng)
        for k, one, two in zip(ok, after_one, after_two, strict=True):
            values[k, 1] = not one.benchmark.second_pass_recommended
            values[k, 2] = not two.benchmark.second_pass_recommended
        for k, trial in enumerate(noise_free):
            result = calibrate(trial, method)
            if result is not None:
                estimate = result[0].estimate
                values[k, 5] = estimate.E_d - trial.robot.E_d
                values[k, 6] = estimate.E_b - trial.robot.wheelbase / trial.robot.odometry.wheelbase
        outcomes.append(_Outcome(method, values))
    return outcomes


def _truth(trial: Trial) -> tuple[Calibration, SimRobot]:
    """The robot calibrated with its true parameters: the ceiling any estimator can reach."""
    from umbmark.estimators.base import ErrorEstimate
    from umbmark.model.active import ActiveParams

    robot = trial.robot
    odo = robot.odometry
    E_d = robot.E_d / (odo.c_right / odo.c_left)
    E_b = robot.wheelbase / odo.wheelbase
    estimate = ErrorEstimate(method=TRUTH, alpha=0.0, beta=0.0, E_d=E_d, E_b=E_b)
    calibration = Calibration(
        estimate, ActiveParams(wheelbase=odo.wheelbase, c_left=odo.c_left, c_right=odo.c_right)
    )
    exact = robot.calibrated(
        robot.diameter_left / odo.wheel_diameter,
        robot.diameter_right / odo.wheel_diameter,
        robot.wheelbase,
    )
    return calibration, exact


#: Columns of :class:`_Outcome`'s values.
_COLUMNS = 10


def _pooled_variance(bench: Benchmark) -> float:
    """The runs' variance per axis about their clusters' centres [m^2], pooled over both
    axes and both clusters (``n - 1`` degrees of freedom per cluster and axis)."""
    squares = sum(float(np.sum(np.square(c.errors - c.cg))) for c in bench.clusters)
    dof = sum(2 * (len(c.errors) - 1) for c in bench.clusters)
    return squares / dof if dof > 0 else math.nan


def _spread(column: np.ndarray) -> float:
    """Sample standard deviation of the finite values (NaN for fewer than two)."""
    known = column[np.isfinite(column)]
    return float(np.std(known, ddof=1)) if known.size > 1 else math.nan


def _share(column: np.ndarray) -> float:
    known = column[np.isfinite(column)]
    return float(known.mean()) if known.size else math.nan


def _summarize(cell: Cell, method: str, values: np.ndarray) -> CellResult:
    accepted = values[values[:, 0] == 0]
    bias = values[:, 5:7] * 1e6
    finite = np.all(np.isfinite(bias), axis=1)
    mean_bias = bias[finite].mean(axis=0) if finite.any() else np.array([math.nan, math.nan])
    worst = np.abs(bias[finite]).max(axis=0) if finite.any() else np.array([math.nan, math.nan])
    return CellResult(
        cell=cell,
        method=method,
        trials=int(values.shape[0]),
        refused=float(values[:, 0].mean()),
        floor_after_one=float(values[:, 1].mean()),
        floor_after_two=float(values[:, 2].mean()),
        coverage_E_d=_share(accepted[:, 3]) if accepted.size else math.nan,
        coverage_E_b=_share(accepted[:, 4]) if accepted.size else math.nan,
        bias_E_d_ppm=float(mean_bias[0]),
        bias_E_b_ppm=float(mean_bias[1]),
        worst_bias_E_d_ppm=float(worst[0]),
        worst_bias_E_b_ppm=float(worst[1]),
        spread_E_d=_spread(values[:, 7]),
        spread_E_b=_spread(values[:, 8]),
        scatter=math.sqrt(float(np.nanmean(values[:, 9]))),
    )

r"""The model of planning a UMBmark test: which square and how many runs for the accuracy
wanted (the job is :func:`umbmark.jobs.plan.plan`).

The standard errors follow from the paper's first-order model (Sec. 4, paper-notes.md)
and the scatter of the return errors. The default (``exact``) estimate is, to first order
at small errors, the paper's x and y estimates averaged: with the centres of gravity
``X, Y`` of ``n`` runs per direction,

    alpha = -(X_cw + Y_cw + X_ccw - Y_ccw) / (8 L),
    beta  = -(X_cw + Y_cw - X_ccw + Y_ccw) / (8 L),

then ``E_b = (pi/2) / (pi/2 - alpha)`` (``dE_b/dalpha = 2/pi`` at 0) and
``E_d = (2L + beta b) / (2L - beta b)`` (``dE_d/dbeta = b/L`` at 0, ``b`` the
wheelbase). How the x and y
return errors of a run co-vary decides the rest; two models (``noise``):

``tape`` (reading error only)
    x and y scatter independently with the same standard deviation ``sigma``, whatever
    the path: ``se(alpha) = se(beta) = sigma / (4 L sqrt(n))``.

``slip`` (the default: scatter driven by the path, as wheel slip makes it)
    Each wheel's travel over the floor differs from what its encoder counts by white
    noise of variance ``s^2`` per metre it travels (``s`` [m^0.5], the simulator's
    ``NoiseModel.slip``). Per metre of a leg that is a heading error of variance
    ``2 s^2 / b^2`` and an error along the path of variance ``s^2 / 2``, independent; per
    90° turn on the spot a heading error of variance ``pi s^2 / (2 b)`` and a shift of
    the centre of variance ``pi b s^2 / 8``, spread over the quarter turn. The robot
    steers by its odometry and never sees these errors: a heading error picked up at the
    point ``p`` swings the rest of the run about ``p`` and moves the return error by
    ``theta (p_y, -p_x)``. Summed over the square (legs ``L``, four turns, the last at the
    start), a run's return error has

        Var(x) = Var(y) = s^2 D,  D = 10 L^3 / (3 b^2) + L + pi L^2 / b + pi b / 4,
        Cov(x, y) = +s^2 K (cw), -s^2 K (ccw),  K = 2 L^3 / b^2 + pi L^2 / (2 b).

    The correlation ``rho = K / D`` (0.53 at ``L = 2b``, 0.6 for ``L >> b``)
    adds to both ``X_cw + Y_cw`` and ``X_ccw - Y_ccw``, so with the per-axis scatter
    ``sigma = s sqrt(D)`` that a user measures,

        se(alpha) = se(beta) = sigma sqrt(1 + rho) / (4 L sqrt(n)),
        Cov(alpha, beta) = 0,

    about 1.25x what independent x and y would give. The scatter grows with the side:
    ``sigma(L) = s sqrt(D(L, b))``; a scatter measured on another square
    (``scatter_side``, or a previous result's ``side_length``) is carried over by it.
    A reading (or placement) error ``r`` per axis (``reading_error``: independent, the
    same on any square) is part of the scatter: ``sigma^2 = s^2 D + r^2`` and
    ``rho = s^2 K / sigma^2``.

Both models: ``se(E_b) = (2/pi) se(alpha)``, ``se(E_d) = (b/L) se(beta)``, and the
radial spread of a cluster, ``sqrt(sum |eps - cg|^2 / (n - 1))``, has the expected square
``Var(x) + Var(y) = 2 sigma^2``, so the SEM the benchmark compares with ``E_max,syst``
(Sec. 5) is ``SEM = sqrt(2) sigma / sqrt(n)`` (its root mean square) and the threshold
3 SEM.

``tests/calibration/test_plan.py`` checks ``D``, ``K`` and the standard errors against the slip
simulator of ``umbmark study`` (4 m with a 0.34 m robot; 0.75 m and 1 m squares with
0.2 m and 0.15 m robots, the last also with a reading error): within 10 %, where the
``tape`` model misses by 18-28 % (``tools/plan_vs_simulation.py`` prints both side by
side). For a given slip ``s`` a
larger square shrinks ``se(E_d)`` (as ``1/sqrt(L)``) but not ``se(E_b)`` (which grows as
``sqrt(L)``): when the scatter is known on some square (``scatter_side``), a
recommendation searches the sides that fit for the fewest runs; without it, the scatter
is the same on every side and the largest square wins.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from umbmark.core.bounds import (
    MAX_SIDE_LENGTH,
    MAX_WHEELBASE,
    finite_float,
    in_metres,
)
from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText
from umbmark.core.messages import info, split_messages
from umbmark.options.plan import (
    DEFAULT_MARGIN,
    DEFAULT_WHEELBASE,
    MAX_PLAN_RUNS,
    NOISE_MODELS,
    PLAN,
    Noise,
)
from umbmark.sources.text import finite, load_json

__all__ = [
    "DEFAULT_MARGIN",
    "DEFAULT_WHEELBASE",
    "MAX_PLAN_RUNS",
    "NOISE_MODELS",
    "SCATTER_RANGE",
    "Noise",
    "PlanReport",
    "PreviousScatter",
    "Scatter",
    "check_scatter",
    "plan_test",
    "read_previous_scatter",
    "slip_coefficients",
]


#: Plausible scatter of the return errors per axis [m]: from a tape's hundredth of a
#: millimetre to a metre (the paper's: 25 mm on a 4 m square).
SCATTER_RANGE = (1e-5, 1.0)


def check_scatter(scatter: float) -> None:
    """Refuse a scatter [m] outside :data:`SCATTER_RANGE`, one given in millimetres or
    centimetres with what it is in metres.

    Raises
    ------
    InputError
        Naming ``scatter`` (the command's ``--scatter``), the range and, for a large one,
        the value in metres.
    """
    low, high = SCATTER_RANGE
    value = finite_float(option("scatter"), scatter)
    if value > high:
        hint = in_metres(option("scatter"), value, SCATTER_RANGE)
        raise InputError(
            f"{option('scatter', value, 'm')} is implausibly large: lengths are in metres "
            f"(plausible: {low:g} to {high:g} m per axis){'; ' + hint if hint else ''}"
        )
    if value < low:
        raise InputError(
            f"{option('scatter', value, 'm')} is outside {low:g} to {high:g} m per axis"
        )


#: Fewest runs per direction a plan recommends (the paper's five).
MIN_PLAN_RUNS = 5
#: Steps between the sides a recommendation tries [m].
SIDE_STEP = 0.05


def slip_coefficients(side_length: float, wheelbase: float) -> tuple[float, float]:
    """``(D, K)`` of the slip model [m]: per unit ``s^2``, the variance of each of ``x``
    and ``y`` of a run's return error and the size of their covariance (``+K`` cw,
    ``-K`` ccw), for a square of side ``side_length`` and a wheelbase ``wheelbase`` [m].

    See the module's documentation for the derivation.
    """
    L, b = side_length, wheelbase
    D = 10.0 * L**3 / (3.0 * b**2) + L + math.pi * L**2 / b + math.pi * b / 4.0
    K = 2.0 * L**3 / b**2 + math.pi * L**2 / (2.0 * b)
    return D, K


@dataclass(frozen=True)
class PreviousScatter:
    """The scatter of a previous calibration (``calibrate --json``).

    Attributes
    ----------
    scatter : float
        Pooled standard deviation of the return errors per axis [m]: the root mean
        square of ``std_cw`` and ``std_ccw`` (x and y).
    side_length : float
        Side of the square it was measured on [m].
    wheelbase : float or None
        Wheelbase active during its runs [m], if the result says.
    source : str
    """

    scatter: float
    side_length: float
    wheelbase: float | None
    source: str


def read_previous_scatter(path: str | Path) -> PreviousScatter:
    """The scatter of the result that ``calibrate --json`` wrote to ``path``.

    Reads ``std_cw`` and ``std_ccw`` (per axis [m]), or else ``sigma_cw`` and
    ``sigma_ccw`` (radial [m]), ``side_length`` and ``active.wheelbase``.

    Raises
    ------
    InputError
        If the file cannot be read or holds no such result.
    """
    data = load_json(path)
    if not isinstance(data, Mapping):
        raise InputError("is no calibrate --json result (not a JSON object)", source=path)
    squares: list[float] = []
    for key in ("std_cw", "std_ccw"):
        value = data.get(key)
        if isinstance(value, list) and len(value) == 2:
            numbers = [finite(v) for v in value]
            squares.extend(v * v for v in numbers if v is not None and v >= 0.0)
    if len(squares) != 4:
        squares = []
        for key in ("sigma_cw", "sigma_ccw"):
            radial = finite(data.get(key))
            if radial is not None and radial >= 0.0:
                squares.extend([0.5 * radial * radial] * 2)
    if len(squares) != 4:
        raise InputError(
            "has no std_cw and std_ccw (or sigma_cw and sigma_ccw): not a calibrate --json "
            "result of a square test",
            source=path,
        )
    scatter = math.sqrt(sum(squares) / 4.0)
    if not SCATTER_RANGE[0] <= scatter <= SCATTER_RANGE[1]:
        low, high = SCATTER_RANGE
        raise InputError(
            f"scatter {scatter:g} m per axis is outside {low:g} to {high:g} m", source=path
        )
    side = finite(data.get("side_length"))
    if side is None or not 0.0 < side <= MAX_SIDE_LENGTH:
        raise InputError("has no plausible side_length [m]", source=path)
    active = data.get("active")
    wheelbase = finite(active.get("wheelbase")) if isinstance(active, Mapping) else None
    if wheelbase is not None and not 0.0 < wheelbase <= MAX_WHEELBASE:
        wheelbase = None
    return PreviousScatter(scatter, side, wheelbase, str(path))


@dataclass(frozen=True)
class PlanReport(JsonText):
    """A UMBmark test plan and the accuracy it gives.

    Attributes
    ----------
    side_length : float
        Side of the square [m].
    runs : int
        Runs per direction.
    wheelbase : float
        Wheelbase [m].
    scatter : float
        Standard deviation of the return error per axis on this square [m].
    noise : {"slip", "tape"}
        The noise model (see the module's documentation).
    correlation : float
        ``rho``: correlation of a run's x and y return errors (cw; ccw the opposite
        sign), 0 for ``tape``.
    slip : float or None
        The wheel slip ``s`` [m^0.5] that gives this scatter (``slip`` model).
    reading_error : float
        The part of the scatter per axis [m] that does not grow with the path.
    scatter_given : float
        The scatter given [m] and the side it was measured on (``scatter_side`` [m], None
        when given for the planned side or under ``tape``).
    scatter_side : float or None
    se_alpha, se_beta : float
        Standard errors of ``alpha`` and ``beta`` [rad].
    se_E_d, se_E_b : float
        Standard errors of ``E_d`` and ``E_b`` (default method, first order).
    sem : float
        Expected SEM of a cluster [m] (root mean square); ``threshold`` = 3 SEM, the
        E_max,syst below which another pass is not worth it (Sec. 5).
    threshold : float
    recommended : bool
        Whether side and runs were chosen by :func:`plan` (else given).
    notes : tuple of str
        What was chosen and why, for people.
    warnings : tuple of str
        Where the figures are rough.
    """

    side_length: float
    runs: int
    wheelbase: float
    scatter: float
    noise: Noise
    correlation: float
    slip: float | None
    reading_error: float
    scatter_given: float
    scatter_side: float | None
    se_alpha: float
    se_beta: float
    se_E_d: float
    se_E_b: float
    sem: float
    threshold: float
    recommended: bool
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    def __repr__(self) -> str:
        return (
            f"PlanReport(L={self.side_length:.2f} m, {self.runs}+{self.runs} runs, "
            f"{self.noise}, se_E_d={self.se_E_d:.2e}, se_E_b={self.se_E_b:.2e})"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready figures (metres, radians)."""
        return {
            "side_length": self.side_length,
            "runs_per_direction": self.runs,
            "wheelbase": self.wheelbase,
            "scatter": self.scatter,
            "noise": self.noise,
            "xy_correlation": self.correlation,
            "slip": self.slip,
            "reading_error": self.reading_error,
            "scatter_given": self.scatter_given,
            "scatter_side": self.scatter_side,
            "se_alpha": self.se_alpha,
            "se_beta": self.se_beta,
            "se_E_d": self.se_E_d,
            "se_E_b": self.se_E_b,
            "sem": self.sem,
            "threshold_3_sem": self.threshold,
            "recommended": self.recommended,
            "notes": list(self.notes),
            "warnings": list(self.warnings),
        }


@dataclass(frozen=True)
class Scatter:
    """The scatter as a function of the side: ``value`` measured on ``side`` (None: on
    the planned side), ``reading`` of it a reading error that is the same on any side."""

    value: float
    side: float | None
    noise: Noise
    wheelbase: float
    reading: float

    def at(self, side: float) -> tuple[float, float]:
        """Per-axis scatter [m] on a square of side ``side`` [m] and the slip's share of
        its variance per unit ``D``, ``s^2`` [m]."""
        if self.noise == "tape":
            return self.value, 0.0
        measured_on = side if self.side is None else self.side
        s2 = (self.value**2 - self.reading**2) / slip_coefficients(measured_on, self.wheelbase)[0]
        return math.sqrt(s2 * slip_coefficients(side, self.wheelbase)[0] + self.reading**2), s2


def _figures(
    side: float, runs: int, wheelbase: float, scatter: float, s2: float
) -> dict[str, float]:
    """The figures of ``runs`` per direction on ``side`` with a per-axis ``scatter`` [m]
    of which ``s2 D`` comes from slip (``s2`` [m], 0 for ``tape``)."""
    rho = s2 * slip_coefficients(side, wheelbase)[1] / scatter**2
    se_angle = scatter * math.sqrt(1.0 + rho) / (4.0 * side * math.sqrt(runs))
    sem = math.sqrt(2.0) * scatter / math.sqrt(runs)
    return {
        "correlation": rho,
        "se_alpha": se_angle,
        "se_beta": se_angle,
        "se_E_b": (2.0 / math.pi) * se_angle,
        "se_E_d": (wheelbase / side) * se_angle,
        "sem": sem,
        "threshold": 3.0 * sem,
    }


def _runs_needed(figures: Mapping[str, float], targets: Mapping[str, float | None]) -> int:
    """Fewest runs per direction (at least five) whose figures (of one run) meet the
    targets: every standard error falls as ``1/sqrt(n)``."""
    needed = MIN_PLAN_RUNS
    for key, target in targets.items():
        if target is not None:
            needed = max(needed, math.ceil((figures[key] / target) ** 2 * (1.0 - 1e-12)))
    return needed


def plan_test(
    given: Scatter,
    side_length: float | None,
    runs: int | None,
    floor: float | None,
    margin: float,
    targets: Mapping[str, float | None],
) -> PlanReport:
    """The plan of :func:`umbmark.jobs.plan.plan` for checked options: ``side_length``
    and ``runs`` predicted, or (where None) recommended for the ``floor`` [m] less the
    ``margin`` [m] and the ``targets`` (``se_E_d``, ``se_E_b``, ``threshold``).

    Raises
    ------
    InputError
        For a side or a number of runs out of range, or a target no plan within bounds
        reaches.
    """
    scatter, scatter_side, model = given.value, given.side, given.noise
    wheelbase, reading_error = given.wheelbase, given.reading
    notes: list[str] = []
    recommended = side_length is None or runs is None
    if side_length is None:
        side_length = _recommend_side(given, floor, margin, runs, targets, notes)
    PLAN["side_length"].check(side_length)
    if side_length < 2.0 * wheelbase:
        raise InputError(
            f"{option('side_length', side_length, 'm')} is less than twice the wheelbase "
            f"({wheelbase:g} m)"
        )
    on_square, s2 = given.at(side_length)
    if runs is None:
        runs = _runs_needed(_figures(side_length, 1, wheelbase, on_square, s2), targets)
        if runs > MAX_PLAN_RUNS:
            raise InputError(
                f"the targets need {runs} runs per direction on a {side_length:.2f} m square "
                f"(at most {MAX_PLAN_RUNS}): a larger square or less scatter"
            )
    PLAN["runs"].check(runs)
    figures = _figures(side_length, runs, wheelbase, on_square, s2)
    if model == "slip" and scatter_side is not None and not math.isclose(scatter_side, side_length):
        notes.append(
            info(
                f"the {scatter * 1000:.1f} mm scatter measured on a {scatter_side:g} m square "
                f"is {on_square * 1000:.1f} mm on a {side_length:.2f} m one (slip grows with "
                "the path)"
            )
        )
    if 3.0 * figures["se_alpha"] > 0.05:
        notes.append(
            "the errors' scatter is large for this square: the first-order figures are rough"
        )
    return PlanReport(
        side_length=side_length,
        runs=runs,
        wheelbase=wheelbase,
        scatter=on_square,
        noise=model,
        slip=math.sqrt(s2) if model == "slip" else None,
        reading_error=reading_error,
        scatter_given=scatter,
        scatter_side=scatter_side if model == "slip" else None,
        recommended=recommended,
        notes=split_messages(notes)[0],
        warnings=split_messages(notes)[1],
        **figures,
    )


def _recommend_side(
    given: Scatter,
    floor: float | None,
    margin: float,
    runs: int | None,
    targets: Mapping[str, float | None],
    notes: list[str],
) -> float:
    """The side that fits (tried every ``SIDE_STEP`` from the largest down to twice the
    wheelbase) needing the fewest runs for the targets of ``E_d`` and ``E_b``, the
    largest such; with ``runs`` given, the one with the smallest largest ratio of
    standard error to target. (``target_e_max`` is in metres on the chosen square: it
    sets the runs, not the side.)"""
    if floor is None:
        raise InputError(
            f"give {option('side_length')} (to predict) or {option('floor')} (to be recommended "
            "one)"
        )
    PLAN["floor"].check(floor)
    wheelbase = given.wheelbase
    largest = min(floor - margin, MAX_SIDE_LENGTH)
    if largest < 2.0 * wheelbase:
        raise InputError(
            f"{option('floor', floor, 'm')} leaves a {largest:.2f} m square for a {wheelbase:g} m "
            "wheelbase: the robot needs a side of at least twice its wheelbase"
        )
    count = math.floor((largest - 2.0 * wheelbase) / SIDE_STEP + 1e-9)
    sides = [max(largest - k * SIDE_STEP, 2.0 * wheelbase) for k in range(count + 1)]
    angular = {k: targets[k] for k in ("se_E_d", "se_E_b")}
    best, best_cost = largest, math.inf
    for side in sides:  # largest first: a tie keeps the larger square
        unit = _figures(side, 1, wheelbase, *given.at(side))
        if runs is None:
            cost = float(_runs_needed(unit, angular))
        else:
            ratios = [unit[k] / t / math.sqrt(runs) for k, t in angular.items() if t is not None]
            cost = max(ratios, default=0.0)
        if cost < best_cost * (1.0 - 1e-9):
            best, best_cost = side, cost
    if best < largest - 1e-9:
        notes.append(
            info(
                f"a {best:.2f} m square reaches the targets with fewer runs than the largest that "
                f"fits ({largest:.2f} m): under slip the scatter grows faster than the return "
                "errors"
            )
        )
    elif best < 4.0:
        notes.append(
            info(
                f"a {best:.2f} m square instead of the paper's 4 m: the standard errors of E_b "
                "and E_d grow on a smaller square for the same scatter"
            )
        )
    return best

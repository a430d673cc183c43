"""Planning a UMBmark test: which square and how many runs for the accuracy wanted.

The standard errors follow from the paper's first-order model (Sec. 4, paper-notes.md)
and the scatter of the return errors. With ``n`` runs per direction whose return errors
scatter with standard deviation ``sigma`` per axis (independent, equal in x and y), each
centre of gravity coordinate has the standard error ``sigma / sqrt(n)``. The default
(``exact``) estimate and the paper's both use x and y: ``alpha`` and ``beta`` are means of
four such coordinates divided by ``4L``, so

- ``se(alpha) = se(beta) = sigma / (4 L sqrt(n))``;
- ``E_b = 90° / (90° - alpha)``, so ``se(E_b) = (pi/2) / (pi/2 - alpha)^2 se(alpha)``,
  ``(2/pi) se(alpha)`` for small errors;
- ``E_d = (L + b sin(beta/2)) / (L - b sin(beta/2))``, so ``se(E_d) = (b / L) se(beta)``
  near ``beta = 0``;
- the paper's rule of thumb (Sec. 5) compares ``E_max,syst`` with 3 SEM, with
  ``SEM = sqrt(2) sigma / sqrt(n)`` (the radial scatter of a cluster over ``sqrt(n)``).

``se(E_b) ~ 1/L`` and ``se(E_d) ~ b/L^2``: a small square hurts ``E_d`` most. The scatter
itself grows with the path (wheel slip) and does not (a tape's reading error); ``plan``
takes it as given, for the side it is given at. ``tests/test_plan.py`` checks these
figures against a Monte Carlo of the exact estimator within 10 %. The x and y scatter are
taken as independent; wheel slip correlates them, and on the slip simulator the estimates
spread about 1.2x what these figures say (``tools/plan_vs_simulation.py``).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from ..errors import InputError
from .inputs import MAX_SIDE_LENGTH, MAX_WHEELBASE, check_length

__all__ = ["MAX_PLAN_RUNS", "PlanReport", "plan"]

#: Most runs per direction a plan recommends.
MAX_PLAN_RUNS = 100
#: Fewest runs per direction a plan recommends (the paper's five).
MIN_PLAN_RUNS = 5
#: Room around the square that the robot and the start area need [m].
DEFAULT_MARGIN = 0.6


@dataclass(frozen=True)
class PlanReport:
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
        Standard deviation of the return error per axis [m].
    se_alpha, se_beta : float
        Standard errors of ``alpha`` and ``beta`` [rad].
    se_E_d, se_E_b : float
        Standard errors of ``E_d`` and ``E_b`` (default method, first order).
    sem : float
        Expected SEM of a cluster [m]; ``threshold`` = 3 SEM, the E_max,syst below which
        another pass is not worth it (Sec. 5).
    threshold : float
    recommended : bool
        Whether side and runs were chosen by :func:`plan` (else given).
    notes : tuple of str
    """

    side_length: float
    runs: int
    wheelbase: float
    scatter: float
    se_alpha: float
    se_beta: float
    se_E_d: float
    se_E_b: float
    sem: float
    threshold: float
    recommended: bool
    notes: tuple[str, ...] = ()

    def __repr__(self) -> str:
        return (
            f"PlanReport(L={self.side_length:.2f} m, {self.runs}+{self.runs} runs, "
            f"se_E_d={self.se_E_d:.2e}, se_E_b={self.se_E_b:.2e})"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready figures (metres, radians)."""
        return {
            "side_length": self.side_length,
            "runs_per_direction": self.runs,
            "wheelbase": self.wheelbase,
            "scatter": self.scatter,
            "se_alpha": self.se_alpha,
            "se_beta": self.se_beta,
            "se_E_d": self.se_E_d,
            "se_E_b": self.se_E_b,
            "sem": self.sem,
            "threshold_3_sem": self.threshold,
            "recommended": self.recommended,
            "notes": list(self.notes),
        }

    def to_json(self) -> str:
        """The JSON text of :meth:`to_dict`."""
        return json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"


def _figures(side: float, runs: int, wheelbase: float, scatter: float) -> dict[str, float]:
    se_angle = scatter / (4.0 * side * math.sqrt(runs))
    sem = math.sqrt(2.0) * scatter / math.sqrt(runs)
    return {
        "se_alpha": se_angle,
        "se_beta": se_angle,
        "se_E_b": (2.0 / math.pi) * se_angle,
        "se_E_d": (wheelbase / side) * se_angle,
        "sem": sem,
        "threshold": 3.0 * sem,
    }


def plan(
    *,
    scatter: float,
    wheelbase: float = 0.34,
    side_length: float | None = None,
    runs: int | None = None,
    floor: float | None = None,
    margin: float = DEFAULT_MARGIN,
    target_E_d: float | None = None,
    target_E_b: float | None = None,
    target_e_max: float | None = None,
) -> PlanReport:
    """Plan a UMBmark test, or predict what a planned one gives.

    Give ``side_length`` and ``runs`` to predict; leave them out and give the ``floor``
    and a target (``target_E_d``, ``target_E_b``: standard errors wanted;
    ``target_e_max``: the E_max,syst [m] that 3 SEM must stay below) to be recommended the
    largest square that fits (``floor - margin``) and the fewest runs per direction (at
    least 5) that reach every target.

    Parameters
    ----------
    scatter : float
        Standard deviation of the return error per axis [m] (from a previous
        calibration's spread, or the paper's ~10 mm on 4 m).
    wheelbase : float
        Wheelbase [m].
    side_length : float, optional
        Side of the square [m].
    runs : int, optional
        Runs per direction.
    floor : float, optional
        Side of the free floor [m] (a square room, or the shorter side of a rectangle).
    margin : float
        Room the robot and the start area need beyond the square [m].
    target_E_d, target_E_b, target_e_max : float, optional

    Raises
    ------
    InputError
        For a value out of range, or a target no plan within bounds reaches.
    """
    if not (math.isfinite(scatter) and 1e-5 <= scatter <= 1.0):
        raise InputError(f"--scatter {scatter:g} m is outside 1e-05 to 1 m")
    check_length("--wheelbase", wheelbase, MAX_WHEELBASE)
    if not (math.isfinite(margin) and 0.0 <= margin <= 5.0):
        raise InputError(f"--margin {margin:g} m is outside 0 to 5 m")
    for flag, value in (
        ("--target-E-d", target_E_d),
        ("--target-E-b", target_E_b),
        ("--target-e-max", target_e_max),
    ):
        if value is not None and not (math.isfinite(value) and 0.0 < value < 1.0):
            raise InputError(f"{flag} {value:g} is outside 0 to 1")
    notes: list[str] = []
    recommended = side_length is None or runs is None
    if side_length is None:
        if floor is None:
            raise InputError("give --side-length (to predict) or --floor (to be recommended one)")
        check_length("--floor", floor, MAX_SIDE_LENGTH + 5.0)
        side_length = min(floor - margin, MAX_SIDE_LENGTH)
        if side_length < 2.0 * wheelbase:
            raise InputError(
                f"--floor {floor:g} m leaves a {side_length:.2f} m square for a {wheelbase:g} m "
                "wheelbase: the robot needs a side of at least twice its wheelbase"
            )
        if side_length < 4.0:
            notes.append(
                f"a {side_length:.2f} m square instead of the paper's 4 m: the standard errors "
                f"of E_b grow as 1/L and those of E_d as 1/L^2"
            )
    check_length("--side-length", side_length, MAX_SIDE_LENGTH)
    if side_length < 2.0 * wheelbase:
        raise InputError(
            f"--side-length {side_length:g} m is less than twice the wheelbase ({wheelbase:g} m)"
        )
    if runs is None:
        unit = _figures(side_length, 1, wheelbase, scatter)
        needed = MIN_PLAN_RUNS
        for target, one in (
            (target_E_d, unit["se_E_d"]),
            (target_E_b, unit["se_E_b"]),
            (target_e_max, unit["threshold"]),
        ):
            if target is not None:
                needed = max(needed, math.ceil((one / target) ** 2))
        if needed > MAX_PLAN_RUNS:
            raise InputError(
                f"the targets need {needed} runs per direction on a {side_length:.2f} m square "
                f"(at most {MAX_PLAN_RUNS}): a larger square or less scatter"
            )
        runs = needed
    if isinstance(runs, bool) or not 2 <= runs <= MAX_PLAN_RUNS:
        raise InputError(f"--runs {runs} is outside 2 to {MAX_PLAN_RUNS}")
    figures = _figures(side_length, runs, wheelbase, scatter)
    alpha_room = 3.0 * figures["se_alpha"]
    if alpha_room > 0.05:
        notes.append(
            "the errors' scatter is large for this square: the first-order figures are rough"
        )
    return PlanReport(
        side_length=side_length,
        runs=runs,
        wheelbase=wheelbase,
        scatter=scatter,
        recommended=recommended,
        notes=tuple(notes),
        **figures,
    )

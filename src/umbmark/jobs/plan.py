"""The plan job: which square and how many runs for the accuracy wanted.

:func:`plan` is what ``umbmark plan`` does: it checks the options and plans with the
model of :mod:`umbmark.calibration.plan` (the derivation is in its docstring).
"""

from __future__ import annotations

import math
from pathlib import Path

from umbmark.calibration.plan import (
    PlanReport,
    Scatter,
    check_scatter,
    plan_test,
    read_previous_scatter,
)
from umbmark.core.errors import InputError, option
from umbmark.options.plan import DEFAULT_WHEELBASE, PLAN, Noise

__all__ = ["plan"]


def plan(
    *,
    scatter: float | None = None,
    wheelbase: float | None = None,
    side_length: float | None = None,
    runs: int | None = None,
    floor: float | None = None,
    margin: float = PLAN["margin"].default,
    target_E_d: float | None = None,
    target_E_b: float | None = None,
    target_e_max: float | None = None,
    noise: str = PLAN["noise"].default,
    scatter_side: float | None = None,
    reading_error: float = PLAN["reading_error"].default,
    previous: str | Path | None = None,
) -> PlanReport:
    """Plan a UMBmark test, or predict what a planned one gives.

    Give ``side_length`` and ``runs`` to predict; leave them out and give the ``floor``
    and a target (``target_E_d``, ``target_E_b``: standard errors wanted;
    ``target_e_max``: the E_max,syst [m] that 3 SEM must stay below) to be recommended the
    square that fits (``floor - margin``) needing the fewest runs per direction (at least
    5) to reach every target, the largest such.

    Parameters
    ----------
    scatter : float, optional
        Standard deviation of the return error per axis [m], as measured (the paper's
        runs: about 10 mm on 4 m). Give it or ``previous``.
    wheelbase : float, optional
        Wheelbase [m] (default: the previous result's, else 0.34).
    side_length : float, optional
        Side of the square [m].
    runs : int, optional
        Runs per direction.
    floor : float, optional
        Side of the free floor [m] (a square room, or the shorter side of a rectangle).
    margin : float
        Room the robot and the start area need beyond the square [m].
    target_E_d, target_E_b, target_e_max : float, optional
    noise : {"slip", "tape"}
        How the return errors scatter (see the module's documentation): ``slip``, driven
        by the path (x and y correlated, growing with the side); ``tape``, a reading
        error only (independent, the same on any square).
    scatter_side : float, optional
        Side of the square the scatter was measured on [m] (``slip``: the scatter is
        carried over to the planned side); default: the planned side.
    reading_error : float
        ``slip``: the part of the scatter [m] per axis that is a reading or placement
        error, independent in x and y and the same on any square (default 0).
    previous : str or Path, optional
        A ``calibrate --json`` result: its scatter (``std_cw``, ``std_ccw``), the side it
        was measured on and its wheelbase.

    Raises
    ------
    InputError
        For a value out of range, or a target no plan within bounds reaches.
    """
    PLAN["noise"].check(noise)
    model: Noise = "slip" if noise == "slip" else "tape"
    if previous is not None:
        if scatter is not None:
            raise InputError(f"give {option('scatter')} or {option('previous')}, not both")
        found = read_previous_scatter(previous)
        scatter = found.scatter
        if scatter_side is None:
            scatter_side = found.side_length
        if wheelbase is None and found.wheelbase is not None:
            wheelbase = found.wheelbase
    if scatter is None:
        raise InputError(
            f"give {option('scatter')} (per axis [m]) or {option('previous')} (a calibrate "
            "--json result)"
        )
    check_scatter(scatter)
    if wheelbase is None:
        wheelbase = DEFAULT_WHEELBASE
    PLAN["wheelbase"].check(wheelbase)
    PLAN["scatter_side"].check(scatter_side)
    PLAN["margin"].check(margin)
    if not (math.isfinite(reading_error) and 0.0 <= reading_error <= scatter):
        raise InputError(
            f"{option('reading_error', reading_error, 'm')} is outside 0 to the scatter "
            f"({scatter:g} m)"
        )
    if reading_error > 0.0 and model == "tape":
        raise InputError(
            f"{option('reading_error')} is part of {option('noise', 'slip')} (under tape it is "
            "all of it)"
        )
    targets = {"se_E_d": target_E_d, "se_E_b": target_E_b, "threshold": target_e_max}
    names = ("target_E_d", "target_E_b", "target_e_max")
    for name, value in zip(names, targets.values(), strict=True):
        if value is not None and not (math.isfinite(value) and 0.0 < value < 1.0):
            raise InputError(f"{option(name, value)} is outside 0 to 1")
    given = Scatter(scatter, scatter_side, model, wheelbase, reading_error)
    return plan_test(given, side_length, runs, floor, margin, targets)

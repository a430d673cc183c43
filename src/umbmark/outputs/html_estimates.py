"""The estimates section of the HTML pages: each pass's estimates with their 95 %
intervals, and the correction composed with the values active (none for absolute figures
given no nominal geometry)."""

from __future__ import annotations

from html import escape
from typing import TYPE_CHECKING

from umbmark.calibration.passes import e_b_words
from umbmark.outputs.components import ANGLE_UNIT, component, to_shown
from umbmark.outputs.html_parts import num, table

if TYPE_CHECKING:
    from umbmark.calibration.result import CalibrationResult
    from umbmark.estimators.base import ErrorEstimate

__all__ = ["MM", "estimate_section", "estimates_section"]

#: Millimetres in a metre: the pages show lengths in mm.
MM = 1000.0


def _estimate(one: CalibrationResult, coarse: float | None = None) -> str:
    """One pass's estimates; ``coarse``: the factor of a coarse turning correction the
    pass was measured after (its E_b the residual on the corrected wheelbase)."""
    cal = one.calibration
    est = cal.estimate
    se = est.standard_errors
    rows = []
    names = [
        ("E_d", "", "D_R / D_L"),
        ("E_b", "", "b_actual / b_nominal"),
        ("E_s", "", "D_avg / D_active"),
        ("alpha", ANGLE_UNIT, "Type A error per turn; > 0: turns too little"),
        ("beta", ANGLE_UNIT, "Type B error per leg; > 0: legs curve left"),
    ]
    for name, unit, means in names:
        value = getattr(est, name)
        if value is None or (not one.nominal and name in ("E_b", "alpha")):
            continue
        interval = est.interval(name)
        low, high = (None, None) if interval is None else interval
        fmt = ".4f" if unit else ".6f"
        meaning = means
        if name == "E_b" and coarse is not None:
            meaning = (
                f"b_actual / b_active: {e_b_words(value, coarse)} with the coarse turning "
                f"correction (wheel_separation_multiplier x{coarse:.4f}) it was measured after"
            )
        rows.append(
            [
                f"{name} [{unit}]" if unit else name,
                *(
                    num(None if v is None else to_shown(v, unit), fmt)
                    for v in (value, se.get(name), low, high)
                ),
                meaning,
            ]
        )
    rows += _absolute_rows(est)
    figures = table(["", "estimate", "standard error", "95 % low", "95 % high", ""], rows, {5})
    if not one.nominal:  # absolute figures only: no correction of a nominal
        return f"<p>Method: <code>{escape(est.method)}</code></p>\n{figures}"
    active = cal.active
    correction = [
        ["c_L", f"{active.c_left:.6f}", f"{cal.new_c_left:.6f}"],
        ["c_R", f"{active.c_right:.6f}", f"{cal.new_c_right:.6f}"],
        [
            "wheel_separation_multiplier",
            f"{active.separation_multiplier:.6f}",
            f"{cal.new_separation_multiplier:.6f}",
        ],
        ["wheelbase [m]", f"{active.effective_wheelbase:.6f}", f"{cal.wheelbase_corrected:.6f}"],
    ]
    return (
        f"<p>Method: <code>{escape(est.method)}</code></p>\n{figures}"
        "<p>Correction, composed with the values active during the runs:</p>\n"
        + table(["", "active", "new"], correction)
    )


def _absolute_rows(est: ErrorEstimate) -> list[list[str]]:
    """The rows of the absolute figures an estimate carries, in their units shown."""
    rows = []
    from umbmark.calibration.result import ABSOLUTE_FIGURES

    for name in ABSOLUTE_FIGURES:
        if name not in est.components or name not in est.standard_errors:
            continue
        shown = component(name)
        interval = est.interval(name)
        low, high = (None, None) if interval is None else interval
        values = (est.components[name], est.standard_errors[name], low, high)
        rows.append(
            [
                shown.heading,
                *("–" if v is None else shown.show(v) for v in values),
                shown.meaning,
            ]
        )
    return rows


def estimate_section(one: CalibrationResult) -> str:
    """The estimates of one calibration with their 95 % intervals, and its correction."""
    return _estimate(one)


def estimates_section(
    passes: list[tuple[str, CalibrationResult]], coarse: float | None = None
) -> str:
    """The page's estimates: each pass's (under its name when several), with its 95 %
    intervals and the correction; ``coarse``: the factor of a coarse turning correction
    applied before the first pass (its E_b then shown as the residual, and composed)."""
    if len(passes) == 1:
        return _estimate(passes[0][1], coarse)
    return "".join(
        f"<h3>{escape(name)}</h3>\n{_estimate(one, coarse if k == 1 else None)}"
        for k, (name, one) in enumerate(passes, 1)
    )

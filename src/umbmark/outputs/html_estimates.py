"""The estimates section of the HTML pages (each pass's estimates with their 95 %
intervals, and the correction composed with the values active), and the tables and
numbers every section of :mod:`umbmark.outputs.html_report` draws with."""

from __future__ import annotations

import math
from collections.abc import Collection
from html import escape
from typing import TYPE_CHECKING

from umbmark.calibration.passes import e_b_words
from umbmark.outputs.components import ANGLE_UNIT, component, to_shown

if TYPE_CHECKING:
    from umbmark.calibration.result import CalibrationResult
    from umbmark.estimators.base import ErrorEstimate

__all__ = ["MM", "estimates_section", "num", "table"]

#: Millimetres in a metre: the pages show lengths in mm.
MM = 1000.0


def num(value: float | None, fmt: str) -> str:
    """``value`` formatted, or a dash for None and non-finite values."""
    if value is None or not math.isfinite(value):
        return "–"
    return format(value, fmt)


def table(head: list[str], rows: list[list[str]], wrap: Collection[int] = ()) -> str:
    """An HTML table (in a scrolling box) of already formatted cells; escaped here.

    Headers wrap between words, numbers never; the cells of the columns ``wrap`` (their
    indices: names, paths, digests, explanations) wrap anywhere, so that a wide table fits
    a page.
    """
    cls = [' class="wrap"' if k in wrap else "" for k in range(len(head))]
    th = "".join(f"<th{c}>{escape(h)}</th>" for c, h in zip(cls, head, strict=True))
    tds = [f"<td{c}>" for c in cls]
    body = "".join(
        "<tr>"
        + "".join(f"{td}{escape(cell)}</td>" for td, cell in zip(tds, row, strict=False))
        + "</tr>\n"
        for row in rows
    )
    return (
        f'<div class="scroll"><table>\n<thead><tr>{th}</tr></thead>\n'
        f"<tbody>\n{body}</tbody></table></div>\n"
    )


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
        if value is None:
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

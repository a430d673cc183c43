"""One self-contained HTML page of UMBmark passes on one robot.

What ``umbmark report`` writes (:func:`passes_html`, one or more passes) and what
``calibrate --report`` writes (:func:`calibration_html`, one pass): the same page. It
needs no network: the Fig. 6 view is inline SVG (:mod:`umbmark.outputs.report_figures`),
the style a small inline sheet that reads on a phone (viewport, a maximum width, tables
that scroll) and prints. Every text from the reports is escaped.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.core.digest import file_sha256
from umbmark.core.version import __version__
from umbmark.outputs.components import component, to_shown
from umbmark.outputs.html_estimates import MM as _MM
from umbmark.outputs.html_estimates import estimates_section
from umbmark.outputs.html_parts import CSS as _CSS
from umbmark.outputs.html_parts import document
from umbmark.outputs.html_parts import num as _num
from umbmark.outputs.html_parts import table as _table
from umbmark.returns.clusters import scatter_standing, sem_verdict

if TYPE_CHECKING:
    from umbmark.calibration.passes import Passes
    from umbmark.calibration.result import CalibrationResult
    from umbmark.calibration.validation import ValidationReport
    from umbmark.returns.clusters import Benchmark

__all__ = ["calibration_html", "fit_messages", "pass_name", "passes_html"]

#: Files of an input folder listed with their SHA-256 at most.
_MAX_FOLDER_FILES = 50


def pass_name(k: int, n: int) -> str:
    """The name of pass ``k`` (1-based) of ``n``: ``pass 1 (before)``, ``pass 2 (after)``."""
    if k == 1:
        return "pass 1 (before)"
    if k == 2:
        return "pass 2 (after)"
    return f"pass {k} (after pass {k - 1})"


def _names(page: Passes) -> list[str]:
    """Each pass's name: a self-calibration's as it named them (``pass 1``, ``pass 2``,
    ``verification``), else :func:`pass_name`'s."""
    n = len(page.passes)
    if page.holds is not None and len(page.holds.labels) == n:
        return list(page.holds.labels)
    return [pass_name(k, n) for k in range(1, n + 1)]


def _passes(page: Passes) -> list[tuple[str, CalibrationResult]]:
    if len(page.passes) == 1 and page.holds is None:
        return [("measured", page.passes[0])]
    return list(zip(_names(page), page.passes, strict=True))


_PREDICTED = "predicted after (replayed)"
_PREDICTED_WORDS = (
    "a prediction from replaying the recorded wheel data of these runs with the new "
    "parameters, not a measured pass: the robot steered by its old odometry"
)


def _verdict(page: Passes) -> str:
    passes = _passes(page)
    last = page.last.benchmark
    if last is None:
        return (
            '<div class="verdict" id="verdict-text"><p>'
            f"{len(page.last.runs)} runs, not squares of a known side in both directions: no "
            "UMBmark figures (E_max,syst, the 3 x SEM rule).</p></div>\n"
        )
    figures = []
    for k, (name, one) in enumerate(passes, 1):
        bench = one.benchmark
        if bench is None:  # pragma: no cover - umbmark.report refuses such passes
            continue
        label = "E_max,syst" if len(passes) == 1 else f"{escape(name)}: E_max,syst"
        figures.append(
            f'<p class="big">{label} = <span class="e-max-syst" data-pass="{k}">'
            f"{bench.e_max_syst * _MM:.1f}</span> mm "
            f"({escape(bench.worst.direction.value)} cluster)</p>"
        )
    if len(passes) > 1:
        first = page.passes[0].benchmark
        if first is not None and last.e_max_syst > 0:
            figures.append(
                f"<p>E_max,syst went from {first.e_max_syst * _MM:.1f} mm to "
                f"{last.e_max_syst * _MM:.1f} mm over {len(passes)} passes: "
                f"{first.e_max_syst / last.e_max_syst:.1f} times smaller.</p>"
            )
    rule = f"<p>{'Last pass: ' if len(passes) > 1 else ''}{escape(sem_verdict(last))}</p>"
    predicted = ""
    if page.predicted is not None:
        p = page.predicted.benchmark
        predicted = (
            f'<p class="predicted" id="predicted-text">Predicted after: E_max,syst = '
            f'<span id="predicted-e-max-syst">{p.e_max_syst * _MM:.1f}</span> mm '
            f"({escape(_PREDICTED_WORDS)}). Drive UMBmark again with the new parameters "
            "to measure it.</p>"
        )
    cls = "verdict" if last.second_pass_recommended else "verdict ok"
    return f'<div class="{cls}" id="verdict-text">{"".join(figures)}{rule}{predicted}</div>\n'


def _cluster_rows(bench: Benchmark) -> list[str]:
    cw, ccw = bench.cw, bench.ccw
    worst = f"{scatter_standing(bench)} the scatter"
    return [
        f"{cw.n} / {ccw.n}",
        f"{cw.cg[0] * _MM:.1f}, {cw.cg[1] * _MM:.1f}",
        f"{ccw.cg[0] * _MM:.1f}, {ccw.cg[1] * _MM:.1f}",
        f"{cw.r_cg * _MM:.1f}",
        f"{ccw.r_cg * _MM:.1f}",
        f"{cw.sigma * _MM:.1f}",
        f"{ccw.sigma * _MM:.1f}",
        f"{cw.sem * _MM:.1f}",
        f"{ccw.sem * _MM:.1f}",
        f"{bench.e_max_syst * _MM:.1f}",
        f"{bench.second_pass_threshold * _MM:.1f}",
        worst,
    ]


def _clusters(page: Passes) -> str:
    """The per-pass table of Eqs. 3.1-3.4: one column per pass (and the prediction)."""
    names = [
        "runs cw / ccw",
        "centre of gravity cw x, y [mm]",
        "centre of gravity ccw x, y [mm]",
        "r_cg cw [mm]",
        "r_cg ccw [mm]",
        "spread sigma cw (radial) [mm]",
        "spread sigma ccw (radial) [mm]",
        "SEM cw = sigma / sqrt(n) [mm]",
        "SEM ccw [mm]",
        "E_max,syst [mm]",
        "3 x SEM (of that cluster) [mm]",
        "3 x SEM rule",
    ]
    columns: list[tuple[str, list[str]]] = [
        (name, _cluster_rows(one.benchmark))
        for name, one in _passes(page)
        if one.benchmark is not None
    ]
    if not columns:
        return ""
    if page.predicted is not None:
        columns.append((_PREDICTED, _cluster_rows(page.predicted.benchmark)))
    rows = [[name, *(col[1][i] for col in columns)] for i, name in enumerate(names)]
    note = (
        f'<p class="predicted">The last column is {escape(_PREDICTED_WORDS)}.</p>\n'
        if page.predicted is not None
        else ""
    )
    return (
        "<h3>Return errors (Eqs. 3.1-3.4)</h3>\n"
        + _table(["", *(name for name, _ in columns)], rows)
        + note
    )


def _figure(page: Passes) -> str:
    from umbmark.outputs.report_figures import (
        PASS_COLOURS,
        PREDICTED_COLOUR,
        SINGLE_COLOUR,
        ClusterSet,
        inline_svg,
        passes_figure,
    )

    n = len(page.passes)
    # One pass: cw and ccw each in its own colour; several: each pass in its own colour.
    names = _names(page)
    sets = [
        ClusterSet(one.benchmark, "", SINGLE_COLOUR, by_direction=True)
        if n == 1
        else ClusterSet(one.benchmark, names[k - 1], PASS_COLOURS[(k - 1) % len(PASS_COLOURS)])
        for k, one in enumerate(page.passes, 1)
        if one.benchmark is not None
    ]
    if page.predicted is not None:
        sets.append(
            ClusterSet(page.predicted.benchmark, _PREDICTED, PREDICTED_COLOUR, predicted=True)
        )
    if not sets:
        return "<p>No runs in both directions: no cluster view.</p>\n"
    svg = inline_svg(passes_figure(sets, "UMBmark return errors"), "umbmark-clusters")
    predicted = (
        f" Grey, dashed: the {escape(_PREDICTED)}, {escape(_PREDICTED_WORDS)}."
        if page.predicted is not None
        else ""
    )
    colours = (
        "each direction in its own colour"
        if n == 1
        else "each pass in its own colour (the legend names them)"
    )
    return (
        f'<figure id="figure">{svg}<figcaption>The return errors of the cw (circles) and '
        f"ccw (squares) runs, {colours}, their centres of gravity (crosses) and E_max,syst "
        "(the circle about the origin), in mm (the paper's Fig. 6 view); a second panel, "
        f"where there is one, zooms on the later sets.{predicted}"
        "</figcaption></figure>\n"
    )


def _runs(page: Passes) -> str:
    many = len(page.passes) > 1
    head = ["#", "run", "kind", "direction", "eps_x [mm]", "eps_y [mm]", "eps_theta [deg]"]
    if many:
        head.insert(0, "pass")
    predicted: list[Sequence[float] | None] = []
    if page.predicted is not None:
        head += ["predicted eps_x [mm]", "predicted eps_y [mm]"]
        replayed = iter(page.predicted.runs)
        predicted = [
            next(replayed).return_error if run.kind == "square" else None
            for run in page.passes[0].runs
        ]
    rows = []
    names = _names(page) if page.holds is not None else None
    for k, one in enumerate(page.passes, 1):
        for i, run in enumerate(one.runs, 1):
            heading = None if run.heading_error is None else math.degrees(run.heading_error)
            row = [
                str(i),
                run.label,
                run.kind,
                run.direction.value,
                f"{run.return_error[0] * _MM:.1f}",
                f"{run.return_error[1] * _MM:.1f}",
                _num(heading, ".3f"),
            ]
            if many:
                row.insert(0, str(k) if names is None else names[k - 1])
            if predicted:
                after = predicted[i - 1]
                row += (
                    ["–", "–"]
                    if after is None
                    else [f"{after[0] * _MM:.1f}", f"{after[1] * _MM:.1f}"]
                )
            rows.append(row)
    note = (
        f'<p class="predicted">The predicted columns are {escape(_PREDICTED_WORDS)}.</p>\n'
        if predicted
        else ""
    )
    return _table(head, rows, wrap={head.index("run")}) + note


def _estimates(page: Passes) -> str:
    coarse = None if page.holds is None else page.holds.coarse  # before the first pass
    return estimates_section(_passes(page), coarse)


def fit_messages(one: CalibrationResult) -> str:
    """The figures of one calibration's fit (each with its unit and meaning), its
    warnings and notes."""
    parts = []
    est = one.estimate
    main = {"alpha", "beta", "E_d", "E_b", "E_s"}  # in the estimates' table already
    components = [(k, v) for k, v in sorted(est.components.items()) if k not in main]
    if components:
        described = [(component(k), v) for k, v in components]
        rows = [[c.heading, _num(to_shown(v, c.unit), c.digits), c.meaning] for c, v in described]
        parts.append(
            f"<p>The figures of the fit (<code>{escape(est.method)}</code>), each in its "
            "unit, with what it says:</p>\n" + _table(["", "value", ""], rows, {2})
        )
    for title, items in (("Warnings", one.warnings), ("Notes", one.notes)):
        if items:
            lis = "".join(f"<li>{escape(item)}</li>\n" for item in items)
            parts.append(f"<p>{title}:</p>\n<ul>\n{lis}</ul>\n")
    if not one.warnings:
        parts.append("<p>Warnings: none.</p>\n")
    return "".join(parts)


def _validation(validation: ValidationReport) -> str:
    candidates = list(validation.candidates)
    rows = [
        [f"{fold.held_out} ({fold.runs} runs)", *(_mm(fold.errors.get(c)) for c in candidates)]
        for fold in validation.folds
    ]
    rows.append(["mean", *(_mm(validation.mean_error(c)) for c in candidates)])
    best = validation.recommended
    words = (
        f"Recommended: <code>{escape(best)}</code> (the lowest mean held-out end error)."
        if best is not None
        else "No estimator predicted held-out runs better than the nominal parameters."
    )
    return (
        f"<h3>Validation: held-out end error [mm], {escape(validation.scheme)}</h3>\n"
        + _table(["held out", *candidates], rows)
        + f"<p>{words}</p>\n"
    )


def _mm(value: float | None) -> str:
    return "–" if value is None else f"{value * _MM:.1f}"


def _messages(page: Passes) -> str:
    passes = _passes(page)
    if len(passes) == 1:
        body = fit_messages(passes[0][1])
    else:
        body = "".join(f"<h3>{escape(name)}</h3>\n{fit_messages(one)}" for name, one in passes)
    if page.validation is not None:
        body += _validation(page.validation)
    return body


def _overlay(page: Passes) -> str:
    from umbmark.outputs.html_verdict import NO_NOMINAL, WITHHELD

    n = len(page.passes)
    last = _names(page)[-1]
    which = "" if n == 1 else f" of the last pass ({last})"
    shown = page.last
    if page.holds is not None and page.holds.held is not None:
        shown = page.passes[page.holds.held - 1]
        which = f" the controller holds ({page.holds.label})"
    elif page.holds is not None:
        which = f" of the last pass ({last}), not applied"
    if shown.overlay_withheld or not shown.nominal:
        return WITHHELD if shown.nominal else NO_NOMINAL
    return (
        f"<p>The correction{which}, composed with the values active during its runs; "
        "copy it into the controller's parameters:</p>\n"
        f'<pre id="overlay-yaml">{escape(shown.overlay_yaml())}</pre>\n'
    )


def _inputs(report: CalibrationResult) -> list[list[str]]:
    """``[path, SHA-256]`` of every input file (the files of an input folder)."""
    rows = []
    for source in report.sources:
        path = Path(source)
        if path.is_file():
            rows.append([source, file_sha256(path)])
        elif path.is_dir():
            files = sorted(p for p in path.rglob("*") if p.is_file())
            for file in files[:_MAX_FOLDER_FILES]:
                rows.append([str(file), file_sha256(file)])
            if len(files) > _MAX_FOLDER_FILES:
                rows.append([f"{source}: {len(files) - _MAX_FOLDER_FILES} more files", ""])
        else:
            rows.append([source, "(not a file: runs given in memory)"])
    return rows


def _parameters(one: CalibrationResult) -> list[str]:
    active = one.calibration.active
    values = [
        _num(one.test.wheelbase, ".4f"),
        f"{active.wheelbase:.6f}",
        f"{active.separation_multiplier:g}",
        f"{active.c_left:g}",
        f"{active.c_right:g}",
        _num(active.wheel_diameter, "g"),
    ]  # none known without a nominal geometry
    shown = values if one.nominal else ["not given"] * len(values)
    return [_num(one.test.side_length, ".4f"), *shown, one.format, one.estimate.method]


def _provenance(page: Passes) -> str:
    passes = _passes(page)
    many = len(passes) > 1
    inputs = [[name, *row] if many else row for name, one in passes for row in _inputs(one)]
    names = [
        "side length L [m]",
        "wheelbase b [m]",
        "active wheelbase [m]",
        "active wheel_separation_multiplier",
        "active c_L",
        "active c_R",
        "active wheel diameter [m]",
        "format",
        "method",
    ]
    columns = [_parameters(one) for _, one in passes]
    params = [[name, *(col[i] for col in columns)] for i, name in enumerate(names)]
    created = page.created.astimezone(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    command = (
        f'<p>Command: <code id="command">{escape(page.command)}</code></p>\n'
        if page.command
        else "<p>Command: not given (made from Python).</p>\n"
    )
    methods = ", ".join(sorted({one.estimate.method for _, one in passes}))
    return (
        "<h3>Inputs</h3>\n"
        + _table(
            ["pass", "file", "SHA-256"] if many else ["file", "SHA-256"],
            inputs,
            wrap={1, 2} if many else {0, 1},
        )
        + "<h3>Parameters active during the runs</h3>\n"
        + _table(["", *(name for name, _ in passes)] if many else ["", ""], params)
        + command
        + f"<p>Format: <code>{escape(page.passes[0].format)}</code>; method: "
        f"<code>{escape(methods)}</code>; umbmark "
        f'<span id="umbmark-version">{escape(__version__)}</span>; made {created}.</p>\n'
    )


def passes_html(page: Passes) -> str:
    """UMBmark passes on one robot as one self-contained HTML page (no external resources).

    Sections: whether to apply the last pass's correction
    (:func:`umbmark.outputs.html_verdict.verdict_section`), the verdict (E_max,syst of
    every pass and the 3 x SEM rule, with the
    per-pass table of Eqs. 3.1-3.4), the Fig. 6 cluster view of every pass in one inline
    SVG figure (and the predicted after of a single pass of recorded runs, marked as a
    prediction), every run, the estimates with their 95 % intervals (alpha and beta in
    degrees) and the correction, the figures of the fit (each with its unit and
    meaning), warnings, notes and any validation table, the laser's mounting in the forms
    a user applies (a calibration from motion intervals:
    :func:`umbmark.outputs.mounting.mounting_html`), the gyro's own calibration and where
    it goes (a calibration with a gyro: :func:`umbmark.outputs.gyro.gyro_html`), the
    ros2_control overlay of the
    last pass and the provenance (inputs with their SHA-256, the parameters active, the
    command, the umbmark version and the method).
    """
    n = len(page.passes)
    title = (
        f"umbmark calibration: {page.passes[0].source}"
        if n == 1
        else f"umbmark: {n} UMBmark passes, {page.passes[0].source} to {page.last.source}"
    )
    if page.holds is not None:  # a self-calibration's passes, by its names
        title = f"umbmark self-calibration: {', '.join(_names(page))}"
    robot = page.passes[0].robot
    if robot:
        title = f"{robot}: {title}"
    from umbmark.outputs.gyro import gyro_html
    from umbmark.outputs.html_verdict import CSS, verdict_section
    from umbmark.outputs.mounting import CSS as MOUNTING_CSS
    from umbmark.outputs.mounting import mounting_forms, mounting_html

    forms = mounting_forms(page.last)  # None but for a calibration from motion intervals
    mounting = [] if forms is None else [("mounting", "The laser's mounting", mounting_html(forms))]
    if page.last.gyro is not None:
        mounting.append(("gyro-calibration", "The gyro", gyro_html(page.last)))
    sections = [
        ("apply", "Apply the correction?", verdict_section(page)),
        ("verdict", "E_max,syst and the 3 x SEM rule", _verdict(page) + _clusters(page)),
        ("clusters", "Cluster view (Fig. 6)", _figure(page)),
        ("runs", "Runs", _runs(page)),
        ("estimates", "Estimates and 95 % intervals", _estimates(page)),
        *mounting,
        ("messages", "Figures of the fit, warnings and notes", _messages(page)),
        ("overlay", "ros2_control overlay", _overlay(page)),
        ("provenance", "Provenance", _provenance(page)),
    ]
    return document(title, sections, f"{_CSS}{CSS}{MOUNTING_CSS}")


def calibration_html(report: CalibrationResult) -> str:
    """One calibration as the page of :func:`passes_html` (what ``--report`` writes).

    With recorded runs the page shows the predicted after too
    (:func:`umbmark.calibration.passes.predict_after`).
    """
    from umbmark.calibration.passes import Passes, predict_after

    page = Passes(
        passes=(report,),
        predicted=predict_after(report),
        created=report.created,
        command=report.command,
    )
    return passes_html(page)

"""One self-contained HTML page of a calibration (what ``calibrate --report`` writes).

The page needs no network: the Fig. 6 view is inline SVG, the style a small inline
sheet that reads on a phone (viewport, a maximum width, tables that scroll) and prints.
Every text from the report is escaped.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import io
import math
import re
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING

from .. import __version__

if TYPE_CHECKING:
    from ..jobs.calibrate import CalibrationReport

__all__ = ["calibration_html", "file_sha256"]

_MM = 1000.0
#: Files of an input folder listed with their SHA-256 at most.
_MAX_FOLDER_FILES = 50

_CSS = """
:root { color-scheme: light; }
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; line-height: 1.45;
  margin: 0 auto; padding: 1rem; max-width: 60rem; color: #111; background: #fff; }
h1 { font-size: 1.5rem; } h2 { font-size: 1.2rem; margin-top: 2rem;
  border-bottom: 1px solid #ccc; }
.verdict { padding: .75rem 1rem; border-left: .4rem solid #c60; background: #fff6ec; }
.verdict.ok { border-color: #2a7; background: #eefaf3; }
.big { font-size: 1.4rem; font-weight: bold; }
.scroll { overflow-x: auto; }
table { border-collapse: collapse; margin: .5rem 0; }
th, td { padding: .2rem .6rem; border-bottom: 1px solid #ddd; text-align: right;
  white-space: nowrap; }
th:first-child, td:first-child { text-align: left; }
pre { background: #f4f4f4; padding: .75rem; overflow-x: auto; font-size: .85rem; }
figure { margin: 0; } figure svg { max-width: 100%; height: auto; }
code { word-break: break-all; }
@media print {
  body { max-width: none; padding: 0; font-size: 10pt; }
  .scroll, pre { overflow: visible; } pre { white-space: pre-wrap; }
  h2 { break-after: avoid; } figure, table { break-inside: avoid; }
}
"""


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, as hex."""
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _num(value: float | None, fmt: str) -> str:
    """``value`` formatted, or a dash for None and non-finite values."""
    if value is None or not math.isfinite(value):
        return "–"
    return format(value, fmt)


def _table(head: list[str], rows: list[list[str]]) -> str:
    """An HTML table (in a scrolling box) of already formatted cells; escaped here."""
    th = "".join(f"<th>{escape(h)}</th>" for h in head)
    body = "".join(
        "<tr>" + "".join(f"<td>{escape(cell)}</td>" for cell in row) + "</tr>\n" for row in rows
    )
    return (
        f'<div class="scroll"><table>\n<thead><tr>{th}</tr></thead>\n'
        f"<tbody>\n{body}</tbody></table></div>\n"
    )


def _svg(report: CalibrationReport) -> str | None:
    """The Fig. 6 view as an inline ``<svg>`` element, or None without a benchmark."""
    if report.benchmark is None:
        return None
    buffer = io.StringIO()
    report.figure().savefig(buffer, format="svg", bbox_inches="tight", metadata={"Date": None})
    text = buffer.getvalue()
    start = text.find("<svg")
    if start < 0:
        return None
    # The metadata names matplotlib's web site; the page keeps no address it could fetch.
    return re.sub(r"\s*<metadata>.*?</metadata>", "", text[start:], flags=re.DOTALL)


def _verdict(report: CalibrationReport) -> str:
    bench = report.benchmark
    if bench is None:
        return (
            '<div class="verdict" id="verdict-text"><p>'
            f"{len(report.runs)} runs, not squares of a known side in both directions: no "
            "UMBmark figures (E_max,syst, the 3 x SEM rule).</p></div>\n"
        )
    e, t = bench.e_max_syst * _MM, bench.second_pass_threshold * _MM
    if bench.second_pass_recommended:
        cls = "verdict"
        words = (
            f"E_max,syst = {e:.1f} mm &gt; 3 x SEM = {t:.1f} mm: the systematic error stands "
            "well above the scatter of the runs. Apply the correction, then run UMBmark "
            "again; another pass is worth it while E_max,syst stays above 3 x SEM."
        )
    else:
        cls = "verdict ok"
        words = (
            f"E_max,syst = {e:.1f} mm &lt;= 3 x SEM = {t:.1f} mm: what remains is within the "
            "scatter of the runs; a further pass is unlikely to improve it (Sec. 5)."
        )
    return (
        f'<div class="{cls}" id="verdict-text">'
        f'<p class="big">E_max,syst = <span id="e-max-syst">{e:.1f}</span> mm '
        f"({escape(bench.worst.direction.value)} cluster)</p>"
        f"<p>{words}</p></div>\n"
    )


def _clusters(report: CalibrationReport) -> str:
    bench = report.benchmark
    if bench is None:
        return ""
    cw, ccw = bench.cw, bench.ccw
    rows = [
        ["runs", str(cw.n), str(ccw.n)],
        ["centre of gravity x [mm]", f"{cw.cg[0] * _MM:.1f}", f"{ccw.cg[0] * _MM:.1f}"],
        ["centre of gravity y [mm]", f"{cw.cg[1] * _MM:.1f}", f"{ccw.cg[1] * _MM:.1f}"],
        ["r_cg [mm]", f"{cw.r_cg * _MM:.1f}", f"{ccw.r_cg * _MM:.1f}"],
        ["spread sigma (radial) [mm]", f"{cw.sigma * _MM:.1f}", f"{ccw.sigma * _MM:.1f}"],
        ["SEM = sigma / sqrt(n) [mm]", f"{cw.sem * _MM:.1f}", f"{ccw.sem * _MM:.1f}"],
    ]
    return "<h3>Return errors (Eqs. 3.1-3.4)</h3>\n" + _table(["", "cw", "ccw"], rows)


def _runs(report: CalibrationReport) -> str:
    rows = [
        [
            str(i),
            run.label,
            run.kind,
            run.direction.value,
            f"{run.return_error[0] * _MM:.1f}",
            f"{run.return_error[1] * _MM:.1f}",
            _num(None if run.heading_error is None else math.degrees(run.heading_error), ".3f"),
        ]
        for i, run in enumerate(report.runs, 1)
    ]
    head = ["#", "run", "kind", "direction", "eps_x [mm]", "eps_y [mm]", "eps_theta [deg]"]
    return _table(head, rows)


def _estimates(report: CalibrationReport) -> str:
    cal = report.calibration
    est = cal.estimate
    se = est.standard_errors
    rows = []
    names = [("E_d", "D_R / D_L"), ("E_b", "b_actual / b_nominal"), ("E_s", "D_avg / D_active")]
    names += [("alpha", "Type A error per turn [rad]"), ("beta", "Type B error per leg [rad]")]
    for name, meaning in names:
        value = getattr(est, name)
        if value is None:
            continue
        interval = est.interval(name)
        low, high = (None, None) if interval is None else interval
        rows.append(
            [
                name,
                f"{value:.6f}",
                _num(se.get(name), ".6f"),
                _num(low, ".6f"),
                _num(high, ".6f"),
                meaning,
            ]
        )
    table = _table(["", "estimate", "standard error", "95 % low", "95 % high", ""], rows)
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
        f"<p>Method: <code>{escape(est.method)}</code></p>\n{table}"
        "<h3>Correction, composed with the values active during the runs</h3>\n"
        + _table(["", "active", "new"], correction)
    )


def _messages(report: CalibrationReport) -> str:
    parts = []
    for title, items in (("Warnings", report.warnings), ("Notes", report.notes)):
        if items:
            lis = "".join(f"<li>{escape(item)}</li>\n" for item in items)
            parts.append(f"<h3>{title}</h3>\n<ul>\n{lis}</ul>\n")
    return "".join(parts) or "<p>None.</p>\n"


def _inputs(report: CalibrationReport) -> list[list[str]]:
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


def _provenance(report: CalibrationReport) -> str:
    cal = report.calibration
    active = cal.active
    params = [
        ["side length L [m]", _num(report.test.side_length, ".4f")],
        ["wheelbase b [m]", _num(report.test.wheelbase, ".4f")],
        ["active wheelbase [m]", f"{active.wheelbase:.6f}"],
        ["active wheel_separation_multiplier", f"{active.separation_multiplier:g}"],
        ["active c_L", f"{active.c_left:g}"],
        ["active c_R", f"{active.c_right:g}"],
        ["active wheel diameter [m]", _num(active.wheel_diameter, "g")],
    ]
    created = report.created.astimezone(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return (
        "<h3>Inputs</h3>\n"
        + _table(["file", "SHA-256"], _inputs(report))
        + "<h3>Parameters active during the runs</h3>\n"
        + _table(["", ""], params)
        + f"<p>Format: <code>{escape(report.format)}</code>; method: "
        f"<code>{escape(cal.estimate.method)}</code>; umbmark "
        f'<span id="umbmark-version">{escape(__version__)}</span>; made {created}.</p>\n'
    )


def calibration_html(report: CalibrationReport) -> str:
    """The calibration as one self-contained HTML page (no external resources).

    Sections: the verdict (E_max,syst and the 3 x SEM rule), the Fig. 6 cluster view
    (inline SVG), the runs, the estimates with their 95 % intervals and the correction,
    warnings and notes, the ros2_control overlay and the provenance (inputs with their
    SHA-256, the parameters active, the umbmark version and the method).
    """
    svg = _svg(report)
    figure = (
        f'<figure id="figure">{svg}<figcaption>The return errors of the cw and ccw runs '
        "and their centres of gravity (the paper's Fig. 6 view).</figcaption></figure>\n"
        if svg is not None
        else "<p>No runs in both directions: no cluster view.</p>\n"
    )
    title = f"umbmark calibration: {report.source}"
    sections = [
        ("verdict", "Verdict", _verdict(report) + _clusters(report)),
        ("clusters", "Cluster view (Fig. 6)", figure),
        ("runs", "Runs", _runs(report)),
        ("estimates", "Estimates and 95 % intervals", _estimates(report)),
        ("messages", "Warnings and notes", _messages(report)),
        (
            "overlay",
            "ros2_control overlay",
            f'<pre id="overlay-yaml">{escape(report.overlay_yaml())}</pre>\n',
        ),
        ("provenance", "Provenance", _provenance(report)),
    ]
    body = "".join(
        f'<section id="{key}">\n<h2>{escape(name)}</h2>\n{content}</section>\n'
        for key, name, content in sections
    )
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{escape(title)}</title>\n<style>{_CSS}</style>\n</head>\n<body>\n"
        f"<h1>{escape(title)}</h1>\n{body}</body>\n</html>\n"
    )

"""The fleet's page: one self-contained HTML file (no script, no file beside it), one row
per robot with its latest figures, their 95 % intervals and a small plot of each over
time (inline SVG: every calibration with its interval, and the course the change model
found), the flags, and what to apply; the robots with no usable recording and why; the
fleet's summary line at the top.
"""

from __future__ import annotations

import datetime as dt
import math
from html import escape

from umbmark.calibration.changes import SECONDS_PER_WEEK
from umbmark.fleets.summary import FIGURE_UNITS, Z95, FigureTrack, FleetSummary, RobotSummary

__all__ = ["fleet_page"]

#: A trend plot's size [px].
PLOT_W, PLOT_H, PAD = 168, 56, 4

_CSS = """
body{font:14px/1.4 system-ui,sans-serif;margin:1.5em auto;max-width:1400px;padding:0 1em;
color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em}
.summary{font-size:1.05em;padding:.6em .8em;background:#f4f4f4;border-radius:4px}
.wrap{overflow-x:auto}
table{border-collapse:collapse;width:100%}
th,td{border-bottom:1px solid #ddd;padding:.35em .5em;vertical-align:top;text-align:left}
th{background:#fafafa;position:sticky;top:0}
td.num{font-variant-numeric:tabular-nums;white-space:nowrap}
tr.changed td:first-child{border-left:4px solid #c0392b}
.flag{color:#c0392b;font-weight:600}
.ok{color:#27ae60}
.note{color:#555;font-size:.9em}
pre{white-space:pre-wrap;overflow-wrap:anywhere;font-size:.85em;margin:.3em 0}
svg{display:block}
code{font-size:.92em}
@media print{body{max-width:none}th{position:static}}
"""


def _plot(track: FigureTrack) -> str:
    """A small SVG of the figure over time: each calibration with its 95 % interval, and
    the course found (steady, a step, a trend)."""
    t = track.times
    lows = [v - Z95 * e for v, e in zip(track.values, track.errors, strict=True)]
    highs = [v + Z95 * e for v, e in zip(track.values, track.errors, strict=True)]
    lo, hi = min(lows), max(highs)
    span_v = hi - lo if hi > lo else 1.0
    t0, t1 = t[0], t[-1]
    span_t = t1 - t0 if t1 > t0 else 1.0

    def x(time: float) -> float:
        return PAD + (PLOT_W - 2 * PAD) * (time - t0) / span_t

    def y(value: float) -> float:
        return PLOT_H - PAD - (PLOT_H - 2 * PAD) * (value - lo) / span_v

    parts = []
    for time, low, high, value in zip(t, lows, highs, track.values, strict=True):
        parts.append(
            f'<path d="M{x(time):.1f} {y(low):.1f}V{y(high):.1f}" stroke="#999"/>'
            f'<circle cx="{x(time):.1f}" cy="{y(value):.1f}" r="1.6" fill="#333"/>'
        )
    change = track.change
    colour = "#27ae60" if change.kind == "steady" else "#c0392b"
    if change.kind == "step" and change.since is not None:
        k = change.since
        before = change.value - change.size
        parts.append(
            f'<path d="M{x(t0):.1f} {y(before):.1f}H{x(t[k - 1]):.1f}M{x(t[k]):.1f} '
            f'{y(change.value):.1f}H{x(t1):.1f}" stroke="{colour}" stroke-width="1.5" '
            'fill="none"/>'
        )
    elif change.kind == "trend":
        first = change.value - change.size * (t1 - t0) / SECONDS_PER_WEEK
        parts.append(
            f'<path d="M{x(t0):.1f} {y(first):.1f}L{x(t1):.1f} {y(change.value):.1f}" '
            f'stroke="{colour}" stroke-width="1.5" fill="none"/>'
        )
    else:
        parts.append(
            f'<path d="M{x(t0):.1f} {y(change.value):.1f}H{x(t1):.1f}" stroke="{colour}" '
            'stroke-width="1.5" fill="none"/>'
        )
    label = escape(f"{track.name} over {len(t)} calibrations: {change.kind}")
    return (
        f'<svg width="{PLOT_W}" height="{PLOT_H}" viewBox="0 0 {PLOT_W} {PLOT_H}" '
        f'role="img" aria-label="{label}"><title>{label}</title>{"".join(parts)}</svg>'
    )


def _apply(robot: RobotSummary) -> str:
    """What to put into the robot's controller and to declare of its laser, from its
    present state: the overlay and the mounting, or why none is offered."""
    apply = robot.apply
    if apply is None:
        return _mounting(robot)
    if not apply.offered:
        why = escape("; ".join(apply.reasons))
        said = f'<span class="flag">not offered: do not apply ({why})</span>'
        return said + _mounting(robot)
    said = f"<pre>{escape(str(apply.overlay).strip())}</pre>"
    if apply.verdict == "care":
        said += (
            '<span class="note">apply with care: ' + escape("; ".join(apply.reasons)) + "</span>"
        )
    return said + _mounting(robot)


def _mounting(robot: RobotSummary) -> str:
    """The laser's mounting to declare (the fleet's estimate of it), whatever the verdict
    on the wheels."""
    forms = robot.mounting
    if forms is None:
        return ""
    return (
        f'<span class="note">laser: {escape(forms.verdict())}</span>'
        f"<pre>{escape(forms.urdf_origin())}\n{escape(forms.ros2_command())}</pre>"
    )


def _row(robot: RobotSummary, figures: list[str]) -> str:
    cells = [
        f"<td><b>{escape(robot.robot)}</b><br>{robot.recordings} recordings, "
        f"{robot.hours:.1f} h</td>"
    ]
    for name in figures:
        track = robot.tracks.get(name)
        if track is None:
            cells.append("<td>-</td>")
            continue
        cells.append(f'<td class="num">{escape(track.shown())}{_plot(track)}</td>')
    flags = robot.flags
    said = (
        "<br>".join(f'<span class="flag">{escape(f)}</span>' for f in flags)
        if flags
        else '<span class="ok">within its intervals</span>'
    )
    said += "".join(f'<br><span class="note">{escape(n)}</span>' for n in robot.notes)
    e_max = "-" if robot.e_max_syst is None else f"{robot.e_max_syst * 1000:.1f} mm"
    cells.append(f"<td>{said}</td><td class='num'>{e_max}</td><td>{_apply(robot)}</td>")
    cls = ' class="changed"' if flags else ""
    return f"<tr{cls}>{''.join(cells)}</tr>"


def fleet_page(summary: FleetSummary, *, title: str = "umbmark fleet", made: str = "") -> str:
    """The fleet's page as HTML text.

    Parameters
    ----------
    summary : FleetSummary
    title : str
        The page's title.
    made : str
        The command that made it, or how (shown under the title).
    """
    usable = [r for r in summary.robots if r.usable]
    figures = [name for name in FIGURE_UNITS if any(name in r.tracks for r in usable)]
    head = "".join(f"<th>{escape(FIGURE_UNITS[name][0])}</th>" for name in figures)
    rows = "".join(_row(r, figures) for r in usable)
    unusable = [r for r in summary.robots if not r.usable]
    left = "".join(
        f"<li><b>{escape(r.robot)}</b>: "
        + "; ".join(
            escape(reason if path in reason else f"{path}: {reason}")
            for path, reason in r.left_out[:5]
        )
        + (f" (and {len(r.left_out) - 5} more)" if len(r.left_out) > 5 else "")
        + "</li>"
        for r in unusable
    )
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    hours = math.fsum(r.hours for r in summary.robots)
    return (
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        "<meta name='viewport' content='width=device-width, initial-scale=1'>"
        f"<title>{escape(title)}</title><style>{_CSS}</style></head><body>"
        f"<h1>{escape(title)}</h1>"
        f"<p>{escape(made or 'made from Python')}; {stamp}; {hours:.1f} h of recordings.</p>"
        f"<p class='summary'>{escape(summary.line())}.</p>"
        "<h2>Robots</h2><div class='wrap'><table><thead><tr><th>robot</th>"
        f"{head}<th>changes</th><th>E_max,syst on 4 m</th><th>to apply</th></tr></thead>"
        f"<tbody>{rows}</tbody></table></div>"
        + (f"<h2>No usable recording</h2><ul>{left}</ul>" if unusable else "")
        + "<p>Each value is the robot's present state with its 95 % interval: the mean of a "
        "steady robot's calibrations, the value since a step, a trend's line now, or the "
        "latest recording alone where it disagrees with the course before it (a change to be "
        "confirmed by the next); a flag is a change beyond five of its own standard errors, "
        "scaled by the scatter of the calibrations.</p></body></html>"
    )

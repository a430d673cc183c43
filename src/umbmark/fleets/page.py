"""The fleet's page: one self-contained HTML file (nothing loaded from elsewhere, no file
beside it), the fleet's summary line at the top, then one compact row per robot: its name
and recordings, its flags, its E_max,syst, what to apply (the multipliers in a line, the
controller's overlay and the laser's mounting folded, each with a copy button), and a
small plot of each figure over time (inline SVG: every calibration with its interval, the
course the change model found, the first and last day on its time axis, the change's day
marked); then the recordings that failed and the robots with no usable recording.

The page reads the same without its one small inline script: the copy buttons are hidden
until it runs, and a click on a folded block selects it whole (CSS ``user-select``).
"""

from __future__ import annotations

import datetime as dt
import math
import os
from collections.abc import Callable
from html import escape

from umbmark.calibration.changes import SECONDS_PER_WEEK
from umbmark.fleets.summary import (
    FIGURE_UNITS,
    Z95,
    FigureTrack,
    FleetSummary,
    RobotSummary,
    _day,
)

__all__ = ["FAILED_SHOWN", "PLOT_H", "PLOT_W", "fleet_page"]

#: A trend plot's size [px]: two side by side fit a phone's 390 px, eight a desk's 1280 px.
PLOT_W, PLOT_H = 140, 70
#: The plot's inner box [px]: left and right margins, the top band (the change's day),
#: the data's bottom, the time axis and its labels' baseline.
_X0, _X1, _TOP, _BOTTOM, _AXIS, _LABEL = 6, PLOT_W - 6, 13, 50, 54, 66
#: A time [s] or value to a plot's pixels.
Scale = Callable[[float], float]
#: Failed recordings listed at most (the JSON holds them all).
FAILED_SHOWN = 200
#: Reasons shown at most for a robot with no usable recording.
REASONS_SHOWN = 5

_CSS = """
body{font:14px/1.4 system-ui,sans-serif;margin:1em auto;max-width:1400px;padding:0 1em;
color:#222}
h1{font-size:1.4em;margin:.4em 0}h2{font-size:1.15em;margin:1.4em 0 .4em}
.summary{font-size:1.05em;padding:.6em .8em;background:#f4f4f4;border-radius:4px;margin:.4em 0}
.jump a{margin-right:1em}
.line{display:grid;grid-template-columns:minmax(8em,13em) minmax(0,1fr) 10.5em minmax(0,26em);
gap:.2em 1em;align-items:start}
.line>*{min-width:0;overflow-wrap:anywhere}
.head{font-weight:600;background:#fafafa;padding:.3em .6em .3em calc(.6em + 4px);
border-bottom:1px solid #ddd}
.robot{border-bottom:1px solid #ddd;border-left:4px solid transparent;padding:.45em .6em}
.robot.changed{border-left-color:#c0392b}
.name{font-weight:700;font-size:1.05em}
.k{display:none;color:#555;font-size:.85em}
.flags{margin:0;padding:0;list-style:none}
.flag{color:#c0392b;font-weight:600}
.ok{color:#27ae60}
.note{color:#555;font-size:.9em}
.num{font-variant-numeric:tabular-nums}
.figs{display:flex;flex-wrap:wrap;align-items:flex-end;gap:.3em .9em;margin-top:.35em}
figure{margin:0;width:min-content}
figcaption{width:0;min-width:100%;font-size:12px;line-height:1.3;white-space:nowrap;overflow:hidden;
text-overflow:ellipsis}
figcaption b{font-weight:600;font-variant-numeric:tabular-nums;white-space:normal}
svg{display:block}
svg text{font-size:10px;fill:#555}
details{margin:.15em 0}
summary{cursor:pointer}
pre{white-space:pre-wrap;overflow-wrap:anywhere;font-size:.8em;margin:.3em 0;padding:.4em;
background:#f6f6f6;border-radius:3px;user-select:all;-webkit-user-select:all}
button.copy{font:inherit;font-size:.85em;padding:0 .6em}
code{font-size:.92em}
ul.list{padding-left:1.2em}
@media (max-width:760px){
body{padding:0 .5em}
.robot{padding:.4em .35em}
.figs{display:grid;grid-template-columns:repeat(2,minmax(0,1fr));gap:.2em .6em}
figure{width:auto}
.line{grid-template-columns:minmax(0,1fr) auto}
.line>.flags,.line>.apply{grid-column:1/-1}
.head{display:none}
.k{display:block}
.emax{text-align:right;grid-row:1;grid-column:2}
}
@media print{body{max-width:none}details{break-inside:avoid}}
"""

#: The copy buttons (hidden without it): the block's text to the clipboard, else selected.
_SCRIPT = """
for (const b of document.querySelectorAll('button.copy')) {
  b.hidden = false;
  b.addEventListener('click', () => {
    const pre = document.getElementById(b.dataset.for);
    const said = t => { b.textContent = t; setTimeout(() => { b.textContent = 'copy'; }, 2000); };
    const select = () => {
      const range = document.createRange(); range.selectNodeContents(pre);
      const s = getSelection(); s.removeAllRanges(); s.addRange(range);
      said(document.execCommand('copy') ? 'copied' : 'selected: copy it');
    };
    if (navigator.clipboard) {
      navigator.clipboard.writeText(pre.textContent).then(() => said('copied'), select);
    } else {
      select();
    }
  });
}
"""


def _scale(track: FigureTrack) -> tuple[float, float]:
    """The values a plot spans: every calibration's 95 % interval and the course."""
    lows = [v - Z95 * e for v, e in zip(track.values, track.errors, strict=True)]
    highs = [v + Z95 * e for v, e in zip(track.values, track.errors, strict=True)]
    change = track.change
    course = [change.value, change.value - change.size]
    if change.kind == "trend":
        course[1] = (
            change.value - change.size * (track.times[-1] - track.times[0]) / SECONDS_PER_WEEK
        )
    lo, hi = min(*lows, *course), max(*highs, *course)
    return lo, hi if hi > lo else lo + 1.0


def _plot(track: FigureTrack) -> str:
    """A small SVG of the figure over time: each calibration with its 95 % interval, the
    course found (steady, a step, a trend), the time axis with its first and last day,
    and the day of the change (``track.change.since``, any kind) marked."""
    t = track.times
    lo, hi = _scale(track)
    t0, t1 = t[0], t[-1]
    span_t = t1 - t0 if t1 > t0 else 1.0

    def x(time: float) -> float:
        return (_X0 + _X1) / 2 if t1 <= t0 else _X0 + (_X1 - _X0) * (time - t0) / span_t

    def y(value: float) -> float:
        return _BOTTOM - (_BOTTOM - _TOP) * (value - lo) / (hi - lo)

    parts = [
        f'<path d="M{_X0} {_AXIS}H{_X1}M{x(t0):.1f} {_AXIS}v3M{x(t1):.1f} {_AXIS}v3" '
        'stroke="#888" fill="none"/>'
    ]
    first, last = _day(t0).isoformat(), _day(t1).isoformat()
    if first == last:
        parts.append(f'<text x="{PLOT_W / 2:.1f}" y="{_LABEL}" text-anchor="middle">{first}</text>')
    else:
        parts.append(
            f'<text x="0" y="{_LABEL}">{first}</text>'
            f'<text x="{PLOT_W}" y="{_LABEL}" text-anchor="end">{last}</text>'
        )
    change = track.change
    colour = "#27ae60" if change.kind == "steady" else "#c0392b"
    since = change.since if change.kind != "steady" else None
    if since is not None and 0 <= since < len(t):
        at = x(t[since])
        anchor = "start" if at < PLOT_W / 4 else "end" if at > 3 * PLOT_W / 4 else "middle"
        parts.append(
            f'<path class="since" d="M{at:.1f} {_TOP - 2}V{_AXIS}" stroke="{colour}" '
            'stroke-dasharray="3 2" fill="none"/>'
            f'<text class="since" x="{at:.1f}" y="10" text-anchor="{anchor}" '
            f'style="fill:{colour}">{_day(t[since]).isoformat()}</text>'
        )
    for time, value, error in zip(t, track.values, track.errors, strict=True):
        parts.append(
            f'<path d="M{x(time):.1f} {y(value - Z95 * error):.1f}V{y(value + Z95 * error):.1f}" '
            f'stroke="#999"/><circle cx="{x(time):.1f}" cy="{y(value):.1f}" r="1.6" fill="#333"/>'
        )
    parts.append(_course(track, x, y, colour))
    label = f"{track.name} over {len(t)} calibrations, {first} to {last}: {change.kind}"
    if since is not None:
        label += f" since {_day(t[since]).isoformat()}"
    return (
        f'<svg width="{PLOT_W}" height="{PLOT_H}" viewBox="0 0 {PLOT_W} {PLOT_H}" '
        f'role="img" aria-label="{escape(label)}"><title>{escape(label)}</title>'
        f"{''.join(parts)}</svg>"
    )


def _course(track: FigureTrack, x: Scale, y: Scale, colour: str) -> str:
    """The course the change model found, as a path: a level, a line, or a level before
    the change and another from it on (``x``, ``y``: time and value to pixels)."""
    t, change = track.times, track.change
    t0, t1 = t[0], t[-1]
    style = f'stroke="{colour}" stroke-width="1.5" fill="none"'
    if change.kind == "trend":
        first = change.value - change.size * (t1 - t0) / SECONDS_PER_WEEK
        return f'<path d="M{x(t0):.1f} {y(first):.1f}L{x(t1):.1f} {y(change.value):.1f}" {style}/>'
    k = change.since
    if change.kind == "steady" or k is None or not 0 < k < len(t):
        return f'<path d="M{x(t0):.1f} {y(change.value):.1f}H{x(t1):.1f}" {style}/>'
    before = change.value - change.size
    after = f"H{x(t1):.1f}" if k < len(t) - 1 else "h2"  # the latest alone: a short mark
    return (
        f'<path d="M{x(t0):.1f} {y(before):.1f}H{x(t[k - 1]):.1f}M{x(t[k]):.1f} '
        f'{y(change.value):.1f}{after}" {style}/>'
    )


def _copyable(text: str, key: str) -> str:
    """A block to copy: selected whole by a click, and a copy button where scripts run."""
    return (
        f'<pre id="{key}">{escape(text)}</pre>'
        f'<button type="button" class="copy" data-for="{key}" hidden>copy</button>'
    )


def _apply(robot: RobotSummary, key: str) -> str:
    """What to put into the robot's controller and to declare of its laser, from its
    present state: the verdict and the multipliers, the overlay folded; or why none is
    offered."""
    apply = robot.apply
    if apply is None:
        return '<span class="note">nothing to apply</span>' + _mounting(robot, key)
    reasons = "; ".join(apply.reasons)
    if not apply.offered:
        said = escape(reasons or "its checks failed")
        return f'<span class="flag">not offered: do not apply ({said})</span>' + _mounting(
            robot, key
        )
    sep, left, right = apply.multipliers
    head = (
        '<span class="ok">apply</span>'
        if apply.verdict != "care"
        else '<span class="flag">apply with care</span> '
        f'<span class="note">({escape(reasons)})</span>'
    )
    said = (
        f'{head}: <span class="num">separation {sep:.6f}, left radius {left:.6f}, right '
        f"radius {right:.6f}</span>"
    )  # what they rest on heads the overlay, folded
    said += (
        "<details><summary>the overlay for the controller (YAML)</summary>"
        f"{_copyable(str(apply.overlay).strip(), f'{key}-overlay')}</details>"
    )
    return said + _mounting(robot, key)


def _mounting(robot: RobotSummary, key: str) -> str:
    """The laser's mounting to declare (the fleet's estimate of it), whatever the verdict
    on the wheels, folded under what to do with it."""
    forms = robot.mounting
    if forms is None:
        return ""
    outside = forms.outside()
    if outside is None:
        short = '<span class="note">laser: no stated mounting to compare</span>'
    elif any(outside):
        short = '<span class="flag">laser: correct the stated mounting</span>'
    else:
        short = '<span class="ok">laser: as stated</span>'
    forms_text = "\n".join([f"{forms.urdf_origin()}", forms.ros2_command(), forms.ros1_command()])
    return (
        f"<details><summary>{short}</summary>"
        f'<span class="note">{escape(forms.verdict())}; {escape(forms.lift_note())}.</span>'
        f"{_copyable(forms_text, f'{key}-laser')}</details>"
    )


def _figure(track: FigureTrack) -> str:
    label = FIGURE_UNITS[track.name][0]
    return (
        f"<figure><figcaption>{escape(label)}<br><b>{escape(track.shown())}</b></figcaption>"
        f"{_plot(track)}</figure>"
    )


def _root(summary: FleetSummary) -> str:
    """The folder (or URL) every recording of the page lies below, with its ``/``: the
    page names recordings below it; empty where they share none, or there is one."""
    paths = [
        p
        for r in summary.robots
        for p in {*(x for t in r.tracks.values() for x in t.paths), *(x for x, _ in r.left_out)}
    ]
    if len(paths) < 2:
        return ""
    common = os.path.commonprefix(paths)  # noqa: RUF071 (by character: URLs too, cut at a "/")
    root = common[: common.rfind("/") + 1]
    return root if root.strip("/") and not root.endswith("://") else ""


def _short(text: str, root: str) -> str:
    """``text`` with every recording named below ``root``."""
    return text.replace(root, "") if root else text


def _row(robot: RobotSummary, figures: list[str], key: str, root: str = "") -> str:
    calibrated = robot.recordings - len(robot.left_out)
    counts = f"{robot.recordings} recording{'' if robot.recordings == 1 else 's'}"
    parts = [f"{len(robot.failed)} failed"] if robot.failed else []
    if len(robot.left_out) > len(robot.failed):
        parts.append(f"{len(robot.left_out) - len(robot.failed)} left out")
    if parts:
        counts += f" ({calibrated} calibrated, {', '.join(parts)})"
    latest = robot.latest
    when = "" if latest is None or latest.start is None else f"<br>latest {_day(latest.start)}"
    who = (
        f'<div class="who"><span class="name">{escape(robot.robot)}</span><br>'
        f'<span class="note">{counts}, {robot.hours:.1f} h{when}</span></div>'
    )
    flags = robot.flags
    said = "".join(f'<li class="flag">{escape(_short(f, root))}</li>' for f in flags) or (
        '<li class="ok">within its intervals</li>'
    )
    said += "".join(f'<li class="note">{escape(_short(n, root))}</li>' for n in robot.notes)
    e_max = "-" if robot.e_max_syst is None else f"{robot.e_max_syst * 1000:.1f} mm"
    cells = (
        f'{who}<ul class="flags">{said}</ul>'
        f'<div class="emax"><span class="k">E_max,syst on 4 m</span>'
        f'<b class="num">{e_max}</b></div>'
        f'<div class="apply">{_apply(robot, key)}</div>'
    )
    plots = "".join(_figure(robot.tracks[n]) for n in figures if n in robot.tracks)
    cls = "robot changed" if flags else "robot"
    return (
        f'<section class="{cls}" id="{key}"><div class="line">{cells}</div>'
        f'<div class="figs">{plots}</div></section>'
    )


def _failed(summary: FleetSummary) -> str:
    """The recordings that could not be read, each with its reason."""
    failed = [(r.robot, path, why) for r in summary.robots for path, why in r.failed]
    if not failed:
        return ""
    items = "".join(
        f"<li><b>{escape(robot)}</b>: {escape(why if path in why else f'{path}: {why}')}</li>"
        for robot, path, why in failed[:FAILED_SHOWN]
    )
    more = len(failed) - FAILED_SHOWN
    if more > 0:
        items += f"<li>and {more} more (all in the fleet's JSON: -o, --json)</li>"
    return (
        f'<h2 id="failed">Failed recordings ({len(failed)})</h2>'
        f'<p class="note">Recordings that could not be read; each is tried again on the '
        f'next run.</p><ul class="list">{items}</ul>'
    )


def _unusable(summary: FleetSummary) -> str:
    """The robots with no recording that gave a calibration, and why."""
    unusable = [r for r in summary.robots if not r.usable]
    if not unusable:
        return ""
    items = []
    for r in unusable:
        failed = {path for path, _ in r.failed}
        reasons = [
            escape(why if path in why else f"{path}: {why}")
            for path, why in r.left_out
            if path not in failed
        ]
        said = "; ".join(reasons[:REASONS_SHOWN])
        if len(reasons) > REASONS_SHOWN:
            said += f" (and {len(reasons) - REASONS_SHOWN} more)"
        if failed:
            said += ("; " if said else "") + f"{len(failed)} failed (listed above)"
        items.append(f"<li><b>{escape(r.robot)}</b>: {said}</li>")
    n = len(unusable)
    return (
        f'<h2 id="unusable">No usable recording ({n} robot{"" if n == 1 else "s"})</h2>'
        f'<ul class="list">{"".join(items)}</ul>'
    )


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
    root = _root(summary)
    rows = "".join(_row(r, figures, f"r{k}", root) for k, r in enumerate(usable))
    failed, unusable = _failed(summary), _unusable(summary)
    jump = (
        "".join(
            f'<a href="#{key}">{said}</a>'
            for key, said, shown in (
                ("robots", "the robots", True),
                ("failed", "the failed recordings", bool(failed)),
                ("unusable", "the robots with no usable recording", bool(unusable)),
            )
            if shown
        )
        if failed or unusable
        else ""
    )
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    hours = math.fsum(r.hours for r in summary.robots)
    head = (
        '<div class="line head"><div>robot</div><div>changes</div>'
        "<div>E_max,syst on 4 m</div><div>to apply</div></div>"
    )
    return (
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        "<meta name='viewport' content='width=device-width, initial-scale=1'>"
        f"<title>{escape(title)}</title><style>{_CSS}</style></head><body>"
        f"<h1>{escape(title)}</h1>"
        f'<p class="note">{escape(made or "made from Python")}; {stamp}; {hours:.1f} h of '
        "recordings.</p>"
        f"<p class='summary'>{escape(summary.line())}.</p>"
        + (f'<p class="note">Recordings are named below {escape(root)}</p>' if root else "")
        + f'<p class="jump note">{jump}</p>'
        f'<h2 id="robots">Robots</h2>{head}{rows}'
        f"{failed}{unusable}"
        "<p class='note'>Each value is the robot's present state with its 95 % interval: "
        "the mean of a steady robot's calibrations, the value since a step, a trend's line "
        "now, or the latest recording alone where it disagrees with the course before it (a "
        "change to be confirmed by the next); a flag is a change beyond five of its own "
        "standard errors, scaled by the scatter of the calibrations. Each plot "
        "runs from the robot's first calibration to its latest (the days under it, UTC), "
        "every calibration with its 95 % interval, the course in green when steady and red "
        "when it changed, the change's day marked by a dashed line. E_max,syst is what the "
        "present errors make on the paper's 4 m square driven by the odometry as configured "
        "in the latest recording, and what to apply comes from the same present state.</p>"
        f"<script>{_SCRIPT}</script></body></html>"
    )

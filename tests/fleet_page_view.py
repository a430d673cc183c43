"""The fleet's page (``umbmark fleet --report``) as a person sees it in headless Chromium
(``test_report_command.Chromium``), at a desk's 1280 x 900 and a phone's 390 x 844: each
robot's row scrolled into view, where its name, flags, E_max,syst and what to apply lie
and what the screenshot shows there, its height, and what each plot's time axis says."""

from __future__ import annotations

import base64
import io
from pathlib import Path
from typing import Any

import numpy as np

#: (width, height, mobile) of the views [px].
VIEWS = ((1280, 900, False), (390, 844, True))
#: The tallest a robot's row may be, folded [px]: three robots on a desk's screen, one on a
#: phone's (844 px) whole, its eight plots (the wheels', the laser's, the gyro's) two a line.
ROW_MAX = {1280: 300, 390: 780}
#: The cells every robot's row shows, by their class.
CELLS = ("name", "flags", "emax", "apply")

_ROW = """
(() => {
  const s = document.querySelectorAll('section.robot')[%d];
  s.scrollIntoView({block: 'start'});
  const box = e => {
    const b = e.getBoundingClientRect(); return [b.left, b.top, b.right, b.bottom];
  };
  const cells = {};
  for (const k of %s) cells[k] = box(s.querySelector('.' + k));
  const plots = [...s.querySelectorAll('figure')].map(f => {
    const svg = f.querySelector('svg');
    return {caption: f.querySelector('figcaption').textContent, box: box(svg),
            days: [...svg.querySelectorAll('text:not(.since)')].map(t => t.textContent),
            since: [...svg.querySelectorAll('text.since')].map(t => t.textContent),
            since_x: [...svg.querySelectorAll('path.since')].map(p => p.getBBox().x),
            points_x: [...svg.querySelectorAll('circle')].map(c => c.cx.baseVal.value)};
  });
  return {robot: s.querySelector('.name').textContent, box: box(s), cells: cells,
          flags: [...s.querySelectorAll('.flags .flag')].map(f => f.textContent),
          apply: s.querySelector('.apply').innerText, plots: plots};
})()
"""
_OVERFLOW = "document.documentElement.scrollWidth - document.documentElement.clientWidth"


def screenshot(browser: Any) -> np.ndarray:
    """The viewport as an array (rows, columns, RGB or RGBA; 0 to 1)."""
    from matplotlib.image import imread

    png = base64.b64decode(browser.call("Page.captureScreenshot", format="png")["data"])
    pixels: np.ndarray = imread(io.BytesIO(png), format="png")
    return pixels


def inside(box: list[float], width: float, height: float) -> bool:
    """Whether ``box`` (left, top, right, bottom [px]) is drawn wholly inside a viewport of
    ``width`` x ``height`` (half a pixel of rounding allowed)."""
    left, top, right, bottom = box
    return -0.5 <= left < right <= width + 0.5 and -0.5 <= top < bottom <= height + 0.5


def _crop(shot: np.ndarray, box: list[float]) -> np.ndarray:
    left, top, right, bottom = (round(v) for v in box)
    return shot[max(top, 0) : max(bottom, 0), max(left, 0) : max(right, 0), :3]


def _inked(shot: np.ndarray, box: list[float]) -> int:
    """Pixels darker than half grey inside ``box`` (text drawn there)."""
    return int(np.sum(_crop(shot, box).mean(axis=-1) < 0.5))


def _red(shot: np.ndarray, box: list[float]) -> int:
    """Red pixels inside ``box`` (a flag's and a change mark's #c0392b, or it blended
    into the white by anti-aliasing; not the green of a steady course, nor grey)."""
    rgb = _crop(shot, box)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return int(np.sum((r > g + 0.2) & (r > b + 0.2)))


def rows_as_seen(browser: Any, page: Path) -> dict[int, list[dict[str, Any]]]:
    """Each robot's row as each view shows it, checked for what every row must show: the
    page never scrolls sideways; scrolled into view, the whole row lies inside the viewport
    and is at most :data:`ROW_MAX` tall; its name, flags, E_max,syst and what to apply are
    drawn inside it (text pixels in each box of the screenshot, a flag's in red); every plot
    lies inside the viewport, and a change's mark is drawn in red where it stands."""
    seen: dict[int, list[dict[str, Any]]] = {}
    for width, height, mobile in VIEWS:
        browser.open(page, width, height, mobile=mobile)
        assert browser.errors() == []
        assert browser.evaluate(_OVERFLOW) <= 0, width
        rows = []
        n = browser.evaluate("document.querySelectorAll('section.robot').length")
        for k in range(n):
            row = browser.evaluate(_ROW % (k, list(CELLS)))
            shot = screenshot(browser)
            where = f"{row['robot']} at {width} px"
            _, top, _, bottom = row["box"]
            assert bottom - top <= ROW_MAX[width], (where, bottom - top)
            assert inside(row["box"], width, height), (where, row["box"])
            for cell in CELLS:
                assert inside(row["cells"][cell], width, height), (where, cell)
                assert _inked(shot, row["cells"][cell]) > 20, (where, cell)
            if row["flags"]:
                assert _red(shot, row["cells"]["flags"]) > 50, where
            for plot in row["plots"]:
                assert inside(plot["box"], width, height), (where, plot)
                x0, y0, _, y1 = plot["box"]
                for x in plot["since_x"]:
                    column = [x0 + x - 1.5, y0, x0 + x + 1.5, y1]
                    assert _red(shot, column) >= 6, (where, plot["caption"])
            rows.append(row)
        seen[width] = rows
    return seen


def plot_of(row: dict[str, Any], label: str) -> dict[str, Any]:
    """The plot of ``row`` whose caption starts with ``label`` (``E_d = D_R / D_L``)."""
    (plot,) = [p for p in row["plots"] if p["caption"].startswith(label)]
    return plot

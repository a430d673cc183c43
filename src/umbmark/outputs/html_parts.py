"""The parts every HTML page of umbmark is built from: the style sheet that reads on a
phone and prints (:data:`CSS`), a number or a dash (:func:`num`), a sentence's capital
(:func:`sentence`), and a table whose cells are escaped (:func:`table`). The page of
UMBmark passes (:mod:`umbmark.outputs.html_report`) and the page of the self-calibration
anywhere (:mod:`umbmark.outputs.anywhere_page`) share them."""

from __future__ import annotations

import math
from collections.abc import Collection
from html import escape

__all__ = ["CSS", "document", "num", "sentence", "table"]

CSS = """
:root { color-scheme: light; }
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; line-height: 1.45;
  margin: 0 auto; padding: 1rem; max-width: 60rem; color: #111; background: #fff; }
h1 { font-size: 1.5rem; }
h1, h3, p, li, figcaption { overflow-wrap: anywhere; } h2 { font-size: 1.2rem; margin-top: 2rem;
  border-bottom: 1px solid #ccc; }
.verdict { padding: .75rem 1rem; border-left: .4rem solid #c60; background: #fff6ec; }
.verdict.ok { border-color: #2a7; background: #eefaf3; }
.big { font-size: 1.4rem; font-weight: bold; }
.scroll { overflow-x: auto; }
table { border-collapse: collapse; margin: .5rem 0; }
th, td { padding: .2rem .6rem; border-bottom: 1px solid #ddd; text-align: right;
  white-space: nowrap; }
th { white-space: normal; vertical-align: bottom; }
.wrap { white-space: normal; overflow-wrap: anywhere; min-width: 6rem; text-align: left; }
th:first-child, td:first-child { text-align: left; }
pre { background: #f4f4f4; padding: .75rem; overflow-x: auto; font-size: .85rem; }
figure { margin: 0; } figure svg { max-width: 100%; height: auto; }
code { word-break: break-all; }
.predicted { color: #555; font-style: italic; }
@media print {
  body { max-width: none; padding: 0; font-size: 10pt; }
  .scroll, pre { overflow: visible; } pre { white-space: pre-wrap; }
  h2 { break-after: avoid; } figure, table { break-inside: avoid; }
}
"""


def num(value: float | None, fmt: str) -> str:
    """``value`` formatted, or a dash for None and non-finite values."""
    if value is None or not math.isfinite(value):
        return "–"
    return format(value, fmt)


def sentence(text: str) -> str:
    """``text`` with its first letter upper case, the rest as it is (URDF, E_d)."""
    return text[:1].upper() + text[1:]


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


def document(title: str, sections: list[tuple[str, str, str]], css: str) -> str:
    """A whole page: ``title``, then each section ``(id, heading, HTML content)`` under its
    heading, with the style sheet ``css`` inline (no file beside it)."""
    body = "".join(
        f'<section id="{key}">\n<h2>{escape(name)}</h2>\n{content}</section>\n'
        for key, name, content in sections
    )
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{escape(title)}</title>\n<style>{css}</style>\n</head>\n<body>\n"
        f"<h1>{escape(title)}</h1>\n{body}</body>\n</html>\n"
    )

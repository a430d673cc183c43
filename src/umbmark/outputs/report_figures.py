"""The figures of the HTML report, and turning a figure into inline SVG.

:func:`passes_figure` draws the Fig. 6 view of several UMBmark passes on one robot in one
axes (before, after, further passes; each pass its own colour, cw and ccw their own
marker), or of a single pass (cw and ccw each in its own colour and marker, as in
:func:`umbmark.outputs.plotting.cluster_figure`), and optionally the *predicted* after of
a single pass (its recorded wheel data replayed with the new parameters) in a style of
its own. Axes in millimetres.
:func:`inline_svg` returns a figure as an ``<svg>`` element that refers to nothing
outside itself (text drawn as paths, no metadata links).
"""

from __future__ import annotations

import io
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from umbmark.outputs.plotting import cluster_extent, draw_clusters, frame_clusters
from umbmark.returns.clusters import Benchmark

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "PASS_COLOURS",
    "PREDICTED_COLOUR",
    "SINGLE_COLOUR",
    "ZOOM_RATIO",
    "ClusterSet",
    "inline_svg",
    "passes_figure",
]

#: Colour of each pass in order (pass 1, 2, ...), repeated beyond.
PASS_COLOURS = ("#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#8c564b", "#e377c2")
#: Colour of the predicted after (replayed wheel data).
PREDICTED_COLOUR = "#7f7f7f"
#: Colour of the E_max,syst circle of a single pass (its clusters take the directions').
SINGLE_COLOUR = "#404040"


@dataclass(frozen=True)
class ClusterSet:
    """One set of return errors to draw: a pass, or a prediction.

    Attributes
    ----------
    benchmark : Benchmark
        Its cw and ccw clusters (return errors [m], shape (n, 2) each).
    name : str
        Its name in the legend (``"pass 1 (before)"``); empty: the legend says only
        ``cw runs``, ``ccw runs``.
    colour : str
        A matplotlib colour.
    predicted : bool
        A prediction, not a measured pass: drawn with dashed outlines, no fill.
    by_direction : bool
        The runs of each direction in that direction's colour
        (:data:`umbmark.outputs.plotting.DIRECTION_COLOURS`), ``colour`` only for the
        E_max,syst circle: the one measured pass of a page.
    """

    benchmark: Benchmark
    name: str
    colour: str
    predicted: bool = False
    by_direction: bool = False


#: A second panel zooms on the later sets when they fit this many times over into the first.
ZOOM_RATIO = 4.0


def _extent(sets: Sequence[ClusterSet]) -> float:
    return cluster_extent([item.benchmark for item in sets])


def _axes(ax: Axes, sets: Sequence[ClusterSet], title: str) -> None:
    for item in sets:
        draw_clusters(
            ax,
            item.benchmark,
            name=item.name,
            colour=None if item.by_direction else item.colour,
            circle_colour=item.colour,
            predicted=item.predicted,
            page=True,
        )
    frame_clusters(ax, _extent(sets), title, page=True)


def passes_figure(sets: Sequence[ClusterSet], title: str = "") -> Figure:
    """The Fig. 6 view of every pass in one figure (millimetres).

    Each set's runs are drawn as open markers (cw circles, ccw squares) in its colour
    (or, ``by_direction``, in their direction's colour),
    its centres of gravity as crosses and its ``E_max,syst`` as a circle about the
    origin; a predicted set is drawn dashed. When the later sets are more than
    :data:`ZOOM_RATIO` times smaller than the first, a second panel shows them zoomed.

    Parameters
    ----------
    sets : sequence of ClusterSet
        The passes in the order driven, then any prediction.
    title : str
        The first panel's title.

    Raises
    ------
    ValueError
        Without a set to draw.
    """
    from matplotlib.figure import Figure

    if not sets:
        raise ValueError("no return errors to draw")
    later = sets[1:]
    zoom = bool(later) and _extent(later) * ZOOM_RATIO < _extent(sets)
    fig = Figure(figsize=(11.0, 6.0) if zoom else (7.0, 6.2), layout="constrained")
    axes = fig.subplots(1, 2 if zoom else 1, squeeze=False)[0]
    _axes(axes[0], sets, title)
    if zoom:
        _axes(axes[1], later, "zoomed on " + ", ".join(item.name for item in later))
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", fontsize="small", ncols=2)
    return fig


def inline_svg(fig: Figure, salt: str) -> str:
    """``fig`` as an inline ``<svg>`` element that needs nothing outside itself.

    Text is drawn as paths (no fonts), the metadata (which names matplotlib's web site)
    is left out, and ``salt`` makes the element ids of this figure differ from those of
    other figures on the same page. Namespace declarations are dropped: the HTML parser
    supplies them for inline SVG.
    """
    from matplotlib import rc_context

    buffer = io.StringIO()
    with rc_context({"svg.hashsalt": salt, "svg.fonttype": "path"}):
        fig.savefig(buffer, format="svg", bbox_inches="tight", metadata={"Date": None})
    text = buffer.getvalue()
    start = text.find("<svg")
    if start < 0:  # pragma: no cover - matplotlib always writes one
        raise ValueError("matplotlib wrote no <svg> element")
    svg = re.sub(r"\s*<metadata>.*?</metadata>", "", text[start:], flags=re.DOTALL)
    # Inside HTML the parser gives <svg> and xlink:href their namespaces; the declarations
    # are the only addresses left, and the page keeps none.
    end = svg.find(">")
    opening = re.sub(r'\s+xmlns(?::\w+)?="[^"]*"', "", svg[:end])
    return opening + svg[end:]

"""Figures, drawn with matplotlib's object-oriented API (no pyplot, no display needed).

:func:`cluster_figure` draws the view of the paper's Fig. 6 and Fig. 11: every run's
return error, cw and ccw marked differently, both centres of gravity and the
``E_max,syst`` circle. Axes are in millimetres, as in the paper's figures.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..benchmark import Benchmark
from ..conventions import Direction
from ..kinematics import WheelParams
from ..runs import Run
from .atomic import atomic_path

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ..sim.engine import Trace

__all__ = [
    "FIGURE_FORMATS",
    "cluster_figure",
    "draw_clusters",
    "replay_figure",
    "save_figure",
    "trajectory_figure",
]

#: File extensions a figure can be saved as.
FIGURE_FORMATS = (".png", ".svg", ".pdf")

_STYLE = {
    Direction.CW: {"marker": "o", "color": "#1f77b4", "label": "cw runs"},
    Direction.CCW: {"marker": "s", "color": "#d62728", "label": "ccw runs"},
}
_MM = 1000.0


def draw_clusters(ax: Axes, bench: Benchmark, title: str = "", tag: str = "") -> None:
    """Draw a benchmark's clusters onto ``ax`` (millimetres).

    ``tag`` is added to the legend entries, to tell two benchmarks apart on one axes.
    """
    from matplotlib.patches import Circle

    suffix = f" ({tag})" if tag else ""
    for cluster in bench.clusters:
        style = _STYLE[cluster.direction]
        mm = cluster.errors * _MM
        ax.scatter(
            mm[:, 0],
            mm[:, 1],
            marker=style["marker"],
            facecolors="none",
            edgecolors=style["color"],
            label=f"{style['label']}{suffix}",
            zorder=3,
        )
        cg = cluster.cg * _MM
        ax.plot(
            cg[0],
            cg[1],
            marker="+",
            markersize=16,
            markeredgewidth=2.5,
            color=style["color"],
            linestyle="none",
            label=f"c.g. {cluster.direction.value}{suffix}: r = {cluster.r_cg * _MM:.1f} mm",
            zorder=4,
        )
    radius = bench.e_max_syst * _MM
    ax.add_patch(
        Circle(
            (0.0, 0.0),
            radius,
            fill=False,
            linestyle="--",
            color="0.4",
            label=f"E_max,syst{suffix} = {radius:.1f} mm",
        )
    )
    ax.axhline(0.0, color="0.8", linewidth=0.8, zorder=1)
    ax.axvline(0.0, color="0.8", linewidth=0.8, zorder=1)
    ax.set_xlabel("return error x [mm]")
    ax.set_ylabel("return error y [mm]")
    ax.set_aspect("equal", adjustable="box")
    if title:
        ax.set_title(title)


def cluster_figure(
    benches: Sequence[tuple[Benchmark, str]], title: str = "UMBmark return errors"
) -> Figure:
    """The Fig. 6 view of one benchmark, or several side by side (Fig. 11: before, after).

    Parameters
    ----------
    benches : sequence of (Benchmark, str)
        Each benchmark with its panel title.
    title : str
        The figure's title.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4 * len(benches), 6.0), layout="constrained")
    axes = fig.subplots(1, len(benches), squeeze=False)[0]
    for ax, (bench, panel_title) in zip(axes, benches, strict=True):
        draw_clusters(ax, bench, panel_title)
        _fit_limits(ax, bench)
        ax.legend(loc="best", fontsize="small")
    fig.suptitle(title)
    return fig


def _fit_limits(ax: Axes, bench: Benchmark) -> None:
    points = np.vstack([c.errors for c in bench.clusters]) * _MM
    extent = max(float(np.abs(points).max()), bench.e_max_syst * _MM, 1.0) * 1.15
    ax.set_xlim(-extent, extent)
    ax.set_ylim(-extent, extent)


def trajectory_figure(
    paths: Sequence[tuple[Trace, str]], title: str = "", side_length: float | None = None
) -> Figure:
    """True paths of simulated runs (the view of Figs. 3-5), one panel each.

    Parameters
    ----------
    paths : sequence of (Trace, str)
        A one-run trace (see :class:`umbmark.sim.engine.Trace`) and its panel title.
    side_length : float, optional
        Draw the nominal square of this side [m] for comparison.
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5.2 * len(paths), 5.2), layout="constrained")
    axes = fig.subplots(1, len(paths), squeeze=False)[0]
    for ax, (trace, name) in zip(axes, paths, strict=True):
        true = trace.true_pose[0]
        odo = trace.odometry_pose[0]
        side = float(np.max(np.abs(odo[:, :2]))) if side_length is None else side_length
        sign = 1.0 if odo[-1, 2] > 0 else -1.0
        corners = np.array([[0, 0], [side, 0], [side, sign * side], [0, sign * side], [0, 0]])
        ax.plot(corners[:, 0], corners[:, 1], "--", color="0.6", label="nominal path")
        ax.plot(true[:, 0], true[:, 1], color="#d62728", label="true path")
        ax.plot(true[-1, 0], true[-1, 1], "o", color="#d62728", label="true end")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(
            f"{name}: ends {1000 * float(np.hypot(*(true[-1, :2] - odo[-1, :2]))):.0f} mm "
            "from where its odometry thinks"
        )
        ax.legend(loc="center", fontsize="small")
    if title:
        fig.suptitle(title)
    return fig


def replay_figure(
    runs: Sequence[Run], odometry: Mapping[str, WheelParams], title: str = ""
) -> Figure:
    """Every recorded run's true path against its odometry, one panel per run.

    Parameters
    ----------
    runs : sequence of Run
        Runs with their time series (``run.log``).
    odometry : mapping of str to WheelParams
        Named parameter sets to integrate the wheel data with (``nominal``,
        ``calibrated``).
    """
    from matplotlib.figure import Figure

    logged = [run for run in runs if run.log is not None]
    if not logged:
        raise ValueError("no run has a time series to draw")
    columns = min(3, len(logged))
    rows = -(-len(logged) // columns)
    fig = Figure(figsize=(4.6 * columns, 4.4 * rows), layout="constrained")
    axes = fig.subplots(rows, columns, squeeze=False).ravel()
    colours = ["#1f77b4", "#2ca02c", "#9467bd", "#8c564b"]
    for ax, run in zip(axes, logged, strict=False):
        log = run.log
        assert log is not None
        truth = log.truth[log.matched]
        ax.plot(truth[:, 0], truth[:, 1], color="black", linewidth=2, label="ground truth")
        for colour, (name, params) in zip(colours, odometry.items(), strict=False):
            odo = log.odometry(params)
            end = float(np.hypot(*(odo[-1, :2] - truth[-1, :2])) * _MM)
            ax.plot(
                odo[:, 0],
                odo[:, 1],
                color=colour,
                linewidth=1,
                label=f"{name}: ends {end:.0f} mm off",
            )
        ax.plot(0.0, 0.0, "k+", markersize=12)
        ax.set_title(f"{run.label} ({run.direction.value})", fontsize="medium")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(loc="best", fontsize="x-small")
    for ax in axes[len(logged) :]:
        ax.set_visible(False)
    if title:
        fig.suptitle(title)
    return fig


def save_figure(fig: Figure, path: str | Path) -> None:
    """Save ``fig`` atomically; the format follows the extension (.png, .svg, .pdf).

    Raises
    ------
    ValueError
        For an extension that is not a figure format.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in FIGURE_FORMATS:
        raise ValueError(
            f"cannot tell the figure format from {str(path)!r}: use a name ending in "
            + ", ".join(FIGURE_FORMATS)
        )
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=suffix[1:], dpi=150)

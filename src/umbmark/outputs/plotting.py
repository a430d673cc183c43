"""Figures, drawn with matplotlib's object-oriented API (no pyplot, no display needed).

:func:`cluster_figure` draws the view of the paper's Fig. 6 and Fig. 11: every run's
return error, cw and ccw marked differently, both centres of gravity and the
``E_max,syst`` circle. Axes are in millimetres, as in the paper's figures.
:func:`replay_figure` draws recorded runs against their odometry, with a zoom on where
they end [mm]; :func:`history_figure` a robot's calibrations over time.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.atomic import atomic_path
from umbmark.core.conventions import Direction
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run
from umbmark.outputs.files import FIGURE_FORMATS
from umbmark.returns.clusters import Benchmark

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from umbmark.sim.result import Trace
    from umbmark.store.history import CalibrationRecord, RobotRecord

__all__ = [
    "DIRECTION_COLOURS",
    "DIRECTION_MARKERS",
    "cluster_extent",
    "cluster_figure",
    "draw_clusters",
    "frame_clusters",
    "history_figure",
    "replay_figure",
    "save_figure",
    "trajectory_figure",
]

#: The colour and the marker of each direction's runs in every cluster figure.
DIRECTION_COLOURS = {Direction.CW: "#1f77b4", Direction.CCW: "#d62728"}
DIRECTION_MARKERS = {Direction.CW: "o", Direction.CCW: "s"}
_MM = 1000.0
#: Characters per line of a cluster panel's title (a long source path is wrapped).
_PANEL_TITLE_WIDTH = 60
#: The legend of what the passes measured (relative to their active parameters).
_PASS_LABEL = "measured by the pass (relative to its active parameters)"


def draw_clusters(
    ax: Axes,
    bench: Benchmark,
    *,
    name: str = "",
    colour: str | None = None,
    circle_colour: str = "0.4",
    predicted: bool = False,
    page: bool = False,
) -> None:
    """Draw the Fig. 6 view of a benchmark onto ``ax`` (millimetres): each run's return
    error as an open marker (cw circles, ccw squares), the centres of gravity as crosses,
    ``E_max,syst`` as a circle about the origin.

    Parameters
    ----------
    ax : Axes
    bench : Benchmark
    name : str
        Put before the legend entries (``"pass 1 (before): cw runs"``), to tell several
        benchmarks on one axes apart.
    colour : str, optional
        The colour of the runs and crosses; None: each direction's own
        (:data:`DIRECTION_COLOURS`).
    circle_colour : str
        The colour of the ``E_max,syst`` circle.
    predicted : bool
        A prediction, not a measured pass: dashed outlines, ``x`` for the centres.
    page : bool
        The style of the HTML report's figure (smaller crosses that the legend leaves
        out, a solid circle) rather than that of ``--plot``.
    """
    from matplotlib.patches import Circle

    for cluster in bench.clusters:
        direction = cluster.direction
        run_colour = colour or DIRECTION_COLOURS[direction]
        mm = cluster.errors * _MM
        ax.scatter(
            mm[:, 0],
            mm[:, 1],
            marker=DIRECTION_MARKERS[direction],
            facecolors="none",
            edgecolors=run_colour,
            linestyles="dashed" if predicted else "solid",
            label=_named(name, f"{direction.value} runs"),
            zorder=3,
        )
        cg = cluster.cg * _MM
        cg_label = f"c.g. {direction.value}: r = {cluster.r_cg * _MM:.1f} mm"
        ax.plot(
            cg[0],
            cg[1],
            marker="x" if predicted else "+",
            markersize=14 if page else 16,
            markeredgewidth=2.5,
            color=run_colour,
            linestyle="none",
            label="_nolegend_" if page else cg_label,
            zorder=4,
        )
    radius = bench.e_max_syst * _MM
    ax.add_patch(
        Circle(
            (0.0, 0.0),
            radius,
            fill=False,
            linestyle=(":" if predicted else "-") if page else "--",
            linewidth=1.2 if page else None,
            color=circle_colour,
            label=_named(name, f"E_max,syst = {radius:.1f} mm"),
        )
    )


def _named(name: str, what: str) -> str:
    return f"{name}: {what}" if name else what


def frame_clusters(ax: Axes, extent: float, title: str = "", *, page: bool = False) -> None:
    """Square limits of half side ``extent`` [mm] about the origin (see
    :func:`cluster_extent`), the axes through it, their labels and ``title`` (wrapped,
    unless ``page``: the style of the HTML report's figure)."""
    ax.set_xlim(-extent, extent)
    ax.set_ylim(-extent, extent)
    grey = "0.85" if page else "0.8"
    ax.axhline(0.0, color=grey, linewidth=0.8, zorder=1)
    ax.axvline(0.0, color=grey, linewidth=0.8, zorder=1)
    ax.set_xlabel("return error x [mm]")
    ax.set_ylabel("return error y [mm]")
    ax.set_aspect("equal", adjustable="box")
    if title and not page:
        import textwrap

        title = textwrap.fill(title, _PANEL_TITLE_WIDTH, break_on_hyphens=False)
    if title:
        ax.set_title(title)


def cluster_extent(benches: Sequence[Benchmark]) -> float:
    """Half the side [mm] of a square about the origin holding every return error and
    ``E_max,syst`` circle of ``benches``."""
    points = np.vstack([c.errors for bench in benches for c in bench.clusters]) * _MM
    radii = [bench.e_max_syst * _MM for bench in benches]
    return max(float(np.abs(points).max()), *radii, 1.0) * 1.15


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
        draw_clusters(ax, bench)
        frame_clusters(ax, cluster_extent([bench]), panel_title)
        ax.legend(loc="best", fontsize="small")
    _suptitle(fig, title)
    return fig


def trajectory_figure(
    paths: Sequence[tuple[Trace, str]], title: str = "", side_length: float | None = None
) -> Figure:
    """True paths of simulated runs (the view of Figs. 3-5), one panel each.

    Parameters
    ----------
    paths : sequence of (Trace, str)
        A one-run trace (see :class:`umbmark.sim.result.Trace`) and its panel title.
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
        _suptitle(fig, title)
    return fig


def replay_figure(
    runs: Sequence[Run], odometry: Mapping[str, WheelParams], title: str = ""
) -> Figure:
    """Every recorded run's true path against its odometry, two panels per run.

    The left panel is the whole path [m]; the right one zooms on where the run ends
    [mm], equal aspect: the true end point and the odometry's end points under each
    parameter set, so that millimetre differences show next to the path in metres.

    Parameters
    ----------
    runs : sequence of Run
        Runs with their time series (``run.log``).
    odometry : mapping of str to WheelParams
        Named parameter sets to integrate the wheel data with (``nominal``,
        ``calibrated``).
    title : str
        The figure's title (the robot's or the recording's name).
    """
    from matplotlib.figure import Figure

    logged = [run for run in runs if run.log is not None]
    if not logged:
        raise ValueError("no run has a time series to draw")
    columns = min(2, len(logged))  # runs per row, each a path and a zoom panel
    rows = -(-len(logged) // columns)
    fig = Figure(figsize=(4.2 * 2 * columns, 4.2 * rows), layout="constrained")
    axes = fig.subplots(rows, 2 * columns, squeeze=False)
    for index, run in enumerate(logged):
        row, column = divmod(index, columns)
        _draw_replay(axes[row, 2 * column], axes[row, 2 * column + 1], run, odometry)
    for index in range(len(logged), rows * columns):
        row, column = divmod(index, columns)
        axes[row, 2 * column].set_visible(False)
        axes[row, 2 * column + 1].set_visible(False)
    if title:
        _suptitle(fig, title)
    return fig


_REPLAY_COLOURS = ("#1f77b4", "#2ca02c", "#9467bd", "#8c564b")
#: Smallest half-width of a replay's end-point zoom [mm].
_ZOOM_MIN_HALF = 5.0


def _draw_replay(ax: Axes, zoom: Axes, run: Run, odometry: Mapping[str, WheelParams]) -> None:
    """One run: its whole path on ``ax`` [m], its end points on ``zoom`` [mm]."""
    log = run.log
    assert log is not None
    truth = log.truth[log.matched]
    ax.plot(truth[:, 0], truth[:, 1], color="black", linewidth=2, label="ground truth")
    zoom.plot(truth[:, 0] * _MM, truth[:, 1] * _MM, color="black", linewidth=2)
    ends = [truth[-1, :2] * _MM]
    for colour, (name, params) in zip(_REPLAY_COLOURS, odometry.items(), strict=False):
        odo = log.odometry(params)
        end = float(np.hypot(*(odo[-1, :2] - truth[-1, :2])) * _MM)
        ax.plot(
            odo[:, 0], odo[:, 1], color=colour, linewidth=1, label=f"{name}: ends {end:.0f} mm off"
        )
        zoom.plot(odo[:, 0] * _MM, odo[:, 1] * _MM, color=colour, linewidth=1)
        zoom.plot(
            odo[-1, 0] * _MM,
            odo[-1, 1] * _MM,
            "o",
            color=colour,
            label=f"{name} end: {end:.1f} mm off",
            zorder=4,
        )
        ends.append(odo[-1, :2] * _MM)
    zoom.plot(
        truth[-1, 0] * _MM,
        truth[-1, 1] * _MM,
        "*",
        color="black",
        markersize=12,
        label="true end",
        zorder=5,
    )
    ax.plot(0.0, 0.0, "k+", markersize=12)
    ax.set_title(f"{run.label} ({run.direction.value})", fontsize="medium")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best", fontsize="x-small")
    points = np.array(ends)
    centre = (points.max(axis=0) + points.min(axis=0)) / 2.0
    half = max(float((points.max(axis=0) - points.min(axis=0)).max()) * 0.65, _ZOOM_MIN_HALF)
    zoom.set_xlim(centre[0] - half, centre[0] + half)
    zoom.set_ylim(centre[1] - half, centre[1] + half)
    zoom.set_aspect("equal", adjustable="box")
    zoom.set_title(f"{run.label}: where it ends", fontsize="medium")
    zoom.set_xlabel("x [mm]")
    zoom.set_ylabel("y [mm]")
    zoom.set_label("end zoom")
    zoom.grid(True, color="0.9")
    zoom.legend(loc="best", fontsize="x-small")


#: Coverage factor of the error bars of :func:`history_figure` (95 %).
Z95 = 1.96
#: Characters of a figure title's line per inch of the figure's width.
_TITLE_CHARS_PER_INCH = 11


def history_figure(robot: RobotRecord, calibrations: Sequence[CalibrationRecord]) -> Figure:
    """A robot's calibrations over time: ``E_d``, ``E_b`` and ``E_max,syst``, stacked.

    Three panels share the time axis (UTC). ``E_d`` and ``E_b`` are what the robot is,
    each pass's errors composed with the parameters active during it
    (:attr:`~umbmark.store.history.CalibrationRecord.robot_E_d`), with error bars of
    ±1.96 standard errors where the calibration has them; when some pass ran on
    parameters other than the nominal ones, what the passes measured is drawn too (grey
    crosses). ``E_max,syst`` (each pass's, on its active parameters) is in millimetres.
    Calibrations marked applied are filled markers, the others open ones. The title
    names the robot and its nominal parameters and, when the robot's ``E_d`` or ``E_b``
    drifted (:func:`umbmark.store.history.drift_verdict`), says so.

    Parameters
    ----------
    robot : RobotRecord
        The robot (name, nominal wheelbase and wheel diameter).
    calibrations : sequence of CalibrationRecord
        Its calibrations, oldest first (at least one).

    Raises
    ------
    ValueError
        Without calibrations.
    """
    from matplotlib import dates
    from matplotlib.figure import Figure

    if not calibrations:
        raise ValueError(f"robot {robot.name} has no calibrations to draw")
    # Matplotlib's date numbers [days], UTC.
    moments = [dt.datetime.fromisoformat(c.time) for c in calibrations]
    times = np.asarray(dates.date2num(moments), dtype=np.float64)  # type: ignore[no-untyped-call]
    applied = np.array([c.applied for c in calibrations])
    fig = Figure(figsize=(8.0, 8.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    # Measured on other parameters than the nominal ones: the passes differ from the robot.
    corrected = any(
        float(c.active[key]) != 1.0
        for c in calibrations
        for key in ("c_L", "c_R", "wheel_separation_multiplier")
    )
    for ax, name, ratio, active in (
        (axes[0], "E_d", "D_R / D_L", "c_R / c_L"),
        (axes[1], "E_b", "b_actual / b_nominal", "wheel_separation_multiplier"),
    ):
        values = np.array([float(getattr(c, f"robot_{name}")) for c in calibrations])
        se = np.array([_finite_or_nan(c.robot_standard_errors.get(name)) for c in calibrations])
        has_se = np.isfinite(se)
        if np.any(has_se):
            ax.errorbar(
                times[has_se],
                values[has_se],
                yerr=Z95 * se[has_se],
                fmt="none",
                ecolor="0.5",
                capsize=4,
                label="±1.96 standard errors (95 %)",
            )
        _trend(ax, times, values, applied, f"robot {name}")
        if corrected:
            measured = [float(getattr(c, name)) for c in calibrations]
            ax.plot(times, measured, "x", color="0.45", label=_PASS_LABEL, zorder=2)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.set_ylabel(f"robot {name} = {ratio}\n[dimensionless]")
        ax.set_title(
            f"robot {name}: each pass's {name} composed with the active {active}",
            fontsize="small",
            loc="left",
        )
    e_max = np.array([np.nan if c.e_max_syst is None else c.e_max_syst * _MM for c in calibrations])
    ax = axes[2]
    known = np.isfinite(e_max)
    if np.any(known):
        _trend(
            ax,
            times[known],
            e_max[known],
            applied[known],
            "E_max,syst",
        )
        ax.set_ylim(bottom=0.0)
    else:
        ax.text(
            0.5,
            0.5,
            "no E_max,syst: no calibration had squares in both directions",
            ha="center",
            va="center",
            transform=ax.transAxes,
        )
    ax.set_ylabel("E_max,syst of the pass [mm]")
    ax.set_xlabel("calibration time (UTC)")
    ax.xaxis_date(tz=dt.timezone.utc)
    locator = dates.AutoDateLocator(tz=dt.timezone.utc)  # type: ignore[no-untyped-call]
    formatter = dates.ConciseDateFormatter(locator, tz=dt.timezone.utc)  # type: ignore[no-untyped-call]
    ax.xaxis.set_major_locator(locator)
    ax.xaxis.set_major_formatter(formatter)
    if times[0] == times[-1]:  # one instant: give the axis a day's span
        ax.set_xlim(times[0] - 0.5, times[0] + 0.5)
    for each in axes:
        each.grid(True, color="0.92")
    handles = [h for h in axes[0].get_legend_handles_labels()[0] if h.get_label() != "robot E_d"]
    axes[0].legend(handles=handles, loc="best", fontsize="x-small")
    diameter = (
        "wheel diameter unknown"
        if robot.wheel_diameter is None
        else f"wheel diameter {robot.wheel_diameter * _MM:.2f} mm"
    )
    title = (
        f"Robot {robot.name}: nominal wheelbase {robot.wheelbase * _MM:.2f} mm, {diameter}; "
        f"{len(calibrations)} calibration(s)"
    )
    from umbmark.store.history import drift_verdict

    verdict = drift_verdict(calibrations)
    if verdict is not None and verdict.startswith("drift"):
        title += "\n" + verdict
    _suptitle(fig, title, fontsize="medium")
    return fig


def _trend(ax: Axes, times: FloatArray, values: FloatArray, applied: BoolArray, name: str) -> None:
    """One quantity over time (``times``: date numbers, shape (n,)): a line through every
    value, applied calibrations filled, the others open."""
    colour = "#1f77b4"
    ax.plot(times, values, "-", color=colour, linewidth=1, label=name, zorder=3)
    marks = ((applied, "applied", colour), (~applied, "not applied", "white"))
    for chosen, label, face in marks:
        if np.any(chosen):
            ax.plot(
                times[chosen],
                values[chosen],
                "o",
                markerfacecolor=face,
                markeredgecolor=colour,
                color=colour,
                label=label,
                zorder=4,
            )


def _suptitle(fig: Figure, title: str, fontsize: str = "large") -> None:
    """Title ``fig``, its lines wrapped to the figure's width (a long path included)."""
    if not title:
        return
    import textwrap

    width = max(int(fig.get_figwidth() * _TITLE_CHARS_PER_INCH), 40)
    lines = [textwrap.fill(line, width, break_on_hyphens=False) for line in title.split("\n")]
    fig.suptitle("\n".join(lines), fontsize=fontsize)


def _finite_or_nan(value: float | None) -> float:
    return float("nan") if value is None or not math.isfinite(value) else float(value)


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

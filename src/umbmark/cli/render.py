"""The human-readable summaries: the one table style of every command (:func:`table`), and
the calibration's summary, every figure with its unit."""

from __future__ import annotations

import math
from collections.abc import Collection, Iterable, Mapping, Sequence

from rich import box
from rich.console import Console
from rich.table import Table
from rich.text import Text

from ..benchmark import Benchmark
from ..jobs.calibrate import CalibrationReport

__all__ = ["column", "render_calibration", "row", "table", "verdict"]

_MM = 1000.0
_METHOD_NAMES = {
    "paper": "the paper's equations (Eqs. 4.20-4.27, x and y averaged)",
    "exact": "exact square geometry, inverted numerically",
    "heading": "final heading errors (Jung & Chung 2011)",
    "endpose": "maximum likelihood on the runs' end poses, exact geometry",
    "straight": "straight runs against a tape (scale only)",
    "endpoints": "least squares on where the recorded runs end",
    "trajectory": "least squares on whole recorded trajectories",
    "trajectory-scrub": "least squares on whole trajectories, turn-dependent wheelbase",
}


def verdict(b: Benchmark) -> str:
    """The 3 x SEM rule of Sec. 5, in words."""
    e, t = b.e_max_syst * _MM, b.second_pass_threshold * _MM
    if b.second_pass_recommended:
        return (
            f"E_max,syst = {e:.1f} mm > 3 x SEM = {t:.1f} mm: the systematic error stands "
            "well above the scatter of the runs. Apply the correction below, then run "
            "UMBmark again; another pass is worth it while E_max,syst stays above 3 x SEM."
        )
    return (
        f"E_max,syst = {e:.1f} mm <= 3 x SEM = {t:.1f} mm: what remains is within the "
        "scatter of the runs; a further pass is unlikely to improve it (Sec. 5)."
    )


def _render_benchmark(report: CalibrationReport, bench: Benchmark, console: Console) -> None:
    test = report.test
    head = Text.assemble(
        ("UMBmark ", "bold"),
        (report.source, "bold cyan"),
        f"  ({bench.cw.n} cw + {bench.ccw.n} ccw runs, square side L = "
        f"{test.side_length:.3f} m, wheelbase b = {test.wheelbase:.4f} m)",
    )
    console.print(head)
    clusters = table("Return errors (Eqs. 3.1-3.4)", ["", "cw", "ccw"])
    cw, ccw = bench.cw, bench.ccw
    rows = [
        ("centre of gravity x [mm]", cw.cg[0] * _MM, ccw.cg[0] * _MM),
        ("centre of gravity y [mm]", cw.cg[1] * _MM, ccw.cg[1] * _MM),
        ("r_cg [mm]", cw.r_cg * _MM, ccw.r_cg * _MM),
        ("spread sigma (radial) [mm]", cw.sigma * _MM, ccw.sigma * _MM),
        ("SEM = sigma / sqrt(n) [mm]", cw.sem * _MM, ccw.sem * _MM),
    ]
    for label, a, b in rows:
        _row(clusters, label, f"{a:.1f}", f"{b:.1f}")
    console.print(clusters)
    console.print(
        Text.assemble(
            ("E_max,syst = ", "bold"),
            (f"{bench.e_max_syst * _MM:.1f} mm", "bold yellow"),
            f"  (the {bench.worst.direction.value} cluster)",
        )
    )
    console.print(verdict(bench))


def _plus_minus(value: float, se: float | None, fmt: str) -> str:
    if se is None or not math.isfinite(se):
        return format(value, fmt)
    return f"{format(value, fmt)} ± {format(se, fmt)}"


def render_calibration(
    report: CalibrationReport, console: Console, *, overlay: bool = True
) -> None:
    """Print the summary of ``report`` on ``console`` (with the overlay to paste)."""
    from ..sources.association import summarize

    for line in summarize(list(report.associations)):
        console.print(line)
    bench, cal = report.benchmark, report.calibration
    est, active = cal.estimate, cal.active
    se = est.standard_errors

    if bench is None:
        console.print(
            Text.assemble(
                ("Calibration of ", "bold"),
                (report.source, "bold cyan"),
                f"  ({len(report.runs)} runs, not squares of a known side in both directions: "
                "no UMBmark figures)",
            )
        )
    else:
        _render_benchmark(report, bench, console)

    name = _METHOD_NAMES.get(est.method, est.method)
    if est.method == "trajectory-scrub" and "spot_wheelbase" not in est.components:
        name += ": not identified, one wheelbase fitted (see the warning)"
    errors = table(f"Systematic errors: {name}", ["", "value"])
    column(errors, "", text=True)
    _row(
        errors,
        "alpha, Type A error per turn",
        _plus_minus(math.degrees(est.alpha), _deg(se.get("alpha")), ".4f") + " deg",
        "> 0: turns too little",
    )
    _row(
        errors,
        "beta, Type B error per leg",
        _plus_minus(math.degrees(est.beta), _deg(se.get("beta")), ".4f") + " deg",
        "> 0: legs curve left",
    )
    _row(
        errors, "E_b = b_actual / b_nominal", _plus_minus(est.E_b, se.get("E_b"), ".6f"), "Eq. 4.27"
    )
    _row(errors, "E_d = D_R / D_L", _plus_minus(est.E_d, se.get("E_d"), ".6f"), "Eq. 4.22")
    if est.E_s is not None:
        _row(errors, "E_s = D_avg / D_active", _plus_minus(est.E_s, se.get("E_s"), ".6f"), "scale")
    if est.method.startswith("trajectory") or est.method == "endpoints":
        _trajectory_rows(errors, est.components, se)
    console.print(errors)
    intervals = [
        f"{name} [{low:.6f}, {high:.6f}]"
        for name in ("E_d", "E_b", "E_s")
        if (interval := est.interval(name)) is not None
        for low, high in [interval]
    ]
    if intervals:
        console.print("95 % intervals: " + ", ".join(intervals))

    correction = table(
        "Correction, composed with the values active during the runs",
        ["", "active", "this pass", "new"],
    )
    _row(
        correction,
        "c_L, left wheel (Eq. 4.31)",
        f"{active.c_left:.6f}",
        f"{cal.c_L:.6f}",
        f"{cal.new_c_left:.6f}",
    )
    _row(
        correction,
        "c_R, right wheel (Eq. 4.32)",
        f"{active.c_right:.6f}",
        f"{cal.c_R:.6f}",
        f"{cal.new_c_right:.6f}",
    )
    _row(
        correction,
        "wheelbase multiplier (E_b)",
        f"{active.separation_multiplier:.6f}",
        f"{est.E_b:.6f}",
        f"{cal.new_separation_multiplier:.6f}",
    )
    _row(
        correction,
        "wheelbase [mm] (Eq. 4.26)",
        f"{active.effective_wheelbase * _MM:.2f}",
        "",
        f"{cal.wheelbase_corrected * _MM:.2f}",
    )
    if cal.wheel_diameter_left is not None and cal.wheel_diameter_right is not None:
        assert active.wheel_diameter is not None
        _row(
            correction,
            "left wheel diameter [mm]",
            f"{active.c_left * active.wheel_diameter * _MM:.3f}",
            "",
            f"{cal.wheel_diameter_left * _MM:.3f}",
        )
        _row(
            correction,
            "right wheel diameter [mm]",
            f"{active.c_right * active.wheel_diameter * _MM:.3f}",
            "",
            f"{cal.wheel_diameter_right * _MM:.3f}",
        )
    console.print(correction)

    if overlay:
        console.print(
            Text("ros2_control overlay (paste it, or write it with --yaml FILE):", style="bold")
        )
        # Plain text, no box: it must copy and paste as it is.
        console.print(Text(report.overlay_yaml().rstrip()), soft_wrap=True)


def _trajectory_rows(errors: Table, comp: Mapping[str, float], se: Mapping[str, float]) -> None:
    """The trajectory fit's own figures: radii, wheelbase(s), time and truth offsets,
    residuals."""
    # Fitted lengths [mm] and the time offset [ms]: value x 1000 in every row.
    for key, label, note, digits in (
        ("r_left", "left wheel radius [mm]", "fitted", ".3f"),
        ("r_right", "right wheel radius [mm]", "fitted", ".3f"),
        ("wheelbase", "wheelbase [mm]", "fitted: the single set exported", ".3f"),
        ("arc_wheelbase", "wheelbase on straights and arcs [mm]", "scrub model", ".3f"),
        ("spot_wheelbase", "wheelbase turning on the spot [mm]", "scrub model", ".3f"),
        ("time_offset", "time offset [ms]", "> 0: ground truth lags the wheels", ".1f"),
        ("truth_offset_x", "tracked point forward [mm]", "fitted: truth offset d_x", ".1f"),
        ("truth_offset_y", "tracked point left [mm]", "fitted: truth offset d_y", ".1f"),
    ):
        if key in comp:
            value = _plus_minus(comp[key] * _MM, se.get(key, math.nan) * _MM, digits)
            _row(errors, label, value, note)
    where = "along the runs" if "samples" in comp else "at the runs' ends"
    counted = f"{comp['runs']:.0f} runs" + (
        f", {comp['samples']:.0f} samples" if "samples" in comp else ""
    )
    _row(
        errors,
        f"residual {where} (rms)",
        f"{comp['rms_position'] * _MM:.2f} mm, {math.degrees(comp['rms_heading']):.3f} deg",
        counted,
    )


def table(
    title: str,
    columns: Sequence[str] = (),
    rows: Iterable[Sequence[str]] = (),
    *,
    left: Collection[str] | None = None,
) -> Table:
    """A table in the one style of every command: a title line, a rule under the headers.

    Cells and headers are plain text (no markup: ``[mm]`` stays as it is); headers carry
    the units. Text columns (by default the first, the row's label) are left-aligned, the
    others (numbers) right-aligned. On a narrow terminal rich wraps headers and text
    between words, so that a number stays whole; piped output is not narrowed at all
    (:func:`umbmark.cli.common.console`).

    Parameters
    ----------
    title : str
        The table's title.
    columns : sequence of str
        The column headers (may be added later with :func:`column`).
    rows : iterable of sequence of str
        Rows of cells (may be added later with :func:`row`).
    left : collection of str, optional
        Headers of the text columns [default: the first column].
    """
    grid = Table(
        title=Text(title),
        title_justify="left",
        box=box.SIMPLE_HEAD,
        padding=(0, 1),
        header_style="bold",
    )
    for index, name in enumerate(columns):
        column(grid, name, text=index == 0 if left is None else name in left)
    for cells in rows:
        row(grid, *cells)
    return grid


def column(grid: Table, header: str, *, text: bool = False) -> None:
    """Add a column: ``text`` left-aligned, else a number column, right-aligned."""
    grid.add_column(Text(header), justify="left" if text else "right")


def row(grid: Table, *cells: str, bold: bool = False) -> None:
    """Add a row of plain-text cells (``bold``: a total or mean row)."""
    grid.add_row(*(Text(cell, style="bold" if bold else "") for cell in cells))


def _row(table: Table, *cells: str) -> None:
    row(table, *cells)


def _deg(value: float | None) -> float | None:
    return None if value is None else math.degrees(value)

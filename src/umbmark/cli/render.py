"""The human-readable summaries: the one table style of every command (:func:`table`), and
the calibration's summary, every figure with its unit."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

from rich import box
from rich.console import Console
from rich.table import Table
from rich.text import Text

from umbmark.calibration.passes import e_b_words
from umbmark.calibration.result import ABSOLUTE_FIGURES, CalibrationResult
from umbmark.estimators.registry import LOGGED, find, method_label
from umbmark.outputs.components import ANGLE_UNIT, component, to_shown
from umbmark.returns.clusters import Benchmark, sem_verdict

if TYPE_CHECKING:
    from umbmark.jobs.selfcal import SelfCalReport
    from umbmark.jobs.selfcal_anywhere import AnywhereReport

__all__ = ["column", "print_table", "render_calibration", "row", "table"]

_MM = 1000.0


def _render_benchmark(report: CalibrationResult, bench: Benchmark, console: Console) -> None:
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
    console.print(sem_verdict(bench))


def _plus_minus(value: float, se: float | None, fmt: str) -> str:
    if se is None or not math.isfinite(se):
        return format(value, fmt)
    return f"{format(value, fmt)} ± {format(se, fmt)}"


def render_calibration(
    report: CalibrationResult, console: Console, *, overlay: bool = True
) -> None:
    """Print the summary of ``report`` on ``console``: the verdict first, the overlay to
    paste last (withheld when the verdict is "do not apply", unless overridden)."""
    from umbmark.runs.association import summarize

    verdict = report.verdict
    style = {"apply": "bold green", "care": "bold yellow", "do-not-apply": "bold red"}
    console.print(Text(verdict.line(), style=style[verdict.level]))
    for line in summarize(list(report.associations)):
        console.print(line)
    bench, sensor = report.benchmark, report.sensor
    if report.gyro is not None:
        _render_gyro_head(report, console)
    elif sensor is not None:
        console.print(
            Text.assemble(
                ("Calibration of ", "bold"),
                (report.source, "bold cyan"),
                f"  ({sensor.n_used} of {len(sensor.kept)} motion intervals, "
                f"{len(sensor.kept) - sensor.n_used} dropped as outliers; no UMBmark figures)",
            )
        )
    elif bench is None:
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

    _render_errors(report, console)
    if not report.nominal:
        console.print(
            Text(
                "No correction and no overlay: no nominal geometry was given (--wheelbase "
                "and --wheel-diameter, or --current-params); the diameters, wheelbase and "
                "mounting above are absolute.",
                style="bold",
            )
        )
        _render_mounting(report, console)
        return
    _render_without(report, console)
    _render_correction(report, console)
    _render_mounting(report, console)
    _render_gyro(report, console)

    if overlay and report.overlay_withheld:
        console.print(
            Text(
                "No ros2_control overlay: the verdict is do not apply (--override-verdict "
                "prints and writes it).",
                style="bold",
            )
        )
    elif overlay:
        console.print(
            Text("ros2_control overlay (paste it, or write it with --yaml FILE):", style="bold")
        )
        # Plain text, no box: it must copy and paste as it is.
        console.print(Text(report.overlay_yaml().rstrip()), soft_wrap=True)


def _render_gyro_head(report: CalibrationResult, console: Console) -> None:
    """The head of a calibration with a gyro: what its intervals held."""
    gyro = report.gyro
    assert gyro is not None
    sensor = report.sensor
    laser = (
        ""
        if sensor is None
        else f", {sensor.n_used} of {len(sensor.kept)} motion intervals of its laser"
    )
    console.print(
        Text.assemble(
            ("Calibration of ", "bold"),
            (report.source, "bold cyan"),
            f"  with its gyro ({gyro.n_intervals - gyro.n_rests} intervals of driving, "
            f"{gyro.n_rests} rests{laser}; no UMBmark figures)",
        )
    )


def _render_gyro(report: CalibrationResult, console: Console) -> None:
    """The gyro's own calibration: its figures and where they go, plain lines."""
    if report.gyro is None:
        return
    from umbmark.calibration.gyro import gyro_lines

    head, *lines = gyro_lines(report.gyro)
    console.print(Text(head, style="bold"))
    for line in lines:
        console.print(Text(f"  {line}"), soft_wrap=True)


def _render_mounting(report: CalibrationResult, console: Console) -> None:
    """The laser's fitted mounting in the forms a user applies (a calibration from motion
    intervals): plain lines, the commands whole to copy."""
    from umbmark.outputs.mounting import mounting_forms

    forms = mounting_forms(report)
    if forms is None:
        return
    for line in forms.lines():
        console.print(Text(line), soft_wrap=True)


def _render_errors(report: CalibrationResult, console: Console) -> None:
    """The systematic errors' table, and their 95 % intervals."""
    est, sensor = report.calibration.estimate, report.sensor
    se = est.standard_errors
    name = method_label(est.method)
    entry = find(est.method)
    if entry is not None and entry.turn_rate and "spot_wheelbase" not in est.components:
        name += ": not identified, one wheelbase fitted (see the warning)"
    errors = table(f"Systematic errors: {name}", ["", "value"])
    column(errors, "", text=True)
    nominal = report.nominal
    for name, label, note in (
        ("alpha", "alpha, Type A error per turn", "> 0: turns too little"),
        ("beta", "beta, Type B error per leg", "> 0: legs curve left"),
    ):
        if nominal or name == "beta":
            shown = _plus_minus(
                to_shown(getattr(est, name), ANGLE_UNIT), _angle(se.get(name)), ".4f"
            )
            _row(errors, label, f"{shown} {ANGLE_UNIT}", note)
    if nominal:
        E_b = _plus_minus(est.E_b, se.get("E_b"), ".6f")
        if "E_b_gyro" in est.components and "gyro_scale" not in est.components:
            if "E_b" in se:
                _row(errors, "E_b relative to the gyro", E_b, "E_b k_g, ± its scale tolerance")
            else:
                _row(errors, "E_b, not corrected", E_b, "relative to the gyro: see its lines")
        else:
            _row(errors, "E_b = b_actual / b_nominal", E_b, "Eq. 4.27")
    _row(errors, "E_d = D_R / D_L", _plus_minus(est.E_d, se.get("E_d"), ".6f"), "Eq. 4.22")
    if est.E_s is not None and nominal:
        _row(errors, "E_s = D_avg / D_active", _plus_minus(est.E_s, se.get("E_s"), ".6f"), "scale")
    if not nominal:
        _row(errors, "E_b, E_s", "not given", "no nominal geometry to compare with")
    if est.method in LOGGED:
        _trajectory_rows(errors, est.components, se)
    if sensor is not None:
        _sensor_rows(errors, est.components, se)
    console.print(errors)
    intervals = [
        f"{name} [{low:.6f}, {high:.6f}]"
        for name in (("E_d", "E_b", "E_s") if nominal else ("E_d",))
        if (interval := est.interval(name)) is not None
        for low, high in [interval]
    ]
    if intervals:
        console.print("95 % intervals: " + ", ".join(intervals))


def _render_without(report: CalibrationResult, console: Console) -> None:
    """The result without the rows far outside their cluster, beside the result."""
    without = report.without
    if without is None:
        return
    e_max = (
        "" if without.e_max_syst is None else f"E_max,syst = {without.e_max_syst * _MM:.1f} mm, "
    )
    words = {"apply": "apply", "care": "apply with care", "do-not-apply": "do not apply"}
    console.print(
        Text(
            f"Without {' and '.join(without.rows)}: {e_max}E_d = {without.E_d:.6f}, "
            f"E_b = {without.E_b:.6f} (its verdict: {words[without.verdict]}); with "
            f"{'them' if len(without.rows) > 1 else 'it'}: E_d = {report.estimate.E_d:.6f}, "
            f"E_b = {report.estimate.E_b:.6f}",
            style="bold",
        )
    )


def _render_correction(report: CalibrationResult, console: Console) -> None:
    """The correction's table: active, this pass, new."""
    cal = report.calibration
    est, active = cal.estimate, cal.active
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


def _sensor_rows(errors: Table, comp: Mapping[str, float], se: Mapping[str, float]) -> None:
    """The absolute figures of a calibration from motion intervals, in their units."""
    for key in ABSOLUTE_FIGURES:
        if key in comp:
            shown = component(key)
            value, error = shown.show(comp[key]), se.get(key)
            if error is not None and math.isfinite(error):
                value += f" ± {shown.show(error)}"
            _row(errors, shown.label, f"{value} {shown.unit}", shown.meaning)


def _trajectory_rows(errors: Table, comp: Mapping[str, float], se: Mapping[str, float]) -> None:
    """The trajectory fit's own figures: radii, wheelbase(s), time and truth offsets,
    residuals."""
    for key, note in (
        ("r_left", "fitted"),
        ("r_right", "fitted"),
        ("wheelbase", "fitted: the single set exported"),
        ("arc_wheelbase", "scrub model"),
        ("spot_wheelbase", "scrub model"),
        ("time_offset", "> 0: ground truth lags the wheels"),
        ("truth_offset_x", "fitted: truth offset d_x"),
        ("truth_offset_y", "fitted: truth offset d_y"),
    ):
        if key in comp:
            c = component(key)
            value = _plus_minus(
                to_shown(comp[key], c.unit), to_shown(se.get(key, math.nan), c.unit), c.digits
            )
            _row(errors, c.heading, value, note)
    where = "along the runs" if "samples" in comp else "at the runs' ends"
    counted = f"{comp['runs']:.0f} runs" + (
        f", {comp['samples']:.0f} samples" if "samples" in comp else ""
    )
    _row(
        errors,
        f"residual {where} (rms)",
        f"{component('rms_position').show(comp['rms_position'])} mm, "
        f"{component('rms_heading').show(comp['rms_heading'])} {ANGLE_UNIT}",
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


#: A header is wrapped to this many characters a line (or its column's widest cell) ...
_HEADER_WIDTH = 9
#: ... and a table is measured as if the console were this wide.
_UNLIMITED = 1_000_000


def print_table(
    console: Console,
    title: str,
    columns: Sequence[str],
    rows: Sequence[Sequence[str]],
    *,
    keys: int = 1,
    left: Collection[str] | None = None,
) -> None:
    """Print a table that fits ``console``: no cell is ever cut or ellipsised.

    A table that fits is printed as it is. A wider one has its headers wrapped between
    words (each column as wide as its widest cell, at least :data:`_HEADER_WIDTH`) and
    its columns split over several tables, each repeating the first ``keys`` columns
    (what a row is about: the grid cell, the method), in the order given. When not even
    the key columns and one more fit, each row is printed as lines of ``header: value``.

    Parameters
    ----------
    console : Console
        Where to print; its width is the limit.
    title : str
        The title (of the first table; the others say which part they are).
    columns, rows, left
        As for :func:`table`.
    keys : int
        How many leading columns every part repeats.
    """

    def part(title: str, chosen: Sequence[int], wrap: bool = True) -> Table:
        grid = table(title, left=left)
        for k in chosen:
            header = name = columns[k]
            if wrap:
                widest = max([len(r[k]) for r in rows] + [len(w) for w in name.split()])
                header = textwrap.fill(name, max(widest, _HEADER_WIDTH), break_long_words=False)
            column(grid, header, text=(k == 0) if left is None else name in left)
        for cells in rows:
            row(grid, *(cells[k] for k in chosen))
        return grid

    def fits(grid: Table) -> bool:  # its natural width, measured without a limit
        unlimited = console.options.update_width(_UNLIMITED)
        return console.measure(grid, options=unlimited).maximum <= console.width

    whole = part(title, range(len(columns)), wrap=False)
    if fits(whole):
        console.print(whole)
        return
    head = list(range(min(keys, len(columns))))
    parts: list[list[int]] = []
    for k in range(len(head), len(columns)):
        if parts and fits(part("", [*parts[-1], k])):
            parts[-1].append(k)
        elif fits(part("", [*head, k])):
            parts.append([*head, k])
        else:  # not even one column beside the keys: a block of lines per row
            console.print(Text(title, style="bold"))
            for cells in rows:
                console.print()
                for name, cell in zip(columns, cells, strict=True):
                    console.print(Text(f"{name}: {cell}"))
            return
    for n, chosen in enumerate(parts or [head], 1):
        console.print(part(title if n == 1 else f"{title} (part {n} of {len(parts)})", chosen))


def column(grid: Table, header: str, *, text: bool = False) -> None:
    """Add a column: ``text`` left-aligned, else a number column, right-aligned."""
    grid.add_column(Text(header), justify="left" if text else "right")


def row(grid: Table, *cells: str, bold: bool = False) -> None:
    """Add a row of plain-text cells (``bold``: a total or mean row)."""
    grid.add_row(*(Text(cell, style="bold" if bold else "") for cell in cells))


def _row(table: Table, *cells: str) -> None:
    row(table, *cells)


def _angle(value: float | None) -> float | None:
    return None if value is None else to_shown(value, ANGLE_UNIT)


def render_selfcal(report: SelfCalReport, screen: Console) -> None:
    """What ``umbmark selfcal`` prints: the coarse check, each pass, before and after, the
    multipliers the controller holds, and how well the corner was measured."""
    screen.print(
        f"Self-calibration of {report.robot}: {report.side_length:g} m squares, fixes by "
        f"{report.measurement}."
    )
    coarse = report.coarse
    if coarse is not None:
        screen.print(coarse.words())
    grid = table(
        "UMBmark passes",
        ["pass", "E_max,syst [mm]", "E_d", "E_b", "verdict", "applied"],
        left={"pass", "verdict", "applied"},
    )
    for k, p in enumerate(report.passes, 1):
        r = p.report
        e = r.e_max_syst
        applied = "-" if p.applied is None else (p.applied.method if p.applied.active else "no")
        row(
            grid,
            p.label,
            "-" if e is None else f"{e * 1000:.1f}",
            f"{r.estimate.E_d:.6f}",
            e_b_words(r.estimate.E_b, report.holds.coarse if k == 1 else None),
            r.verdict.words,
            applied,
        )
    screen.print(grid)
    if report.holds.coarse is not None and report.passes:
        screen.print(
            f"{report.passes[0].label}'s E_b is the residual on the wheelbase the coarse turning "
            f"check corrected (wheel_separation_multiplier x{report.holds.coarse:.4f}); "
            "composed: with that correction."
        )
    before, after = report.e_max_syst_before, report.e_max_syst_after
    if before is not None and after is not None and after > 0:
        screen.print(
            f"[bold]E_max,syst {before * 1000:.1f} mm -> {after * 1000:.1f} mm "
            f"({before / after:.1f}-fold)[/bold]"
        )
    elif before is not None and after is None:
        was_applied = any(p.applied is not None and p.applied.active for p in report.passes)
        why = (
            "the correction was applied but not verified (--no-verify)"
            if was_applied
            else "nothing was applied, so there is nothing to verify"
        )
        screen.print(f"E_max,syst {before * 1000:.1f} mm; {why}.")
    screen.print(report.holds.words(), markup=False, highlight=False)
    errors = report.measurement_errors()
    if errors is not None:
        screen.print(
            f"Fixes ({report.measurement}) against the virtual robot's truth: "
            f"{errors[0] * 1000:.2f} mm, "
            f"{math.degrees(errors[1]):.3f} deg rms."
        )
    for p in report.passes:
        if p.applied is not None and not p.applied.active:
            screen.print(f"{p.label}: {p.applied.message}")


def render_anywhere(report: AnywhereReport, screen: Console) -> None:
    """What ``umbmark selfcal --routine anywhere`` prints: the calibration (wheels, E_d,
    E_b, E_s, the laser's mounting, with standard errors), what was applied, and the
    verification's errors before and after."""
    first = report.calibration
    screen.print(
        f"Self-calibration anywhere of {report.robot}: {first.matched} while driving the "
        "pattern (turns on the spot both ways, straights forward and back, arcs)."
    )
    render_calibration(first.report, screen, overlay=False)
    applied = first.applied
    if applied is None:
        why = "--apply none" if first.report.verdict.applies else "the verdict is do not apply"
        screen.print(f"Not applied: {why}.")
    elif applied.active:
        screen.print(f"Applied ({applied.method}): {applied.message}.", markup=False)
    else:
        screen.print(f"Not applied yet: {applied.message}.", markup=False)
    verification = report.verification
    if verification is not None:
        grid = table(
            "Verification: the pattern driven again on the new parameters",
            ["", "before", "after"],
            left={""},
        )
        before, after = first.errors(), verification.errors()
        for key, what in (
            ("E_d", "E_d = D_R / D_L"),
            ("E_b", "E_b = b_actual / b_used"),
            ("E_s", "E_s = D_avg / D_used"),
        ):
            b, a = before[key], after[key]
            row(grid, what, "-" if b is None else f"{b:.6f}", "-" if a is None else f"{a:.6f}")
        screen.print(grid)
        screen.print(
            f"The verification's own verdict (not applied): {verification.report.verdict.words}."
        )
    elif applied is not None and applied.active:
        screen.print("The correction was applied but not verified (--no-verify).")
    final = report.final
    screen.print(
        f"The controller holds: wheel_separation_multiplier "
        f"{final.wheel_separation_multiplier:.6f}, left_wheel_radius_multiplier "
        f"{final.left_wheel_radius_multiplier:.6f}, right_wheel_radius_multiplier "
        f"{final.right_wheel_radius_multiplier:.6f}.",
        markup=False,
        highlight=False,
    )

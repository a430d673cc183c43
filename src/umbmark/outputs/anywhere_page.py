"""The page of the self-calibration anywhere (``selfcal --routine anywhere``,
``OUT/report.html``): one self-contained HTML page, built from the same parts as the page
of UMBmark passes (:mod:`umbmark.outputs.html_parts`, the verdict's box, the estimates'
table, the figures of the fit).

Its sections: whether the correction was applied and what the controller holds; the
motion intervals of each drive of the pattern, matched and left out (by reason), used by
the fit and dropped as outliers, and the motion they hold; the fit (E_d, E_b, E_s, alpha,
beta, the wheels and the laser's mounting with their 95 % intervals, the correction);
the laser's mounting in the forms a user applies (:mod:`umbmark.outputs.mounting`) with
its difference from the stated one and a top view of both (inline SVG); the gyro, where
the robot has an IMU (what the wheels were calibrated against, its scale ``k_g`` and
bias with their intervals, ``E_b k_g`` without a laser, what is not determined); the
errors before and after (the verification's drive); the fit's figures, warnings and
notes; the ros2_control overlay; the provenance. Every text is escaped.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping
from dataclasses import dataclass, field
from html import escape
from typing import TYPE_CHECKING

from umbmark.core.version import __version__
from umbmark.outputs.html_parts import CSS, document, num, sentence, table

if TYPE_CHECKING:
    from umbmark.calibration.result import CalibrationResult
    from umbmark.estimators.gyro_result import GyroCalibration

__all__ = ["AnywherePage", "PatternPass", "anywhere_html"]


@dataclass(frozen=True)
class PatternPass:
    """One drive of the pattern, as the page shows it.

    Attributes
    ----------
    label : str
        ``pass 1`` or ``verification``.
    result : CalibrationResult
        Its calibration.
    tried : int
        Motion intervals cut from the drive.
    left_out : mapping of str to int
        Intervals that could not be scan matched, by reason.
    gyro : GyroCalibration or None
        The gyro's calibration (None: the robot has no IMU).
    """

    label: str
    result: CalibrationResult
    tried: int
    left_out: Mapping[str, int] = field(default_factory=dict)
    gyro: GyroCalibration | None = None


@dataclass(frozen=True)
class AnywherePage:
    """What the page of the self-calibration anywhere shows.

    Attributes
    ----------
    robot : str
    calibration : PatternPass
        The drive whose correction was applied (or not).
    verification : PatternPass or None
        The pattern driven again on the applied correction.
    applied : str
        What applying did, in one sentence.
    final : mapping of str to float
        The multipliers the controller holds at the end.
    checks : tuple of str
        What the checks before moving found.
    command : str or None
        The command line (None: made from Python).
    against : str
        What the wheels were calibrated against, for people.
    imu : str or None
        The IMU used, its topic and mounting (None: none).
    laser : bool
        Whether the robot has a laser (False: calibrated against the gyro alone).
    """

    robot: str
    calibration: PatternPass
    verification: PatternPass | None
    applied: str
    final: Mapping[str, float]
    checks: tuple[str, ...] = ()
    command: str | None = None
    created: dt.datetime = field(default_factory=lambda: dt.datetime.now(dt.timezone.utc))
    against: str = "the laser's scan matching"
    imu: str | None = None
    laser: bool = True


def _apply(page: AnywherePage) -> str:
    from umbmark.outputs.html_verdict import verdict_box

    result = page.calibration.result
    held = "".join(
        f"<tr><td>{escape(k)}</td><td>{v:.6f}</td></tr>\n" for k, v in page.final.items()
    )
    return (
        verdict_box(result.verdict, "Pass 1: ")
        + f'<p id="applied">{escape(page.applied)}</p>\n'
        + "<p>The controller holds at the end:</p>\n"
        + f'<div class="scroll"><table id="final"><tbody>\n{held}</tbody></table></div>\n'
    )


def _intervals(page: AnywherePage) -> str:
    if not page.laser:
        return (
            "<p>The robot has no laser: no motion intervals were scan matched. The drive "
            "was cut into intervals of rest and driving, the wheels against the gyro "
            '(below, <a href="#imu">the gyro</a>).</p>\n'
        )
    rows = []
    for one in (page.calibration, page.verification):
        if one is None:
            continue
        sensor = one.result.sensor
        left = ", ".join(f"{n} {why}" for why, n in sorted(one.left_out.items())) or "none"
        matched = one.tried - sum(one.left_out.values())
        used = "–" if sensor is None else str(sensor.n_used)
        dropped = "–" if sensor is None else str(len(sensor.kept) - sensor.n_used)
        motion = "–"
        if sensor is not None:
            e = sensor.excitation
            motion = (
                f"{e.n_spot} turns on the spot, {e.n_straight} straights, {e.n_arc} arcs; "
                f"{e.n_left} turning left, {e.n_right} right"
            )
        rows.append([one.label, str(one.tried), str(matched), left, used, dropped, motion])
    head = ["drive", "intervals cut", "matched", "left out (why)", "used by the fit",
            "dropped as outliers", "what they hold"]  # fmt: skip
    return (
        "<p>Each drive of the pattern is cut into motion intervals of 1 to 2 s; each is "
        "scan matched (the laser's own motion) and set against the wheels' rotation. "
        "Intervals that cannot be matched are left out (why, below); the fit drops the "
        "outliers among the rest.</p>\n" + table(head, rows, wrap={3, 6})
    )


def _fit(page: AnywherePage) -> str:
    from umbmark.outputs.html_estimates import estimate_section

    what = "the scan-matching calibration of Censi et al. 2013"
    if page.imu is not None:
        what = (
            "the wheels and the gyro against the laser's scan matching, together"
            if page.laser
            else "the wheels against the gyro alone: E_b is E_b k_g, relative to the gyro"
        )
    return (
        f"<p>The first drive's fit ({escape(what)}), against the parameters the controller "
        "ran with:</p>\n" + estimate_section(page.calibration.result)
    )


def _mounting(page: AnywherePage) -> str:
    from umbmark.outputs.mounting import mounting_forms, mounting_html

    forms = mounting_forms(page.calibration.result)
    if forms is None:  # without a laser: a calibration from intervals has a mounting
        return "<p>The robot has no laser: no mounting was fitted.</p>\n"
    return mounting_html(forms)


def _gyro(page: AnywherePage) -> str:
    """The gyro: what was used, its scale and bias, and what the wheels are relative to."""
    import math

    passes = [p for p in (page.calibration, page.verification) if p is not None and p.gyro]
    relative = not page.laser  # E_b k_g: what the wheels and the gyro alone give
    unknown = any(p.gyro is not None and p.gyro.undetermined for p in passes)
    head = ["drive", "k_g", "95 % interval", "bias [deg/s]", "95 % interval",
            *(["E_b k_g", "95 % interval"] if relative else []), "intervals (rests)",
            *(["not determined"] if unknown else [])]  # fmt: skip
    rows = []
    for one in passes:
        g = one.gyro
        assert g is not None

        def shown(name: str, fmt: str, scale: float = 1.0, g: GyroCalibration = g) -> list[str]:
            value, interval = g.get(name), g.interval(name)
            if value is None or interval is None:
                return ["no laser" if name == "k_g" and relative else "–", "–"]
            low, high = (scale * v for v in interval)
            return [format(scale * value, fmt), f"{low:{fmt}} to {high:{fmt}}"]

        rows.append([
            one.label, *shown("k_g", ".5f"), *shown("bias", ".4f", math.degrees(1.0)),
            *(shown("E_b_k_g", ".5f") if relative else []), f"{g.n_intervals} ({g.n_rests})",
            *(["; ".join(f"{n}: {why}" for n, why in g.undetermined.items()) or "none"]
              if unknown else []),
        ])  # fmt: skip
    first = page.calibration.gyro
    said = ""
    if first is not None and not page.laser:
        said = (
            f"<p>Without a laser the gyro's scale is not known: the wheelbase is relative to "
            f"it (E_b k_g), its interval widened by the gyro scale tolerance, "
            f"+-{100 * first.scale_tolerance:g} %. E_d does not depend on the gyro's scale. "
            "Apply with care at best; a laser (or motion capture) separates the two.</p>\n"
        )
    notes = [] if first is None else list(first.warnings)  # its mounting's notes among them
    wrap = {len(head) - 1} if unknown else set()
    return (
        f'<p id="gyro-used">The wheels were calibrated against {escape(page.against)}. '
        f"{escape(sentence(page.imu or 'no IMU'))}.</p>\n"
        + said
        + "<p>k_g is the factor that corrects the gyro, omega_true = k_g (omega_read - "
        "bias) (a driver's gyro scale); the bias is its mean over the drive, to subtract "
        "from the yaw rate (a driver's gyro offset).</p>\n"
        + f'<div id="gyro-table">{table(head, rows, wrap=wrap)}</div>'
        + "".join(f"<p>{escape(sentence(n))}.</p>\n" for n in notes)
    )


def _before_after(page: AnywherePage) -> str:
    before = page.calibration.result.estimate
    verification = page.verification
    after = None if verification is None else verification.result.estimate
    rows = []
    for name, meaning in (
        ("E_d", "D_R / D_L"),
        ("E_b", "b_actual / b_used"),
        ("E_s", "D_avg / D_used"),
    ):
        cells = []
        for est in (before, after):
            value = None if est is None else getattr(est, name)
            interval = None if est is None else est.interval(name)
            cells += [
                num(value, ".6f"),
                "–" if interval is None else f"{interval[0]:.6f} to {interval[1]:.6f}",
            ]
        rows.append([f"{name} = {meaning}", *cells])
    head = ["", "before", "95 % interval", "after", "95 % interval"]
    if verification is None:
        words = (
            "<p>No verification: the correction was not applied (or verifying was turned "
            "off), so the pattern was not driven again.</p>\n"
        )
    else:
        words = (
            "<p>After: the pattern driven again on the applied correction, calibrated the "
            "same way; what is left should be 1 within its interval. The verification's own "
            f"verdict (not applied): {escape(verification.result.verdict.words)}.</p>\n"
        )
    return (
        "<p>Before: the first drive, against the parameters it ran with.</p>\n"
        + f'<div id="before-after-table">{table(head, rows)}</div>'
        + words
    )


def _messages(page: AnywherePage) -> str:
    from umbmark.outputs.html_report import fit_messages

    out = "".join(f"<p>{escape(sentence(c))}.</p>\n" for c in page.checks)
    for one in (page.calibration, page.verification):
        if one is not None:
            out += f"<h3>{escape(one.label)}</h3>\n{fit_messages(one.result)}"
    return out


def _overlay(page: AnywherePage) -> str:
    from umbmark.outputs.html_verdict import WITHHELD

    result = page.calibration.result
    if result.overlay_withheld:
        return WITHHELD
    return (
        "<p>The correction of the first drive, composed with the values active during it "
        "(what <code>overlay.yaml</code> holds):</p>\n"
        f'<pre id="overlay-yaml">{escape(result.overlay_yaml())}</pre>\n'
    )


def _provenance(page: AnywherePage) -> str:
    result = page.calibration.result
    active = result.calibration.active
    rows = [
        ["active wheelbase [m]", f"{active.wheelbase:.6f}"],
        ["active wheel_separation_multiplier", f"{active.separation_multiplier:g}"],
        ["active c_L", f"{active.c_left:g}"],
        ["active c_R", f"{active.c_right:g}"],
        ["active wheel diameter [m]", num(active.wheel_diameter, "g")],
    ]
    files = [[one.label, src] for one in (page.calibration, page.verification)
             if one is not None for src in one.result.sources]  # fmt: skip
    created = page.created.astimezone(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    command = (
        f'<p>Command: <code id="command">{escape(page.command)}</code></p>\n'
        if page.command
        else ""
    )
    return (
        "<h3>Motion intervals (tuple files)</h3>\n"
        + table(["drive", "file"], files, wrap={1})
        + "<h3>Parameters active during the first drive</h3>\n"
        + table(["", ""], rows)
        + command
        + f"<p>Method: <code>{escape(result.estimate.method)}</code>; umbmark "
        f'<span id="umbmark-version">{escape(__version__)}</span>; made {created}.</p>\n'
    )


def anywhere_html(page: AnywherePage) -> str:
    """The self-calibration anywhere as one self-contained HTML page (the module's
    documentation: its sections)."""
    from umbmark.outputs.html_verdict import CSS as VERDICT_CSS
    from umbmark.outputs.mounting import CSS as MOUNTING_CSS

    title = f"{page.robot}: umbmark self-calibration anywhere"
    sections = [
        ("apply", "Apply the correction?", _apply(page)),
        ("intervals", "Motion intervals used and left out", _intervals(page)),
        ("fit", "The fit: estimates and 95 % intervals", _fit(page)),
        ("mounting", "The laser's mounting", _mounting(page)),
        *([("imu", "The gyro", _gyro(page))] if page.imu is not None else []),
        ("before-after", "Before and after", _before_after(page)),
        ("messages", "Checks, figures of the fit, warnings and notes", _messages(page)),
        ("overlay", "ros2_control overlay", _overlay(page)),
        ("provenance", "Provenance", _provenance(page)),
    ]
    return document(title, sections, f"{CSS}{VERDICT_CSS}{MOUNTING_CSS}")

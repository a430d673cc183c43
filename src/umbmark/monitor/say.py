"""What the monitor says at one moment: :func:`said`, its
:class:`~umbmark.monitor.status.MonitorStatus` (the figures, the level, one line)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from umbmark.monitor.course import Z95
from umbmark.monitor.status import FIGURES, ChangeFound, Figure, Level, MonitorStatus

if TYPE_CHECKING:
    from umbmark.monitor.core import Monitor

__all__ = ["change_line", "said"]


def change_line(change: ChangeFound, odometer: float) -> str:
    """One change for people: ``E_d changed by -0.0060 +- 0.0004 since 482.0 s, 41 m
    ago``."""
    sure = "" if change.confirmed else " (to be confirmed by the next stretch)"
    beyond = " beyond the tolerance" if change.beyond_tolerance else ""
    ago = max(0.0, odometer - change.since_metres)
    return (
        f"{change.figure} changed{beyond} by {change.size:+.4g} +- {change.size_half_width:.2g} "
        f"since {change.since:.1f} s, {ago:.0f} m ago{sure}"
    )


def _figures(monitor: Monitor) -> tuple[Figure, ...]:
    fit = monitor.window_estimate()
    out = []
    for name, unit in FIGURES:
        if fit is not None and name in fit.values:
            value, se = fit.values[name]
            out.append(Figure(name, value, Z95 * se, unit, fit.notes.get(name, "")))
            continue
        present = monitor.course.present(name)
        if present is not None and (fit is None or fit.intervals == 0):
            out.append(Figure(name, present[0], Z95 * present[1], unit, "from the course"))
            continue
        note = "no driving yet" if fit is None else fit.notes.get(name, "not determined")
        out.append(Figure(name, None, None, unit, note))
    return tuple(out)


def said(monitor: Monitor, now: float) -> MonitorStatus:
    """The monitor's status at ``now`` [s]."""
    s = monitor.setup
    figures = _figures(monitor)
    changes = monitor.changes()
    pending = [c for c in changes if c.confirmed and c.since_metres > monitor._applied_at_odometer]
    stale = monitor.arrivals.silent(now, s.inputs, s.stale_after) if monitor.arrivals.last else ()
    level: Level = "OK"
    if pending:
        level = "ERROR" if any(c.beyond_tolerance for c in pending) else "WARN"
    if stale:
        level = "STALE"
    lines = [change_line(c, monitor.odometer) for c in changes if c in pending or not c.confirmed]
    if stale:
        lines.insert(0, f"silent for more than {s.stale_after:g} s: {', '.join(stale)}")
    if not lines:
        lines.append(f"no change over {monitor.stretches} stretches of driving "
                     f"({monitor.odometer:.0f} m)")  # fmt: skip
    window = monitor.window_estimate()
    driving = window.driving if window is not None else None
    return MonitorStatus(
        time=now,
        robot=s.robot,
        level=level,
        message="; ".join(lines),
        figures=figures,
        metres=0.0 if driving is None else driving.metres,
        radians_left=0.0 if driving is None else driving.left,
        radians_right=0.0 if driving is None else driving.right,
        odometer=monitor.odometer,
        since=monitor._since,
        changes=changes,
        stale=stale,
        outliers=monitor.outliers,
        applied=monitor._applied_line,
    )

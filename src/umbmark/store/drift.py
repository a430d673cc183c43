"""Whether a robot's errors drift between its recorded calibrations.

A pass measures ``E_d`` and ``E_b`` relative to the odometry parameters active during it:
a pass on odometry already corrected by an earlier calibration measures what is left
after the correction (``E_b`` near 1), not the robot. What the robot *is* comes from
composing the measured errors with those parameters, the composition ``umbmark
calibrate`` makes for the new parameters (:class:`umbmark.calibration.compose.Calibration`):

- ``robot E_d = c_R,new / c_L,new = E_d c_R,active / c_L,active`` (Eqs. 4.31-4.32), the
  robot's ``D_R / D_L``;
- ``robot E_b = wheel_separation_multiplier,new = E_b x multiplier,active`` (Eq. 4.26),
  its effective wheelbase over the configured (nominal) one.

:func:`drift_verdict` follows those over every calibration, in time, with the course model
the fleet uses (:func:`umbmark.calibration.changes.change_of`): steady, changed in the
latest calibration (to be confirmed by the next), stepped at a calibration (confirmed),
trending, and one-offs left out, every judgement counting the calibrations' own scatter
(:attr:`CalibrationRecord.robot_E_d <umbmark.store.records.CalibrationRecord.robot_E_d>`).
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from umbmark.calibration.changes import Z_CHANGE, Change, change_of

#: z of a 95 % interval.
Z95 = 1.959964

if TYPE_CHECKING:
    from umbmark.store.records import CalibrationRecord

__all__ = ["DEFINITIONS", "DRIFT_MIN_CALIBRATIONS", "drift_verdict"]

#: Fewest calibrations the drift check needs (two are compared on their intervals).
DRIFT_MIN_CALIBRATIONS = 2

#: What a calibration's figures in the history mean (``history --json`` prints them).
DEFINITIONS = {
    "E_d": "measured by the pass: D_R / D_L relative to the odometry parameters active during it",
    "E_b": "measured by the pass: b_actual / b_effective relative to the odometry "
    "parameters active during it",
    "robot_E_d": "what the robot is: the pass's E_d composed with the active c_L, c_R "
    "(E_d c_R / c_L = the new c_R / c_L), the robot's D_R / D_L",
    "robot_E_b": "what the robot is: the pass's E_b composed with the active "
    "wheel_separation_multiplier (E_b x multiplier = the new multiplier), the robot's "
    "effective wheelbase over the nominal one",
    "robot_wheelbase": "the robot's effective wheelbase [m]: robot_E_b x nominal wheelbase",
    "k_g": "the gyro's scale a calibration with a gyro and an absolute heading found "
    "(omega_true = k_g (omega_read - bias)); followed over time like robot_E_d",
    "E_b_relative_to_gyro": "the calibration's E_b is relative to the gyro (E_b k_g, from "
    "wheels and gyro alone): left out of robot_E_b's course",
    "drift": f"robot_E_d and robot_E_b followed over every calibration in time (E_b on the "
    "last one's nominal wheelbase) as the fleet follows its figures: a change beyond "
    f"{Z_CHANGE:g} of its standard errors, scaled by the calibrations' own scatter, is drift "
    "(in the latest calibration alone: to be confirmed by the next)",
}


def _when(record: CalibrationRecord) -> float:
    """A calibration's time [s since 1970, UTC]."""
    when = dt.datetime.fromisoformat(record.time.replace("Z", "+00:00"))
    if when.tzinfo is None:
        when = when.replace(tzinfo=dt.timezone.utc)
    return when.timestamp()


def _said(name: str, change: Change, ids: Sequence[int], days: Sequence[str]) -> str:
    """One figure's course in words."""
    ci = f"± {Z95 * change.size_se:.1e}"
    if change.kind == "latest":
        before = change.value - change.size
        return (
            f"robot {name} changed in the latest calibration, {ids[-1]} ({days[-1]}): "
            f"{before:.6f} -> {change.value:.6f} ({change.size:+.2e} {ci}), against "
            f"{change.compared} before it; to be confirmed by the next"
        )
    if change.kind == "step" and change.since is not None:
        k = change.since
        return (
            f"robot {name} stepped from {change.value - change.size:.6f} to {change.value:.6f} "
            f"({change.size:+.2e} {ci}) at calibration {ids[k]} ({days[k]}), confirmed by "
            f"{change.confirmed_by}"
        )
    if change.kind == "trend":
        return (
            f"robot {name} trends by {change.size:+.2e} {ci} per week over {change.compared} "
            f"calibrations, now {change.value:.6f}"
        )
    return (
        f"robot {name} {change.value:.6f} ± {Z95 * change.se:.1e} over {change.compared} "
        f"calibrations ({ids[0]} to {ids[-1]})"
    )


def _follows(record: CalibrationRecord, name: str) -> bool:
    """Whether ``record`` is part of the course of ``name``: ``E_b`` not relative to the
    gyro, ``k_g`` where it found the gyro's scale."""
    if name == "E_b":
        return not record.relative_to_gyro
    if name == "k_g":
        return record.k_g is not None
    return True


def _figure(
    record: CalibrationRecord, name: str, last_nominal: float
) -> tuple[float, float | None]:
    """The robot's ``name`` of ``record`` and its standard error: ``E_b`` on the last
    nominal wheelbase, ``k_g`` as found (its error the fit's ``gyro_scale``)."""
    if name == "k_g":
        se = record.standard_errors.get("gyro_scale")
        return float(record.k_g or 0.0), None if se is None else float(se)
    scale = float(record.active["wheelbase"]) / last_nominal if name == "E_b" else 1.0
    se = record.robot_standard_errors.get(name)
    return float(getattr(record, f"robot_{name}")) * scale, None if se is None else se * scale


def drift_verdict(calibrations: Sequence[CalibrationRecord]) -> str | None:
    """Whether the robot's ``E_d`` or ``E_b`` (or its gyro's scale ``k_g``) drifted over
    its calibrations. ``E_b`` relative to the gyro (:attr:`~umbmark.store.records.
    CalibrationRecord.relative_to_gyro`) is left out of ``E_b``'s course, said so.

    It follows what the robot is, :attr:`~umbmark.store.history.CalibrationRecord.robot_E_d`
    and ``robot_E_b`` (each pass's measured errors composed with the parameters active
    during it), not what the passes measured: passes on corrected odometry measure what
    the correction left. Each is a series over the calibrations' times with their
    standard errors (the active parameters are exact), judged by
    :func:`umbmark.calibration.changes.change_of`; ``E_b`` of a robot whose nominal
    wheelbase was changed between calibrations (a fleet's) is put on the last nominal.

    Parameters
    ----------
    calibrations : sequence of CalibrationRecord
        A robot's calibrations (any order: they are taken by time).

    Returns
    -------
    str or None
        One line for people, starting ``drift:`` where a figure changed and ``no drift:``
        where none did; None with fewer than :data:`DRIFT_MIN_CALIBRATIONS`.
    """
    if len(calibrations) < DRIFT_MIN_CALIBRATIONS:
        return None
    ordered = sorted(calibrations, key=_when)
    times = np.array([_when(c) for c in ordered], dtype=np.float64)
    ids = [c.id for c in ordered]
    days = [dt.datetime.fromtimestamp(t, dt.timezone.utc).date().isoformat() for t in times]
    last_nominal = float(ordered[-1].active["wheelbase"])
    drifted: list[str] = []
    steady: list[str] = []
    unknown: list[str] = []
    one_offs: list[str] = []
    for name in ("E_d", "E_b", "k_g"):
        rows = [k for k, c in enumerate(ordered) if _follows(c, name)]
        if name != "E_d" and len(rows) < DRIFT_MIN_CALIBRATIONS:
            continue  # no gyro's scale; E_b of calibrations relative to the gyro alone
        values, errors = [], []
        for k in rows:
            value, se = _figure(ordered[k], name, last_nominal)
            values.append(value)
            errors.append(math.nan if se is None else se)
        if not all(math.isfinite(e) and e > 0 for e in errors):
            unknown.append(f"robot {name}")
            continue
        at = [ids[k] for k in rows]
        change = change_of(times[rows], np.array(values), np.array(errors))
        (drifted if change.changed else steady).append(
            _said(name, change, at, [days[k] for k in rows])
        )
        one_offs += [f"calibration {at[k]} in robot {name}" for k in change.one_offs]
    relative = [c.id for c in ordered if c.relative_to_gyro]
    if relative:
        steady.append(
            f"E_b of calibration{'s' if len(relative) > 1 else ''} "
            f"{', '.join(map(str, relative))} relative to the gyro (E_b k_g) left out of "
            "robot E_b"
        )
    parts = []
    if drifted:
        parts.append(f"drift: {'; '.join(drifted)}")
    if steady:
        parts.append(f"{'within noise' if drifted else 'no drift'}: {'; '.join(steady)}")
    if one_offs:
        parts.append(f"one-off, left out: {', '.join(one_offs)}")
    if unknown:
        parts.append(f"no standard errors to judge {', '.join(unknown)}")
    return ". ".join(parts)

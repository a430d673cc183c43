"""The monitor's stretches of driving in the calibration history (``umbmark monitor``).

Each stretch the monitor calibrated is recorded as the fleet records a recording
(:func:`umbmark.store.fleet_recordings.record_recording`): a calibration of its robot
(``umbmark history NAME`` lists it, with its drift) and a row of the fleet's recordings
whose outcome holds every figure (``umbmark fleet``'s summary follows the same course),
under the reading-options key :data:`MONITOR_KEY` and the path ``monitor:ROBOT/TIME``.
Its figures are relative to the parameters the controller ran with during it, as every
calibration's are (what the robot *is* is their composition with them: ``robot_E_d``),
and the monitor's own record (``record["monitor"]``: the robot's figures with their
standard errors, the odometer, the robot's clock) is what a monitor started again takes
its course up from (:func:`read_stretches`). No new table: the schema is unchanged.
"""

from __future__ import annotations

import datetime as dt
import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from umbmark.store.fleet_recordings import RecordingRow, record_recording
from umbmark.store.history import History
from umbmark.store.records import NewCalibration

__all__ = ["MONITOR_KEY", "StretchRecord", "read_stretches", "record_stretch", "relative_figures"]

#: The reading-options key of the monitor's rows (no recording file has it).
MONITOR_KEY = "monitor"


@dataclass(frozen=True)
class StretchRecord:
    """One stretch as the history keeps it.

    Attributes
    ----------
    robot : str
    method : str
        The estimator (``scan-matching``, or ``gyro`` without a laser).
    wall_start, wall_end : float
        Its span on the wall clock [s since 1970, UTC].
    time : float
        Its start on the robot's clock [s].
    odometer, end_odometer : float
        The monitor's odometer at its start and end [m].
    figures : dict of str to (float, float)
        What the robot is (relative to the nominal geometry, multipliers 1): each
        determined figure and its standard error.
    active : dict of str to float
        The controller's parameters during it: ``wheelbase``, ``wheel_diameter`` [m],
        ``c_L``, ``c_R``, ``wheel_separation_multiplier``.
    """

    robot: str
    method: str
    wall_start: float
    wall_end: float
    time: float
    odometer: float
    end_odometer: float
    figures: Mapping[str, tuple[float, float]]
    active: Mapping[str, float]


def relative_figures(
    figures: Mapping[str, tuple[float, float]], active: Mapping[str, float]
) -> dict[str, tuple[float, float]]:
    """The robot's figures relative to the active parameters (what a pass measures)."""
    c_l, c_r, sep = active["c_L"], active["c_R"], active["wheel_separation_multiplier"]
    out = dict(figures)
    if "E_d" in figures:
        v, s = figures["E_d"]
        out["E_d"] = (v * c_l / c_r, s * c_l / c_r)
    if "E_b" in figures:
        v, s = figures["E_b"]
        out["E_b"] = (v / sep, s / sep)
    if "E_s" in figures and "E_d" in out:
        rel_d = out["E_d"][0]
        scale = 0.5 * (c_l * 2.0 / (rel_d + 1.0) + c_r * 2.0 * rel_d / (rel_d + 1.0))
        v, s = figures["E_s"]
        out["E_s"] = (v / scale, s / scale)
    return out


def record_stretch(history: History, stretch: StretchRecord) -> int | None:
    """Record one stretch (the module's notes); its calibration's id, None where it
    determined neither ``E_d`` nor ``E_b`` (then only the fleet's row is written)."""
    start = dt.datetime.fromtimestamp(stretch.wall_start, dt.timezone.utc)
    path = f"monitor:{stretch.robot}/{start.strftime('%Y-%m-%dT%H:%M:%S.%fZ')}"
    relative = relative_figures(stretch.figures, stretch.active)
    errors = {k: s for k, (_, s) in relative.items()}
    active = {**stretch.active, "wheel_diameter": stretch.active.get("wheel_diameter")}
    calibration = None
    if "E_d" in relative and "E_b" in relative:
        calibration = NewCalibration(
            time=start, method=stretch.method, E_d=relative["E_d"][0], E_b=relative["E_b"][0],
            E_s=relative["E_s"][0] if "E_s" in relative else None, e_max_syst=None,
            standard_errors=errors, active=active, new={}, verdict={},
            wheelbase=float(stretch.active["wheelbase"]),
            wheel_diameter=stretch.active.get("wheel_diameter"),
        )  # fmt: skip
    hours = (stretch.wall_end - stretch.wall_start) / 3600.0
    monitor = {
        "figures": {k: list(v) for k, v in stretch.figures.items()},
        "time": stretch.time,
        "odometer": stretch.odometer,
        "end_odometer": stretch.end_odometer,
    }
    outcome: dict[str, Any] = {  # the keys of umbmark.fleets.outcome.RecordingOutcome
        "path": path, "robot": stretch.robot, "start": stretch.wall_start, "hours": hours,
        "digest": None, "status": "calibrated" if calibration else "left out",
        "method": stretch.method if calibration else None,
        "figures": {k: list(v) for k, v in relative.items()}, "e_max_syst": None,
        "multipliers": None, "verdict": None,
        "reason": None if calibration else "the stretch determined neither E_d nor E_b",
        "wheelbase": float(stretch.active["wheelbase"]), "named_by": None,
        "record": {"standard_errors": errors, "active": active, "new": {}, "verdict": {},
                   "wheel_diameter": stretch.active.get("wheel_diameter"),
                   "monitor": monitor},
    }  # fmt: skip
    row = RecordingRow(
        stretch.robot, path, None, path, MONITOR_KEY, stretch.wall_start, hours,
        "calibrated" if calibration else "left out", outcome["reason"], outcome,
    )  # fmt: skip
    return record_recording(history, row, calibration)


def read_stretches(history: History, robot: str, most: int) -> list[StretchRecord]:
    """The robot's last ``most`` stretches, oldest first (a monitor started again)."""
    with history.transaction() as db:
        rows = db.execute(
            "SELECT outcome FROM recordings WHERE robot = ? AND options_key = ? "
            "ORDER BY id DESC LIMIT ?",
            (robot, MONITOR_KEY, int(most)),
        ).fetchall()
    out = []
    for (text,) in reversed(rows):
        outcome = json.loads(text)
        record = outcome.get("record") or {}
        mine = record.get("monitor") or {}
        hours = float(outcome.get("hours") or 0.0)
        out.append(
            StretchRecord(
                robot,
                str(outcome.get("method") or ""),
                float(outcome["start"]),
                float(outcome["start"]) + 3600.0 * hours,
                float(mine.get("time", 0.0)),
                float(mine.get("odometer", 0.0)),
                float(mine.get("end_odometer", 0.0)),
                {k: (float(v[0]), float(v[1])) for k, v in (mine.get("figures") or {}).items()},
                dict(record.get("active") or {}),
            )
        )
    return out

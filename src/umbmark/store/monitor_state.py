"""What a robot's monitor keeps in the history besides its stretches
(:mod:`umbmark.store.monitor_stretches`): its state, and what it applied.

- **Its state** (the ``monitors`` table, schema 5): the odometer as the monitor last said it
  (the chunk in progress included) and the odometer at its last apply. A monitor started
  again, killed or not, takes them up: its odometer never goes back, and a change it
  applied before is not applied again.
- **What it applied**: a calibration of the robot (``umbmark history NAME`` lists it,
  marked applied): the robot's present state by its course (relative to the parameters
  active before, as every calibration's figures are), the new multipliers, the verdict;
  ``umbmark calibrate`` and ``selfcal`` then compose their passes with those multipliers
  (:func:`~umbmark.store.history.compose_last_applied`).
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from umbmark.store.history import History, utc_stamp
from umbmark.store.monitor_stretches import relative_figures
from umbmark.store.records import NewCalibration

__all__ = ["AppliedRecord", "MonitorState", "read_state", "record_applied", "save_state"]


@dataclass(frozen=True)
class MonitorState:
    """A robot's monitor as it last was.

    Attributes
    ----------
    odometer : float
        Its odometer as it last said it [m].
    applied_odometer : float or None
        Its odometer at its last apply [m]; None: it applied nothing.
    """

    odometer: float
    applied_odometer: float | None


def read_state(history: History, robot: str) -> MonitorState | None:
    """The robot's monitor's state, None where none was kept."""
    with history.transaction() as db:
        row = db.execute(
            "SELECT odometer, applied_odometer FROM monitors WHERE robot = ?", (robot,)
        ).fetchone()
    if row is None:
        return None
    return MonitorState(float(row[0]), None if row[1] is None else float(row[1]))


def save_state(history: History, robot: str, state: MonitorState) -> None:
    """Keep the robot's monitor's state (replacing the one kept)."""
    now = utc_stamp()
    with history.transaction(write=True) as db:
        db.execute(
            "INSERT INTO monitors (robot, odometer, applied_odometer, updated) "
            "VALUES (?, ?, ?, ?) ON CONFLICT(robot) DO UPDATE SET odometer = excluded.odometer, "
            "applied_odometer = excluded.applied_odometer, updated = excluded.updated",
            (robot, float(state.odometer), state.applied_odometer, now),
        )


@dataclass(frozen=True)
class AppliedRecord:
    """One apply of the monitor.

    Attributes
    ----------
    robot, method : str
        The robot; the estimator of its stretches (``scan-matching``, ``gyro``).
    wall : float
        When [s since 1970, UTC].
    odometer : float
        The monitor's odometer then [m].
    figures : dict of str to (float, float)
        The robot's present ``E_d``, ``E_b`` (``E_s``) by its course, what it *is*
        (relative to the nominal geometry), with their standard errors.
    active : dict of str to float
        The controller's parameters before: ``wheelbase``, ``wheel_diameter`` [m],
        ``c_L``, ``c_R``, ``wheel_separation_multiplier``.
    new : dict of str to float
        The multipliers applied: ``c_L``, ``c_R``, ``wheel_separation_multiplier``.
    verdict : dict
        The verdict on them (:meth:`umbmark.calibration.verdict.Verdict.to_dict`).
    how : str
        The apply path's line.
    """

    robot: str
    method: str
    wall: float
    odometer: float
    figures: Mapping[str, tuple[float, float]]
    active: Mapping[str, float]
    new: Mapping[str, float]
    verdict: Mapping[str, Any]
    how: str


def record_applied(history: History, applied: AppliedRecord) -> int:
    """Record the apply as a calibration of the robot, marked applied; its id."""
    relative = relative_figures(applied.figures, applied.active)
    new = {
        **applied.new,
        "left_wheel_radius_multiplier": applied.new["c_L"],
        "right_wheel_radius_multiplier": applied.new["c_R"],
        "wheelbase": applied.active["wheelbase"] * applied.new["wheel_separation_multiplier"],
    }
    when = dt.datetime.fromtimestamp(applied.wall, dt.timezone.utc)
    source = f"monitor:{applied.robot}/applied at {applied.odometer:.1f} m ({applied.how})"
    calibration = NewCalibration(
        time=when, method=applied.method, E_d=relative["E_d"][0], E_b=relative["E_b"][0],
        E_s=relative["E_s"][0] if "E_s" in relative else None, e_max_syst=None,
        standard_errors={k: s for k, (_, s) in relative.items()}, active=dict(applied.active),
        new=new, verdict=dict(applied.verdict), wheelbase=float(applied.active["wheelbase"]),
        wheel_diameter=applied.active.get("wheel_diameter"),
    )  # fmt: skip
    id = history.record(applied.robot, calibration, [source], digests={source: None},
                        same_nominal=False)  # fmt: skip
    history.mark_applied(applied.robot, id, override_verdict=True)
    return id

"""The history job: a robot's recorded calibrations and whether its errors drift.

:func:`history` is what ``umbmark history`` does; its report's
:meth:`~HistoryReport.to_dict` is what ``umbmark history --json`` prints.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any

from ..errors import InputError
from ..history_store import CalibrationRecord, History, RobotRecord

__all__ = ["HistoryReport", "history"]


@dataclass(frozen=True)
class HistoryReport:
    """The robots of a history file, or one robot's calibrations.

    Attributes
    ----------
    path : str
        The history file.
    robot : str or None
        The robot asked for; None to list the robots.
    robots : tuple of RobotRecord
        Every robot (when ``robot`` is None).
    calibrations : tuple of CalibrationRecord
        The robot's calibrations, oldest first.
    drift : str or None
        The drift verdict (3 calibrations or more).
    notes : tuple of str
    """

    path: str
    robot: str | None = None
    robots: tuple[RobotRecord, ...] = ()
    calibrations: tuple[CalibrationRecord, ...] = ()
    drift: str | None = None
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres): what ``history --json`` prints."""
        if self.robot is None:
            return {"history": self.path, "robots": [r.to_dict() for r in self.robots]}
        out: dict[str, Any] = {
            "robot": self.robot,
            "history": self.path,
            "calibrations": [c.to_dict() for c in self.calibrations],
            "drift": self.drift,
        }
        if self.notes:
            out["notes"] = list(self.notes)
        return out

    def to_json(self) -> str:
        """The JSON text of :meth:`to_dict`."""
        return json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"


def history(
    robot: str | None = None,
    *,
    history: str | os.PathLike[str] | None = None,
    applied: int | None = None,
) -> HistoryReport:
    """The robots of a history file, or one robot's calibrations and drift verdict.

    Parameters
    ----------
    robot : str, optional
        The robot; None lists the robots.
    history : path, optional
        The history file (default: ``$UMBMARK_HISTORY``, else the per-user file).
    applied : int, optional
        Mark this calibration of ``robot`` as applied first.

    Returns
    -------
    HistoryReport

    Raises
    ------
    InputError
        For an unknown robot or calibration, or a file that is not a history.
    """
    store = History(history)
    path = str(store.path)
    if robot is None:
        if applied is not None:
            raise InputError("--applied needs the robot's NAME")
        return HistoryReport(path=path, robots=tuple(store.robots()))
    if store.robot(robot) is None:
        known = ", ".join(r.name for r in store.robots()) or "none yet"
        raise InputError(f"no robot {robot!r} in the history (robots: {known})", source=path)
    notes: tuple[str, ...] = ()
    if applied is not None:
        store.mark_applied(robot, applied)
        notes = (f"calibration {applied} of {robot} marked applied",)
    calibrations = tuple(store.calibrations(robot))
    return HistoryReport(
        path=path,
        robot=robot,
        calibrations=calibrations,
        drift=store.drift(robot),
        notes=notes,
    )

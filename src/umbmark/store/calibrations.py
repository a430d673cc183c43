"""A calibration and a robot's history: the robot's last applied calibration taken as the
parameters active during the runs (:func:`~umbmark.store.history.compose_last_applied`),
a result refused for another robot (:func:`same_robot`), and the result recorded with the
line saying so (:func:`recorded`).

``umbmark calibrate --robot NAME`` and the self-calibration's passes record their
calibrations through here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TypeVar

from umbmark.calibration.result import CalibrationResult
from umbmark.runs.read import RunSource, source_name
from umbmark.store.history import History
from umbmark.store.records import NewCalibration

__all__ = ["history_entry", "recorded", "same_robot"]

Result = TypeVar("Result", bound=CalibrationResult)


def same_robot(result: Result, store: History, robot: str, composed: str | None) -> Result:
    """Refuse a result of another robot than the history's ``robot``; note what was
    composed from its last applied calibration (``composed``)."""
    active = result.calibration.active
    store.check_identity(robot, active.wheelbase, active.wheel_diameter)
    return result if composed is None else replace(result, notes=(*result.notes, composed))


def recorded(
    result: Result,
    store: History,
    robot: str,
    sources: Sequence[RunSource],
    override_verdict: bool,
) -> Result:
    """The result, recorded in the history, with the line saying so."""
    inputs = [n for n in map(source_name, sources) if n != "runs"]
    id = store.record(robot, history_entry(result), inputs)
    said = store.recorded_line(robot, id, result.verdict, overridden=override_verdict)
    return replace(result, recorded=said)


def history_entry(result: CalibrationResult) -> NewCalibration:
    """What the history records of a calibration."""
    data = result.to_dict()
    active = result.calibration.active
    return NewCalibration(
        time=result.created,
        method=data["method"],
        E_d=data["E_d"],
        E_b=data["E_b"],
        E_s=data["E_s"],
        e_max_syst=data["e_max_syst"],
        standard_errors=data["standard_errors"],
        active=data["active"],
        new=data["new"],
        verdict=data["apply"],
        wheelbase=active.wheelbase,
        wheel_diameter=active.wheel_diameter,
    )

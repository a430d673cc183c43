"""A calibration and a robot's history: the robot's last applied calibration taken as the
parameters active during the runs (:func:`~umbmark.store.history.compose_last_applied`),
a result refused for another robot (:func:`same_robot`), and the result recorded with the
line saying so (:func:`recorded`).

``umbmark calibrate --robot NAME`` and the self-calibration's passes record their
calibrations through here.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import replace
from typing import TypeVar

from umbmark.calibration.result import CalibrationResult
from umbmark.calibration.sources import calibrate_sources
from umbmark.runs.read import RunSource, source_name
from umbmark.runs.read_options import ReadOptions, SourceOptions
from umbmark.store.history import History, compose_last_applied
from umbmark.store.records import NewCalibration

__all__ = ["calibrate_recorded", "history_entry", "recorded", "same_robot"]

Result = TypeVar("Result", bound=CalibrationResult)


def calibrate_recorded(
    sources: Sequence[RunSource],
    options: SourceOptions,
    *,
    robot: str | None = None,
    history: str | os.PathLike[str] | None = None,
    method: str | None = None,
    wheelbase: float | None = None,
) -> CalibrationResult:
    """The calibration of ``sources`` as ``umbmark calibrate --robot`` makes it, without
    its files: with ``robot``, the robot's last applied calibration taken as active where
    the options say nothing of it, a result of another robot refused, and the result
    recorded in ``history`` (the self-calibration's passes)."""
    if robot is None:
        return calibrate_sources(
            sources, ReadOptions.of(options), method=method, wheelbase=wheelbase
        )
    store = History(history)
    options, composed = compose_last_applied(store, robot, options)
    found = calibrate_sources(sources, ReadOptions.of(options), method=method, wheelbase=wheelbase)
    found = same_robot(replace(found, robot=robot), store, robot, composed)
    return recorded(found, store, robot, sources, False)


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
        verdict=data["verdict"],
        wheelbase=active.wheelbase,
        wheel_diameter=active.wheel_diameter,
        controller=data["controller"],
    )

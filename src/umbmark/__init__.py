"""umbmark: measure and correct the systematic odometry errors of differential-drive robots.

Implements Borenstein & Feng (1996), *Measurement and Correction of Systematic Odometry
Errors in Mobile Robots* (UMBmark), and goes past it.

Every command is a function here, with the command's options as keywords (lengths in
metres, angles in radians, times in seconds) and a report as its result::

    import umbmark

    report = umbmark.calibrate("runs.csv", side_length=4, wheelbase=0.34, unit="mm")
    report.e_max_syst            # [m], Eq. 3.4
    report.estimate.E_d          # D_R / D_L
    report.calibration.new_c_left
    print(report.overlay_yaml())  # the ros2_control overlay
    report.to_dict()             # exactly what `umbmark calibrate --json` prints

Bad input raises :class:`InputError` (a ``ValueError``): the one line the command prints,
naming the options as keywords (``unit="mm"`` where the command says ``--unit mm``); a
keyword a function does not take raises ``TypeError`` naming the close one. The names
below are imported on first use, so that ``import umbmark`` (and ``umbmark --help``) stay
fast. Conventions (frame, signs, units) are in
:mod:`umbmark.core.conventions`.
"""

from __future__ import annotations

import importlib
import inspect
from typing import TYPE_CHECKING

from umbmark.core.version import __version__

_EXPORTS = {
    # jobs: one function per command, and their reports
    "calibrate": "umbmark.jobs.calibrate",
    "replay": "umbmark.jobs.replay",
    "report": "umbmark.jobs.report",
    "PassesReport": "umbmark.jobs.report",
    "info": "umbmark.jobs.info",
    "history": "umbmark.jobs.history",
    "HistoryReport": "umbmark.jobs.history",
    "fleet": "umbmark.jobs.fleet",
    "simulate_fleet": "umbmark.jobs.simulate_fleet",
    "FleetSimulation": "umbmark.jobs.simulate_fleet",
    "FleetReport": "umbmark.jobs.fleet",
    "monitor_sim": "umbmark.jobs.monitor",
    "MonitorSimReport": "umbmark.jobs.monitor",
    "History": "umbmark.store.history",
    "plan": "umbmark.jobs.plan",
    "PlanReport": "umbmark.calibration.plan",
    "validate": "umbmark.jobs.validate",
    "study": "umbmark.jobs.study",
    "StudyReport": "umbmark.jobs.study",
    "ValidationReport": "umbmark.calibration.validation",
    "simulate": "umbmark.jobs.simulate",
    "demo": "umbmark.jobs.demo",
    "reproduce_table1": "umbmark.jobs.reproduce",
    "reproduce_fig4": "umbmark.jobs.reproduce",
    "example": "umbmark.jobs.example",
    "example_sessions": "umbmark.jobs.example",
    "CalibrationReport": "umbmark.outputs.calibration",
    "ReplayReport": "umbmark.jobs.replay",
    "InfoReport": "umbmark.jobs.info",
    "SimulationReport": "umbmark.jobs.simulate",
    "SimSetup": "umbmark.sim.setup",
    "DemoReport": "umbmark.jobs.demo",
    "SourceOptions": "umbmark.runs.read_options",
    # the robot calibrates itself (the paper's Sec. 6)
    "selfcal": "umbmark.jobs.selfcal",
    "SelfCalReport": "umbmark.jobs.selfcal",
    "SelfcalSetup": "umbmark.routines.setup",
    "AnywhereReport": "umbmark.jobs.selfcal_anywhere",
    "VirtualRobot": "umbmark.robot.virtual",
    "Robot": "umbmark.robot.base",
    "connect": "umbmark.robot.connect",
    "InputError": "umbmark.core.errors",
    # building blocks
    "ActiveParams": "umbmark.model.active",
    "Benchmark": "umbmark.returns.clusters",
    "Calibration": "umbmark.calibration.compose",
    "Direction": "umbmark.core.conventions",
    "EndPose": "umbmark.model.run",
    "ErrorEstimate": "umbmark.estimators.base",
    "Run": "umbmark.model.run",
    "SquareTest": "umbmark.estimators.base",
    "WheelParams": "umbmark.model.kinematics",
    "estimate_errors": "umbmark.estimators.dispatch",
    "integrate_odometry": "umbmark.model.kinematics",
    "read_runs_table": "umbmark.sources.runs_table.reader",
    "umbmark_benchmark": "umbmark.returns.clusters",
}

__all__ = [
    "ActiveParams",
    "AnywhereReport",
    "Benchmark",
    "Calibration",
    "CalibrationReport",
    "DemoReport",
    "Direction",
    "EndPose",
    "ErrorEstimate",
    "FleetReport",
    "FleetSimulation",
    "History",
    "HistoryReport",
    "InfoReport",
    "InputError",
    "MonitorSimReport",
    "PassesReport",
    "PlanReport",
    "ReplayReport",
    "Robot",
    "Run",
    "SelfCalReport",
    "SelfcalSetup",
    "SimSetup",
    "SimulationReport",
    "SourceOptions",
    "SquareTest",
    "StudyReport",
    "ValidationReport",
    "VirtualRobot",
    "WheelParams",
    "__version__",
    "calibrate",
    "connect",
    "demo",
    "estimate_errors",
    "example",
    "example_sessions",
    "fleet",
    "history",
    "info",
    "integrate_odometry",
    "monitor_sim",
    "plan",
    "read_runs_table",
    "replay",
    "report",
    "reproduce_fig4",
    "reproduce_table1",
    "selfcal",
    "simulate",
    "simulate_fleet",
    "study",
    "umbmark_benchmark",
    "validate",
]

if TYPE_CHECKING:
    from umbmark.calibration.compose import Calibration
    from umbmark.calibration.plan import PlanReport
    from umbmark.calibration.validation import ValidationReport
    from umbmark.core.conventions import Direction
    from umbmark.core.errors import InputError
    from umbmark.estimators.base import ErrorEstimate, SquareTest
    from umbmark.estimators.dispatch import estimate_errors
    from umbmark.jobs.calibrate import calibrate
    from umbmark.jobs.demo import DemoReport, demo
    from umbmark.jobs.example import example, example_sessions
    from umbmark.jobs.fleet import FleetReport, fleet
    from umbmark.jobs.history import HistoryReport, history
    from umbmark.jobs.info import InfoReport, info
    from umbmark.jobs.monitor import MonitorSimReport, monitor_sim
    from umbmark.jobs.plan import plan
    from umbmark.jobs.replay import ReplayReport, replay
    from umbmark.jobs.report import PassesReport, report
    from umbmark.jobs.reproduce import reproduce_fig4, reproduce_table1
    from umbmark.jobs.selfcal import SelfCalReport, selfcal
    from umbmark.jobs.selfcal_anywhere import AnywhereReport
    from umbmark.jobs.simulate import SimulationReport, simulate
    from umbmark.jobs.simulate_fleet import FleetSimulation, simulate_fleet
    from umbmark.jobs.study import StudyReport, study
    from umbmark.jobs.validate import validate
    from umbmark.model.active import ActiveParams
    from umbmark.model.kinematics import WheelParams, integrate_odometry
    from umbmark.model.run import EndPose, Run
    from umbmark.outputs.calibration import CalibrationReport
    from umbmark.returns.clusters import Benchmark, umbmark_benchmark
    from umbmark.robot.base import Robot
    from umbmark.robot.connect import connect
    from umbmark.robot.virtual import VirtualRobot
    from umbmark.routines.setup import SelfcalSetup
    from umbmark.runs.read_options import SourceOptions
    from umbmark.sim.setup import SimSetup
    from umbmark.sources.runs_table.reader import read_runs_table
    from umbmark.store.history import History


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'umbmark' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    if inspect.isfunction(value):
        # Called from Python: a misspelt keyword is a TypeError naming the close one, and
        # an InputError names options as keywords (unit="mm"), not as flags (--unit mm).
        from umbmark.core.errors import python_api

        value = python_api(value)
    globals()[name] = value  # imported once
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))

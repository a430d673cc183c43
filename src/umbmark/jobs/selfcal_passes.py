"""The self-calibration's passes: driven, recorded and calibrated one at a time
(:class:`PassDriver`), applied (:func:`apply_pass`), what the controller holds after them
(:func:`holds_of`), and those of a routine stopped for a controller restart
(:func:`resumed_passes`). The routine itself is :func:`umbmark.jobs.selfcal.selfcal`."""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

from umbmark.calibration.passes import Holds
from umbmark.core.conventions import Direction
from umbmark.jobs.selfcal_report import PassResult
from umbmark.outputs.calibration import CalibrationReport
from umbmark.robot.base import ApplyMethod, ApplyResult, DriveParams, Robot
from umbmark.routines.drive import DriveLimits
from umbmark.routines.measure import Measure
from umbmark.routines.passes import Home, drive_pass, strays
from umbmark.routines.preflight import check_side
from umbmark.routines.record import MeasuredRun, pass_folder, record_pass, return_error
from umbmark.routines.resume import SelfCalState
from umbmark.routines.watch import Watch
from umbmark.runs.read_options import SourceOptions

__all__ = ["PassDriver", "apply_pass", "controller_options", "holds_of", "resumed_passes"]


def controller_options(controller: str | None) -> SourceOptions:
    """The reading options that key a pass's calibration by ``controller`` (none: the
    default, said so)."""
    return {} if controller is None else {"controller": controller}


def resumed_passes(
    folder: Path, state: SelfCalState, controller: str | None = None
) -> list[PassResult]:
    """The passes a stopped self-calibration drove, their parameters now applied."""
    from umbmark.store.calibrations import calibrate_recorded

    out = []
    for label, where, params in state.passes:
        found = calibrate_recorded([folder / where], controller_options(controller))
        report = CalibrationReport.of(found)
        out.append(PassResult(label, folder / where, report, params))
    if out:
        out[-1] = replace(
            out[-1], applied=ApplyResult("yaml", True, "applied by the controller's restart")
        )
    return out


@dataclass(frozen=True)
class PassDriver:
    """Drives, records and calibrates one pass at a time."""

    robot: Robot
    how: Measure
    folder: Path
    side: float
    runs: int
    limits: DriveLimits
    name: str
    watch: Watch
    record_as: str | None = None
    history: str | os.PathLike[str] | None = None
    kept: bool = True
    controller: str | None = None

    def __call__(self, label: str, home: Home) -> PassResult:
        from umbmark.store.calibrations import calibrate_recorded

        params = self.robot.drive_params()
        check_side(self.side, params)  # a correction applied may have moved the limit

        def said(k: int, direction: Direction, what: str) -> None:
            self.watch.status(label, k, direction, what)

        def ran(k: int, direction: Direction, run: MeasuredRun) -> None:
            self.watch.run_measured(label, k, direction, return_error(run))

        measured = drive_pass(
            self.robot, self.how, self.side, self.runs, home, self.limits, said, ran
        )
        where = pass_folder(self.folder, label)
        record_pass(where, measured, params, self.side, self.how.method, self.name)
        found = calibrate_recorded(
            [where], controller_options(self.controller), robot=self.record_as,
            history=self.history,
        )  # fmt: skip
        report = CalibrationReport.of(found)
        return PassResult(label, where, report, params, warnings=strays(measured, self.limits))

    def mark_applied(self, result: PassResult) -> None:
        """Mark the pass's calibration applied in the history (it was recorded last)."""
        if self.record_as is None or result.applied is None or not result.applied.active:
            return
        from umbmark.store.history import History

        store = History(self.history)
        (last,) = store.calibrations(self.record_as)[-1:]
        store.mark_applied(self.record_as, last.id)


def apply_pass(
    robot: Robot, result: PassResult, method: ApplyMethod
) -> tuple[PassResult, DriveParams]:
    """Apply the pass's correction, composed with its active parameters, unless the
    verdict says not to or ``method`` is ``none``; the corrected parameters."""
    if method == "none" or not result.report.verdict.applies:
        return result, result.params
    calibration = result.report.calibration
    new = replace(
        result.params,
        wheel_separation_multiplier=calibration.new_separation_multiplier,
        left_wheel_radius_multiplier=calibration.new_c_left,
        right_wheel_radius_multiplier=calibration.new_c_right,
    )
    return replace(result, applied=robot.apply(new, method)), new


def holds_of(passes: list[PassResult], final: DriveParams, coarse: float | None = None) -> Holds:
    """What the controller holds: the last pass applied (passes are applied in order until
    one is not), how each was applied, the multipliers the controller reports and the
    factor of a coarse turning correction applied before the first pass."""
    active = [p.applied is not None and p.applied.active for p in passes]
    applied = [k for k, on in enumerate(active, 1) if on]
    return Holds(
        labels=tuple(p.label for p in passes),
        held=applied[-1] if applied else None,
        separation_multiplier=final.wheel_separation_multiplier,
        c_left=final.left_wheel_radius_multiplier,
        c_right=final.right_wheel_radius_multiplier,
        methods=tuple(
            p.applied.method if on and p.applied is not None else None
            for p, on in zip(passes, active, strict=True)
        ),
        coarse=coarse,
    )

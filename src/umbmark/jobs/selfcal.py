"""The self-calibration job (the paper's Sec. 6): the robot drives UMBmark by itself,
measures where it stopped against an L-shaped corner, calibrates, applies the correction
and checks it.

:func:`selfcal` is what ``umbmark selfcal`` does; its report's :meth:`SelfCalReport.to_dict`
is what ``umbmark selfcal --json`` prints. The steps:

1. checks before anything moves: the odometry is alive, the controller answers, the corner
   is found (the first fix is the start of every run), the floor of both squares is free;
2. a coarse turning check (:mod:`umbmark.autocal.coarse`), corrected when the robot turns
   far from what its odometry believes, so that a square is possible at all;
3. a UMBmark pass: ``runs`` cw then ``runs`` ccw runs, each from the start, recorded as a
   run log in ``out/pass-N`` (what ``umbmark calibrate``, ``report`` and ``replay`` read);
4. the calibration (:func:`umbmark.calibrate`, the default estimator), composed with the
   parameters active during the pass;
5. applying it (unless its verdict is "do not apply");
6. further passes while the paper's 3 x SEM rule says another is worth it, at most
   ``max_passes``;
7. a verification pass on the final parameters;
8. the history entry (``robot_name``), the HTML report of all passes and the overlay.

What a person still does: place the robot in the corner, and calibrate the scale error
``E_s`` with a tape (``docs/driving.md``): UMBmark cannot see it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.autocal.coarse import CoarseTurning, coarse_turning
from umbmark.autocal.corner_sensors import TapeMarks
from umbmark.autocal.drive import DriveLimits, settle
from umbmark.autocal.measure import MEASURE_METHODS, Measure, MeasureMethod, take_fix
from umbmark.autocal.passes import Home, corner_truth, drive_pass
from umbmark.autocal.preflight import preflight
from umbmark.autocal.record import MeasuredRun, record_pass
from umbmark.autocal.resume import SelfCalState, pending_problem, read_state, write_state
from umbmark.core.conventions import Direction, wrap_angle
from umbmark.core.errors import InputError
from umbmark.core.jsontext import JsonText
from umbmark.robot.base import APPLY_METHODS, ApplyMethod, ApplyResult, DriveParams, Robot

if TYPE_CHECKING:
    from umbmark.jobs.calibrate import CalibrationReport

__all__ = ["MAX_SELFCAL_PASSES", "PassResult", "SelfCalReport", "selfcal"]

#: Most UMBmark passes one self-calibration drives (verification not counted).
MAX_SELFCAL_PASSES = 5
#: Most runs per direction in a pass.
MAX_SELFCAL_RUNS = 20

#: Live progress: (pass label, run number, direction, what) for a terminal.
Progress = Callable[[str, int, Direction | None, str], None]


@dataclass(frozen=True)
class PassResult:
    """One UMBmark pass of the self-calibration.

    Attributes
    ----------
    label : str
        ``pass 1``, ``pass 2``, ..., ``verification``.
    folder : Path
        Its run log.
    report : CalibrationReport
        Its calibration (composed with the parameters active during it).
    params : DriveParams
        The parameters the controller ran with during the pass.
    applied : ApplyResult or None
        What applying its correction did (None: not applied).
    warnings : tuple of str
        Runs whose odometry did not end where it was sent (the benchmark assumes the
        robot follows the square by its odometry).
    """

    label: str
    folder: Path
    report: CalibrationReport
    params: DriveParams
    applied: ApplyResult | None = None
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (metres, radians)."""
        estimate = self.report.estimate
        return {
            "label": self.label,
            "folder": str(self.folder),
            "e_max_syst": self.report.e_max_syst,
            "E_d": estimate.E_d,
            "E_b": estimate.E_b,
            "verdict": self.report.verdict.words,
            "active": _multipliers(self.params),
            "applied": None if self.applied is None else self.applied.active,
            "apply_method": None if self.applied is None else self.applied.method,
            "apply_message": None if self.applied is None else self.applied.message,
            "warnings": list(self.warnings),
        }


@dataclass(frozen=True)
class SelfCalReport(JsonText):
    """What a self-calibration did and found.

    Attributes
    ----------
    robot : str
        The robot's name.
    side_length : float
        The square's side [m].
    measurement : str
        ``lidar``, ``ranges``, ``truth`` or ``tape``.
    coarse : CoarseTurning or None
        The coarse turning check (None: not made).
    coarse_applied : ApplyResult or None
    passes : tuple of PassResult
        The UMBmark passes, the verification last.
    final : DriveParams
        The parameters the controller holds at the end.
    fix_errors : array, shape (k, 3), or None
        Each fix's error against the truth (a virtual robot): ``x, y`` [m], heading [rad].
    checks : tuple of str
        What the checks before moving found.
    files : tuple of Path
        Files written.
    restart : str or None
        The routine stopped for a controller restart: what to do, and how to go on
        (``umbmark selfcal --resume DIR``).
    """

    robot: str
    side_length: float
    measurement: str
    coarse: CoarseTurning | None
    coarse_applied: ApplyResult | None
    passes: tuple[PassResult, ...]
    final: DriveParams
    fix_errors: np.ndarray | None = None
    checks: tuple[str, ...] = ()
    files: tuple[Path, ...] = field(default=(), compare=False)
    restart: str | None = None

    @property
    def e_max_syst_before(self) -> float | None:
        """E_max,syst of the first pass [m]."""
        return self.passes[0].report.e_max_syst if self.passes else None

    @property
    def e_max_syst_after(self) -> float | None:
        """E_max,syst of the last pass (the verification, if driven) [m]; None when only
        one pass was driven (nothing after a correction)."""
        return self.passes[-1].report.e_max_syst if len(self.passes) > 1 else None

    def measurement_errors(self) -> tuple[float, float] | None:
        """RMS position [m] and heading [rad] error of the fixes against the truth."""
        if self.fix_errors is None or self.fix_errors.size == 0:
            return None
        e = self.fix_errors
        position = float(np.sqrt(np.mean(e[:, 0] ** 2 + e[:, 1] ** 2)))
        return position, float(np.sqrt(np.mean(e[:, 2] ** 2)))

    def to_dict(self) -> dict[str, Any]:
        """What ``umbmark selfcal --json`` prints (metres, radians)."""
        measurement: dict[str, Any] = {"method": self.measurement}
        errors = self.measurement_errors()
        if errors is not None:
            measurement["rms_position_error"] = errors[0]
            measurement["rms_heading_error"] = errors[1]
            measurement["fixes"] = int(self.fix_errors.shape[0])  # type: ignore[union-attr]
        return {
            "robot": self.robot,
            "side_length": self.side_length,
            "checks": list(self.checks),
            "coarse": None if self.coarse is None else self.coarse.to_dict(),
            "passes": [p.to_dict() for p in self.passes],
            "e_max_syst_before": self.e_max_syst_before,
            "e_max_syst_after": self.e_max_syst_after,
            "applied": _multipliers(self.final),
            "measurement": measurement,
            "files": [str(f) for f in self.files],
            "restart": self.restart,
        }


def _multipliers(params: DriveParams) -> dict[str, float]:
    return {
        "wheel_separation_multiplier": params.wheel_separation_multiplier,
        "left_wheel_radius_multiplier": params.left_wheel_radius_multiplier,
        "right_wheel_radius_multiplier": params.right_wheel_radius_multiplier,
    }


def _check_counts(side_length: float, runs: int, max_passes: int) -> None:
    if not (0.5 <= side_length <= 20.0):
        raise InputError(f"--side-length {side_length!r} m: give 0.5 to 20 m")
    if not (2 <= runs <= MAX_SELFCAL_RUNS):
        raise InputError(f"--runs {runs!r}: give 2 to {MAX_SELFCAL_RUNS} per direction")
    if not (1 <= max_passes <= MAX_SELFCAL_PASSES):
        raise InputError(f"--max-passes {max_passes!r}: give 1 to {MAX_SELFCAL_PASSES}")


def selfcal(
    robot: Robot,
    *,
    side_length: float = 4.0,
    runs: int = 5,
    measure: MeasureMethod = "lidar",
    apply: bool | ApplyMethod = True,
    verify: bool = True,
    max_passes: int = 3,
    robot_name: str | None = None,
    history: str | os.PathLike[str] | None = None,
    out: str | os.PathLike[str] | None = None,
    report: str | os.PathLike[str] | None = None,
    progress: Progress | None = None,
    limits: DriveLimits | None = None,
    ask: Callable[[str], str] | None = None,
    tape_marks: Sequence[float] | None = None,
    coarse: bool = True,
    resume: str | os.PathLike[str] | None = None,
    notify: Callable[[str], None] | None = None,
) -> SelfCalReport:
    """Calibrate ``robot`` by itself: UMBmark driven by its odometry, measured at the
    corner, applied and verified (module documentation).

    Parameters
    ----------
    robot : Robot
        Placed at the start, in view of the L-shaped corner.
    side_length, runs : float, int
        The square's side [m] and runs per direction (5 in the paper).
    measure : {"lidar", "ranges", "truth", "tape"}
        How the fixes are taken (``tape``: a person answers ``ask`` at each stop).
    apply : bool or {"reconfigure", "yaml", "none"}
        How corrections reach the controller: ``True`` is ``reconfigure`` (at once, as
        dynamic_reconfigure does), ``yaml`` writes the controller's parameter file,
        ``False`` or ``none`` applies nothing (one pass).
    verify : bool
        Drive a verification pass on the final parameters.
    max_passes : int
        Most UMBmark passes before the verification.
    robot_name, history : optional
        Record every pass in the robot's history (SQLite) and mark the applied ones.
    out : path, optional
        Folder for the run logs, the report and the overlay [default: ``selfcal-<robot>``].
    report : path, optional
        The HTML page of all passes [default: ``report.html`` in ``out``].
    limits : DriveLimits, optional
        Speeds, accelerations and safety limits.
    ask : callable, optional
        For ``tape``: shows a prompt, returns the person's answer.
    tape_marks : six floats, optional
        For ``tape``: ``x1, y1, x2, y2, x3, y3`` [m], the marks on the robot (its base
        frame) the distances are measured from, the first two to the wall behind the
        start, the third to the side wall [default: the robot's ``tape_marks()``].
    coarse : bool
        Check first that the robot turns as its odometry believes (lidar or truth).
    resume : path, optional
        The folder of a self-calibration stopped for a controller restart: go on with its
        settings (the ones given here are not used), once the controller holds the
        parameters it stopped on (:mod:`umbmark.autocal.resume`).
    notify : callable, optional
        Lines for a person, as they happen (the robot cannot take parameters live, ...).

    Raises
    ------
    InputError
        Bad options, or a check before moving failed (with the cause).
    umbmark.core.errors.SafetyError
        The robot was stopped for safety (a zero velocity was the last command).
    """
    state = None
    if resume is not None:
        state = read_state(Path(resume))
        s = state.settings
        side_length, runs, measure = s["side_length"], s["runs"], s["measure"]
        max_passes, verify, out, coarse = s["max_passes"], s["verify"], resume, False
    _check_counts(side_length, runs, max_passes)
    if measure not in MEASURE_METHODS:
        raise InputError(f"--measure {measure!r}: use one of {', '.join(MEASURE_METHODS)}")
    method = _apply_method(apply)
    limits = limits or DriveLimits()
    marks = _tape_marks(robot, tape_marks) if measure == "tape" else None
    how = Measure(measure, ask=ask, marks=marks)
    name = robot_name or robot.name
    folder = Path(out) if out is not None else Path(f"selfcal-{_slug(name)}")
    if state is None and folder.exists() and any(folder.iterdir()):
        raise InputError("is not empty: a self-calibration writes its passes there", source=folder)
    can_apply = getattr(robot, "can_apply", None)
    restart_note = can_apply() if callable(can_apply) and method != "none" else None
    passes: list[PassResult] = []
    if state is not None:
        problem = pending_problem(robot.drive_params(), state.pending)
        if problem is not None:
            raise InputError(f"{problem} ({folder / 'overlay.yaml'})")
        passes = _resumed(folder, state)
    try:
        checks = preflight(robot, how, side_length, limits)
        if restart_note is not None:
            checks.append(restart_note)
            if notify is not None:
                notify(restart_note)
        odom = settle(robot, limits).pose
        first = take_fix(robot, how)
        home = Home(first.pose, first, odom)
        home.fixes.append((first, corner_truth(robot, how)))
        coarse_check, coarse_applied, pending = None, None, None
        if coarse and method != "none" and measure in ("lidar", "truth"):
            if progress is not None:
                progress("coarse", 0, None, "turning check")
            coarse_check = coarse_turning(robot, how, limits)
            if coarse_check.needed:
                params = robot.drive_params()
                coarse_params = replace(
                    params,
                    wheel_separation_multiplier=params.wheel_separation_multiplier
                    * coarse_check.ratio,
                )
                coarse_applied = robot.apply(coarse_params, method)
                if not coarse_applied.active:
                    pending = coarse_params
            # where it stands now, by a fix without a prior (the turns moved its odometry)
            home.odometry = settle(robot, limits).pose
            home.fix = take_fix(robot, how)
        drive = _Passes(
            robot, how, folder, side_length, runs, home, limits, name, progress,
            record_as=robot_name, history=history,
        )  # fmt: skip
        start_at = len(passes) + 1
        if passes:  # resumed: a further pass only where the last one's rule says so
            bench = passes[-1].report.benchmark
            if bench is None or not bench.second_pass_recommended:
                start_at = max_passes + 1
        for k in range(start_at, max_passes + 1):
            if pending is not None:
                break
            result, new = _apply(robot, drive(f"pass {k}"), method)
            drive.mark_applied(result)
            home.reanchor(robot)
            passes.append(result)
            bench = result.report.benchmark
            if result.applied is None or not result.applied.active:
                if restart_note is not None and result.applied is not None:
                    pending = new
                break
            if bench is None or not bench.second_pass_recommended:
                break
        last = passes[-1].applied if passes else None
        if verify and pending is None and last is not None and last.active:
            passes.append(drive("verification"))
    except BaseException:
        robot.send_velocity(0.0, 0.0)
        raise
    robot.send_velocity(0.0, 0.0)
    files = _outputs(passes, folder, Path(report) if report is not None else None)
    restart = None
    if pending is not None:
        restart, more = _stop_for_restart(
            robot,
            folder,
            passes,
            pending,
            state,
            locals_settings(side_length, runs, measure, max_passes, verify),
        )
        files.extend(more)
    errors = [
        (
            fix.pose.x - truth.x,
            fix.pose.y - truth.y,
            float(wrap_angle(fix.pose.theta - truth.theta)),
        )
        for fix, truth in home.fixes
        if truth is not None
    ]
    return SelfCalReport(
        robot=name,
        side_length=side_length,
        measurement=measure,
        coarse=coarse_check,
        coarse_applied=coarse_applied,
        passes=tuple(passes),
        final=robot.drive_params(),
        fix_errors=np.asarray(errors, dtype=np.float64).reshape(-1, 3) if errors else None,
        checks=tuple(checks),
        files=tuple(files),
        restart=restart,
    )


def locals_settings(
    side_length: float, runs: int, measure: str, max_passes: int, verify: bool
) -> dict[str, Any]:
    """The test's settings a resumed self-calibration goes on with."""
    return {
        "side_length": side_length, "runs": runs, "measure": measure,
        "max_passes": max_passes, "verify": verify,
    }  # fmt: skip


def _stop_for_restart(
    robot: Robot,
    folder: Path,
    passes: list[PassResult],
    pending: DriveParams,
    state: SelfCalState | None,
    settings: dict[str, Any],
) -> tuple[str, list[Path]]:
    """Write the overlay of the pending parameters and the state; what to do next."""
    from umbmark.robot.ros_common import restart_commands, write_params

    controller = getattr(getattr(robot, "options", None), "controller", "/diff_drive_controller")
    overlay = folder / "restart-overlay.yaml"
    write_params(overlay, pending, controller, ros2=True)
    path = write_state(
        folder,
        SelfCalState(
            settings,
            tuple((p.label, str(p.folder.relative_to(folder)), p.params) for p in passes),
            pending,
        ),
    )
    text = (
        f"stopped for a controller restart: {restart_commands(controller, pending, str(overlay))}"
        f"; then: umbmark selfcal --resume {folder} (with the same robot options)"
    )
    return text, [overlay, path]


def _resumed(folder: Path, state: SelfCalState) -> list[PassResult]:
    """The passes a stopped self-calibration drove, their parameters now applied."""
    from umbmark.jobs.calibrate import calibrate

    out = []
    for label, where, params in state.passes:
        report = calibrate(folder / where)
        out.append(PassResult(label, folder / where, report, params))
    if out:
        out[-1] = replace(
            out[-1], applied=ApplyResult("yaml", True, "applied by the controller's restart")
        )
    return out


@dataclass(frozen=True)
class _Passes:
    """Drives, records and calibrates one pass at a time."""

    robot: Robot
    how: Measure
    folder: Path
    side: float
    runs: int
    home: Home
    limits: DriveLimits
    name: str
    progress: Progress | None
    record_as: str | None = None
    history: str | os.PathLike[str] | None = None

    def __call__(self, label: str) -> PassResult:
        from umbmark.jobs.calibrate import calibrate

        params = self.robot.drive_params()

        def said(k: int, direction: Direction, what: str) -> None:
            if self.progress is not None:
                self.progress(label, k, direction, what)

        measured = drive_pass(
            self.robot, self.how, self.side, self.runs, self.home, self.limits, said
        )
        where = self.folder / label.replace(" ", "-")
        record_pass(where, measured, params, self.side, self.how.method, self.name)
        report = calibrate(where, robot=self.record_as, history=self.history)
        return PassResult(label, where, report, params, warnings=_strays(measured, self.limits))

    def mark_applied(self, result: PassResult) -> None:
        """Mark the pass's calibration applied in the history (it was recorded last)."""
        if self.record_as is None or result.applied is None or not result.applied.active:
            return
        from umbmark.store.history import History

        store = History(self.history)
        (last,) = store.calibrations(self.record_as)[-1:]
        store.mark_applied(self.record_as, last.id)


def _strays(measured: list[MeasuredRun], limits: DriveLimits) -> tuple[str, ...]:
    """A warning for each run whose odometry ended farther from the commanded end than the
    limits (a robot answering commands late, a controller that does not settle)."""
    out = []
    counted: dict[Direction, int] = {}
    for m in measured:
        k = counted[m.run.direction] = counted.get(m.run.direction, 0) + 1
        distance, heading = m.run.end_error
        if distance > limits.end_position or heading > limits.end_heading:
            out.append(
                f"{m.run.direction.value} run {k}: the odometry ended {distance * 1000:.1f} mm "
                f"and {math.degrees(heading):.2f} deg from where it was sent (limits "
                f"{limits.end_position * 1000:g} mm, {math.degrees(limits.end_heading):g} deg): "
                "the run is not the square the benchmark assumes"
            )
    return tuple(out)


def _apply(robot: Robot, result: PassResult, method: ApplyMethod) -> tuple[PassResult, DriveParams]:
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


def _outputs(passes: list[PassResult], folder: Path, page: Path | None) -> list[Path]:
    """The report of all passes and the overlay of the final parameters."""
    from umbmark.jobs.report import report

    written: list[Path] = []
    if not passes:
        return written
    page = page or folder / "report.html"
    report(*(p.folder for p in passes), output=page)
    written.append(page)
    last_applied = [p for p in passes if p.applied is not None and p.applied.active]
    if last_applied:
        overlay = folder / "overlay.yaml"
        last_applied[-1].report.write(yaml=overlay)
        written.append(overlay)
    return written


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "-" for c in name)[:60] or "robot"


def _tape_marks(robot: Robot, given: Sequence[float] | None) -> TapeMarks:
    """The marks a person measures from: the given ones, else the robot's own
    (``tape_marks()``, as the virtual robot has); refused when neither."""
    if given is not None:
        values = [float(v) for v in given]
        if len(values) != 6 or not all(math.isfinite(v) and abs(v) <= 2.0 for v in values):
            raise InputError(
                f"--tape-marks {','.join(f'{v:g}' for v in values)}: give X1,Y1,X2,Y2,X3,Y3, "
                "three points on the robot in its base frame, in metres (within 2 m)"
            )
        marks = ((values[0], values[1]), (values[2], values[3]), (values[4], values[5]))
        if math.dist(marks[0], marks[1]) < 0.05:
            raise InputError(
                "--tape-marks: the first two marks (measured to the same wall) must be at "
                "least 50 mm apart, or the heading cannot be told"
            )
        return TapeMarks(marks=marks)
    own = getattr(robot, "tape_marks", None)
    if callable(own):
        return TapeMarks(marks=tuple((float(x), float(y)) for x, y in own()))
    raise InputError(
        "--measure tape needs --tape-marks: the three points on the robot the distances "
        "are measured from (X1,Y1,X2,Y2,X3,Y3 in its base frame, metres; the first two to "
        "the wall behind the start, the third to the side wall)"
    )


def _apply_method(apply: bool | ApplyMethod) -> ApplyMethod:
    """``apply`` as a method: True is ``reconfigure``, False is ``none``."""
    if apply is True:
        return "reconfigure"
    if apply is False:
        return "none"
    if apply not in APPLY_METHODS:
        raise InputError(f"--apply {apply!r}: use one of {', '.join(APPLY_METHODS)}")
    return apply

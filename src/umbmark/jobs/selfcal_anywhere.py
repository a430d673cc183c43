"""The self-calibration anywhere (``umbmark selfcal --routine anywhere``): the robot drives
a short excitation pattern on about 2 x 2 m of floor, calibrates its wheels and its
laser's mounting from the laser's own motion (:mod:`umbmark.routines.anywhere`), and its
gyro with them where it has an IMU (:mod:`umbmark.routines.anywhere_gyro`), applies the
result through the same paths as the UMBmark routine, and verifies by driving the
pattern again.

1. checks before anything moves: the odometry settles, the robot has a laser or an IMU,
   its IMU's frame has a mounting, and the laser sees a scene with structure (no open
   space, no corridor);
2. the pattern, ``repeats`` times in a row, recorded (wheels, sweeps, the gyro; with a
   gyro each repetition between rests);
3. its motion intervals, written as a tuple file in ``out/pass-1`` (or a temporary folder
   without ``out``), calibrated by :func:`umbmark.calibrate` with the scan-matching
   estimator and the parameters active during the drive (the verdict, the history entry
   under ``robot_name``); with an IMU, by the ``gyro`` estimator on the wheels, the gyro
   and those intervals together (the gyro's scale and bias too), or without a laser on
   the wheels and the gyro alone (``E_d``, and ``E_b`` relative to the gyro: apply with
   care at best);
4. applied (``robot.apply``) unless its verdict is "do not apply" or ``apply`` is
   ``none``; the history marks it applied, ``out/overlay.yaml`` holds it (also where the
   controller takes it only on a restart: a ROS 2 controller without the controller
   manager's messages; the report's apply message says how);
5. with ``verify`` and the result applied: the pattern again, calibrated the same way
   (``out/verification``): what is left after the correction;
6. with ``out``: ``out/report.html``, the page of it all
   (:mod:`umbmark.outputs.anywhere_page`): the intervals used and left out, the fit, the
   verdict, before and after, and the laser's mounting in the forms a user applies (the
   URDF origin, the static transform publishers' arguments, the difference from the
   mounting the robot states).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText
from umbmark.estimators.registry import SCAN_MATCHING
from umbmark.options.spec import READ
from umbmark.robot.base import ApplyMethod, ApplyResult, DriveParams, Robot, ScanSweep
from umbmark.routines.anywhere import (
    GYRO_PATTERN,
    GYRO_REST,
    PATTERN,
    PATTERN_REACH,
    Move,
    check_scene,
    drive_pattern,
    first_scan,
    intervals_note,
    pattern_intervals,
)
from umbmark.routines.drive import DriveLimits, settle
from umbmark.routines.record import OVERLAY_FILE, pass_folder

if TYPE_CHECKING:
    from umbmark.estimators.gyro_result import GyroCalibration
    from umbmark.outputs.calibration import CalibrationReport
    from umbmark.routines.anywhere import PatternRecording
    from umbmark.scans.intervals import IntervalReport

__all__ = ["AnywherePass", "AnywhereReport", "selfcal_anywhere", "square_only"]

#: The file of a pass's motion intervals (``docs/formats.md``: tuple files).
INTERVALS_FILE = "intervals.tuple"
#: The page of the routine, in ``out``.
REPORT_FILE = "report.html"
#: Most repeats of the pattern in one pass.
MAX_REPEATS = 10

#: Live progress: (pass label, move number, None, what), as the UMBmark routine's.
Progress = Callable[[str, int, None, str], None]


@dataclass(frozen=True)
class AnywherePass:
    """One drive of the pattern and its calibration.

    Attributes
    ----------
    label : str
        ``pass 1`` or ``verification``.
    folder : Path or None
        Where its intervals were written (None: not kept).
    report : CalibrationReport
        Its calibration (scan-matching, composed with ``params``).
    params : DriveParams
        The parameters the controller ran with during the drive.
    matched : str
        The intervals matched and left out, for people.
    applied : ApplyResult or None
        What applying its correction did (None: not applied).
    tried : int
        The motion intervals cut from the drive.
    left_out : tuple of (str, int)
        The intervals that could not be scan matched, by reason.
    gyro : GyroCalibration or None
        The gyro's calibration (its scale, bias, the figures relative to it), where the
        robot has an IMU.
    """

    label: str
    folder: Path | None
    report: CalibrationReport
    params: DriveParams
    matched: str
    applied: ApplyResult | None = None
    tried: int = 0
    left_out: tuple[tuple[str, int], ...] = ()
    gyro: GyroCalibration | None = None

    def errors(self) -> dict[str, float | None]:
        """``E_d``, ``E_b``, ``E_s`` against the parameters active during the drive."""
        est = self.report.estimate
        return {"E_d": est.E_d, "E_b": est.E_b, "E_s": est.E_s}


@dataclass(frozen=True)
class AnywhereReport(JsonText):
    """What the self-calibration anywhere did and found.

    Attributes
    ----------
    robot : str
    calibration : AnywherePass
        The pass whose result was applied (or not).
    verification : AnywherePass or None
        The pattern driven again on the applied parameters (None: not driven).
    final : DriveParams
        The parameters the controller holds at the end, as it reports them.
    checks : tuple of str
        What the checks before moving found.
    files : tuple of Path
        Files written.
    imu : str or None
        The IMU used, its topic and its frame's mounting (None: none).
    laser : bool
        Whether the laser's motion was a reference (False: calibrated against the gyro
        alone).
    """

    robot: str
    calibration: AnywherePass
    verification: AnywherePass | None
    final: DriveParams
    checks: tuple[str, ...] = ()
    files: tuple[Path, ...] = field(default=(), compare=False)
    imu: str | None = None
    laser: bool = True

    @property
    def against(self) -> str:
        """What the wheels were calibrated against, for people and the JSON."""
        if self.imu is None:
            return "the laser's scan matching"
        if self.laser and self.calibration.gyro is None:
            return "the laser's scan matching alone (the IMU left out: see the warnings)"
        if self.laser:
            return "the laser's scan matching and the gyro together (the gyro calibrated too)"
        return "the gyro alone (no laser): E_b relative to the gyro's scale"

    @property
    def applied(self) -> ApplyResult | None:
        """What applying the calibration did (None: not applied)."""
        return self.calibration.applied

    def html(self) -> str:
        """The routine's page (what ``out/report.html`` holds)."""
        from umbmark.outputs.anywhere_page import AnywherePage, PatternPass, anywhere_html

        def shown(one: AnywherePass | None) -> PatternPass | None:
            if one is None:
                return None
            return PatternPass(one.label, one.report, one.tried, dict(one.left_out), one.gyro)

        first = shown(self.calibration)
        assert first is not None
        return anywhere_html(
            AnywherePage(
                robot=self.robot,
                calibration=first,
                verification=shown(self.verification),
                applied=self.applied_words(),
                final=_multipliers(self.final),
                checks=self.checks,
                against=self.against,
                imu=self.imu,
                laser=self.laser,
            )
        )

    def applied_words(self) -> str:
        """What applying did, in one sentence."""
        applied = self.applied
        if applied is None:
            verdict = self.calibration.report.verdict
            why = "apply none was asked" if verdict.applies else "the verdict is do not apply"
            return f"Not applied: {why}."
        if applied.active:
            return f"Applied ({applied.method}): {applied.message}."
        return f"Not applied yet: {applied.message}."

    def to_dict(self) -> dict[str, Any]:
        """What ``umbmark selfcal --routine anywhere --json`` prints (metres, radians): the
        calibration's fields as ``umbmark calibrate --scan-topic --json`` gives them, and
        the routine's own."""
        out = self.calibration.report.to_dict()
        applied = self.applied
        out.update(
            {
                "routine": "anywhere",
                "robot": self.robot,
                "checks": list(self.checks),
                "intervals_matched": self.calibration.matched,
                "applied": None if applied is None else applied.active,
                "apply_method": None if applied is None else applied.method,
                "apply_message": None if applied is None else applied.message,
                "before": self.calibration.errors(),
                "after": None if self.verification is None else self.verification.errors(),
                "verification": None
                if self.verification is None
                else _pass_dict(self.verification),
                "final": _multipliers(self.final),
                "files": [str(f) for f in self.files],
                "calibrated_against": self.against,
                "laser": self.laser,
                "imu": self.imu,
                "gyro_calibration": None
                if self.calibration.gyro is None
                else self.calibration.gyro.to_dict(),
            }
        )
        return out


def _pass_dict(one: AnywherePass) -> dict[str, Any]:
    """A pass's calibration as JSON, with its gyro's."""
    out = one.report.to_dict()
    if one.gyro is not None:
        out["gyro_calibration"] = one.gyro.to_dict()
    return out


def _multipliers(params: DriveParams) -> dict[str, float]:
    """The multipliers ``params`` hold, by their controller names."""
    return {
        "wheel_separation_multiplier": params.wheel_separation_multiplier,
        "left_wheel_radius_multiplier": params.left_wheel_radius_multiplier,
        "right_wheel_radius_multiplier": params.right_wheel_radius_multiplier,
    }


def selfcal_anywhere(
    robot: Robot,
    *,
    apply: ApplyMethod = "reconfigure",
    verify: bool = True,
    robot_name: str | None = None,
    history: str | os.PathLike[str] | None = None,
    out: str | os.PathLike[str] | None = None,
    progress: Progress | None = None,
    limits: DriveLimits | None = None,
    force: bool = False,
    repeats: int = 4,
    controller: str | None = None,
    gyro_scale_tolerance: float = READ["gyro_scale_tolerance"].default,
) -> AnywhereReport:
    """Calibrate ``robot`` anywhere (the module's documentation); the options as
    :func:`umbmark.selfcal`'s (``apply`` as a method). ``repeats``: how often the pattern
    is driven in a row for one calibration (1 to :data:`MAX_REPEATS`). ``controller``:
    the controller the overlay and the history are keyed by (None: the default).
    ``gyro_scale_tolerance``: without a laser, how far the gyro's scale may be off (a
    fraction): ``E_b``'s interval is widened by it.

    Raises
    ------
    InputError
        Neither a laser nor an IMU, a scene without structure, too few intervals matched,
        an IMU frame without a mounting, bad options.
    umbmark.core.errors.SafetyError
        The robot was stopped for safety (a zero velocity was the last command).
    """
    if not (1 <= repeats <= MAX_REPEATS):
        raise InputError(f"repeats {repeats!r}: give 1 to {MAX_REPEATS}")
    READ["gyro_scale_tolerance"].check(gyro_scale_tolerance)
    limits = limits or DriveLimits()
    folder = None if out is None else Path(out)
    _check_folder(folder, force)
    name = robot_name or robot.name
    kept = contextlib.nullcontext(str(folder))
    try:
        settle(robot, limits)
        imu = robot.imu()
        scan = first_scan(robot, limits)
        laser = scan is not None
        checks = _checks(robot, limits, imu is not None, scan)
        if imu is not None:
            checks.append(f"gyro: {imu.describe()}")
        with kept if folder is not None else tempfile.TemporaryDirectory(prefix="umbmark-") as logs:
            drive = _Pass(robot, Path(logs), limits, progress, repeats, robot_name, history,
                          force, controller, laser, imu is not None,
                          gyro_scale_tolerance)  # fmt: skip
            first = drive("pass 1")
            first = _apply(robot, first, apply)
            if first.applied is not None and first.applied.active and robot_name is not None:
                _mark_applied(robot_name, history)
            verification = None
            if verify and first.applied is not None and first.applied.active:
                verification = drive("verification")
    except BaseException:
        robot.send_velocity(0.0, 0.0)
        raise
    robot.send_velocity(0.0, 0.0)
    files: list[Path] = []
    passes = [p for p in (first, verification) if p is not None]
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)  # without a laser no pass wrote into it
        files += [p.folder / INTERVALS_FILE for p in passes if p.folder is not None and laser]
        if first.applied is not None:  # applied, or waiting for a controller restart
            files += first.report.write(yaml=folder / OVERLAY_FILE, force=force)
    else:
        first = replace(first, folder=None)
        verification = None if verification is None else replace(verification, folder=None)
    report = AnywhereReport(
        robot=name,
        calibration=first,
        verification=verification,
        final=robot.drive_params(),
        checks=tuple(checks),
        files=tuple(files),
        imu=None if imu is None else imu.describe(),
        laser=laser,
    )
    if folder is None:
        return report
    from umbmark.core.atomic import atomic_write_text

    atomic_write_text(folder / REPORT_FILE, report.html())
    return replace(report, files=(*report.files, folder / REPORT_FILE))


def _checks(robot: Robot, limits: DriveLimits, gyro: bool, scan: ScanSweep | None) -> list[str]:
    """The checks of the scene before moving: the laser's (:func:`check_scene`, from its
    sweep ``scan``); without a laser, a robot with an IMU (``gyro``) is calibrated against
    it alone, said, and one with neither refused."""
    if scan is not None:
        check_scene(robot, limits, scan)
        return ["the laser sees a scene with structure: scan matching can measure motion"]
    if not gyro:
        check_scene(robot, limits)  # refuses: no laser scan, and no IMU
    reach = PATTERN_REACH + limits.outline.reach
    return [
        "no laser: the wheels are calibrated against the gyro alone (E_d, and E_b relative "
        "to the gyro's scale: E_b k_g)",
        f"no laser watches for obstacles: keep {2 * reach:.1f} x {2 * reach:.1f} m around "
        "the robot clear",
    ]


def _check_folder(folder: Path | None, force: bool) -> None:
    """Refuse, before anything moves, an output folder that cannot be made, or one that
    holds files (without ``force``)."""
    if folder is None:
        return
    from umbmark.outputs.files import OutputPlan

    OutputPlan.of(logs=folder, force=True)
    if not force and folder.is_dir() and any(folder.iterdir()):
        raise InputError(
            f"holds files: choose a new or empty folder, leave {option('out')} out (umbmark "
            f"selfcal then makes selfcal-ROBOT-2, ...), or pass {option('force')} to write "
            "into it",
            source=folder,
            python="holds files: choose a new or empty folder, or pass force=True",
        )


@dataclass(frozen=True)
class _Pass:
    """Drives the pattern, writes its intervals, calibrates them."""

    robot: Robot
    folder: Path
    limits: DriveLimits
    progress: Progress | None
    repeats: int
    record_as: str | None
    history: str | os.PathLike[str] | None
    force: bool
    controller: str | None = None
    laser: bool = True
    gyro: bool = False
    tolerance: float = READ["gyro_scale_tolerance"].default

    @property
    def moves(self) -> tuple[Move, ...]:
        """The pattern ``repeats`` times; with a gyro, each between rests."""
        if not self.gyro:
            return PATTERN * self.repeats
        return (*(GYRO_PATTERN * self.repeats), Move("rest", GYRO_REST))

    def __call__(self, label: str) -> AnywherePass:
        from umbmark.outputs.calibration import CalibrationReport
        from umbmark.sources.tuples import write_tuples

        def said(k: int, what: str) -> None:
            if self.progress is not None:
                self.progress(label, k, None, what)

        recording = drive_pattern(self.robot, self.limits, said, self.moves, laser=self.laser)
        where = pass_folder(self.folder, label)
        if not self.laser:
            return self._gyro_only(label, recording, where)
        matched = pattern_intervals(recording)
        where.mkdir(parents=True, exist_ok=True)
        path = write_tuples(where / INTERVALS_FILE, matched.intervals, force=self.force)
        left_out = tuple(sorted(matched.left_out.items()))
        note = intervals_note(matched)
        p = recording.params
        if self.gyro and recording.gyro is not None:
            from umbmark.routines.anywhere_gyro import calibrate_pattern_gyro

            both = calibrate_pattern_gyro(
                recording, matched, tolerance=self.tolerance, source=path,
                robot=self.record_as, history=self.history, controller=self.controller,
            )  # fmt: skip
            return AnywherePass(
                label, where, CalibrationReport.of(both.result), p, note, tried=matched.tried,
                left_out=left_out, gyro=both.gyro,
            )  # fmt: skip
        return self._scan_only(label, recording, matched, where, path)

    def _gyro_only(self, label: str, recording: PatternRecording, where: Path) -> AnywherePass:
        """A drive calibrated against the gyro alone (no laser); refused where the gyro
        fell silent or froze (nothing else measured the turns)."""
        from umbmark.outputs.calibration import CalibrationReport
        from umbmark.routines.anywhere_gyro import calibrate_pattern_gyro

        if recording.gyro_trouble is not None:
            raise InputError(
                f"{recording.gyro_trouble}: without a laser nothing else measured the turns; "
                "nothing calibrated, nothing applied (drive again once the IMU reads)"
            )
        found = calibrate_pattern_gyro(
            recording, None, tolerance=self.tolerance, robot=self.record_as,
            history=self.history, controller=self.controller,
        )  # fmt: skip
        g = found.gyro
        note = f"{g.n_intervals} intervals of the wheels against the gyro ({g.n_rests} rests)" + (
            f", {g.n_outliers} dropped as outliers" if g.n_outliers else ""
        )
        return AnywherePass(label, None, CalibrationReport.of(found.result), recording.params,
                            note, tried=g.n_intervals, gyro=g)  # fmt: skip

    def _scan_only(
        self,
        label: str,
        recording: PatternRecording,
        matched: IntervalReport,
        where: Path,
        path: Path,
    ) -> AnywherePass:
        """A drive calibrated against the laser's scan matching alone (no IMU, or its
        readings left out, warned)."""
        from umbmark.outputs.calibration import CalibrationReport
        from umbmark.store.calibrations import calibrate_recorded

        p = recording.params
        found = calibrate_recorded(
            [path],
            {
                "wheel_diameter": 2.0 * p.wheel_radius,
                "current_c_l": p.left_wheel_radius_multiplier,
                "current_c_r": p.right_wheel_radius_multiplier,
                "current_separation_multiplier": p.wheel_separation_multiplier,
                **({} if self.controller is None else {"controller": self.controller}),
            },
            method=SCAN_MATCHING.name,
            wheelbase=p.wheel_separation,
            robot=self.record_as,
            history=self.history,
        )
        left = () if recording.gyro_trouble is None else (
            f"{recording.gyro_trouble}: the gyro is left out, the wheels calibrated by the "
            "laser's scan matching alone (nothing of the gyro calibrated or applied)",
        )  # fmt: skip
        found = replace(found, stated_mounting=recording.stated,
                        input_warnings=(*found.input_warnings, *left))  # fmt: skip
        report = CalibrationReport.of(found)
        left_out = tuple(sorted(matched.left_out.items()))
        note = intervals_note(matched)
        return AnywherePass(label, where, report, p, note, tried=matched.tried, left_out=left_out)


def _apply(robot: Robot, result: AnywherePass, method: ApplyMethod) -> AnywherePass:
    """Apply the pass's correction, composed with its active parameters, unless the
    verdict says not to or ``method`` is ``none`` (as the UMBmark routine does)."""
    if method == "none" or not result.report.verdict.applies:
        return result
    cal = result.report.calibration
    new = replace(
        result.params,
        wheel_separation_multiplier=cal.new_separation_multiplier,
        left_wheel_radius_multiplier=cal.new_c_left,
        right_wheel_radius_multiplier=cal.new_c_right,
    )
    return replace(result, applied=robot.apply(new, method))


def _mark_applied(robot: str, history: str | os.PathLike[str] | None) -> None:
    """Mark the robot's last calibration (the pass just applied) applied in the history."""
    from umbmark.store.history import History

    store = History(history)
    (last,) = store.calibrations(robot)[-1:]
    store.mark_applied(robot, last.id)


def square_only(**given: bool) -> None:
    """Refuse the square routine's options with ``--routine anywhere``: none says anything
    to it, and a user who gave one expects it to count."""
    named = [option(name) for name, on in given.items() if on]
    if named:
        raise InputError(
            f"{', '.join(named)}: the square routine's option{'s' if len(named) > 1 else ''}; "
            f"{option('routine', 'anywhere')} drives its own pattern and takes none of them"
        )

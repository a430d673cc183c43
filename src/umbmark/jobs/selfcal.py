"""The self-calibration job (the paper's Sec. 6): the robot drives UMBmark by itself,
measures where it stopped against an L-shaped corner, calibrates, applies the correction
and checks it.

:func:`selfcal` is what ``umbmark selfcal`` does; its report's :meth:`SelfCalReport.to_dict`
is what ``umbmark selfcal --json`` prints. The steps:

1. checks before anything moves: the odometry is alive, the controller answers, the corner
   is found (the first fix is the start of every run), the floor of both squares is free;
2. a coarse turning check (:mod:`umbmark.routines.coarse`), corrected when the robot turns
   far from what its odometry believes, so that a square is possible at all;
3. a UMBmark pass: ``runs`` cw then ``runs`` ccw runs, each from the start, recorded as a
   run log in ``out/pass-N`` (what ``umbmark calibrate``, ``report`` and ``replay`` read;
   without ``out``, in a temporary folder removed at the end: the library writes only
   where its caller says);
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

import contextlib
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from umbmark.calibration.passes import Holds
from umbmark.calibration.result import unnamed_controller
from umbmark.core.conventions import wrap_angle
from umbmark.core.errors import InputError, unexpected_keyword
from umbmark.jobs.selfcal_anywhere import AnywhereReport, selfcal_anywhere, square_only
from umbmark.jobs.selfcal_passes import PassDriver, apply_pass, holds_of, resumed_passes
from umbmark.jobs.selfcal_report import PassResult, SelfCalReport
from umbmark.options.selfcal import MAX_SELFCAL_PASSES, MAX_SELFCAL_RUNS, ROUTINE
from umbmark.robot.base import ApplyMethod, ApplyResult, DriveParams, Robot
from umbmark.routines.coarse import CoarseTurning, coarse_turning
from umbmark.routines.drive import DriveLimits, settle
from umbmark.routines.measure import (
    CornerSide,
    Measure,
    MeasureMethod,
    first_fix,
    marks_for,
    take_fix,
)
from umbmark.routines.outputs import check_outputs, write_outputs
from umbmark.routines.passes import Home, corner_truth
from umbmark.routines.preflight import preflight
from umbmark.routines.record import clear_selfcal, recorded_passes
from umbmark.routines.resume import SelfCalState, pending_problem, read_state, write_state
from umbmark.routines.setup import Routine, SelfcalSetup
from umbmark.routines.watch import Progress, RunsLeft, Stopped, Watch, mark_stopped

__all__ = [
    "MAX_SELFCAL_PASSES",
    "MAX_SELFCAL_RUNS",
    "PassResult",
    "SelfCalReport",
    "SelfcalSetup",
    "default_folder",
    "selfcal",
]


def selfcal(
    robot: Robot,
    setup: SelfcalSetup | None = None,
    *,
    routine: Routine = "umbmark",
    progress: Progress | None = None,
    ask: Callable[[str], str] | None = None,
    notify: Callable[[str], None] | None = None,
    runs_left: Callable[[RunsLeft], None] | None = None,
    **changes: object,
) -> SelfCalReport | AnywhereReport:
    """Calibrate ``robot`` by itself: UMBmark driven by its odometry, measured at the
    corner, applied and verified (module documentation).

    What ``umbmark selfcal`` does: the settings as a :class:`SelfcalSetup` (its fields
    and defaults), or its fields as keywords (``umbmark.selfcal(robot, side_length=2,
    runs=3, out="cal")``), or both (the keywords change the setup's fields).

    Parameters
    ----------
    robot : Robot
        Placed at the start, in view of the L-shaped corner.
    setup : SelfcalSetup, optional
        The test, how its results are applied and where they go
        (:class:`umbmark.routines.setup.SelfcalSetup`) [default: its defaults].
    routine : {"umbmark", "anywhere"}
        ``anywhere``: :func:`umbmark.jobs.selfcal_anywhere.selfcal_anywhere` (no corner;
        the square routine's fields, :data:`umbmark.routines.setup.SQUARE_ONLY`, refused
        given).
    progress : callable, optional
        What the robot does now: ``(pass label, run, direction, what)``.
    ask : callable, optional
        For ``measure="tape"``: shows a prompt, returns the person's answer.
    notify : callable, optional
        Lines for a person, as they happen: each check, the coarse check, each run's
        return error, each pass's result.
    runs_left : callable, optional
        Called with a :class:`~umbmark.routines.watch.RunsLeft` (runs done out of planned,
        the time left) as each pass begins and each run ends.
    **changes
        Fields of ``setup`` to change, or of the default one (``side_length=2.0``).

    Raises
    ------
    InputError
        Bad options, or a check before moving failed (with the cause).
    TypeError
        A keyword that is no field of :class:`SelfcalSetup`, naming the close one.
    umbmark.core.errors.SafetyError
        The robot was stopped for safety (a zero velocity was the last command).
        Every exception comes after a zero velocity; one raised once the robot moved
        carries what the controller holds (:func:`umbmark.routines.watch.stopped`).
    """
    known = [f.name for f in fields(SelfcalSetup)]
    for name in changes:
        if name not in known:
            raise unexpected_keyword("selfcal", name, [*known, *_CALLS])
    ROUTINE.check(routine)
    if routine == "anywhere":
        square_only(**SelfcalSetup.square_options(setup, changes))
    chosen = replace(setup or SelfcalSetup(), **changes)  # type: ignore[arg-type]
    chosen = replace(chosen, limits=chosen.drive_limits(robot))
    if routine == "anywhere":
        g = chosen
        return selfcal_anywhere(
            robot, apply=g.apply_method, verify=g.verify, robot_name=g.robot_name,
            history=g.history, out=g.out, progress=progress, limits=g.limits, force=g.force,
            controller=robot_controller(robot, g.controller),
            gyro_scale_tolerance=g.gyro_scale_tolerance,
        )  # fmt: skip
    return _squares(robot, chosen, _Calls(progress, ask, notify, runs_left))


selfcal.__keyword_fields__ = SelfcalSetup  # type: ignore[attr-defined]  # its **changes

#: selfcal's keywords besides the setup's fields.
_CALLS = ("setup", "routine", "progress", "ask", "notify", "runs_left")


@dataclass(frozen=True)
class _Calls:
    """What :func:`selfcal` calls as it goes: progress, a person's answers, lines for a
    person, the runs left."""

    progress: Progress | None
    ask: Callable[[str], str] | None
    notify: Callable[[str], None] | None
    runs_left: Callable[[RunsLeft], None] | None


def _squares(robot: Robot, g: SelfcalSetup, calls: _Calls) -> SelfCalReport:
    """The UMBmark routine (:func:`selfcal`'s steps 1 to 8) with the settings given."""
    state = None
    if g.resume is not None:  # the settings it stopped with
        state = read_state(Path(g.resume))
        s = state.settings
        g = replace(
            g, side_length=s["side_length"], runs=s["runs"], measure=s["measure"],
            max_passes=s["max_passes"], verify=s["verify"], out=g.resume, coarse=False,
            corner_side=s.get("corner_side", "right"),
        )  # fmt: skip
    method = g.apply_method
    controller = robot_controller(robot, g.controller)
    limits = g.limits or DriveLimits()
    marks = marks_for(robot, g.tape_marks) if g.measure == "tape" else None
    how = Measure(g.measure, ask=calls.ask, marks=marks, side=g.corner_side)
    name = g.robot_name or robot.name
    folder = None if g.out is None else Path(g.out)
    page = None if g.report is None else Path(g.report)
    can_apply = getattr(robot, "can_apply", None)
    restart_note = can_apply() if callable(can_apply) and method != "none" else None
    if restart_note is not None and folder is None:
        raise InputError(
            f"{restart_note}: the routine stops for that restart and resumes from its folder; "
            "give out=DIR"
        )
    prior: list[PassResult] = []
    if state is not None and folder is not None:
        problem = pending_problem(robot.drive_params(), state.pending)
        if problem is not None:
            raise InputError(f"{problem} ({folder / 'overlay.yaml'})")
        prior = resumed_passes(folder, state, controller)
        check_outputs(None, page, g.force)  # the folder's own page and overlay are replaced
    else:
        check_outputs(folder, page, g.force)  # before anything moves
    kept = contextlib.nullcontext(str(folder))
    with kept if folder is not None else tempfile.TemporaryDirectory(prefix="umbmark-") as logs:
        drive = PassDriver(
            robot, how, Path(logs), g.side_length, g.runs, limits, name,
            Watch(calls.progress, calls.notify, calls.runs_left, g.runs), record_as=g.robot_name,
            history=g.history, kept=folder is not None, controller=controller,
        )  # fmt: skip
        found = _calibrate(
            drive, method, g.verify, g.max_passes, (g.coarse, g.gyro_scale_tolerance),
            folder if g.force and state is None else None,
            _Restart(restart_note, calls.notify, prior),
        )  # fmt: skip
        final = robot.drive_params()
        holds = holds_of(found.passes, final, found.coarse_factor)
        files = write_outputs(
            [p.folder for p in found.passes if p.folder is not None],
            None if holds.held is None else found.passes[holds.held - 1].report,
            holds, folder, page, g.force or state is not None, controller, g.command,
        )  # fmt: skip
        if controller is None and found.passes and calls.notify is not None:
            calls.notify(unnamed_controller())  # the overlay's keys: the default
        restart = None
        if found.pending is not None and folder is not None:
            settings = locals_settings(g.side_length, g.runs, g.measure, g.max_passes, g.verify)
            restart, more = _stop_for_restart(
                controller, folder, found.passes, found.pending,
                {**settings, "corner_side": found.side},
            )  # fmt: skip
            files.extend(more)
    return _report(name, g.side_length, g.measure, found, final, holds, files, restart, folder)


def _report(
    name: str,
    side_length: float,
    measure: MeasureMethod,
    found: _Found,
    final: DriveParams,
    holds: Holds,
    files: list[Path],
    restart: str | None,
    folder: Path | None,
) -> SelfCalReport:
    """What the routine found, its passes without their folders when it kept none."""
    passes = found.passes if folder is not None else [replace(p, folder=None) for p in found.passes]
    errors = [
        (
            fix.pose.x - truth.x,
            fix.pose.y - truth.y,
            float(wrap_angle(fix.pose.theta - truth.theta)),
        )
        for fix, truth in found.home.fixes
        if truth is not None
    ]
    return SelfCalReport(
        robot=name,
        side_length=side_length,
        measurement=measure,
        coarse=found.coarse,
        coarse_applied=found.coarse_applied,
        passes=tuple(passes),
        final=final,
        holds=holds,
        fix_errors=np.asarray(errors, dtype=np.float64).reshape(-1, 3) if errors else None,
        checks=tuple(found.checks),
        files=tuple(files),
        restart=restart,
    )


def default_folder(robot: str) -> Path:
    """Where ``umbmark selfcal`` writes when not told: ``selfcal-<robot>`` (the command
    takes ``selfcal-<robot>-2``, ... when an earlier run left files there)."""
    return Path(f"selfcal-{_slug(robot)}")


@dataclass(frozen=True)
class _Restart:
    """A robot that takes new parameters only on a controller restart: the note said
    before moving (``None`` where it takes them live), where to say it, and the passes a
    resumed self-calibration drove before the restart."""

    note: str | None
    notify: Callable[[str], None] | None
    prior: list[PassResult]


@dataclass(frozen=True)
class _Found:
    """What driving the passes gave; ``pending``: parameters that wait for a controller
    restart (the routine stopped for it)."""

    checks: list[str]
    home: Home
    coarse: CoarseTurning | None
    coarse_applied: ApplyResult | None
    passes: list[PassResult]
    pending: DriveParams | None = None
    side: CornerSide = "right"

    @property
    def coarse_factor(self) -> float | None:
        """The factor the coarse turning correction applied (None: none applied)."""
        applied = self.coarse_applied is not None and self.coarse_applied.active
        return self.coarse.ratio if applied and self.coarse is not None else None


def _calibrate(
    drive: PassDriver,
    method: ApplyMethod,
    verify: bool,
    max_passes: int,
    coarse: tuple[bool, float],
    replacing: Path | None,
    restart: _Restart,
) -> _Found:
    """The checks, the coarse turning check, the passes and the verification; a zero
    velocity at the end and on any error. ``replacing``: the folder whose earlier
    self-calibration is removed once the checks before moving have passed. A pass whose
    parameters wait for a controller restart ends the passes (none is driven on
    parameters that were not applied)."""
    robot, how, limits, watch = drive.robot, drive.how, drive.limits, drive.watch
    passes = list(restart.prior)
    moved = False
    try:
        checks = preflight(robot, how, drive.side, limits, say=watch.say)
        if restart.note is not None:
            checks.append(restart.note)
            if restart.notify is not None:
                restart.notify(restart.note)
        odom = settle(robot, limits).pose
        first, how, side_line = first_fix(robot, how)  # auto: on the side found
        drive = replace(drive, how=how)
        if side_line is not None:
            checks.append(side_line)
            watch.say(side_line)
        home = Home(first.pose, first, odom)
        home.fixes.append((first, corner_truth(robot, how)))
        moved = True  # the checks and the first fix passed: the robot moves from here on
        if replacing is not None:
            clear_selfcal(replacing, remove=True)
        coarse_check, coarse_applied, pending = None, None, None
        gyro = robot.imu() is not None  # it measures the turns: no fix needed for them
        measured = ("lidar", "truth", "ranges") if gyro else ("lidar", "truth")
        if coarse[0] and method != "none" and how.method in measured:
            watch.status("coarse", 0, None, "turning check")
            coarse_check = coarse_turning(robot, how, limits, coarse[1])
            watch.say(coarse_check.words())
            if coarse_check.needed:
                params = robot.drive_params()
                coarse_params = replace(
                    params,
                    wheel_separation_multiplier=params.wheel_separation_multiplier
                    * coarse_check.ratio,
                )
                coarse_applied = robot.apply(coarse_params, method)
                if coarse_applied.wrote is not None:
                    watch.say(coarse_applied.wrote)
                if not coarse_applied.active and restart.note is not None:
                    pending = coarse_params
            # where it stands now, by a fix without a prior (the turns moved its odometry)
            home.odometry = settle(robot, limits).pose
            home.fix = take_fix(robot, how)
        start_at = len(passes) + 1
        if passes:  # resumed: a further pass only where the last one's rule says so
            bench = passes[-1].report.benchmark
            if bench is None or not bench.second_pass_recommended:
                start_at = max_passes + 1
        for k in range(start_at, max_passes + 1):
            if pending is not None:
                break
            watch.begin_pass(max_passes - k + 1 + int(verify))
            result, new = apply_pass(robot, drive(f"pass {k}", home), method)
            passes.append(result)
            if result.applied is not None and result.applied.wrote is not None:
                watch.say(result.applied.wrote)  # the user's file changed: said at once
            after_coarse = coarse_applied is not None and coarse_applied.active and k == 1
            ratio = coarse_check.ratio if after_coarse and coarse_check is not None else None
            watch.say(result.summary(ratio))
            drive.mark_applied(result)
            home.reanchor(robot)
            bench = result.report.benchmark
            if result.applied is None or not result.applied.active:
                if restart.note is not None and result.applied is not None:
                    pending = new
                break
            if bench is None or not bench.second_pass_recommended:
                break
        last = passes[-1].applied if passes else None
        if verify and pending is None and last is not None and last.active:
            watch.begin_pass(1)
            passes.append(drive("verification", home))
            watch.say(passes[-1].summary())
    except BaseException as exc:
        robot.send_velocity(0.0, 0.0)
        if moved or not isinstance(exc, InputError):
            mark_stopped(exc, _stopped(robot, passes, drive))
        raise
    robot.send_velocity(0.0, 0.0)
    return _Found(checks, home, coarse_check, coarse_applied, passes, pending, how.sided)


def _stopped(robot: Robot, passes: list[PassResult], drive: PassDriver) -> Stopped:
    """What a routine stopped mid-way leaves: what the controller holds (known from the
    passes, asked of the controller only before the first ended), the passes kept."""
    applied = [p for p in passes if p.applied is not None and p.applied.active]
    try:
        if applied:  # the last applied pass's correction
            c = applied[-1].report.calibration
            params = replace(
                applied[-1].params,
                wheel_separation_multiplier=c.new_separation_multiplier,
                left_wheel_radius_multiplier=c.new_c_left,
                right_wheel_radius_multiplier=c.new_c_right,
            )
        else:
            params = passes[-1].params if passes else robot.drive_params()
        holds = holds_of(passes, params).words()
    except Exception as exc:  # a robot gone with the stop: say so, keep the stop's cause
        holds = f"what the controller holds could not be read ({exc})"
    if not drive.kept:
        return Stopped(holds, tuple(p.label for p in passes), None)
    finished = {p.folder for p in passes}
    unfinished = tuple(
        (where, n) for where, n in recorded_passes(drive.folder) if where not in finished and n > 0
    )
    return Stopped(holds, tuple(p.label for p in passes), drive.folder, unfinished)


def locals_settings(
    side_length: float, runs: int, measure: str, max_passes: int, verify: bool
) -> dict[str, Any]:
    """The test's settings a resumed self-calibration goes on with."""
    return {
        "side_length": side_length, "runs": runs, "measure": measure,
        "max_passes": max_passes, "verify": verify,
    }  # fmt: skip


def robot_controller(robot: Robot, given: str | None) -> str | None:
    """The controller the corrections are for: the one ``given``, else a ROS robot's own
    (its options' ``controller``), else None (the default, said so)."""
    if given is not None:
        return given
    ros = getattr(robot, "options", None)
    name = getattr(ros, "controller", None)
    return name if isinstance(name, str) and name.strip("/") else None


def _stop_for_restart(
    controller: str | None,
    folder: Path,
    passes: list[PassResult],
    pending: DriveParams,
    settings: dict[str, Any],
) -> tuple[str, list[Path]]:
    """Write the overlay of the pending parameters and the state; what to do next."""
    from umbmark.core.atomic import atomic_write_text
    from umbmark.robot.ros_common import multipliers, restart_commands
    from umbmark.sources.params.reader import DEFAULT_CONTROLLER, key_path_of
    from umbmark.sources.params.writer import ros2_control_overlay

    name = controller or DEFAULT_CONTROLLER
    overlay = folder / "restart-overlay.yaml"
    m = multipliers(pending)
    new = (
        m["left_wheel_radius_multiplier"],
        m["right_wheel_radius_multiplier"],
        m["wheel_separation_multiplier"],
    )
    atomic_write_text(overlay, ros2_control_overlay(new, (), key_path_of(name)))
    path = write_state(
        folder,
        SelfCalState(
            settings,
            tuple(
                (p.label, str(p.folder.relative_to(folder)), p.params)
                for p in passes
                if p.folder is not None
            ),
            pending,
        ),
    )
    text = (
        f"stopped for a controller restart: {restart_commands(name, pending, str(overlay))}"
        f"; then: umbmark selfcal --resume {folder} (with the same robot options)"
    )
    return text, [overlay, path]


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "-" for c in name)[:60] or "robot"

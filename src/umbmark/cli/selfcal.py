"""``umbmark selfcal``: parse the options, connect to the robot, call
:func:`umbmark.selfcal`, render."""

from __future__ import annotations

import contextlib
import shlex
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from umbmark.cli.click_options import Command, apply, force_option, option, spec_option
from umbmark.core.errors import InputError, SafetyError
from umbmark.options.selfcal import (
    APPLY,
    CORNER_SIDE,
    DRIVING,
    MAX_PASSES,
    MEASURE,
    OBSTACLE_MARGIN,
    ROBOT_WIDTH,
    ROUTINE,
    RUNS,
    SIM_IMU_OPTIONS,
    SQUARE_SIDE,
    TAPE_MARKS,
)
from umbmark.options.spec import HISTORY, OUTPUTS, READ, TEST

if TYPE_CHECKING:
    from rich.console import Console

    from umbmark.jobs.selfcal_anywhere import AnywhereReport
    from umbmark.routines.watch import Progress, RunsLeft, Stopped
    from umbmark.sim.imu import ImuSetup

__all__ = ["selfcal"]

ROBOT = "The robot"
ROS = "ROS robots (--ros1, --ros2)"


@click.command(
    cls=Command,
    short_help="The robot calibrates itself: drives the squares, measures at a corner, applies.",
)
@apply(
    [
        option("--sim", "backend", flag_value="sim", section=ROBOT,
               help="The virtual robot (its errors: --sim-E-d, --sim-E-b, --sim-E-s, --sim-slip); "
               "with --routine anywhere in an 8 x 6 m room, its laser 120 mm ahead, 40 mm "
               "right of its centre, turned 4 deg."),
        option("--ros1", "backend", flag_value="ros1", section=ROBOT,
               help="A ROS 1 robot (rospy; ROS_MASTER_URI)."),
        option("--ros2", "backend", flag_value="ros2", section=ROBOT,
               help="A ROS 2 robot (rclpy: pip install '.[ros2]' in umbmark's checkout; "
               "ROS_DOMAIN_ID)."),
        option("--sim-E-d", "--E-d", "E_d", section=ROBOT, type=float, default=1.004,
               show_default=True,
               help="With --sim: the virtual robot's true wheel-diameter ratio D_R / D_L (Eq. "
               "2.3); by default a robot with errors to calibrate (simulate's has none unless "
               "told)."),
        option("--sim-E-b", "--E-b", "E_b", section=ROBOT, type=float, default=0.97,
               show_default=True,
               help="With --sim: the virtual robot's true wheelbase over nominal, b_actual / b "
               "(Eq. 2.4); by default a robot with errors to calibrate."),
        option("--sim-E-s", "--E-s", "E_s", section=ROBOT, type=float, default=1.0,
               show_default=True,
               help="With --sim: the virtual robot's true average wheel diameter over nominal, "
               "D_avg / D_n."),
        option("--sim-slip", "--slip", "slip", section=ROBOT, type=float, default=0.0004,
               show_default=True, help="With --sim: the virtual robot's wheel slip [m^0.5]."),
        option("--seed", section=ROBOT, type=click.IntRange(0, 2**63 - 1), default=1,
               show_default=True, help="Seed of the virtual robot's slip and sensor noise."),
        option("--sim-laser/--sim-no-laser", "sim_laser", section=ROBOT, default=True,
               help="With --sim: the virtual robot has a laser (--sim-no-laser: none; "
               "--routine anywhere then calibrates against its gyro alone)."),
        *(spec_option(spec, section=ROBOT) for spec in SIM_IMU_OPTIONS),
        option("--imu/--no-imu", "use_imu", section=ROBOT, default=True,
               help="Use the robot's IMU where it has one: ROS, the sensor_msgs/Imu topic "
               "on the graph (--imu-topic), its frame's mounting from /tf_static or the "
               "robot description; --sim, the virtual robot's (--sim-gyro-scale, ...). "
               "--routine anywhere calibrates the gyro too, and the coarse turning check "
               "measures the turns with it."),
        spec_option(ROUTINE),
        spec_option(SQUARE_SIDE),
        spec_option(RUNS),
        spec_option(MEASURE),
        spec_option(TAPE_MARKS),
        spec_option(CORNER_SIDE, help=f"{CORNER_SIDE.help} With --sim, the virtual "
                    "robot's corner stands there (auto: on the right)."),
        spec_option(APPLY),
        spec_option(MAX_PASSES),
        option("--verify/--no-verify", section=TEST, default=True,
               help="Drive a last pass on the final parameters (--no-verify: leave it out)."),
        option("--coarse/--no-coarse", section=TEST, default=True,
               help="Check first that the robot turns as its odometry believes."),
        spec_option(READ["gyro_scale_tolerance"], section=TEST,
                    help="How far the gyro's scale may be off, a fraction (MEMS datasheets: "
                    "0.03 for +-3 % at 25 C): the coarse check's ratio by the gyro is known "
                    "to it, and --routine anywhere without a laser widens E_b's interval "
                    "by it (E_b is then relative to the gyro)."),
        option("--speed", section=DRIVING, type=float, default=0.2, show_default=True,
               help="Cruise speed on the legs [m/s] (0.01 to 1)."),
        option("--acceleration", section=DRIVING, type=float, default=0.3, show_default=True,
               help="Acceleration limit [m/s^2] (0.01 to 5)."),
        option("--turn-rate", section=DRIVING, type=float, default=0.8, show_default=True,
               help="Top turn rate on the spot [rad/s] (0.05 to 3)."),
        spec_option(OBSTACLE_MARGIN),
        spec_option(ROBOT_WIDTH),
        option("--cmd-vel", section=ROS, default="",
               help="Velocity command topic, Twist or TwistStamped as the controller takes it "
               "[default: ROS 2 the one the controller subscribes, CONTROLLER/cmd_vel or "
               "Humble's CONTROLLER/cmd_vel_unstamped; ROS 1 /cmd_vel]."),
        option("--odom-topic", section=ROS, default="",
               help="Odometry topic, nav_msgs/Odometry [default: ROS 2 CONTROLLER/odom, "
               "ROS 1 /odom]."),
        option("--laser-mount", section=ROS, default=None, metavar="X,Y,YAW",
               help="ROS 2: the laser's mounting in the base frame (metres, degrees) "
               "[default: from the URDF on /robot_description]."),
        option("--scan-topic", section=ROS, default="/scan", show_default=True,
               help="Laser scan topic (sensor_msgs/LaserScan); its mounting from TF."),
        spec_option(READ["imu_topic"], section=ROS,
                    help="The IMU's topic (sensor_msgs/Imu), its frame's mounting from "
                    "/tf_static or the robot description [default: the one on the graph; "
                    "of several, a check line names them and the one taken]."),
        option("--range-topics", section=ROS, default=None,
               help="Three sensor_msgs/Range topics, comma-separated (--measure ranges)."),
        option("--truth-topic", section=ROS, default=None,
               help="Ground-truth pose topic, geometry_msgs/PoseStamped (--measure truth)."),
        option("--base-frame", section=ROS, default="base_link", show_default=True,
               help="The robot's base frame."),
        spec_option(READ["controller"], section=ROS),
        option("--params-file", section=ROS, type=click.Path(dir_okay=False), default=None,
               help="The YAML the controller loads: the new multipliers are written into it "
               "in place (every other byte kept; the previous file kept as FILE.bak)."),
        option("--reload", section=ROS, is_flag=True,
               help="ROS 2: apply each pass through the controller manager (deactivate, "
               "configure, activate; Rolling: unload and load with --params-file appended); "
               "needs controller_manager_msgs."),
        option("--resume", section=OUTPUTS, type=click.Path(file_okay=False), default=None,
               metavar="DIR",
               help="Go on with the self-calibration that stopped in DIR for a controller "
               "restart (its settings; the robot options as before)."),
        option("--robot", section=OUTPUTS, default=None,
               help="Record every pass in the history under this name (umbmark history NAME)."),
        spec_option(HISTORY),
        option("--out", section=OUTPUTS, type=click.Path(file_okay=False), default=None,
               help="Folder for the passes' run logs, the report and the overlay: new or "
               "empty, or (--force) one holding an earlier self-calibration [default: "
               "selfcal-ROBOT, or selfcal-ROBOT-2, -3, ... when an earlier run left files "
               "there]."),
        option("--report", section=OUTPUTS, type=click.Path(dir_okay=False), default=None,
               help="The HTML page of all passes [default: report.html in --out]."),
        force_option("In --out, an earlier self-calibration is replaced whole (its passes "
                     "removed once the checks before moving have passed); a folder holding "
                     "anything else is refused all the same.", section=OUTPUTS),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print one JSON object (metres, radians)."),
    ]
)  # fmt: skip
def selfcal(backend: str | None, json_out: bool, **options: Any) -> None:
    """The robot calibrates itself (the paper's Sec. 6; --routine anywhere: without a corner).

    Placed at its start in view of an L-shaped corner, the robot checks what it needs,
    checks that it turns as its odometry believes, drives UMBmark (5 cw, then 5 ccw runs,
    steering by its odometry, back to the start by the corner between runs), measures
    where it stopped against the corner, calibrates, applies the correction to its
    controller, repeats while the paper's 3 x SEM rule says another pass is worth it, and
    verifies. A zero velocity is sent on any error, on Ctrl-C and on every safety stop,
    then one line says what the controller holds, which passes are on disk and the
    command that runs it again (exit status 130 after Ctrl-C, 3 after a safety stop).

    With --routine anywhere the robot needs no corner and about 2 x 2 m of floor: it
    drives turns on the spot both ways, straights forward and back and arcs, calibrates
    its wheels, E_s and its laser's mounting against the laser's own motion (scan
    matching), applies the result and drives the pattern again to verify.
    """
    from umbmark.cli.common import command_line, console, note, warn, wrote
    from umbmark.cli.render import render_anywhere, render_selfcal
    from umbmark.core.errors import InputError
    from umbmark.jobs.selfcal import default_folder
    from umbmark.jobs.selfcal import selfcal as run_selfcal
    from umbmark.jobs.selfcal_anywhere import AnywhereReport, square_only
    from umbmark.outputs.files import fresh_folder
    from umbmark.robot.connect import connect
    from umbmark.robot.ros_common import RosOptions, laser_mount
    from umbmark.routines.setup import SelfcalSetup

    if backend is None:
        raise InputError("choose the robot: --sim, --ros1 or --ros2")
    use_imu, imu_topic = options.pop("use_imu"), options.pop("imu_topic")
    if imu_topic is not None and not use_imu:
        raise InputError("--imu-topic and --no-imu: give one of them")
    imu = _sim_imu({spec.name: options.pop(spec.name) for spec in SIM_IMU_OPTIONS})
    ranges = options.pop("range_topics")
    ros = RosOptions(
        cmd_vel=options.pop("cmd_vel"),
        odom=options.pop("odom_topic"),
        scan=options.pop("scan_topic"),
        ranges=tuple(t.strip() for t in ranges.split(",")) if ranges else (),
        truth=options.pop("truth_topic"),
        base_frame=options.pop("base_frame"),
        controller=options["controller"] or "/diff_drive_controller",
        params_file=options.pop("params_file"),
        reload=options.pop("reload"),
        laser_mount=None if options["laser_mount"] is None else laser_mount(options["laser_mount"]),
        imu=(imu_topic or "") if use_imu else None,
    )
    options.pop("laser_mount")
    sim = {k: options.pop(k) for k in ("E_d", "E_b", "E_s", "slip", "seed")}
    from umbmark.routines.drive import DriveLimits

    limits = DriveLimits(
        speed=options.pop("speed"),
        acceleration=options.pop("acceleration"),
        turn_rate=options.pop("turn_rate"),
        obstacle_margin=options.pop("obstacle_margin"),
    )
    anywhere = options["routine"] == "anywhere"
    robot = connect(
        backend,  # type: ignore[arg-type]
        ros=ros,
        room=anywhere,
        corner_side=options["corner_side"],
        imu=imu if use_imu else None,
        laser=options.pop("sim_laser"),
        **sim,
    )
    if options["out"] is None:  # the command's own folder; a new one beside an earlier run's
        options["out"] = fresh_folder(default_folder(options["robot"] or robot.name))
    ask = _ask_person if options["measure"] == "tape" else None
    options["tape_marks"] = _numbers(options.pop("tape_marks"))
    folder = Path(options["out"])
    routine = options.pop("routine")
    try:
        if anywhere:  # before the square's options are checked: it takes none of them
            square_only(**SelfcalSetup.square_options(None, options))
        setup = SelfcalSetup(
            limits=limits, robot_name=options.pop("robot"), command=command_line(sys.argv),
            **options,
        )  # fmt: skip
        with _watching() as (progress, runs_left):
            report = run_selfcal(
                robot, setup, routine=routine, progress=progress, ask=ask,
                runs_left=runs_left, notify=note,
            )  # fmt: skip
    except (KeyboardInterrupt, SafetyError, InputError) as exc:
        _stopped(exc, folder)
        raise
    finally:
        robot.close()
    if isinstance(report, AnywhereReport):
        for line in report.checks:
            note(line)
        for line in report.calibration.report.warnings:
            warn(line)
        wrote(report.files)
        if json_out:
            click.echo(report.to_json(), nl=False)
        else:
            render_anywhere(report, console())
            _render_gyro(report, console())
        return
    for p in report.passes:
        for line in p.warnings:
            warn(f"{p.label}, {line}")
    wrote(report.files)
    if report.restart is not None:
        warn(report.restart)
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    render_selfcal(report, console())


def _sim_imu(values: dict[str, Any]) -> ImuSetup:
    """The virtual robot's IMU of ``--sim-imu-rate``, ``--sim-gyro-scale``, ... (checked
    by their own options, so that a bad one is named as given)."""
    from umbmark.sim.imu import ImuSetup

    for spec in SIM_IMU_OPTIONS:
        spec.check(values[spec.name])
    return ImuSetup.of_options({k.removeprefix("sim_"): v for k, v in values.items()})


def _render_gyro(report: AnywhereReport, screen: Console) -> None:
    """The gyro's part of the anywhere routine: the IMU used, what the wheels were
    calibrated against, the gyro's scale and bias (:func:`gyro_lines`)."""
    from umbmark.calibration.gyro import gyro_lines

    gyro = report.calibration.gyro
    if gyro is None or report.imu is None:
        return
    screen.print(
        f"Gyro: {report.imu}; the wheels calibrated against {report.against}.",
        markup=False, highlight=False,
    )  # fmt: skip
    for line in gyro_lines(gyro):
        screen.print(f"  {line}", markup=False, highlight=False)


@contextlib.contextmanager
def _watching() -> Iterator[tuple[Progress, Callable[[RunsLeft], None]]]:
    """The progress line: on a terminal, rich's live line on stderr (what the robot does
    now, a bar of the runs done out of planned, the time left), the routine's lines
    printed above it; elsewhere a plain line at each run's end."""
    from rich import progress as bars
    from rich.console import Console

    from umbmark.cli.common import progress_lines

    err = Console(stderr=True)
    if not err.is_terminal:
        line = progress_lines()  # at each run's end

        def plain(left: RunsLeft) -> None:
            line(left.done, left.planned, left.text())

        yield (lambda label, k, direction, what: None), plain
        return
    with bars.Progress(
        bars.SpinnerColumn(), bars.TextColumn("{task.description}"), bars.BarColumn(),
        bars.TextColumn("{task.fields[left]}"), bars.TimeElapsedColumn(), console=err,
        transient=True,
    ) as bar:  # fmt: skip
        task = bar.add_task("self-calibration (Ctrl-C stops)", total=None, left="")

        def status(label: str, k: int, direction: object, what: str) -> None:
            step = f"run {k} ({getattr(direction, 'value', '')})" if direction else f"move {k}"
            run = f", {step}" if k else ""  # the anywhere pattern's moves have no direction
            bar.update(task, description=f"{label}{run}: {what} (Ctrl-C stops)")

        def counted(left: RunsLeft) -> None:
            bar.update(task, total=left.planned, completed=left.done, left=left.text())

        yield status, counted


def _stopped(exc: BaseException, folder: Path) -> None:
    """After a stop mid-routine (the zero velocity sent): one line with its cause, what
    the controller holds, the passes on disk and the command that runs it again; exit
    130 after Ctrl-C, 3 after a safety stop, 2 for bad input. Nothing where the routine
    had not begun (a refusal before moving is the usual one line)."""
    from umbmark.cli.common import EXIT_BAD_INPUT, error_line, input_error_line
    from umbmark.cli.main import EXIT_ENVIRONMENT, EXIT_INTERRUPTED
    from umbmark.routines.watch import stopped

    stop = stopped(exc)
    if stop is None:
        return
    again = _again(stop, folder)
    if isinstance(exc, KeyboardInterrupt):
        sys.stderr.write("\n" if sys.stderr.isatty() else "")
        error_line(f"interrupted, the robot stopped (zero velocity sent); {stop.text()}; {again}")
        raise click.exceptions.Exit(EXIT_INTERRUPTED) from None
    if isinstance(exc, SafetyError):
        error_line(f"stopped for safety: {exc}; {stop.text()}; {again}")
        raise click.exceptions.Exit(EXIT_ENVIRONMENT) from None
    assert isinstance(exc, InputError)
    line = input_error_line(exc, click.get_current_context().command)
    error_line(f"{line}; the robot stopped; {stop.text()}; {again}")
    raise click.exceptions.Exit(EXIT_BAD_INPUT) from None


def _again(stop: Stopped, folder: Path) -> str:
    """The command that goes on: this one again (from the parameters the controller holds
    now, which each pass composes with), its passes into a new folder beside ``folder``
    so that none on disk is replaced; a resumed one, as it was given."""
    from umbmark.outputs.files import fresh_folder

    args = sys.argv[1:]
    if "selfcal" not in args:  # called from Python: the options are not known here
        return "to go on, run umbmark selfcal again with the same options"
    given = args[args.index("selfcal") + 1 :]
    if "--resume" in given or any(a.startswith("--resume=") for a in given):
        return f"to go on: umbmark selfcal {shlex.join(given)}"
    kept, skip = [], False
    for a in given:
        if skip:
            skip = False
        elif a == "--out":
            skip = True
        elif not a.startswith("--out=") and a != "--force":
            kept.append(a)
    new = fresh_folder(folder)  # a folder holding an earlier try is refused
    command = shlex.join([*kept, "--out", str(new)])
    return f"to run it again from what the controller holds: umbmark selfcal {command}"


def _ask_person(prompt: str) -> str:
    """A tape measurement's answer, typed at the terminal (or piped in, one per line)."""
    try:
        return input(prompt)
    except EOFError:
        raise InputError(
            "--measure tape: the input ended before the distances were given "
            "(a person types them at each stop)"
        ) from None


def _numbers(text: str | None) -> list[float] | None:
    """``--tape-marks``' comma-separated numbers (None when not given)."""
    if text is None:
        return None
    try:
        return [float(part) for part in text.split(",")]
    except ValueError:
        raise InputError(
            f"--tape-marks {text[:60]!r}: give six numbers X1,Y1,X2,Y2,X3,Y3 in metres"
        ) from None

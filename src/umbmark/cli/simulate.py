"""``umbmark simulate``: parse the options, call :func:`umbmark.simulate`, render."""

from __future__ import annotations

import math
from typing import Any

import click

from umbmark.cli.click_options import Command, apply, force_option, option, spec_option
from umbmark.options.fleet import FLEET_SIMULATION_OPTIONS
from umbmark.options.simulate import IMU_OPTIONS, SIMULATE_OPTIONS
from umbmark.options.spec import OUTPUTS

__all__ = ["simulate"]


@click.command(cls=Command)
@apply(
    [
        *(spec_option(spec) for spec in SIMULATE_OPTIONS),
        option("--output", "-o", section=OUTPUTS, type=click.Path(),
               help="Write the runs table (CSV, metres, radians)."),
        option("--logs", section=OUTPUTS, type=click.Path(file_okay=False),
               help="Write each run's time series (time, true pose, encoder counts) into "
               "this folder, in the run-log format that calibrate reads."),
        option("--bag", section=OUTPUTS, type=click.Path(),
               help="Write the runs as one ROS bag, recorded as on a robot with motion "
               "capture: /joint_states, /odom, /tf and /mocap/robot/pose, the robot resting "
               "2 s near the start between runs. NAME.bag is ROS 1, another name a ROS 2 "
               "bag folder (needs the ros extra)."),
        option("--bag-storage", section=OUTPUTS, type=click.Choice(["sqlite3", "mcap"]),
               help="Storage of a ROS 2 --bag [default: sqlite3, as rosbags writes]."),
        option("--scan", section=OUTPUTS, is_flag=True,
               help="With --bag: a 2D laser too, in a room around the runs: /scan at 10 Hz "
               "(360 beams, 1 cm noise), its mounting (0.1 m ahead of the axle) on /tf_static "
               "and in /robot_description with the nominal wheels, for calibrate --scan-topic "
               "/scan."),
        option("--imu", section=OUTPUTS, is_flag=True,
               help="With --bag: an IMU too (a MEMS gyro and accelerometer): /imu "
               "(sensor_msgs/Imu in imu_link, its mounting on /tf_static and in "
               "/robot_description), as the options of 'The IMU' say; its truth in --json."),
        *(spec_option(spec) for spec in IMU_OPTIONS),
        force_option("A --logs folder's run log is replaced whole (its older runs are "
                     "removed, never mixed with the new ones; a folder holding another "
                     ".csv is refused all the same)."),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print a JSON summary."),
        *(spec_option(spec) for spec in FLEET_SIMULATION_OPTIONS),
    ]
)  # fmt: skip
def simulate(json_out: bool, turn_angle: float, **options: Any) -> None:
    """Drive a virtual robot with known errors around a path, steering by its own odometry.

    Writes the runs table that umbmark calibrate reads (-o) and, with --logs, every run's
    time series, or with --bag all runs as one ROS bag. The robot's controller follows the
    path in its odometry frame; its wheels move it by their true diameters; its encoders
    quantize the rotation.
    """
    from umbmark import simulate as run_simulation
    from umbmark.cli.common import console, progress_bar, wrote

    fleet = {k: options.pop(k) for k in ("fleet", "days", "minutes", "out")}
    imu = _imu(options)
    if fleet["fleet"] is not None:
        if imu is not False:
            from umbmark.core.errors import InputError, option

            raise InputError(
                f"{option('fleet')} records an IMU on every robot, each with errors of its own "
                f"(truth.json): leave out {option('imu')} and its options"
            )
        _fleet(json_out, fleet, options)
        return
    runs = options["runs"] * (2 if options["direction"] == "both" else 1)
    bag = f", writing {options['bag']}" if options["bag"] else ""
    with progress_bar(f"simulating {runs} runs{bag}") as progress:
        report = run_simulation(
            turn_angle=math.radians(turn_angle), progress=progress, imu=imu, **options
        )
    wrote(options[key] for key in ("output", "logs", "bag") if options[key])
    summary = report.to_dict()
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    robot, noise = report.robot, report.robot.noise
    out = console()

    def errors(values: dict[str, float]) -> str:
        return ", ".join(f"{name} = {value:.6f}" for name, value in values.items())

    out.print(
        f"Simulated {len(report.runs)} run(s) of {report.path_name}; slip {noise.slip:g} "
        f"m^0.5, bumps {noise.bump_rate:g} per m; seed {report.seed}."
    )
    out.print(
        "True errors, relative to the nominal wheels (D_n = "
        f"{robot.odometry.wheel_diameter * 1000:g} mm, b = {report.nominal_wheelbase * 1000:g} "
        f"mm): {errors(report.true_errors)}."
    )
    if options.get("params") is not None:
        odo = robot.odometry
        out.print(
            "Errors left to the odometry of --params, relative to its parameters (c_L = "
            f"{odo.c_left:.6f}, c_R = {odo.c_right:.6f}, b = {odo.wheelbase * 1000:.2f} mm): "
            f"{errors(report.odometry_errors)}; a calibration of these runs measures these."
        )
    for key, label in (
        ("e_max_syst", "E_max,syst of these runs"),
        ("distance_ratio", "true over odometry distance (E_s)"),
        ("rotation_ratio", "true over odometry rotation"),
    ):
        figure = summary.get(key)
        if isinstance(figure, float):
            shown = f"{figure * 1000:.1f} mm" if key == "e_max_syst" else f"{figure:.6f}"
            out.print(f"{label}: {shown}")
    shift = summary.get("centre_shift")
    if isinstance(shift, float):
        out.print(f"sideways shift of the centre: {shift * 1000:.3f} mm")
    if report.imu is not None:
        out.print(_imu_truth(report.imu.truth()), markup=False)


def _imu(options: dict[str, Any]) -> Any:
    """The IMU asked for: ``--imu`` with the IMU's options (refused without it)."""
    from umbmark.core.errors import InputError
    from umbmark.core.errors import option as named
    from umbmark.options.simulate import IMU

    values = {name: options.pop(name) for name in IMU}
    wanted = options.pop("imu")
    if not wanted:
        changed = [name for name, value in values.items() if value != IMU[name].default]
        if changed:
            raise InputError(f"{named(changed[0])} sets the IMU of {named('imu')}: give it too")
        return False
    from umbmark.sim.imu import ImuSetup

    return ImuSetup.of_options(values)


def _imu_truth(truth: dict[str, Any]) -> str:
    """The IMU's truth in a line (degrees, deg/s)."""
    roll, pitch, yaw = (math.degrees(a) for a in truth["mounting"]["rpy"])
    return (
        f"IMU {truth['topic']} ({truth['frame']}, {truth['rate']:g} Hz, {truth['readings']} "
        f"readings): k_g = {truth['k_g']:.6f}, yaw bias {math.degrees(truth['yaw_bias']):.4f} "
        f"deg/s at the start and {math.degrees(truth['yaw_bias_end']):.4f} deg/s at the end, "
        f"noise {math.degrees(truth['noise_density']):.4g} deg/s/sqrt(Hz), mounted at roll "
        f"{roll:.2f}, pitch {pitch:.2f}, yaw {yaw:.2f} deg"
        + (f"; {truth['clipped']} readings clipped at the full scale" if truth["clipped"] else "")
    )


def _fleet(json_out: bool, fleet: dict[str, Any], options: dict[str, Any]) -> None:
    """``--fleet N``: a simulated fleet's recordings (the other outputs do not apply)."""
    from umbmark import simulate_fleet
    from umbmark.cli.common import console, progress_bar, wrote
    from umbmark.core.errors import InputError, option

    for name in ("output", "logs", "bag", "scan"):  # its IMU is every robot's
        if options.get(name):
            raise InputError(
                f"{option('fleet')} writes its recordings into {option('out')}, not {option(name)}"
            )
    storage = options.get("bag_storage") or "mcap"
    with progress_bar(f"simulating {fleet['fleet']} robots for {fleet['days']} days") as bar:
        report = simulate_fleet(
            fleet["out"], fleet=fleet["fleet"], days=fleet["days"], minutes=fleet["minutes"],
            seed=options["seed"], bag_storage=storage, force=options["force"], progress=bar,
        )  # fmt: skip
    wrote([report.folder])
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    out = console()
    out.print(
        f"{len(report.recordings)} recordings of {len(report.events)} robots in "
        f"{report.folder} (truth.json beside them):",
        markup=False,
    )
    for robot, event in report.events.items():
        out.print(f"  {robot}: {event}", markup=False)
    out.print(
        f"Watch it: umbmark fleet {report.folder} --robot-from '{{robot}}/{{date}}/*' "
        "--report fleet.html",
        markup=False,
    )

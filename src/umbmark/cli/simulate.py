"""``umbmark simulate``: parse the options, call :func:`umbmark.simulate`, render."""

from __future__ import annotations

import math
from typing import Any

import click

from umbmark.cli.click_options import Command, apply, force_option, option
from umbmark.options.spec import OUTPUTS

__all__ = ["simulate"]

ROBOT = "The robot"
DRIVE = "What it drives"
NOISE = "Non-systematic errors"


def _number(*decls: str, section: str, default: float, help_text: str) -> Any:
    return option(
        *decls, section=section, type=float, default=default, show_default=True, help=help_text
    )


@click.command(cls=Command)
@apply(
    [
        _number("--E-d", "E_d", section=ROBOT, default=1.0,
                help_text="True wheel-diameter ratio D_R / D_L (Eq. 2.3), with the wheels "
                "of nominal diameter D_n (without --params' c_L, c_R)."),
        _number("--E-b", "E_b", section=ROBOT, default=1.0,
                help_text="True wheelbase over nominal, b_actual / b (Eq. 2.4), with b of "
                "--wheelbase (without --params' correction)."),
        _number("--E-s", "E_s", section=ROBOT, default=1.0,
                help_text="True average wheel diameter over nominal, D_avg / D_n."),
        _number("--wheelbase", "-b", section=ROBOT, default=0.34,
                help_text="Nominal wheelbase b [m]."),
        _number("--wheel-diameter", section=ROBOT, default=0.15,
                help_text="Nominal wheel diameter D_n [m]."),
        _number("--encoder-resolution", section=ROBOT, default=2000.0,
                help_text="Encoder pulses per motor revolution."),
        _number("--gear-ratio", section=ROBOT, default=20.0,
                help_text="Motor revolutions per wheel revolution."),
        option("--params", section=ROBOT, type=click.Path(dir_okay=False),
               help="Calibration result (calibrate -o) whose c_L, c_R and wheelbase the "
               "robot's odometry uses; --E-d, --E-b, --E-s stay the truth relative to the "
               "nominal values (printed so), the errors left to the odometry are printed "
               "too."),
        option("--path", section=DRIVE, type=click.Choice(["square", "straight", "turn"]),
               default="square", show_default=True,
               help="square (UMBmark), straight (a leg of --side-length, to measure E_s) or "
               "turn (on the spot, by --turn-angle)."),
        _number("--side-length", "-L", section=DRIVE, default=4.0,
                help_text="Side of the square [m]."),
        option("--runs", "-n", section=DRIVE, type=int, default=5, show_default=True,
               help="Runs in each direction (1 to 1000; a run may take at most 2 million "
               "sampling periods, all runs 1e9, with --logs 5 million)."),
        option("--direction", section=DRIVE, type=click.Choice(["both", "cw", "ccw"]),
               default="both", show_default=True,
               help="both (UMBmark), or cw / ccw only (uni-directional)."),
        _number("--turn-angle", section=DRIVE, default=360.0,
                help_text="Angle of --path turn [deg], ccw positive."),
        _number("--dt", section=DRIVE, default=0.01, help_text="Sampling period [s]."),
        _number("--speed", section=DRIVE, default=0.2, help_text="Speed on the legs [m/s]."),
        option("--noise-free", section=NOISE, is_flag=True,
               help="No slip and no bumps (only quantization)."),
        _number("--slip", section=NOISE, default=0.0004,
                help_text="Wheel slip [m^0.5]: each wheel's floor travel errs by slip x "
                "sqrt(travel). The default gives the paper's ~25 mm spread on a 4 m square."),
        _number("--bump-rate", section=NOISE, default=0.0,
                help_text="Floor bumps per metre of wheel travel."),
        _number("--bump-size", section=NOISE, default=0.002,
                help_text="Extra wheel rotation per bump, as a length [m]."),
        option("--seed", section=NOISE, type=int, default=1, show_default=True,
               help="Seed of the random errors (0 to 2^63-1)."),
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
        force_option("A --logs folder's run log is replaced whole (its older runs are "
                     "removed, never mixed with the new ones; a folder holding another "
                     ".csv is refused all the same)."),
        option("--json", "json_out", section=OUTPUTS, is_flag=True,
               help="Print a JSON summary."),
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

    runs = options["runs"] * (2 if options["direction"] == "both" else 1)
    bag = f", writing {options['bag']}" if options["bag"] else ""
    with progress_bar(f"simulating {runs} runs{bag}") as progress:
        report = run_simulation(turn_angle=math.radians(turn_angle), progress=progress, **options)
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

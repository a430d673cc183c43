"""``umbmark simulate``: drive a virtual robot with known errors, write what it measured."""

from __future__ import annotations

import math
from enum import Enum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from .common import check_length_flag, check_positive_flag, progress_bar, reports_input_errors

if TYPE_CHECKING:
    from ..sim.engine import SimResult
    from ..sim.robot import VirtualRobot

__all__ = ["PathChoice", "simulate"]


class PathChoice(str, Enum):
    """Paths ``umbmark simulate`` can drive."""

    square = "square"
    straight = "straight"
    turn = "turn"


class DirectionChoice(str, Enum):
    """Which directions to drive a square in."""

    both = "both"
    cw = "cw"
    ccw = "ccw"


@reports_input_errors
def simulate(
    E_d: Annotated[
        float, typer.Option("--E-d", help="True wheel-diameter ratio D_R / D_L (Eq. 2.3).")
    ] = 1.0,
    E_b: Annotated[
        float, typer.Option("--E-b", help="True wheelbase over nominal, b_actual / b (Eq. 2.4).")
    ] = 1.0,
    E_s: Annotated[
        float, typer.Option("--E-s", help="True average wheel diameter over nominal, D_avg / D_n.")
    ] = 1.0,
    side_length: Annotated[
        float, typer.Option("--side-length", "-L", help="Side of the square [m].")
    ] = 4.0,
    wheelbase: Annotated[
        float, typer.Option("--wheelbase", "-b", help="Nominal wheelbase b [m].")
    ] = 0.34,
    wheel_diameter: Annotated[
        float, typer.Option("--wheel-diameter", help="Nominal wheel diameter D_n [m].")
    ] = 0.15,
    encoder_resolution: Annotated[
        float, typer.Option("--encoder-resolution", help="Encoder pulses per motor revolution.")
    ] = 2000,
    gear_ratio: Annotated[
        float, typer.Option("--gear-ratio", help="Motor revolutions per wheel revolution.")
    ] = 20.0,
    runs: Annotated[int, typer.Option("--runs", "-n", help="Runs in each direction.")] = 5,
    direction: Annotated[
        DirectionChoice,
        typer.Option("--direction", help="both (UMBmark), or cw / ccw only (uni-directional)."),
    ] = DirectionChoice.both,
    path: Annotated[
        PathChoice,
        typer.Option(
            "--path",
            help="square (UMBmark), straight (a leg of --side-length, to measure E_s) or "
            "turn (on the spot, by --turn-angle).",
        ),
    ] = PathChoice.square,
    turn_angle: Annotated[
        float, typer.Option("--turn-angle", help="Angle of --path turn [deg], ccw positive.")
    ] = 360.0,
    noise_free: Annotated[
        bool, typer.Option("--noise-free", help="No slip and no bumps (only quantization).")
    ] = False,
    slip: Annotated[
        float,
        typer.Option(
            "--slip",
            help="Wheel slip [m^0.5]: each wheel's floor travel errs by slip x sqrt(travel). "
            "The default gives the paper's ~25 mm spread on a 4 m square.",
        ),
    ] = 0.0004,
    bump_rate: Annotated[
        float, typer.Option("--bump-rate", help="Floor bumps per metre of wheel travel.")
    ] = 0.0,
    bump_size: Annotated[
        float,
        typer.Option("--bump-size", help="Extra wheel rotation per bump, as a length [m]."),
    ] = 0.002,
    params: Annotated[
        Path | None,
        typer.Option(
            "--params",
            help="Calibration result (calibrate -o) whose c_L, c_R and wheelbase the robot's "
            "odometry uses; the truth stays relative to the nominal values.",
            show_default=False,
        ),
    ] = None,
    dt: Annotated[float, typer.Option("--dt", help="Sampling period [s].")] = 0.01,
    speed: Annotated[float, typer.Option("--speed", help="Speed on the legs [m/s].")] = 0.2,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the random errors.")] = 1,
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help="Write the runs table (CSV, metres, radians).",
            show_default=False,
        ),
    ] = None,
    logs: Annotated[
        Path | None,
        typer.Option(
            "--logs",
            help="Write each run's time series (time, true pose, encoder counts) into this "
            "folder, in the run-log format that calibrate --format log reads.",
            show_default=False,
        ),
    ] = None,
    json_out: Annotated[bool, typer.Option("--json", help="Print a JSON summary.")] = False,
) -> None:
    """Drive a virtual robot with known errors around a path, steering by its own odometry.

    Writes the runs table that umbmark calibrate reads (-o) and, with --logs, every run's
    time series. The robot's controller follows the path in its odometry frame; its
    wheels move it by their true diameters; its encoders quantize the rotation.
    """
    import numpy as np
    from rich.console import Console

    from ..conventions import Direction
    from ..errors import InputError
    from ..io.result_file import read_calibrated_params
    from ..io.runs_table import write_runs_table
    from ..kinematics import WheelParams
    from ..sim import paths
    from ..sim.engine import simulate as run_simulation
    from ..sim.robot import ControlConfig, NoiseModel, VirtualRobot
    from ..sim.summary import describe_simulation

    for name, value in (("--E-d", E_d), ("--E-b", E_b), ("--E-s", E_s)):
        check_positive_flag(name, value)
        if not 0.5 < value < 2.0:
            raise InputError(f"{name} {value:g} is not a plausible ratio (0.5 to 2)")
    check_length_flag("--side-length", side_length, 100.0)
    check_length_flag("--wheelbase", wheelbase, 10.0)
    check_length_flag("--wheel-diameter", wheel_diameter, 10.0)
    for name, value in (
        ("--encoder-resolution", encoder_resolution),
        ("--gear-ratio", gear_ratio),
        ("--dt", dt),
        ("--speed", speed),
    ):
        check_positive_flag(name, value)
    if runs < 1:
        raise InputError(f"--runs must be at least 1, got {runs}")
    if path is PathChoice.square and direction is DirectionChoice.both and runs < 2:
        raise InputError("--runs must be at least 2 for UMBmark (the paper uses 5)")
    for name, value in (("--slip", slip), ("--bump-rate", bump_rate), ("--bump-size", bump_size)):
        if not (math.isfinite(value) and value >= 0):
            raise InputError(f"{name} must be >= 0, got {value:g}")
    if output is not None and path is not PathChoice.square:
        raise InputError("-o writes a runs table of square runs: use --path square")

    odometry = WheelParams(
        wheelbase=wheelbase,
        wheel_diameter=wheel_diameter,
        encoder_resolution=encoder_resolution,
        gear_ratio=gear_ratio,
    )
    noise = NoiseModel() if noise_free else NoiseModel(slip, bump_rate, bump_size)
    robot = VirtualRobot.with_errors(odometry, E_d=E_d, E_b=E_b, E_s=E_s, noise=noise)
    if params is not None:
        applied = read_calibrated_params(params).applied_to(odometry)
        robot = robot.calibrated(applied.c_left, applied.c_right, applied.wheelbase)

    if path is PathChoice.square:
        chosen = paths.square(side_length)
        directions = {
            DirectionChoice.both: [Direction.CW] * runs + [Direction.CCW] * runs,
            DirectionChoice.cw: [Direction.CW] * runs,
            DirectionChoice.ccw: [Direction.CCW] * runs,
        }[direction]
    elif path is PathChoice.straight:
        chosen = paths.straight_line(side_length)
        directions = [Direction.CCW] * runs
    else:
        chosen = paths.spot_turn(math.radians(turn_angle))
        directions = [Direction.CCW] * runs

    control = ControlConfig(dt=dt, speed=speed)
    with progress_bar(f"simulating {len(directions)} runs") as progress:
        result = run_simulation(
            robot,
            chosen,
            directions,
            control,
            np.random.default_rng(seed),
            record=logs is not None,
            progress=progress,
        )
    sim_runs = result.runs()
    note = _provenance(robot, chosen.name, seed, noise)
    if output is not None:
        write_runs_table(output, sim_runs, comment=note)
    if logs is not None:
        _write_logs(logs, result, robot, side_length, note)

    summary = describe_simulation(robot, result, chosen.name, path.value)
    if json_out:
        import json

        typer.echo(json.dumps(summary, indent=2))
        return
    console = Console()
    console.print(
        f"Simulated {len(directions)} run(s) of {chosen.name}: true E_d = {robot.E_d:.6f}, "
        f"E_b = {E_b:.6f}, E_s = {robot.E_s:.6f}; slip {noise.slip:g} m^0.5, "
        f"bumps {noise.bump_rate:g} per m; seed {seed}.",
        highlight=False,
    )
    for key, label in (
        ("e_max_syst", "E_max,syst of these runs"),
        ("distance_ratio", "true over odometry distance (E_s)"),
        ("rotation_ratio", "true over odometry rotation"),
    ):
        figure = summary.get(key)
        if isinstance(figure, float):
            shown = f"{figure * 1000:.1f} mm" if key == "e_max_syst" else f"{figure:.6f}"
            console.print(f"{label}: {shown}", highlight=False)
    shift = summary.get("centre_shift")
    if isinstance(shift, float):
        console.print(f"sideways shift of the centre: {shift * 1000:.3f} mm", highlight=False)
    for written in (output, logs):
        if written is not None:
            console.print(f"wrote {written}", highlight=False)


def _provenance(robot: VirtualRobot, path_name: str, seed: int, noise: object) -> str:
    from .. import __version__

    o = robot.odometry
    return (
        f"Simulated by umbmark {__version__}: {path_name}, seed {seed}.\n"
        f"True robot: D_L = {robot.diameter_left:.6f} m, D_R = {robot.diameter_right:.6f} m, "
        f"b = {robot.wheelbase:.6f} m (E_d = {robot.E_d:.6f}, E_s = {robot.E_s:.6f}).\n"
        f"Odometry: D_n = {o.wheel_diameter:g} m, b = {o.wheelbase:.6f} m, c_L = {o.c_left:.6f}, "
        f"c_R = {o.c_right:.6f}, {o.encoder_resolution:g} pulses x {o.gear_ratio:g}.\n"
        f"Noise: {noise}"
    )


def _write_logs(
    folder: Path, result: SimResult, robot: VirtualRobot, side_length: float, note: str
) -> None:
    from ..errors import InputError
    from ..sources.runlog import LogMetadata, write_log_csv, write_metadata

    assert result.trace is not None
    if folder.exists() and not folder.is_dir():
        raise InputError("exists and is not a folder", source=folder)
    odo = robot.odometry
    write_metadata(
        folder,
        LogMetadata(
            wheel_diameter=odo.wheel_diameter,
            wheelbase=odo.wheelbase,
            wheel_data="counts",
            encoder_resolution=odo.encoder_resolution,
            gear_ratio=odo.gear_ratio,
            side_length=side_length,
            c_left=odo.c_left,
            c_right=odo.c_right,
            extra={
                "truth": {
                    "wheel_diameter_left": robot.diameter_left,
                    "wheel_diameter_right": robot.diameter_right,
                    "wheelbase": robot.wheelbase,
                }
            },
        ),
    )
    trace = result.trace
    for i in range(len(result.directions)):
        end = int(result.samples_used[i])
        write_log_csv(
            folder / f"run-{i + 1:02d}.csv",
            trace.time[: end + 1],
            trace.true_pose[i, : end + 1],
            trace.counts[i, : end + 1],
            comment=note,
        )

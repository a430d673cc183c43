"""``umbmark calibrate``: benchmark a set of runs and compute the correction."""

from __future__ import annotations

import datetime as dt
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from .common import (
    AngleUnit,
    Estimator,
    LengthUnit,
    check_length_flag,
    check_positive_flag,
    reports_input_errors,
    warn,
)

if TYPE_CHECKING:
    from ..result import CalibrationReport

__all__ = ["calibrate", "provenance"]

#: Largest plausible square side and wheelbase [m]: beyond, a unit slip is likelier.
_MAX_SIDE = 100.0
_MAX_WHEELBASE = 10.0


@reports_input_errors
def calibrate(
    source: Annotated[
        Path,
        typer.Argument(
            help="Runs table (CSV: direction, x_abs, y_abs, x_odo, y_odo[, theta_abs, theta_odo]).",
            show_default=False,
        ),
    ],
    side_length: Annotated[
        float | None,
        typer.Option(
            "--side-length", "-L", help="Side of the square path [m].", show_default=False
        ),
    ] = None,
    wheelbase: Annotated[
        float | None,
        typer.Option(
            "--wheelbase",
            "-b",
            help="Wheelbase b the odometry was configured with during the runs [m] "
            "(ros2_control wheel_separation). Taken from --current-params if it has it.",
            show_default=False,
        ),
    ] = None,
    unit: Annotated[
        LengthUnit, typer.Option("--unit", help="Unit of the lengths in the runs table.")
    ] = LengthUnit.m,
    angle_unit: Annotated[
        AngleUnit, typer.Option("--angle-unit", help="Unit of the headings in the runs table.")
    ] = AngleUnit.rad,
    method: Annotated[
        Estimator,
        typer.Option(
            "--method",
            "-m",
            help="Estimator: paper (Eqs. 4.20-4.27 as printed), exact (exact square "
            "geometry, for large errors), heading (final headings, Jung & Chung 2011; "
            "needs theta columns).",
        ),
    ] = Estimator.paper,
    wheel_diameter: Annotated[
        float | None,
        typer.Option(
            "--wheel-diameter",
            help="Nominal wheel diameter D_n [m]; adds the corrected wheel diameters.",
            show_default=False,
        ),
    ] = None,
    current_c_l: Annotated[
        float | None,
        typer.Option(
            "--current-c-l",
            help="Left wheel factor c_L active during the runs (ros2_control "
            "left_wheel_radius_multiplier). Default 1.0, or from --current-params.",
            show_default=False,
        ),
    ] = None,
    current_c_r: Annotated[
        float | None,
        typer.Option(
            "--current-c-r",
            help="Right wheel factor c_R active during the runs. Default 1.0, or from "
            "--current-params.",
            show_default=False,
        ),
    ] = None,
    current_separation_multiplier: Annotated[
        float | None,
        typer.Option(
            "--current-separation-multiplier",
            help="wheel_separation_multiplier active during the runs. Default 1.0, or from "
            "--current-params.",
            show_default=False,
        ),
    ] = None,
    current_params: Annotated[
        Path | None,
        typer.Option(
            "--current-params",
            help="What was active during the runs: a ros2_control (or ROS 1) parameter YAML "
            "(its multipliers, wheel_separation, wheel_radius) or a previous result "
            "(calibrate -o) whose new values were applied. Flags override.",
            show_default=False,
        ),
    ] = None,
    controller: Annotated[
        str | None,
        typer.Option(
            "--controller",
            help="Controller name in the parameter files [default: the one in "
            "--current-params, else diff_drive_controller].",
            show_default=False,
        ),
    ] = None,
    json_out: Annotated[
        bool, typer.Option("--json", help="Print one JSON object (metres, radians) instead.")
    ] = False,
    output: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", help="Write the JSON result to this file.", show_default=False
        ),
    ] = None,
    yaml_path: Annotated[
        Path | None,
        typer.Option(
            "--yaml", help="Write a ros2_control overlay YAML to this file.", show_default=False
        ),
    ] = None,
    ros1_yaml_path: Annotated[
        Path | None,
        typer.Option(
            "--ros1-yaml",
            help="Write ROS 1 diff_drive_controller parameters to this file.",
            show_default=False,
        ),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Draw the clusters (Fig. 6 view) to this .png, .svg or .pdf file.",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Benchmark runs around a square (UMBmark) and compute the correction.

    Prints E_max,syst, the centres of gravity and their spread, the verdict of the paper's
    3 x SEM rule, the estimated errors alpha, beta, E_d, E_b, the correction factors c_L,
    c_R and the corrected wheelbase, composed with the parameters that were active during
    the runs, and the ros2_control overlay to apply them.
    """
    from rich.console import Console

    from ..benchmark import umbmark_benchmark
    from ..calibration import ActiveParams, Calibration
    from ..errors import InputError
    from ..estimators import SquareTest, estimate_errors
    from ..io.atomic import atomic_write_text
    from ..io.result_file import is_result_file, read_active_from_result
    from ..io.ros_params import (
        ActiveMultipliers,
        read_active_multipliers,
        ros1_params,
        ros2_control_overlay,
    )
    from ..io.runs_table import read_runs_table
    from ..result import CalibrationReport
    from .render import render_report

    if side_length is None:
        raise InputError("--side-length is required: the side of the square path, in metres")
    check_length_flag("--side-length", side_length, _MAX_SIDE)
    for name, value in (
        ("--current-c-l", current_c_l),
        ("--current-c-r", current_c_r),
        ("--current-separation-multiplier", current_separation_multiplier),
    ):
        if value is not None:
            check_positive_flag(name, value)
    if wheel_diameter is not None:
        check_length_flag("--wheel-diameter", wheel_diameter, _MAX_WHEELBASE)
    for name, path in (("--yaml", yaml_path), ("--ros1-yaml", ros1_yaml_path)):
        if path is not None and path.suffix.lower() not in (".yaml", ".yml"):
            raise InputError(f"{name} {path}: the file name should end in .yaml or .yml")
    if plot is not None and plot.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise InputError(f"--plot {plot}: the file name should end in .png, .svg or .pdf")

    active_file = None
    if current_params is not None:
        active_file = (
            read_active_from_result(current_params)
            if is_result_file(current_params)
            else read_active_multipliers(current_params, controller)
        )
    if wheelbase is None and active_file is not None:
        wheelbase = active_file.wheel_separation
    if wheelbase is None:
        raise InputError(
            "--wheelbase is required: the wheelbase the odometry used during the runs, in metres"
        )
    check_length_flag("--wheelbase", wheelbase, _MAX_WHEELBASE)
    if wheel_diameter is None and active_file is not None and active_file.wheel_radius:
        wheel_diameter = 2.0 * active_file.wheel_radius

    def pick(flag: float | None, from_file: float) -> float:
        return from_file if flag is None else flag

    from_file = active_file or ActiveMultipliers()
    controller = controller or from_file.controller
    active = ActiveParams(
        wheelbase=wheelbase,
        c_left=pick(current_c_l, from_file.left_wheel_radius_multiplier),
        c_right=pick(current_c_r, from_file.right_wheel_radius_multiplier),
        separation_multiplier=pick(
            current_separation_multiplier, from_file.wheel_separation_multiplier
        ),
        wheel_diameter=wheel_diameter,
    )

    runs = read_runs_table(
        source, unit=unit.value, angle_unit=angle_unit.value, side_length=side_length
    )
    try:
        bench = umbmark_benchmark(runs)
        test = SquareTest(side_length=side_length, wheelbase=active.effective_wheelbase)
        estimate = estimate_errors(method.value, bench, runs, test)
    except ValueError as exc:
        raise InputError(str(exc), source=source) from None
    report = CalibrationReport(
        source=str(source),
        runs=runs,
        benchmark=bench,
        test=test,
        calibration=Calibration(estimate, active),
    )

    comments = provenance(report)
    overlay = ros2_control_overlay(report.calibration, comments, controller)
    for message in report.warnings:
        warn(message)
    if json_out:
        typer.echo(report.to_json(), nl=False)
    else:
        render_report(report, Console(), overlay)
    if output is not None:
        report.write_json(output)
    if yaml_path is not None:
        atomic_write_text(yaml_path, overlay)
    if ros1_yaml_path is not None:
        atomic_write_text(ros1_yaml_path, ros1_params(report.calibration, comments, controller))
    if plot is not None:
        from ..plotting import cluster_figure, save_figure

        save_figure(cluster_figure([(report.benchmark, str(source))]), plot)


def provenance(report: CalibrationReport) -> list[str]:
    """Comment lines saying where a parameter file came from."""
    from .. import __version__

    cal = report.calibration
    active = cal.active
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return [
        f"Written by umbmark {__version__} on {stamp} from {report.source} "
        f"(method {cal.estimate.method}).",
        f"E_d = {cal.estimate.E_d:.6f}, E_b = {cal.estimate.E_b:.6f}; "
        f"E_max,syst of these runs = {report.benchmark.e_max_syst * 1000:.1f} mm.",
        "Multiplied into the values active during the runs: separation "
        f"{active.separation_multiplier:g}, left {active.c_left:g}, right {active.c_right:g}.",
        "diff_drive_controller reads these on configure: reload or restart the controller.",
    ]

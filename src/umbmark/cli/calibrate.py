"""``umbmark calibrate``: benchmark runs, estimate the errors, compute the correction."""

from __future__ import annotations

import datetime as dt
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from .common import (
    AngleUnit,
    Estimator,
    LengthUnit,
    check_figure_path,
    check_length_flag,
    reports_input_errors,
    warn,
)
from .source_options import (
    ControllerOpt,
    CurrentCLOpt,
    CurrentCROpt,
    CurrentParamsOpt,
    CurrentSepOpt,
    FormatChoice,
    FormatOpt,
    LeftJointOpt,
    LeftTicksOpt,
    MaxGapOpt,
    MinRestOpt,
    RightJointOpt,
    RightTicksOpt,
    SourceArg,
    SourceFlags,
    SplitChoice,
    SplitOpt,
    TfChildOpt,
    TfParentOpt,
    TicksPerRevOpt,
    TimeChoice,
    TimeSourceOpt,
    TruthTopicOpt,
    WheelbaseOpt,
    WheelDiameterOpt,
    WheelTopicOpt,
    WindowsOpt,
    load_source,
)

if TYPE_CHECKING:
    from ..result import CalibrationReport

__all__ = ["calibrate", "provenance"]

#: Largest plausible square side [m]: beyond, a unit slip is likelier.
_MAX_SIDE = 100.0
OUTPUTS = "Outputs"


@reports_input_errors
def calibrate(
    source: SourceArg,
    side_length: Annotated[
        float | None,
        typer.Option(
            "--side-length",
            "-L",
            help="Side of the square path [m]. Logged sources may know it (OptiOdom L, "
            "run-log side_length).",
            show_default=False,
        ),
    ] = None,
    wheelbase: WheelbaseOpt = None,
    method: Annotated[
        Estimator,
        typer.Option(
            "--method",
            "-m",
            help="Estimator: paper (Eqs. 4.20-4.27 as printed), exact (exact square "
            "geometry, for large errors), heading (final headings, Jung & Chung 2011; "
            "needs headings), trajectory (least squares on whole ground-truth trajectories "
            "of any shape, logged sources only; finds E_s too).",
        ),
    ] = Estimator.paper,
    fmt: FormatOpt = FormatChoice.auto,
    unit: Annotated[
        LengthUnit, typer.Option("--unit", help="Unit of the lengths in a runs table.")
    ] = LengthUnit.m,
    angle_unit: Annotated[
        AngleUnit, typer.Option("--angle-unit", help="Unit of the headings in a runs table.")
    ] = AngleUnit.rad,
    wheel_diameter: WheelDiameterOpt = None,
    current_c_l: CurrentCLOpt = None,
    current_c_r: CurrentCROpt = None,
    current_separation_multiplier: CurrentSepOpt = None,
    current_params: CurrentParamsOpt = None,
    controller: ControllerOpt = None,
    window: Annotated[
        float,
        typer.Option(
            "--window", help="Window length of the trajectory fit [s].", show_default=True
        ),
    ] = 1.0,
    split: SplitOpt = SplitChoice.rests,
    windows: WindowsOpt = None,
    max_gap: MaxGapOpt = 0.25,
    min_rest: MinRestOpt = 1.0,
    wheel_topic: WheelTopicOpt = "/joint_states",
    left_joint: LeftJointOpt = "left_wheel_joint",
    right_joint: RightJointOpt = "right_wheel_joint",
    left_ticks_topic: LeftTicksOpt = None,
    right_ticks_topic: RightTicksOpt = None,
    ticks_per_rev: TicksPerRevOpt = None,
    truth_topic: TruthTopicOpt = None,
    tf_parent: TfParentOpt = None,
    tf_child: TfChildOpt = None,
    time_source: TimeSourceOpt = TimeChoice.header,
    json_out: Annotated[
        bool,
        typer.Option(
            "--json", help="Print one JSON object (metres, radians).", rich_help_panel=OUTPUTS
        ),
    ] = False,
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help="Write the JSON result to this file.",
            rich_help_panel=OUTPUTS,
            show_default=False,
        ),
    ] = None,
    yaml_path: Annotated[
        Path | None,
        typer.Option(
            "--yaml",
            help="Write a ros2_control overlay YAML.",
            rich_help_panel=OUTPUTS,
            show_default=False,
        ),
    ] = None,
    ros1_yaml_path: Annotated[
        Path | None,
        typer.Option(
            "--ros1-yaml",
            help="Write ROS 1 diff_drive_controller parameters.",
            rich_help_panel=OUTPUTS,
            show_default=False,
        ),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Draw the clusters (Fig. 6 view) to a .png, .svg or .pdf file.",
            rich_help_panel=OUTPUTS,
            show_default=False,
        ),
    ] = None,
    tum: Annotated[
        Path | None,
        typer.Option(
            "--tum",
            help="Logged sources: write TUM trajectories of every run (ground truth, nominal "
            "and calibrated odometry) into this folder, for evo_traj.",
            rich_help_panel=OUTPUTS,
            show_default=False,
        ),
    ] = None,
) -> None:
    """Benchmark runs around a square (UMBmark) and compute the correction.

    From a runs table (end points measured by hand) or from logged runs (run logs, OptiOdom
    sessions, ROS bags: the odometry end poses are integrated from the recorded wheels, the
    true ones taken from the ground truth). Prints E_max,syst, the centres of gravity and
    their spread, the verdict of the paper's 3 x SEM rule, the estimated errors alpha,
    beta, E_d, E_b (and E_s), the correction factors c_L, c_R and the corrected wheelbase,
    composed with the parameters active during the runs, and the ros2_control overlay.
    """
    from rich.console import Console

    from ..association import summarize
    from ..benchmark import umbmark_benchmark
    from ..calibration import Calibration
    from ..errors import InputError
    from ..estimators import SquareTest, estimate_errors
    from ..estimators.trajectory import trajectory_estimate
    from ..io.atomic import atomic_write_text
    from ..io.ros_params import ros1_params, ros2_control_overlay
    from ..result import CalibrationReport
    from .render import render_report

    if side_length is not None:
        check_length_flag("--side-length", side_length, _MAX_SIDE)
    for name, path in (("--yaml", yaml_path), ("--ros1-yaml", ros1_yaml_path)):
        if path is not None and path.suffix.lower() not in (".yaml", ".yml"):
            raise InputError(f"{name} {path}: the file name should end in .yaml or .yml")
    check_figure_path("--plot", plot)
    table = fmt is FormatChoice.table or (fmt is FormatChoice.auto and source.suffix == ".csv")
    if table and side_length is None and method is not Estimator.trajectory:
        raise InputError("--side-length is required: the side of the square path, in metres")

    flags = SourceFlags(
        source=source,
        format=fmt,
        unit=unit.value,
        angle_unit=angle_unit.value,
        side_length=side_length,
        wheelbase=wheelbase,
        wheel_diameter=wheel_diameter,
        current_c_l=current_c_l,
        current_c_r=current_c_r,
        current_separation_multiplier=current_separation_multiplier,
        current_params=current_params,
        controller=controller,
        split=split,
        windows=windows,
        max_gap=max_gap,
        min_rest=min_rest,
        wheel_topic=wheel_topic,
        left_joint=left_joint,
        right_joint=right_joint,
        left_ticks_topic=left_ticks_topic,
        right_ticks_topic=right_ticks_topic,
        ticks_per_rev=ticks_per_rev,
        truth_topic=truth_topic,
        tf_parent=tf_parent,
        tf_child=tf_child,
        time_source=time_source,
    )
    resolved = load_source(flags)
    loaded, active = resolved.loaded, resolved.active
    side = loaded.side_length
    runs = loaded.runs
    for note in loaded.notes:
        warn(note)

    bench = None
    try:
        bench = umbmark_benchmark(runs)
    except ValueError as exc:
        if method is not Estimator.trajectory:
            raise InputError(str(exc), source=source) from None
    try:
        if method is Estimator.trajectory:
            logs = [run.log for run in runs if run.log is not None]
            if not logs or resolved.params is None:
                raise InputError(
                    "the trajectory method needs logged runs (a run log, an OptiOdom session "
                    "or a bag), not a runs table",
                    source=source,
                )
            if not window > 0:
                raise InputError(f"--window must be > 0 s, got {window:g}")
            estimate, _ = trajectory_estimate(logs, resolved.params, side, window)
            test = SquareTest(side or 1.0, active.effective_wheelbase)
        else:
            if side is None:
                raise InputError(
                    "--side-length is required: the side of the square path, in metres",
                    source=source,
                )
            assert bench is not None
            test = SquareTest(side, active.effective_wheelbase)
            estimate = estimate_errors(method.value, bench, runs, test)
    except ValueError as exc:
        raise InputError(str(exc), source=source) from None

    extra: dict[str, object] = {"format": loaded.format}
    if loaded.associations:
        extra["time_association"] = {name: assoc.to_dict() for name, assoc in loaded.associations}
    if loaded.notes:
        extra["notes"] = list(loaded.notes)
    report = CalibrationReport(
        source=str(source),
        runs=runs,
        benchmark=bench,
        test=test,
        calibration=Calibration(estimate, active),
        extra=extra,
    )
    comments = provenance(report)
    overlay = ros2_control_overlay(report.calibration, comments, resolved.controller)
    # Files first: a summary piped into `head` must not cost the user their outputs.
    if output is not None:
        report.write_json(output)
    if yaml_path is not None:
        atomic_write_text(yaml_path, overlay)
    if ros1_yaml_path is not None:
        atomic_write_text(
            ros1_yaml_path, ros1_params(report.calibration, comments, resolved.controller)
        )
    if plot is not None:
        if bench is None:
            raise InputError("--plot needs runs in both directions (cw and ccw)", source=source)
        from ..plotting import cluster_figure, save_figure

        save_figure(cluster_figure([(bench, str(source))]), plot)
    if tum is not None:
        from ..io.tum import write_tum_runs

        if resolved.params is None:
            raise InputError("--tum needs logged runs with time series", source=source)
        cal = report.calibration
        calibrated = resolved.params.with_corrections(
            c_left=cal.new_c_left, c_right=cal.new_c_right, wheelbase=cal.wheelbase_corrected
        )
        write_tum_runs(tum, runs, {"nominal": resolved.params, "calibrated": calibrated})
    for message in report.warnings:
        warn(message)
    if json_out:
        typer.echo(report.to_json(), nl=False)
    else:
        console = Console()
        for line in summarize(loaded.associations):
            console.print(line, highlight=False)
        render_report(report, console, overlay)


def provenance(report: CalibrationReport) -> list[str]:
    """Comment lines saying where a parameter file came from."""
    from .. import __version__

    cal = report.calibration
    active = cal.active
    stamp = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    e_max = (
        ""
        if report.benchmark is None
        else f"; E_max,syst of these runs = {report.benchmark.e_max_syst * 1000:.1f} mm"
    )
    return [
        f"Written by umbmark {__version__} on {stamp} from {report.source} "
        f"(method {cal.estimate.method}).",
        f"E_d = {cal.estimate.E_d:.6f}, E_b = {cal.estimate.E_b:.6f}{e_max}.",
        "Multiplied into the values active during the runs: separation "
        f"{active.separation_multiplier:g}, left {active.c_left:g}, right {active.c_right:g}.",
        "diff_drive_controller reads these on configure: reload or restart the controller.",
    ]

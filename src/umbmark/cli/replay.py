"""``umbmark replay``: re-integrate recorded runs with other parameters, and compare."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .common import check_figure_path, reports_input_errors, warn
from .source_options import (
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

__all__ = ["replay"]


@reports_input_errors
def replay(
    source: SourceArg,
    params: Annotated[
        Path | None,
        typer.Option(
            "--params",
            "-p",
            help="Calibration result (calibrate -o result.json) to replay with; without it, "
            "only the source's nominal parameters are replayed.",
            show_default=False,
        ),
    ] = None,
    fmt: FormatOpt = FormatChoice.auto,
    wheelbase: WheelbaseOpt = None,
    wheel_diameter: WheelDiameterOpt = None,
    current_c_l: CurrentCLOpt = None,
    current_c_r: CurrentCROpt = None,
    current_separation_multiplier: CurrentSepOpt = None,
    current_params: CurrentParamsOpt = None,
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
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    tum: Annotated[
        Path | None,
        typer.Option(
            "--tum",
            help="Write TUM trajectories of every run (ground truth, nominal, calibrated).",
            show_default=False,
        ),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot",
            help="Draw every run's true path and odometry paths to a .png, .svg or .pdf file.",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Replay recorded runs: integrate their wheel data again and compare with the truth.

    Each run's end-pose error (odometry end against ground truth) is computed with the
    source's nominal parameters and, with --params, with a calibration result. Use it to
    check a calibration on runs that were not used to compute it: calibrate on one
    session, replay another (a circle, another day).
    """
    import json
    import math

    from rich.console import Console
    from rich.table import Table
    from rich.text import Text

    from ..association import summarize
    from ..errors import InputError
    from ..io.result_file import read_calibrated_params
    from ..logged import end_errors, reintegrate

    flags = SourceFlags(
        source=source,
        format=fmt,
        wheelbase=wheelbase,
        wheel_diameter=wheel_diameter,
        current_c_l=current_c_l,
        current_c_r=current_c_r,
        current_separation_multiplier=current_separation_multiplier,
        current_params=current_params,
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
    from ..sources.load import detect_format

    check_figure_path("--plot", plot)

    is_table = fmt is FormatChoice.table or (
        fmt is FormatChoice.auto and detect_format(source) == "table"
    )
    resolved = None if is_table else load_source(flags)
    nominal = None if resolved is None else resolved.params
    if resolved is None or nominal is None:
        raise InputError(
            "replay needs recorded wheel data (a run log, an OptiOdom session or a bag), "
            "not a runs table",
            source=source,
        )
    for note in resolved.loaded.notes:
        warn(note)
    runs = resolved.loaded.runs
    sets = {"nominal": nominal}
    if params is not None:
        sets["calibrated"] = read_calibrated_params(params).applied_to(nominal)
    results = {name: reintegrate(runs, p) for name, p in sets.items()}
    errors = {name: end_errors(r) for name, r in results.items()}
    headings = {name: [run.heading_error for run in r] for name, r in results.items()}
    final = "calibrated" if "calibrated" in sets else "nominal"
    summary: dict[str, object] = {
        "source": str(source),
        "format": resolved.loaded.format,
        "params": None if params is None else str(params),
        "runs": [
            {
                "label": run.label,
                "direction": run.direction.value,
                **{f"end_error_{name}": float(errors[name][i]) for name in sets},
                **{f"heading_error_{name}": headings[name][i] for name in sets},
            }
            for i, run in enumerate(runs)
        ],
        "mean_end_error": float(errors[final].mean()),
        "mean_end_error_nominal": float(errors["nominal"].mean()),
        "parameters": {
            name: {
                "wheelbase": p.wheelbase,
                "wheel_diameter_left": p.diameter_left,
                "wheel_diameter_right": p.diameter_right,
            }
            for name, p in sets.items()
        },
        "time_association": {name: assoc.to_dict() for name, assoc in resolved.loaded.associations},
    }
    if "calibrated" in sets:
        summary["mean_end_error_calibrated"] = float(errors["calibrated"].mean())
    if tum is not None:
        from ..io.tum import write_tum_runs

        write_tum_runs(tum, runs, sets)
    if plot is not None:
        from ..plotting import replay_figure, save_figure

        save_figure(replay_figure(runs, sets, title=f"Replay of {source}"), plot)
    if json_out:
        typer.echo(json.dumps(summary, indent=2))
        return

    console = Console()
    table = Table(
        title=Text(f"Replay of {source}: odometry end against ground truth"),
        title_justify="left",
    )
    table.add_column(Text("run"))
    table.add_column(Text("dir"))
    for name in sets:
        table.add_column(Text(f"{name}\nend [mm]"), justify="right")
        table.add_column(Text(f"{name}\nheading [deg]"), justify="right")
    for i, run in enumerate(runs):
        cells = [run.label, run.direction.value]
        for name in sets:
            h = headings[name][i]
            cells += [
                f"{1000 * errors[name][i]:.1f}",
                "" if h is None else f"{math.degrees(h):+.2f}",
            ]
        table.add_row(*(Text(c) for c in cells))
    cells = ["mean", ""]
    for name in sets:
        cells += [f"{1000 * errors[name].mean():.1f}", ""]
    table.add_row(*(Text(c, style="bold") for c in cells))
    console.print(table)
    for name, p in sets.items():
        console.print(
            f"{name}: b = {1000 * p.wheelbase:.2f} mm, D_L = {1000 * p.diameter_left:.3f} mm, "
            f"D_R = {1000 * p.diameter_right:.3f} mm",
            highlight=False,
        )
    for line in summarize(resolved.loaded.associations):
        console.print(line, highlight=False)

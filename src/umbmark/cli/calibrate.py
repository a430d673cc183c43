"""``umbmark calibrate``: parse the options, call :func:`umbmark.calibrate`, render."""

from __future__ import annotations

import sys
from typing import Any

import click

from umbmark.cli.click_options import (
    Command,
    apply,
    force_option,
    option,
    override_option,
    source_options,
    spec_option,
    tum_time_option,
)
from umbmark.estimators.registry import AUTO, CHOICES, DEFAULT, INTERVALS, method_help, names
from umbmark.options.spec import HISTORY, OUTPUTS, SIDE_LENGTH, TEST, WHEELBASE

__all__ = ["calibrate"]


@click.command(cls=Command, no_args_is_help=True)
@click.argument("sources", nargs=-1, required=True, type=click.Path())
@apply(
    [
        spec_option(SIDE_LENGTH),
        spec_option(WHEELBASE, section=TEST),
        option(
            "--method",
            "-m",
            section=TEST,
            type=click.Choice(CHOICES),
            default=None,
            show_default=f"{DEFAULT.name}; {INTERVALS[0]} for tuple files and with --scan-topic",
            help=method_help(),
        ),
        option(
            "--fit-truth-offset",
            section=TEST,
            is_flag=True,
            help=f"With --method {' or '.join(names(trajectories=True))}: fit where the ground "
            "truth's tracked point (a motion-capture marker) sits in the robot frame, instead of "
            "taking it as the axle centre (see --truth-offset to give it).",
        ),
        override_option(
            "Print and write the overlay (--yaml, --ros1-yaml) even when the verdict is do "
            "not apply; take --current-params even when it is a result for another nominal "
            "wheelbase or wheel diameter than the sources' own (more than 1 % apart).",
            section=TEST,
        ),
        option(
            "--robot",
            section=TEST,
            help="Record the calibration in the history under this robot's name (umbmark "
            "history NAME lists them); refused when the robot is known with another nominal "
            "wheelbase or wheel diameter (one unknown on either side is no difference).",
        ),
        spec_option(HISTORY, section=TEST),
    ]
)
@source_options(wheelbase=False)
@apply(
    [
        option(
            "--json",
            "json_out",
            section=OUTPUTS,
            is_flag=True,
            help="Print one JSON object (metres, radians) instead of the summary.",
        ),
        option("--output", "-o", section=OUTPUTS, type=click.Path(), help="Write the JSON result."),
        option("--yaml", section=OUTPUTS, type=click.Path(), help="Write a ros2_control overlay."),
        option(
            "--ros1-yaml",
            section=OUTPUTS,
            type=click.Path(),
            help="Write ROS 1 diff_drive_controller parameters.",
        ),
        option(
            "--plot",
            section=OUTPUTS,
            type=click.Path(),
            help="Draw the clusters (Fig. 6 view) to a .png, .svg or .pdf file.",
        ),
        option(
            "--report",
            section=OUTPUTS,
            type=click.Path(),
            help="Write one self-contained HTML page (.html): the verdict, the clusters, the "
            "runs, the estimates with 95 % intervals, the overlay and the provenance.",
        ),
        option(
            "--tum",
            section=OUTPUTS,
            type=click.Path(),
            help="Logged runs: write TUM trajectories of every run (ground truth, nominal and "
            "calibrated odometry) into this folder, for evo.",
        ),
        tum_time_option(),
        force_option(),
    ]
)
def calibrate(sources: tuple[str, ...], json_out: bool, **options: Any) -> None:
    """Benchmark runs around a square (UMBmark) and compute the correction.

    SOURCES: runs tables (end points measured by hand), run-log folders, OptiOdom session
    folders or ROS bags; several are pooled. From logged runs the odometry end poses are
    integrated from the recorded wheels and the true ones taken from the ground truth.
    Prints first the verdict on the correction (apply; apply with care: why; do not
    apply: why, and what to record instead), then E_max,syst, the centres of gravity and
    their spread, the paper's 3 x SEM rule, the estimated errors alpha, beta, E_d, E_b
    (and E_s), the correction factors c_L, c_R and the corrected wheelbase, composed with
    the parameters active during the runs, and the ros2_control overlay: withheld, and
    not written, when the verdict is do not apply (--override-verdict prints and writes
    it; --force only replaces files that exist).
    """
    from umbmark import calibrate as run_calibration
    from umbmark.cli.common import (
        EXIT_DO_NOT_APPLY,
        command_line,
        console,
        note,
        warn,
        working,
        wrote,
    )

    options["command"] = command_line(sys.argv)
    method = str(options.get("method"))
    if options.get("scan_topic") is not None:  # scan matching: seconds to minutes
        with working(f"matching the scans of {options['scan_topic']}"):
            report = run_calibration(*sources, **options)
    elif method in names(trajectories=True) or method == AUTO:  # fits that can take minutes
        with working(f"calibrating, --method {method}"):
            report = run_calibration(*sources, **options)
    else:
        report = run_calibration(*sources, **options)
    for line in report.notes:
        note(line)
    for message in report.warnings:
        warn(message)
    outputs = ("output", "yaml", "ros1_yaml", "plot", "tum", "report")
    wrote(options[key] for key in outputs if options[key] and key not in report.withheld)
    if report.recorded is not None:
        note(report.recorded)
    if json_out:
        click.echo(report.to_json(), nl=False)
    else:
        from umbmark.cli.render import render_calibration

        render_calibration(report, console())
    if report.overlay_withheld:  # a valid result, not to apply: a script can tell
        click.get_current_context().exit(EXIT_DO_NOT_APPLY)

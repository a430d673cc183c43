"""``umbmark info``: parse the options, call :func:`umbmark.info`, render."""

from __future__ import annotations

import datetime as dt
from typing import TYPE_CHECKING, Any

import click

from umbmark.cli.click_options import Command, apply, option
from umbmark.options.spec import LOGS, OUTPUTS

if TYPE_CHECKING:
    from rich.console import Console

    from umbmark.jobs.info import InfoReport, LoggedInfo
    from umbmark.sources.bag.info.candidates import Candidate
    from umbmark.sources.bag.info.summary import BagInfo

__all__ = ["info"]


@click.command(cls=Command, no_args_is_help=True)
@click.argument("source", type=click.Path())
@apply(
    [
        option(
            "--max-messages",
            section=LOGS,
            type=click.IntRange(min=1, max=1_000_000),
            help="Bags: messages looked into per topic at most, spread over the topic's "
            "time span [default: 2000].",
        ),
        option(
            "--format",
            "-f",
            "format",
            section=LOGS,
            type=click.Choice(["auto", "bag", "log", "optiodom"]),
            default="auto",
            show_default=True,
            help="Source format (auto: by the path).",
        ),
        option("--json", "json_out", section=OUTPUTS, is_flag=True, help="Print one JSON object."),
    ]
)
def info(source: str, json_out: bool, **options: Any) -> None:
    """What is in a ROS bag, a run log or an OptiOdom session: pick the options from it.

    SOURCE: a ROS 1 .bag file, a ROS 2 bag folder (sqlite3 or MCAP), a run-log folder or
    an OptiOdom session folder. For a bag: every topic with its type, message count,
    rate and duration; the joints of the JointState topics, which of them move and how
    fast; the /tf and /tf_static transforms and their chains; Gazebo's models; the
    wheelbase and wheel diameter of a recorded robot_description, or which of them are
    still needed; the candidates for the wheels, the controller's odometry and the ground
    truth (ranked, with their rates and the --max-gap they need; never the odometry
    itself, and a warning when no independent reference is recorded); the IMUs
    (sensor_msgs/Imu) with their mounting in the base frame; and the options to
    calibrate with. Only a bounded number of messages per topic is looked into
    (--max-messages).
    """
    from umbmark import info as run_info
    from umbmark.cli.common import console, note, warn

    report = run_info(source, **options)
    for line in report.notes:
        note(line)
    for message in report.warnings:
        warn(message)
    if json_out:
        click.echo(report.to_json(), nl=False)
        return
    out = console()
    if report.bag is not None:
        _render_bag(report, report.bag, out)
    elif report.logged is not None:
        _render_logged(report, report.logged, out)


def _number(value: float | None, fmt: str) -> str:
    return "" if value is None else format(value, fmt)


def _more(count: int, what: str) -> str:
    return f"... and {count} more {what}" if count > 0 else ""


def _render_bag(report: InfoReport, bag: BagInfo, out: Console) -> None:
    from rich.text import Text

    from umbmark.cli.render import row, table

    when = (
        ""
        if bag.start is None
        else ", from "
        + dt.datetime.fromtimestamp(bag.start, dt.timezone.utc).isoformat(timespec="seconds")
    )
    out.print(
        Text(
            f"{report.source}: ROS bag ({bag.storage}), {bag.messages} messages, "
            f"{bag.duration:.1f} s{when}"
        )
    )
    topics = table(
        "Topics",
        ["topic", "type", "messages", "rate [Hz]", "duration [s]"],
        left=("topic", "type"),
    )
    for topic in bag.topics:
        row(
            topics,
            topic.name,
            topic.msgtype,
            str(topic.count),
            _number(topic.rate, ".1f"),
            _number(topic.duration, ".1f"),
        )
    out.print(topics)
    if bag.topics_not_listed:
        out.print(Text(_more(bag.topics_not_listed, "topics")))

    for js in bag.joint_states:
        scanned = "all" if js.complete else f"{js.scanned} spread over the topic"
        joints = table(
            f"Joints of {js.topic} ({scanned} messages looked into)",
            ["joint", "messages", "position range [rad]", "max speed [rad/s]", "moves"],
            left=("joint", "moves"),
        )
        for joint in js.joints:
            row(
                joints,
                joint.name,
                str(joint.samples),
                _number(joint.position_range, ".3f"),
                _number(joint.max_speed, ".3f"),
                "yes" if joint.moving else "no",
            )
        out.print(joints)
        if js.not_listed:
            out.print(Text(_more(js.not_listed, "joints")))

    if bag.transforms:
        tfs = table(
            "Transforms (parent -> child)",
            ["parent -> child", "topic", "rate [Hz]", "moves"],
            left=("parent -> child", "topic", "moves"),
        )
        for tf in bag.transforms:
            row(
                tfs,
                f"{tf.parent} -> {tf.child}",
                tf.topic,
                "static" if tf.static else _number(tf.rate, ".1f"),
                "yes" if tf.moving else "no",
            )
        out.print(tfs)
        if bag.transforms_not_listed:
            out.print(Text(_more(bag.transforms_not_listed, "transforms")))
    if bag.chains:
        out.print(Text("TF chains:"))
        for chain in bag.chains:
            out.print(Text("  " + " -> ".join(chain)))
        if bag.chains_not_listed:
            out.print(Text("  " + _more(bag.chains_not_listed, "chains")))
    for ms in bag.model_states:
        models = table(
            f"Models of {ms.topic} ({ms.scanned} messages looked into)",
            ["model", "messages", "position range [m]", "moves"],
            left=("model", "moves"),
        )
        for model in ms.models:
            row(models, model.name, str(model.samples), f"{model.position_range:.3f}",
                "yes" if model.moving else "no")  # fmt: skip
        out.print(models)
        if ms.not_listed:
            out.print(Text(_more(ms.not_listed, "models")))

    _render_candidates("Wheels", bag.wheels, out)
    _render_candidates("Controller odometry", bag.odometry, out)
    _render_candidates("Ground truth", bag.truth, out)
    if not bag.independent:
        out.print(Text("  No ground truth independent of the odometry (see the warning)."))
    _render_imus(bag, out)
    _render_geometry(bag, out)
    if bag.suggested_options is not None:
        out.print(Text(f"Suggested options: {bag.suggested_options}", style="bold"))
    else:
        out.print(Text("No wheel data or ground truth found to suggest options for."))
    if bag.scan_options is not None:
        needs = "".join(f" {flag} ..." for flag in bag.needs)
        out.print(
            Text(
                "Wheels against the laser's scan matching (umbmark calibrate --help, "
                "--scan-topic): umbmark "
                f"calibrate {bag.path} {bag.scan_options}{needs}",
                style="bold",
            )
        )
    looked = (
        "every message of the topics looked into was read"
        if bag.complete
        else f"at most {bag.max_messages} messages per topic were looked into"
        " (--max-messages), spread over each topic's time span"
    )
    out.print(Text(f"Counts and rates are the bag's own; {looked}."))


def _render_candidates(title: str, candidates: tuple[Candidate, ...], out: Console) -> None:
    from rich.text import Text

    if not candidates:
        out.print(Text(f"{title}: none found"))
        return
    out.print(Text(f"{title}:"))
    for candidate in candidates:
        moves = {True: "", False: " [does not move]", None: ""}[candidate.moving]
        rate = "" if candidate.rate is None else f", {candidate.rate:.1f} Hz"
        gap = candidate.gap_option
        needs = (
            f", needs --max-gap {gap[1]} s" if gap is not None and title == "Ground truth" else ""
        )
        options = f"   {candidate.command_line}" if candidate.options else ""
        out.print(Text(f"  {candidate.label}{rate}{needs}{moves}{options}"))
        if candidate.warning is not None:
            out.print(Text(f"    not suggested: {candidate.warning}"))


def _render_imus(bag: BagInfo, out: Console) -> None:
    """The IMUs: each with its rate and mounting, the option that reads it or why not."""
    from rich.text import Text

    if not bag.imus:
        out.print(Text("IMU: none found"))
        return
    out.print(Text("IMU:"))
    for imu in bag.imus:
        options = "".join(f"   {flag} {value}" for flag, value in imu.options)
        out.print(Text(f"  {imu.describe()}{options}"))
        if imu.problem is not None:
            out.print(Text(f"    not suggested: {imu.problem}"))


def _render_geometry(bag: BagInfo, out: Console) -> None:
    """Where the wheelbase and wheel diameter come from, or which are still needed."""
    from rich.text import Text

    if bag.robot is not None:
        out.print(Text(f"Wheel geometry: {bag.robot.describe()}"))
    if bag.needs:
        why = (
            ""
            if bag.robot is not None
            else f" ({bag.robot_problem})"
            if bag.robot_problem
            else " (the bag holds no robot_description)"
        )
        out.print(Text(f"Still needed: {' and '.join(bag.needs)}{why}"))


def _render_logged(report: InfoReport, logged: LoggedInfo, out: Console) -> None:
    from rich.text import Text

    from umbmark.cli.render import row, table

    kind = "run log" if report.format == "log" else "OptiOdom session"
    runs = "no runs found" if logged.runs is None else f"{logged.runs} runs"
    out.print(Text(f"{report.source}: {kind}, {runs}, {logged.duration:.1f} s recorded"))
    files = table("Files", ["file", "wheel samples", "ground truth samples", "duration [s]"])
    for f in logged.files:
        row(files, f.name, str(f.wheel_samples), str(f.truth_samples), f"{f.duration:.1f}")
    out.print(files)
    if logged.files_not_listed:
        out.print(Text(_more(logged.files_not_listed, "files")))
    p = logged.params
    side = "" if logged.side_length is None else f", square side {logged.side_length:g} m"
    out.print(
        Text(
            f"Wheel parameters: b = {1000 * p.wheelbase:.2f} mm, D_L = "
            f"{1000 * p.diameter_left:.3f} mm, D_R = {1000 * p.diameter_right:.3f} mm, "
            f"{p.encoder_resolution:g} pulses per motor turn, gear ratio {p.gear_ratio:g}{side}"
        )
    )

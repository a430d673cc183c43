"""The reading options are written once (issue 16, item 2): :mod:`umbmark.options.spec`.

The click options of every command that reads sources, the defaults and checks of
:class:`ReadOptions`, the defaults of :class:`BagOptions` and the keys of the
``SourceOptions`` TypedDict all agree with it; a bound in it is refused by the command and
by the library with the same line (expected lines written out by hand)."""

from __future__ import annotations

import typing
from dataclasses import fields
from pathlib import Path

import click
import pytest

import umbmark
from umbmark.cli.calibrate import calibrate as calibrate_command
from umbmark.cli.replay import replay as replay_command
from umbmark.cli.report import report as report_command
from umbmark.cli.validate import validate as validate_command
from umbmark.core.errors import InputError
from umbmark.options.spec import (
    BAGS,
    OUTPUTS,
    PARAMETERS,
    READ,
    READ_OPTIONS,
    SIDE_LENGTH,
    TEST,
    TUM_TIME,
    WHEELBASE,
    Spec,
)
from umbmark.runs.load import FORMATS, Format
from umbmark.runs.read_options import ReadOptions, SourceOptions
from umbmark.sources.bag.bag_options import BagOptions, check_options

from helpers import api_error, cli_error

READERS = {
    "calibrate": calibrate_command,
    "replay": replay_command,
    "report": report_command,
    "validate": validate_command,
}

#: BagOptions spells one reading option otherwise.
BAG_NAMES: dict[str, str] = {}  # BagOptions takes the spec's names


def _param(command: click.Command, name: str) -> click.Option:
    (param,) = [p for p in command.params if isinstance(p, click.Option) and p.name == name]
    return param


def _same_option(command: click.Command, spec: Spec, section: str, help_text: str) -> None:
    param = _param(command, spec.name)
    assert tuple(param.opts) == spec.flags
    assert param.help == help_text
    assert getattr(param, "section", None) == section
    # what the command hands the library when the option is not given
    argv = ["source.csv", "-o", "r.html"] if command is report_command else ["source.csv"]
    assert command.make_context(command.name, argv).params[spec.name] == spec.default
    assert param.nargs == spec.nargs
    if spec.choices:
        assert isinstance(param.type, click.Choice)
        assert tuple(param.type.choices) == spec.choices
    if spec.kind == "number":
        assert isinstance(param.type, click.types.FloatParamType)


# --- the specification itself, against values written here ----------------------------


def test_the_spec_holds_the_documented_values() -> None:
    assert READ["format"].choices == ("auto", "table", "log", "optiodom", "bag", "tuples")
    assert READ["format"].flags == ("--format", "-f")
    assert READ["max_gap"].default == 0.25
    assert READ["min_rest"].default == 1.0
    assert READ["wheel_topic"].default == "/joint_states"
    assert READ["time_source"].default == "header"
    assert READ["unit"].choices == ("m", "cm", "mm")
    assert READ["max_gap"].section == READ["format"].section
    assert READ["left_field"].section == BAGS
    assert WHEELBASE.flags == ("--wheelbase", "-b")
    assert SIDE_LENGTH.flags == ("--side-length", "-L")
    # one entry per keyword, flags the keyword with "-" for "_"
    assert READ["gyro_scale_tolerance"].default == 0.03  # MPU-6050: +-3 % at 25 C
    assert len(READ) == len(READ_OPTIONS) == 35
    for spec in READ_OPTIONS:
        assert spec.flag == "--" + spec.name.replace("_", "-")


# --- derived: the click options ----------------------------------------------------------


@pytest.mark.parametrize("name", sorted(READERS))
def test_every_reading_option_is_a_click_option_of_each_reading_command(name: str) -> None:
    command = READERS[name]
    for spec in READ_OPTIONS:
        _same_option(command, spec, spec.section, spec.help)
    # and in the order of the spec (--help lists them so)
    listed = [p.name for p in command.params if p.name in READ]
    assert listed == [spec.name for spec in READ_OPTIONS]


def test_the_shared_square_options_are_the_specs() -> None:
    _same_option(calibrate_command, WHEELBASE, TEST, WHEELBASE.help)
    _same_option(replay_command, WHEELBASE, PARAMETERS, WHEELBASE.help)
    _same_option(validate_command, WHEELBASE, PARAMETERS, WHEELBASE.help)
    _same_option(calibrate_command, SIDE_LENGTH, TEST, SIDE_LENGTH.help)
    _same_option(report_command, SIDE_LENGTH, TEST, SIDE_LENGTH.help)
    _same_option(validate_command, SIDE_LENGTH, TEST, "Side of squares [m].")


# --- derived: the library's defaults ---------------------------------------------------


def test_read_options_are_the_specs_with_its_defaults() -> None:
    defaults = {f.name: f.default for f in fields(ReadOptions)}
    assert defaults == {spec.name: spec.default for spec in READ_OPTIONS}


def test_source_options_keys_are_the_specs() -> None:
    hints = typing.get_type_hints(SourceOptions)
    assert set(hints) == set(READ)
    for name, hint in hints.items():
        if typing.get_origin(hint) is typing.Literal:
            assert typing.get_args(hint) == READ[name].choices, name
    assert typing.get_args(Format) == FORMATS == READ["format"].choices


def test_bag_options_defaults_are_the_specs() -> None:
    bag = {f.name: f.default for f in fields(BagOptions)}
    for spec in READ_OPTIONS:
        name = BAG_NAMES.get(spec.name, spec.name)
        if name in bag:
            assert bag[name] == spec.default, name
    assert bag["wheel_topic"] == "/joint_states"
    assert bag["time_source"] == "header"


# --- a bound: the same line from the command and the library ----------------------------


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("spec") / "logs"
    umbmark.simulate(E_d=1.004, E_b=1.02, runs=2, side_length=2, dt=0.02, logs=path)
    return path


@pytest.mark.parametrize(
    ("argv", "keywords", "command_line", "python"),
    [
        (["--max-gap", "61"], {"max_gap": 61.0},
         "--max-gap must be at most 60 s, got 61 s",
         "max_gap must be at most 60 s, got 61 s"),
        (["--min-rest", "0"], {"min_rest": 0.0},
         "--min-rest must be > 0, got 0 s",
         "min_rest must be > 0, got 0 s"),
        (["--current-c-l", "9"], {"current_c_l": 9.0},
         "--current-c-l 9 is not a plausible factor: it must be within 0.2 to 5",
         "current_c_l=9 is not a plausible factor: it must be within 0.2 to 5"),
        (["--truth-offset", "6", "0"], {"truth_offset": (6.0, 0.0)},
         "--truth-offset must be within 5 m of the axle centre, not 6.0",
         "truth_offset must be within 5 m of the axle centre, not 6.0"),
    ],
)  # fmt: skip
def test_a_bound_gives_the_same_line_on_the_command_line_and_in_python(
    logs: Path, argv: list[str], keywords: dict[str, object], command_line: str, python: str
) -> None:
    assert cli_error("calibrate", str(logs), *argv) == f"umbmark: error: {command_line}\n"
    assert api_error(umbmark.calibrate, logs, **keywords) == python
    with pytest.raises(InputError) as caught:
        ReadOptions.of(keywords)
    assert caught.value.command_line() == command_line


# --- the field checks, once: the same line from ReadOptions and from the bag reader ----


@pytest.mark.parametrize(
    ("given", "line"),
    [
        ({"left_field": "left_ticks"},
         "--left-field and --right-field go together: give both or neither"),
        ({"right_wheel_frame": "wheel_right_link"},
         "--left-wheel-frame and --right-wheel-frame go together: give both or neither"),
        ({"msg_dir": "msgs"},
         "--msg-dir is for wheel data in a custom message type: give it with --left-field "
         "and --right-field"),
        ({"left_field": "a", "right_field": "b", "odom_topic": "/odom"},
         "--left-field/--right-field read the wheels from --wheel-topic: leave out "
         "--odom-topic"),
        ({"left_field": "a", "right_field": "b", "left_ticks_topic": "/l",
          "right_ticks_topic": "/r"},
         "--left-field/--right-field read the wheels from --wheel-topic: leave out "
         "--left-ticks-topic"),
    ],
)  # fmt: skip
def test_the_field_checks_say_the_same_in_the_job_and_the_bag_reader(
    given: dict[str, object], line: str
) -> None:
    with pytest.raises(InputError) as caught:
        ReadOptions.of(given)
    assert caught.value.command_line() == line
    bag_given = {k: Path(str(v)) if k == "msg_dir" else v for k, v in given.items()}
    if "left_ticks_topic" in given:
        bag_given["ticks_per_rev"] = 100.0
    with pytest.raises(InputError) as caught:
        check_options(BagOptions(**bag_given), "robot.bag")  # type: ignore[arg-type]
    assert caught.value.command_line() == f"robot.bag: {line}"


def test_messages_name_a_spec_option_by_its_long_flag() -> None:
    """A message about ``format`` reads ``--format`` (not ``-f``) on the command line."""
    from umbmark.cli.common import flags_of
    from umbmark.cli.main import cli

    command = cli.commands["calibrate"]
    flags = flags_of(command)
    for spec in (*READ_OPTIONS, WHEELBASE, SIDE_LENGTH):
        assert flags[spec.name] == spec.flag, spec.name
        assert spec.flag.startswith("--")


@pytest.mark.parametrize(
    ("spec", "argv", "value", "command_line", "python"),
    [
        (WHEELBASE, ["--wheelbase", "11"], 11.0,
         "--wheelbase 11 m is implausibly large: lengths are in metres (at most 10 m here; "
         "plausible: 0.001 to 10 m)",
         "wheelbase=11 m is implausibly large: lengths are in metres (at most 10 m here; "
         "plausible: 0.001 to 10 m)"),
        (SIDE_LENGTH, ["-L", "101"], 101.0,
         "--side-length 101 m is implausibly large: lengths are in metres (at most 100 m "
         "here; plausible: 0.001 to 100 m)",
         "side_length=101 m is implausibly large: lengths are in metres (at most 100 m "
         "here; plausible: 0.001 to 100 m)"),
    ],
)  # fmt: skip
def test_the_square_options_bound_is_the_one_the_command_and_the_library_refuse(
    logs: Path, spec: Spec, argv: list[str], value: float, command_line: str, python: str
) -> None:
    assert cli_error("calibrate", str(logs), *argv) == f"umbmark: error: {command_line}\n"
    assert api_error(umbmark.calibrate, logs, **{spec.name: value}) == python
    with pytest.raises(InputError) as caught:
        spec.check(value)
    assert caught.value.command_line() == command_line


def test_tum_time_is_the_specs() -> None:
    from umbmark.outputs.tum import TUM_TIMES, TumTime

    assert TUM_TIME.choices == ("recording", "run")
    assert typing.get_args(TumTime) == TUM_TIMES == TUM_TIME.choices
    for command in (calibrate_command, replay_command):
        _same_option(command, TUM_TIME, OUTPUTS, TUM_TIME.help)


def test_none_is_refused_where_the_option_has_a_default() -> None:
    """None means "not given" only for options without a default; ``max_gap=None`` is a
    mistake, refused with one line (it was before the spec)."""
    for keywords, line in [
        ({"max_gap": None}, "--max-gap must be a number, not 'None'"),
        ({"format": None}, "--format None: use one of auto, table, log, optiodom, bag, tuples"),
    ]:
        with pytest.raises(InputError) as caught:
            ReadOptions.of(keywords)
        assert caught.value.command_line() == line
    assert ReadOptions.of({"wheel_diameter": None}).wheel_diameter is None

"""The self-calibration's settings as one value (:class:`umbmark.SelfcalSetup`): taken by
:func:`umbmark.selfcal` as the value, as its fields by keyword, or both; checked once, by
the option specs the command line is made from, so that a value is refused alike from
both. Expected lines are written by hand."""

from __future__ import annotations

import typing
from dataclasses import fields
from pathlib import Path

import pytest

import umbmark
from umbmark.core.errors import InputError
from umbmark.jobs.selfcal import selfcal
from umbmark.options.selfcal import APPLY, CORNER_SIDE, MAX_PASSES, MEASURE, RUNS, SQUARE_SIDE
from umbmark.robot.base import ApplyMethod
from umbmark.robot.virtual import VirtualRobot
from umbmark.routines.measure import CornerChoice, MeasureMethod
from umbmark.routines.setup import SQUARE_ONLY, SelfcalSetup
from umbmark.routines.watch import RunsLeft

from helpers import api_error, run_cli

#: A short pass: 1 m squares, 2 runs each way, nothing applied (so one pass), no coarse check.
SHORT = {"side_length": 1.0, "runs": 2, "max_passes": 1, "apply": False, "coarse": False}


def _run(*args: object, **kwargs: object) -> tuple[dict[str, object], int]:
    """The report's JSON of a self-calibration of the same virtual robot (seeded), and the
    runs it drove."""
    counted: list[RunsLeft] = []
    report = umbmark.selfcal(VirtualRobot(seed=1), *args, runs_left=counted.append, **kwargs)
    return report.to_dict(), max(left.done for left in counted)


@pytest.mark.slow
def test_the_value_and_the_keywords_drive_the_same_run() -> None:
    by_keywords, runs = _run(**SHORT)
    assert runs == 4  # 2 cw and 2 ccw, one pass, nothing applied: no verification
    assert by_keywords["side_length"] == 1.0
    assert _run(SelfcalSetup(**SHORT)) == (by_keywords, runs)  # type: ignore[arg-type]
    # the keywords change the value's fields
    assert _run(SelfcalSetup(side_length=3.0, runs=5), **SHORT) == (by_keywords, runs)
    other, more = _run(**{**SHORT, "runs": 3})
    assert more == 6
    assert other != by_keywords


def test_the_defaults_are_the_option_specs() -> None:
    setup = SelfcalSetup()
    for spec in (SQUARE_SIDE, RUNS, MAX_PASSES, MEASURE, CORNER_SIDE):
        assert getattr(setup, spec.name) == spec.default
    assert setup.apply is True
    assert setup.apply_method == APPLY.default == "reconfigure"
    assert SelfcalSetup(apply=False).apply_method == "none"


def test_the_spec_choices_are_the_library_types() -> None:
    assert MEASURE.choices == typing.get_args(MeasureMethod)
    assert APPLY.choices == typing.get_args(ApplyMethod)
    assert CORNER_SIDE.choices == typing.get_args(CornerChoice)
    assert set(SQUARE_ONLY) <= {f.name for f in fields(SelfcalSetup)}


@pytest.mark.parametrize(
    ("misspelt", "meant"), [("side_lenght", "side_length"), ("max_pass", "max_passes")]
)
def test_a_misspelt_keyword_is_refused_naming_the_close_one(misspelt: str, meant: str) -> None:
    robot = VirtualRobot(seed=1)
    expected = f"selfcal() got an unexpected keyword argument {misspelt!r}; did you mean {meant}=?"
    for function in (umbmark.selfcal, selfcal):  # the facade's, and the job's own
        with pytest.raises(TypeError) as caught:
            function(robot, **{misspelt: 3})
        assert str(caught.value) == expected
    with pytest.raises(TypeError, match="side_lenght"):
        SelfcalSetup(side_lenght=3)  # type: ignore[call-arg]
    assert robot.commands == []


@pytest.mark.parametrize(
    ("option", "value", "flags", "python"),
    [
        ("runs", 1, ("--runs", "1"), "runs must be 2 to 20, got 1"),
        ("side_length", 0.1, ("-L", "0.1"), "side_length must be 0.5 to 20 m, got 0.1 m"),
        ("max_passes", 9, ("--max-passes", "9"), "max_passes must be 1 to 5, got 9"),
        ("robot_width", 3, ("--robot-width", "3"), "robot_width must be 0.1 to 2 m, got 3 m"),
    ],
)
def test_a_value_is_refused_alike_by_the_command_and_by_python(
    tmp_path: Path, option: str, value: object, flags: tuple[str, str], python: str
) -> None:
    robot = VirtualRobot(seed=1)
    assert api_error(umbmark.selfcal, robot, **{option: value}) == python
    assert api_error(umbmark.selfcal, robot, SelfcalSetup(), **{option: value}) == python
    assert robot.commands == []
    with pytest.raises(InputError) as caught:
        SelfcalSetup(**{option: value})  # type: ignore[arg-type]
    flag = f"--{option.replace('_', '-')}"
    assert caught.value.command_line() == flag + python.removeprefix(option)
    proc = run_cli("selfcal", "--sim", *flags, "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "umbmark: error: " + flag + python.removeprefix(option)
    ]
    assert list(tmp_path.iterdir()) == []


def test_a_runs_count_must_be_whole() -> None:
    assert api_error(SelfcalSetup, runs=2.5) == "--runs must be a whole number, not '2.5'"
    message = api_error(umbmark.selfcal, VirtualRobot(seed=1), runs=2.5)
    assert message == "runs must be a whole number, not '2.5'"


def test_the_anywhere_routine_refuses_a_setups_square_options() -> None:
    robot = VirtualRobot(seed=1)
    message = api_error(
        umbmark.selfcal, robot, SelfcalSetup(runs=3, corner_side="left"), routine="anywhere"
    )
    assert message == (
        'runs, corner_side: the square routine\'s options; routine="anywhere" drives its '
        "own pattern and takes none of them"
    )
    # refused as the square routine's before its own check (0.1 m is no side of a square)
    message = api_error(umbmark.selfcal, robot, routine="anywhere", side_length=0.1)
    assert message.startswith("side_length: the square routine's option;")
    assert robot.commands == []

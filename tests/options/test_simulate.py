"""The options of simulate, study, demo and reproduce written once (issue 24, item 4):
each is a Spec of ``umbmark.options.simulate``, whence the click option (same flags,
default and help) and the library's check, which the command line and Python meet
alike, each naming the option its own way. Expected lines are written by hand."""

from __future__ import annotations

import math

import click
import pytest

import umbmark
from umbmark.cli.demo import demo as demo_command
from umbmark.cli.reproduce import table1 as table1_command
from umbmark.cli.simulate import simulate as simulate_command
from umbmark.cli.study import study as study_command
from umbmark.core.errors import InputError
from umbmark.options.simulate import (
    DEMO_RUNS,
    SEED,
    SIMULATE,
    SIMULATE_OPTIONS,
    STUDY,
    STUDY_OPTIONS,
)
from umbmark.options.spec import Bound, Spec
from umbmark.sim.setup import SimSetup

from helpers import api_error, assert_click_options_are_specs, cli_error

# --- the new kinds of the spec ------------------------------------------------------------


def _refusal(spec: Spec, value: object) -> InputError:
    with pytest.raises(InputError) as caught:
        spec.check(value)
    return caught.value


def test_a_range_includes_both_ends_and_refuses_beyond() -> None:
    spec = Spec("dt", ("--dt",), "S", "h", kind="number", unit="s", bound=Bound("range", 0.5, 0.1))
    spec.check(0.1)
    spec.check(0.5)
    error = _refusal(spec, 0.6)
    assert error.command_line() == "--dt must be 0.1 to 0.5 s, got 0.6 s"
    assert _refusal(spec, math.inf).command_line() == "--dt must be a finite number, got inf"


def test_a_ratio_excludes_its_ends_and_needs_a_positive_number() -> None:
    spec = Spec("E_b", ("--E-b",), "S", "h", kind="number", bound=Bound("ratio", 2.0, 0.5))
    spec.check(1.999)
    assert _refusal(spec, 2.0).command_line() == "--E-b 2 is not a plausible ratio (0.5 to 2)"
    assert _refusal(spec, 0.5).command_line() == "--E-b 0.5 is not a plausible ratio (0.5 to 2)"
    assert _refusal(spec, -1.0).command_line() == "--E-b must be > 0, got -1"


def test_an_integer_takes_whole_numbers_within_its_range() -> None:
    spec = Spec("runs", ("--runs",), "S", "h", kind="integer", bound=Bound("range", 9, 2))
    spec.check(2)
    spec.check(9)
    assert _refusal(spec, 10).command_line() == "--runs must be 2 to 9, got 10"
    assert _refusal(spec, 2.5).command_line() == "--runs must be a whole number, not '2.5'"
    assert _refusal(spec, True).command_line() == "--runs must be a whole number, not 'True'"


def test_a_list_has_one_to_most_values_each_checked() -> None:
    spec = Spec("slip", ("--slip",), "S", "h", kind="number", bound=Bound("range", 1.0, 0.0),
                most=3)  # fmt: skip
    spec.check([0.0, 1.0])
    assert _refusal(spec, []).command_line() == "--slip must list 1 to 3 values, got 0"
    assert _refusal(spec, [0.0] * 4).command_line() == "--slip must list 1 to 3 values, got 4"
    assert _refusal(spec, [0.5, 2.0]).command_line() == "--slip must be 0 to 1, got 2"
    assert _refusal(spec, 0.5).command_line() == "--slip must list 1 to 3 values, not '0.5'"


# --- the click options are the spec's -----------------------------------------------------


@pytest.mark.parametrize(
    ("command", "specs", "same_help"),
    [
        (simulate_command, SIMULATE_OPTIONS, True),
        (study_command, STUDY_OPTIONS, True),
        (demo_command, (DEMO_RUNS,), True),
        (demo_command, (SEED,), False),  # demo's and table1's --seed keep their own help
        (table1_command, (SEED,), False),
    ],
)
def test_the_click_options_are_the_specs(
    command: click.Command, specs: tuple[Spec, ...], same_help: bool
) -> None:
    assert_click_options_are_specs(command, specs, same_help=same_help)


def test_the_library_defaults_are_the_specs() -> None:
    setup = SimSetup()
    for spec in SIMULATE_OPTIONS:
        if spec.name == "turn_angle":  # degrees on the command line, radians here
            assert setup.turn_angle == pytest.approx(2 * math.pi)
        elif spec.name != "params":
            assert getattr(setup, spec.name) == spec.default, spec.name
    assert STUDY["slip"].default == (0.0004,)
    assert SIMULATE["seed"].default == STUDY["seed"].default == 1


# --- refused alike by the command line and by Python --------------------------------------


@pytest.mark.parametrize(
    ("args", "kwargs", "line", "python"),
    [
        (("simulate", "--E-b", "3"), {"E_b": 3.0},
         "--E-b 3 is not a plausible ratio (0.5 to 2)",
         "E_b=3 is not a plausible ratio (0.5 to 2)"),
        (("simulate", "--speed", "6"), {"speed": 6.0},
         "--speed must be 0.01 to 5 m/s, got 6 m/s", "speed must be 0.01 to 5 m/s, got 6 m/s"),
        (("simulate", "-n", "1001"), {"runs": 1001},
         "--runs must be 1 to 1000, got 1001",
         "runs must be 1 to 1000, got 1001"),
    ],
)  # fmt: skip
def test_a_bound_is_refused_alike_by_the_command_and_by_python(
    args: tuple[str, ...], kwargs: dict[str, object], line: str, python: str
) -> None:
    assert cli_error(*args) == f"umbmark: error: {line}\n"
    assert api_error(umbmark.simulate, **kwargs) == python


def test_a_study_grid_value_is_refused_alike() -> None:
    line = cli_error("study", "--slip", "0.001,0.02", "--trials", "1")
    assert line == "umbmark: error: --slip must be 0 to 0.01, got 0.02\n"
    assert (
        api_error(umbmark.study, slip=[0.001, 0.02], trials=1) == "slip must be 0 to 0.01, got 0.02"
    )

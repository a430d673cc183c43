"""The options of plan written once: each is a Spec of ``umbmark.options.plan``, whence
the click option (same flags, default, help, type and choices) and the library's check,
which the command line and Python meet alike, each naming the option its own way.
Expected lines are written by hand (the bounds: 2 to 100 runs, a margin of 0 to 5 m, a
floor of at most 105 m)."""

from __future__ import annotations

import inspect

import pytest

import umbmark
from umbmark.cli.plan import plan as plan_command
from umbmark.options.plan import PLAN, PLAN_OPTIONS
from umbmark.options.spec import SIDE_LENGTH, WHEELBASE

from helpers import api_error, assert_click_options_are_specs, cli_error


def test_the_click_options_are_the_specs() -> None:
    assert_click_options_are_specs(plan_command, PLAN_OPTIONS, besides={"json_out", "force"})


def test_shared_options_are_the_shared_specs() -> None:
    """plan's --wheelbase and --side-length are the shared ones in its words."""
    for mine, shared in ((PLAN["wheelbase"], WHEELBASE), (PLAN["side_length"], SIDE_LENGTH)):
        assert (mine.flags, mine.bound, mine.default) == (shared.flags, shared.bound, None)


def test_the_library_defaults_are_the_specs() -> None:
    defaults = {name: p.default for name, p in inspect.signature(umbmark.plan).parameters.items()}
    assert (defaults["margin"], defaults["noise"], defaults["reading_error"]) == (0.6, "slip", 0.0)


@pytest.mark.parametrize(
    ("args", "kwargs", "line", "python"),
    [
        (("plan", "--scatter", "0.01", "-L", "4", "--runs", "1"),
         {"scatter": 0.01, "side_length": 4.0, "runs": 1},
         "--runs must be 2 to 100, got 1", "runs must be 2 to 100, got 1"),
        (("plan", "--scatter", "0.01", "-L", "4", "--runs", "101"),
         {"scatter": 0.01, "side_length": 4.0, "runs": 101},
         "--runs must be 2 to 100, got 101", "runs must be 2 to 100, got 101"),
        (("plan", "--scatter", "0.01", "--floor", "3", "--target-E-b", "0.01", "--margin", "7"),
         {"scatter": 0.01, "floor": 3.0, "target_E_b": 0.01, "margin": 7.0},
         "--margin must be 0 to 5 m, got 7 m", "margin must be 0 to 5 m, got 7 m"),
        (("plan", "--scatter", "0.01", "--floor", "300", "--target-E-b", "0.01"),
         {"scatter": 0.01, "floor": 300.0, "target_E_b": 0.01},
         "--floor 300 m is implausibly large: lengths are in metres (at most 105 m here; "
         "plausible: 0.001 to 105 m)",
         "floor=300 m is implausibly large: lengths are in metres (at most 105 m here; "
         "plausible: 0.001 to 105 m)"),
    ],
)  # fmt: skip
def test_a_bound_is_refused_alike_by_the_command_and_by_python(
    args: tuple[str, ...], kwargs: dict[str, object], line: str, python: str
) -> None:
    assert cli_error(*args) == f"umbmark: error: {line}\n"
    assert api_error(umbmark.plan, **kwargs) == python


def test_a_whole_number_and_a_choice_are_the_specs() -> None:
    error = api_error(umbmark.plan, scatter=0.01, side_length=4.0, runs=5.5)
    assert error == "runs must be a whole number, not '5.5'"
    assert api_error(umbmark.plan, scatter=0.01, side_length=4.0, runs=5, noise="x") == (
        "noise='x': use one of slip, tape"
    )

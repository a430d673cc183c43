"""The options of reproduce written once: each is a Spec of ``umbmark.options.reproduce``,
whence the click option (same flags, default, help, type) and the library's check of the
seeds, which the command line and Python meet alike. Expected lines are written by hand
(1 to 1000 seeds)."""

from __future__ import annotations

import inspect

import click
import pytest

import umbmark
from umbmark.cli.reproduce import fig4 as fig4_command
from umbmark.cli.reproduce import table1 as table1_command
from umbmark.options.reproduce import FIG4_OPTIONS, TABLE1_OPTIONS
from umbmark.options.simulate import SEED
from umbmark.options.spec import Spec

from helpers import api_error, assert_click_options_are_specs, cli_error


@pytest.mark.parametrize(
    ("command", "specs"), [(table1_command, TABLE1_OPTIONS), (fig4_command, FIG4_OPTIONS)]
)
def test_the_click_options_are_the_specs(command: click.Command, specs: tuple[Spec, ...]) -> None:
    assert_click_options_are_specs(command, specs, besides={"json_out", "force"})


def test_the_seed_is_the_simulators_and_the_defaults_the_specs() -> None:
    seed = next(spec for spec in TABLE1_OPTIONS if spec.name == "seed")
    assert (seed.flags, seed.bound, seed.default) == (SEED.flags, SEED.bound, SEED.default)
    assert inspect.signature(umbmark.reproduce_table1).parameters["seeds"].default == 10


def test_the_seeds_are_refused_alike_by_the_command_and_by_python() -> None:
    line = cli_error("reproduce", "table1", "--seeds", "0")
    assert line == "umbmark: error: --seeds must be 1 to 1000, got 0\n"
    assert api_error(umbmark.reproduce_table1, seeds=0) == "seeds must be 1 to 1000, got 0"
    assert api_error(umbmark.reproduce_table1, seeds=True) == (
        "seeds must be a whole number, not 'True'"
    )

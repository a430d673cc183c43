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

from helpers import api_error, cli_error


def _params(command: click.Command) -> dict[str, click.Option]:
    return {p.name: p for p in command.params if isinstance(p, click.Option) and p.name}


@pytest.mark.parametrize(
    ("command", "specs"), [(table1_command, TABLE1_OPTIONS), (fig4_command, FIG4_OPTIONS)]
)
def test_the_click_options_are_the_specs(command: click.Command, specs: tuple[Spec, ...]) -> None:
    params = _params(command)
    for spec in specs:
        param = params[spec.name]
        assert set(param.opts) == set(spec.flags), spec.name
        assert param.help == spec.help, spec.name
        if spec.default is None:  # not given: click's default is no value
            assert not isinstance(param.default, (bool, int, float, str)), spec.name
        else:
            assert param.default == spec.default, spec.name
        expected = {"integer": click.INT, "number": click.FLOAT}.get(spec.kind)
        if expected is not None:
            assert param.type is expected, spec.name
        if spec.kind == "file":
            assert isinstance(param.type, click.Path), spec.name
            assert not param.type.dir_okay, spec.name
    # the command's own options besides the spec's: --json (and the shared --force)
    assert set(params) - {spec.name for spec in specs} <= {"json_out", "force"}


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

"""The public API as a notebook user meets it: names, keywords, the README's example."""

from __future__ import annotations

import dataclasses
import json
import os
import re
import subprocess
import sys

import pytest

import umbmark
from umbmark.core.errors import InputError, option, option_names
from umbmark.runs.read_options import ReadOptions, SourceOptions

from helpers import ROOT


def test_every_public_name_resolves():
    for name in umbmark.__all__:
        assert getattr(umbmark, name) is not None, name
    assert set(umbmark.__all__) <= set(dir(umbmark))
    with pytest.raises(AttributeError):
        _ = umbmark.calibrat  # type: ignore[attr-defined]


def test_source_options_are_the_read_options():
    """The keywords a type checker knows (SourceOptions) are the ones the jobs accept."""
    assert set(SourceOptions.__annotations__) == {f.name for f in dataclasses.fields(ReadOptions)}


@pytest.mark.slow
def test_readme_python_example_runs_as_written(tmp_path, monkeypatch):
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Use from Python")[1].split("\n## ")[0]
    (code,) = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    for name in ("runs.csv", "clusters.png", "result.json", "overlay.yaml"):
        assert (tmp_path / name).stat().st_size > 0, name
    result = json.loads((tmp_path / "result.json").read_text())
    assert (
        result == umbmark.calibrate("runs.csv", side_length=4, wheelbase=0.34, unit="mm").to_dict()
    )


def test_reports_serialize_to_what_they_hold(table):
    rows = [("cw", 0.1, 0.05, 0, 0)] * 2 + [("ccw", 0.12, -0.04, 0, 0), ("ccw", 0.13, -0.05, 0, 0)]
    report = umbmark.calibrate(table(rows), side_length=4, wheelbase=0.34)
    assert json.loads(report.to_json()) == report.to_dict()
    sim = umbmark.simulate(runs=2, noise_free=True)
    assert json.loads(sim.to_json()) == sim.to_dict()


def test_python_dash_m_is_the_command():
    proc = subprocess.run(
        [sys.executable, "-m", "umbmark", "--version"],
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ},
    )
    assert proc.stdout == f"umbmark {umbmark.__version__}\n"


# --- errors read as the caller writes ----------------------------------------------------

EXAMPLE = str(ROOT / "src" / "umbmark" / "data" / "labmate_runs_mm.csv")


@pytest.mark.parametrize(
    ("call", "args", "keywords", "message"),
    [
        (umbmark.calibrate, (EXAMPLE,), {"unti": "mm"},
         "calibrate() got an unexpected keyword argument 'unti'; did you mean unit=?"),
        (umbmark.calibrate, (EXAMPLE,), {"sidelength": 4},
         "calibrate() got an unexpected keyword argument 'sidelength'; did you mean "
         "side_length=?"),
        (umbmark.simulate, (), {"rusn": 3},
         "simulate() got an unexpected keyword argument 'rusn'; did you mean runs=?"),
        (umbmark.simulate, (), {"e_d": 1.01},
         "simulate() got an unexpected keyword argument 'e_d'; did you mean E_d=?"),
        (umbmark.plan, (), {"scater": 0.01},
         "plan() got an unexpected keyword argument 'scater'; did you mean scatter=?"),
        (umbmark.report, (EXAMPLE,), {"wheelbase": 0.34, "xyzzy": 1},
         "report() got an unexpected keyword argument 'xyzzy'"),
    ],
)  # fmt: skip
def test_a_misspelt_keyword_is_a_type_error_naming_the_close_one(
    call: object, args: tuple[object, ...], keywords: dict[str, object], message: str
) -> None:
    assert callable(call)
    with pytest.raises(TypeError) as caught:
        call(*args, **keywords)
    assert str(caught.value) == message


@pytest.mark.slow
def test_input_errors_name_keywords_to_python_and_flags_to_the_command_line(tmp_path) -> None:
    from helpers import api_error, cli_error

    # A table in mm read as metres: the hint names the unit as each caller writes it.
    line = api_error(umbmark.calibrate, EXAMPLE, side_length=4, wheelbase=0.34)
    assert line.endswith('are these mm, not m? (unit="mm")')
    assert "--" not in line
    cli = cli_error("calibrate", EXAMPLE, "-L", "4", "-b", "0.34")
    assert cli.endswith("are these mm, not m? (--unit mm)\n")
    flags = line.replace('unit="mm"', "--unit mm")
    assert cli == f"umbmark: error: {flags}\n"
    # A bare option, a number, an output (-o) and a flag (--force).
    assert api_error(umbmark.calibrate, EXAMPLE, unit="mm") == (
        "side_length is required: the side of the square path, in metres"
    )
    assert cli_error("calibrate", EXAMPLE, "--unit", "mm") == (
        "umbmark: error: --side-length is required: the side of the square path, in metres\n"
    )
    assert api_error(umbmark.simulate, runs=2000) == "runs must be 1 to 1000, got 2000"
    assert cli_error("simulate", "--runs", "2000") == (
        "umbmark: error: --runs must be 1 to 1000, got 2000\n"
    )
    out = tmp_path / "runs.csv"
    out.write_text("keep me\n")
    assert api_error(umbmark.simulate, path="straight", output=out) == (
        'output writes a runs table of square runs: use path="square"'
    )
    assert cli_error("simulate", "--path", "straight", "-o", str(out)) == (
        "umbmark: error: --output writes a runs table of square runs: use --path square\n"
    )
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "other.csv").write_text("x\n")
    assert "force=True" in api_error(umbmark.simulate, runs=2, logs=logs)
    assert "--force" in cli_error("simulate", "--runs", "2", "--logs", str(logs))
    # The command's degrees are the library's radians: 0.01 deg is 0.000174533 rad.
    tiny = api_error(umbmark.simulate, path="turn", turn_angle=1.74533e-4, speed=1.0, dt=0.05)
    assert tiny.startswith("turn_angle=0.000174533 rad is ")
    cli = cli_error(
        "simulate", "--path", "turn", "--turn-angle", "0.01", "--speed", "1", "--dt", "0.05"
    )
    assert cli.startswith("umbmark: error: --turn-angle 0.01 deg is ")


def test_the_error_keeps_both_forms() -> None:
    with pytest.raises(umbmark.InputError) as caught:
        umbmark.calibrate(EXAMPLE, wheelbase=0.34, unit="mm", side_length=-4)
    error = caught.value
    assert str(error) == "side_length must be > 0, got -4 m"
    assert error.args == (str(error),)
    assert error.command_line() == "--side-length must be > 0, got -4 m"
    assert option_names(error.problem) == ["side_length"]  # the option, by its keyword
    # Where the command's words are command-line syntax, the error carries Python's too.
    with pytest.raises(umbmark.InputError) as caught:
        umbmark.history(plot="trend.png")
    assert str(caught.value) == "plot needs the robot's name (umbmark.history(name, plot=file))"
    assert caught.value.command_line().startswith("--plot needs the robot's NAME (umbmark")


def test_every_option_reads_as_one_of_its_own_flags_on_the_command_line() -> None:
    """An error naming an option by its keyword prints one of that option's flags, the
    long one where it has one (``previous`` is ``--from``, ``output`` ``--output``)."""
    import click

    from umbmark.cli.common import input_error_line
    from umbmark.cli.main import cli

    checked = 0
    for command in cli.commands.values():
        for param in command.params:
            if not isinstance(param, click.Option) or param.name in (None, "help"):
                continue
            if param.is_flag and not param.is_bool_flag:
                continue  # a switch among several (selfcal's --sim/--ros1/--ros2)
            line = input_error_line(InputError(f"{option(param.name)} is wrong"), command)
            flag = line.removesuffix(" is wrong")
            assert flag in param.opts, (command.name, param.name, flag)
            assert flag.startswith("--") or not any(o.startswith("--") for o in param.opts)
            checked += 1
    assert checked > 100
    calibrate = cli.commands["calibrate"]
    assert input_error_line(InputError(option("output")), calibrate) == "--output"
    assert input_error_line(InputError(option("previous")), cli.commands["plan"]) == "--from"


def test_every_function_knows_its_keywords() -> None:
    """So that each refuses a misspelt keyword (none takes arbitrary ones)."""
    import inspect

    from umbmark.core.errors import keywords_of

    functions = [n for n in umbmark.__all__ if inspect.isfunction(getattr(umbmark, n))]
    assert "calibrate" in functions
    for name in functions:
        assert keywords_of(getattr(umbmark, name)) is not None, name

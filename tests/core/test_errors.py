"""An error names options by their keyword (``core.errors.option``), and each layer
renders them: flags on the command line, keywords from Python. Expected lines are written
by hand."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import click
import pytest

from umbmark.core.errors import InputError, Keyword, option, option_names

from helpers import walked

PACKAGE = Path(__file__).resolve().parents[2] / "src" / "umbmark"
#: Where flags are the text itself: the command line, and the option spec's help texts.
FLAG_HOMES = ("cli", "options")


def test_an_option_reads_as_a_flag_on_the_command_line_and_as_a_keyword_in_python():
    error = InputError(f"{option('side_length', -4.0, 'm')} must be > 0", source="runs.csv")
    assert error.command_line() == "runs.csv: --side-length -4 m must be > 0"
    keywords = {"side_length": Keyword("side_length")}
    assert error.python(keywords) == "runs.csv: side_length=-4 m must be > 0"


def test_the_command_names_its_own_flag():
    error = InputError(f"{option('previous', 'a.json')} is not a result")
    assert error.command_line({"previous": "--from"}) == "--from a.json is not a result"
    assert error.python({"previous": Keyword("previous", path=True)}) == (
        "previous='a.json' is not a result"
    )


def test_python_takes_si_units_choices_flags_and_names():
    problem = (
        f"{option('turn_angle', 360.0, 'deg')}, {option('unit', 'mm')}, "
        f"{option('force')}, {option('tf_parent', 'base_link')}"
    )
    keywords = {
        "turn_angle": Keyword("turn_angle"),
        "unit": Keyword("unit", choices=("m", "cm", "mm")),
        "force": Keyword("force", flag=True),
        "tf_parent": Keyword("tf_parent", text=True),
    }
    assert InputError(problem).command_line() == (
        "--turn-angle 360 deg, --unit mm, --force, --tf-parent base_link"
    )
    assert InputError(problem).python(keywords) == (
        "turn_angle=6.28319 rad, unit=\"mm\", force=True, tf_parent='base_link'"
    )


def test_an_option_the_function_does_not_take_stays_a_flag():
    error = InputError(f"see {option('json')}")
    assert error.python({"unit": Keyword("unit")}) == "see --json"


def test_the_names_an_error_carries():
    text = f"{option('left_field')} and {option('right_field')} go together"
    assert option_names(text) == ["left_field", "right_field"]
    assert "\ue000" not in InputError(text).command_line()


def test_a_computations_problem_reads_with_flags_and_keeps_the_names():
    from umbmark.core.errors import ProblemError
    from umbmark.core.messages import info, split_messages

    error = ProblemError(f"the fit diverged; try {option('method', 'trajectory')}")
    assert str(error) == "the fit diverged; try --method trajectory"
    assert option_names(error.problem) == ["method"]
    notes, warnings = split_messages([info(f"read {option('unit', 'mm')}"), error.problem])
    assert notes == ("read --unit mm",)
    assert warnings == ("the fit diverged; try --method trajectory",)


def _known_options() -> set[str]:
    """Every keyword a command line option stands for: the commands' click options."""
    from umbmark.cli.main import cli

    names: set[str] = set()
    for command in cli.commands.values():
        for param in command.params:
            if isinstance(param, click.Option) and param.name:
                names.add(param.name)
    return names


_FLAG = re.compile(r"(?<![\w-])--([a-zA-Z][a-zA-Z0-9]*(?:-[a-zA-Z0-9]+)*)(?![\w-])")


def _problem_texts(call: ast.Call) -> list[ast.AST]:
    """The problem of an ``InputError(...)`` call: its first argument (``python=`` is the
    Python text, written by hand)."""
    return call.args[:1]


def _flags_written(module: Path, known: set[str], root: Path = PACKAGE) -> list[str]:
    found = []
    for call in walked(module):
        if not isinstance(call, ast.Call):
            continue
        name = getattr(call.func, "id", None) or getattr(call.func, "attr", None)
        if name != "InputError":
            continue
        for node in _problem_texts(call):
            for part in ast.walk(node):
                if isinstance(part, ast.Constant) and isinstance(part.value, str):
                    for flag in _FLAG.findall(part.value):
                        keyword = flag.replace("-", "_")
                        if keyword in known:
                            where = module.relative_to(root)
                            found.append(f"{where}:{part.lineno}: --{flag}")
    return found


@pytest.mark.slow
def test_library_errors_name_options_by_keyword_not_by_flag():
    known = _known_options()
    assert {"side_length", "unit", "force", "previous"} <= known
    found = []
    for module in sorted(PACKAGE.rglob("*.py")):
        if module.relative_to(PACKAGE).parts[0] in FLAG_HOMES:
            continue
        found += _flags_written(module, known)
    assert not found, "write option(NAME) instead:\n" + "\n".join(found)


@pytest.mark.parametrize("flag", ["--side-length", "--unit"])
def test_the_check_finds_a_flag_written_in_an_error(tmp_path: Path, flag: str):
    module = tmp_path / "probe.py"
    module.write_text(f'raise InputError(f"{flag} must be positive")\n')
    assert _flags_written(module, {"side_length", "unit"}, tmp_path) == [f"probe.py:1: {flag}"]

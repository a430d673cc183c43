"""The estimator registry: one table that names every estimator, read by everything else.

The names are written in the registry alone; every function it names exists and takes
the calling convention of its kind; reading it costs no numpy (the command line builds
its options from it); the model check is the dispatch's, made once, not the estimators'.
"""

from __future__ import annotations

import ast
import inspect
import math
import subprocess
import sys
import typing
from pathlib import Path

import pytest
from click.testing import CliRunner

from umbmark.cli.main import cli
from umbmark.core.conventions import Direction
from umbmark.estimators.base import SquareTest
from umbmark.estimators.dispatch import estimate_errors
from umbmark.estimators.registry import ESTIMATORS, NAMES, SQUARE, Method
from umbmark.model.run import EndPose, Run
from umbmark.returns.clusters import umbmark_benchmark

PACKAGE = Path(__file__).resolve().parents[2] / "src" / "umbmark"


def test_the_method_type_is_the_tables_names():
    assert typing.get_args(Method) == NAMES
    assert len(set(NAMES)) == len(NAMES)


@pytest.mark.parametrize("entry", ESTIMATORS, ids=lambda e: e.name)
def test_every_estimator_function_takes_its_kinds_calling_convention(entry):
    signature = inspect.signature(entry.load())
    if entry.needs == "square":
        keywords = {"runs": [], "test": None}
        if entry.fits_end_poses:
            keywords |= {"E_s": None, "fit": None}
        signature.bind(None, **keywords)
    elif entry.needs == "intervals":
        signature.bind(None, None, None, **dict(entry.options))
    elif entry.needs == "imu":
        keywords = {"reference": None, "scale_tolerance": 0.03, **dict(entry.options)}
        signature.bind(None, None, None, **keywords)
    else:
        keywords = dict(entry.options)
        if entry.trajectories:
            keywords["fit_truth_offset"] = False
        signature.bind([], None, None, **keywords)


def _names_in_code(path: Path) -> list[tuple[int, str]]:
    """String constants of the code (not docstrings, not the value of an option a message
    names: ``option("method", "trajectory")`` is text, as ``--method trajectory`` was)
    that are an estimator's name."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    in_messages = {
        id(node.args[1])
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and getattr(node.func, "id", None) == "option"
        and len(node.args) > 1
    }
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and node.value in NAMES
        and id(node) not in docstrings | in_messages
    ]


@pytest.mark.slow
def test_estimator_names_are_written_in_the_registry_alone():
    found = {
        f"{path.relative_to(PACKAGE)}:{line}": name
        for path in sorted(PACKAGE.rglob("*.py"))
        if path.name != "registry.py"
        for line, name in _names_in_code(path)
    }
    assert found == {}


def test_reading_the_registry_imports_no_numpy():
    code = (
        "import sys, umbmark.estimators.registry as r; r.method_help(); "
        "print('numpy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_validate_help_names_every_estimator_it_compares():
    from umbmark.calibration.heldout import CANDIDATES

    text = " ".join(CliRunner().invoke(cli, ["validate", "--help"]).output.split())
    listed = text.split("[default: all: ")[1].split("]")[0]
    assert listed.split(", ") == [c for c in CANDIDATES if c != "nominal"]


def _swapped_label_runs() -> list[Run]:
    """Five runs a direction about the exact ends of a robot, a 2 cm regular pentagon
    each; the third cw run labelled ccw (the model check's warning names it)."""
    from umbmark.model.square import square_run_end

    runs = []
    for d in ("cw", "ccw"):
        x, y, theta = square_run_end(1.00084, 336.17 / 340, 1.0, 4.0, 0.34, Direction(d))
        for k in range(5):
            dx, dy = 0.02 * math.cos(2 * math.pi * k / 5), 0.02 * math.sin(2 * math.pi * k / 5)
            label = f"{d} run {k + 1}"
            runs.append(Run(Direction(d), EndPose(x + dx, y + dy, theta), EndPose(0, 0, 0), label))
    swapped = runs[2]
    runs[2] = Run(Direction.CCW, swapped.true_end, swapped.odometry_end, swapped.label)
    return runs


@pytest.mark.parametrize("method", SQUARE)
def test_the_model_check_is_the_dispatchs_not_the_estimators(method):
    runs = _swapped_label_runs()
    bench = umbmark_benchmark(runs)
    test = SquareTest(4.0, 0.34)
    entry = next(e for e in ESTIMATORS if e.name == method)
    alone = entry.load()(bench, runs=runs, test=test)
    assert not any("labelled ccw, sits in the cw cluster" in w for w in alone.warnings)
    dispatched = estimate_errors(method, bench, runs, test)
    assert dispatched.warnings[0].startswith("cw run 3, labelled ccw, sits in the cw cluster")
    assert dispatched.E_d == alone.E_d

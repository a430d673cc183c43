"""Notes are not warnings: what was done or chosen is printed as a plain ``umbmark: ...``
line, what makes a result shaky as ``umbmark: warning: ...``; the report decides
(``report.notes``, ``report.warnings``), the command prints what it says."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import umbmark
from robot_bags import TB3, drive, turtlebot3_bag
from umbmark.core.messages import Info, info, split_messages

from helpers import run_cli, write_table


def _lines(stderr: str, text: str) -> list[str]:
    return [line for line in stderr.splitlines() if text in line]


def test_split_keeps_the_order_and_gives_plain_strings():
    notes, warnings = split_messages(["a unit looks wrong", info("chose exact"), "run left out"])
    assert notes == ("chose exact",)
    assert warnings == ("a unit looks wrong", "run left out")
    assert type(notes[0]) is str
    assert isinstance(info("x"), Info)
    assert json.dumps([info("x")]) == '["x"]'


@pytest.fixture(scope="module")
def second_pass(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A runs table driven with a first pass's parameters, which its header records."""
    folder = tmp_path_factory.mktemp("passes")
    robot = {"E_d": 1.02, "E_b": 1.03, "noise_free": True}
    umbmark.simulate(**robot, output=folder / "pass1.csv")
    umbmark.calibrate(folder / "pass1.csv", side_length=4, wheelbase=0.34, output=folder / "r.json")
    umbmark.simulate(**robot, params=folder / "r.json", output=folder / "pass2.csv")
    return folder / "pass2.csv"


@pytest.mark.slow
def test_the_active_parameters_a_header_records_are_a_note(second_pass: Path):
    proc = run_cli("calibrate", str(second_pass), "-L", "4")
    assert proc.returncode == 0, proc.stderr
    (line,) = _lines(proc.stderr, "active parameters from")
    assert line.startswith("umbmark: active parameters from the table's header: c_L = 0.9")
    assert "warning" not in proc.stderr
    data = json.loads(run_cli("calibrate", str(second_pass), "-L", "4", "--json").stdout)
    assert [n for n in data["notes"] if n.startswith("active parameters from")]
    assert data["warnings"] == []


@pytest.mark.slow
def test_a_conflict_with_the_header_stays_a_warning(second_pass: Path):
    proc = run_cli("calibrate", str(second_pass), "-L", "4", "--current-c-l", "1")
    assert proc.returncode == 0, proc.stderr
    (line,) = _lines(proc.stderr, "--current-c-l gives c_L = 1")
    assert line.startswith("umbmark: warning: --current-c-l gives c_L = 1, but the table's")


@pytest.mark.slow
def test_the_parameters_of_the_last_applied_calibration_are_a_note(tmp_path: Path):
    table, db = tmp_path / "runs.csv", tmp_path / "h.sqlite3"
    umbmark.example(str(table))
    args = ("calibrate", str(table), "-L", "4", "-b", "0.34", "--unit", "mm")
    where = ("--robot", "r", "--history", str(db))
    assert run_cli(*args, *where).returncode == 0
    assert run_cli("history", "r", "--history", str(db), "--applied", "1").returncode == 0
    proc = run_cli(*args, *where)
    (line,) = _lines(proc.stderr, "taken as active during the runs")
    assert line.startswith("umbmark: robot r: taken as active during the runs, the new param")


@pytest.mark.slow
def test_what_a_bag_says_of_itself_is_a_note(tmp_path: Path):
    """The wheels from the robot description, the model-state truth stamped with receive
    times: what was read and how, nothing doubtful."""
    bag = turtlebot3_bag(tmp_path / "tb3", "mcap", drive(TB3, 1.004, 1.02))
    args = ["--truth-topic", "/gazebo/model_states", "--time-source", "bag", "-L", "1"]
    proc = run_cli("calibrate", str(bag), *args)
    assert proc.returncode == 0, proc.stderr
    (wheels,) = _lines(proc.stderr, "from the bag's robot description")
    assert wheels.startswith("umbmark: wheelbase and wheel diameter from the bag's robot")
    (truth,) = _lines(proc.stderr, "which has no header")
    assert truth.startswith("umbmark: ground truth: model turtlebot3_burger of /gazebo/")
    assert "warning" not in proc.stderr
    replayed = run_cli("replay", str(bag), *args[:-2])
    assert replayed.returncode == 0, replayed.stderr
    assert _lines(replayed.stderr, "umbmark: wheelbase and wheel diameter from the bag's")
    assert "warning" not in replayed.stderr


@pytest.mark.slow
def test_plan_says_what_it_chose_plainly_and_warns_where_it_is_rough():
    chosen = run_cli("plan", "--floor", "3", "--scatter", "0.025", "--wheelbase", "0.34")
    assert chosen.returncode == 0, chosen.stderr
    assert chosen.stderr.startswith("umbmark: a 2.40 m square instead of the paper's 4 m")
    assert "warning" not in chosen.stderr
    rough = run_cli("plan", "--scatter", "0.3", "-L", "2", "--runs", "5", "--wheelbase", "0.34")
    assert rough.stderr == (
        "umbmark: warning: the errors' scatter is large for this square: the first-order "
        "figures are rough\n"
    )
    data = json.loads(
        run_cli("plan", "--scatter", "0.3", "-L", "2", "--runs", "5", "--json").stdout
    )
    assert data["notes"] == []
    assert data["warnings"] == [rough.stderr[len("umbmark: warning: ") : -1]]


@pytest.mark.slow
def test_a_unit_that_looks_wrong_stays_a_warning(tmp_path: Path):
    # Return errors of 2 to 5 cm written in metres, read as mm: 20 to 54 micrometres.
    rows = [
        ("cw", 0.020, 0.010, 0, 0), ("cw", 0.030, 0.020, 0, 0),
        ("ccw", 0.050, -0.020, 0, 0), ("ccw", 0.040, -0.010, 0, 0),
    ]  # fmt: skip
    path = write_table(tmp_path / "runs.csv", rows, "direction,x_abs,y_abs,x_odo,y_odo")
    proc = run_cli("calibrate", str(path), "-L", "4", "-b", "0.34", "--unit", "mm")
    # A valid result with the warning; runs scattering less than a tape resolves are a
    # unit mistake: not to apply (exit status 4, docs/reading-results.md).
    assert proc.returncode == 4, proc.stderr
    (line,) = _lines(proc.stderr, "(--unit m)")
    assert line.startswith("umbmark: warning: the end points and return errors reach only")

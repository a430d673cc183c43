"""A second pass without ``--current-params``: the parameters the input records are used.

``umbmark simulate`` records the odometry parameters its robot drove with: in a runs
table as a ``# umbmark-active:`` comment line, in a run log's ``metadata.yaml``. A robot
with known errors is calibrated (pass 1), driven again with the corrected parameters, and
calibrated again without saying what was active (pass 2): the new parameters must be the
composition of both passes, close to the robot's true factors. The truth is what the
simulation was told: ``c_L = 2 / (E_d + 1)``, ``c_R = 2 E_d / (E_d + 1)`` (Eqs. 4.31,
4.32 with the true ``E_d``, the average diameter nominal) and the separation multiplier
``E_b`` (Eq. 2.4: the true wheelbase is ``E_b b``).
"""

from __future__ import annotations

import json

import pytest
import yaml

import umbmark
from umbmark.model.active import ActiveParams
from umbmark.sources.runs_table.reader import read_table_active
from umbmark.sources.runs_table.writer import format_active, write_runs_table

from helpers import api_error, run_cli

E_D, E_B = 1.02, 1.03
TRUE_C_L, TRUE_C_R = 2 / (E_D + 1), 2 * E_D / (E_D + 1)  # 0.990099, 1.009901
#: The noise-free simulator's quantization leaves errors of some 1e-6 in the factors.
TOLERANCE = 2e-5


@pytest.fixture(scope="module")
def passes(tmp_path_factory):  # type: ignore[no-untyped-def]
    """Pass 1 calibrated from its table; pass 2 driven with its result (table and logs)."""
    folder = tmp_path_factory.mktemp("passes")
    robot = {"E_d": E_D, "E_b": E_B, "noise_free": True}
    umbmark.simulate(**robot, output=folder / "pass1.csv")
    umbmark.calibrate(
        folder / "pass1.csv", side_length=4, wheelbase=0.34, output=folder / "r1.json"
    )
    umbmark.simulate(
        **robot, params=folder / "r1.json", output=folder / "pass2.csv", logs=folder / "logs2"
    )
    return folder


def _new(report: umbmark.CalibrationReport) -> tuple[float, float, float]:
    cal = report.calibration
    return cal.new_c_left, cal.new_c_right, cal.new_separation_multiplier


def test_pass_two_alone_is_not_the_truth(passes):
    # The premise: without composing, pass 2 alone would give factors near 1, far from the
    # truth (E_d = 1.02 moves c_L and c_R by 1 %, E_b the multiplier by 3 %).
    alone = umbmark.calibrate(
        passes / "pass2.csv", side_length=4, wheelbase=0.34, current_c_l=1.0, current_c_r=1.0,
        current_separation_multiplier=1.0,
    )  # fmt: skip
    c_l, _c_r, multiplier = _new(alone)
    assert abs(c_l - 1.0) < 1e-3
    assert abs(multiplier - 1.0) < 1e-3
    assert abs(c_l - TRUE_C_L) > 5e-3


def test_the_table_header_records_what_the_robot_drove_with(passes):
    first = json.loads((passes / "r1.json").read_text())
    recorded = read_table_active(passes / "pass2.csv")
    assert recorded is not None
    assert recorded.c_left == pytest.approx(first["new"]["c_L"], rel=1e-11)
    assert recorded.c_right == pytest.approx(first["new"]["c_R"], rel=1e-11)
    assert recorded.wheelbase == 0.34  # the configured wheel_separation stays
    assert recorded.wheel_diameter == 0.15
    assert recorded.separation_multiplier * 0.34 == pytest.approx(first["wheelbase"], rel=1e-11)
    assert read_table_active(passes / "pass1.csv").c_left == 1.0  # pass 1: nominal


def test_second_pass_from_the_table_composes_to_the_truth(passes):
    report = umbmark.calibrate(passes / "pass2.csv", side_length=4)  # no --wheelbase either
    c_l, c_r, multiplier = _new(report)
    assert c_l == pytest.approx(TRUE_C_L, abs=TOLERANCE)
    assert c_r == pytest.approx(TRUE_C_R, abs=TOLERANCE)
    assert multiplier == pytest.approx(E_B, abs=TOLERANCE)
    assert report.calibration.active.wheelbase == 0.34
    assert report.calibration.wheelbase_corrected == pytest.approx(E_B * 0.34, rel=TOLERANCE)
    (note,) = [n for n in report.notes if n.startswith("active parameters")]
    assert "from the table's header" in note
    assert "c_L = 0.990099" in note  # what pass 1 found, the truth to 1e-6
    assert "wheelbase = 0.34 m" in note


@pytest.mark.slow
def test_second_pass_from_the_run_log_composes_to_the_truth(passes):
    report = umbmark.calibrate(passes / "logs2", method="exact")
    c_l, c_r, multiplier = _new(report)
    assert c_l == pytest.approx(TRUE_C_L, abs=TOLERANCE)
    assert c_r == pytest.approx(TRUE_C_R, abs=TOLERANCE)
    assert multiplier == pytest.approx(E_B, abs=TOLERANCE)
    assert report.calibration.active.wheelbase == 0.34
    assert any("from the run log's metadata.yaml" in n for n in report.notes)


def test_second_pass_on_the_command_line(passes, tmp_path):
    overlay = tmp_path / "overlay.yaml"
    proc = run_cli(
        "calibrate", str(passes / "pass2.csv"), "-L", "4", "--yaml", str(overlay), "--json"
    )
    assert proc.returncode == 0, proc.stderr
    assert "active parameters from the table's header" in proc.stderr
    params = yaml.safe_load(overlay.read_text())["diff_drive_controller"]["ros__parameters"]
    assert params["left_wheel_radius_multiplier"] == pytest.approx(TRUE_C_L, abs=TOLERANCE)
    assert params["right_wheel_radius_multiplier"] == pytest.approx(TRUE_C_R, abs=TOLERANCE)
    assert params["wheel_separation_multiplier"] == pytest.approx(E_B, abs=TOLERANCE)


def test_given_parameters_win_and_a_difference_is_named(passes):
    report = umbmark.calibrate(
        passes / "pass2.csv", side_length=4, wheelbase=0.34, current_c_l=1.0, current_c_r=1.0,
        current_separation_multiplier=1.0,
    )  # fmt: skip
    assert report.calibration.active.c_left == 1.0
    text = " ".join(report.warnings)
    assert "--current-c-l gives c_L = 1, but the table's header records c_L = 0.990099" in text
    assert "--current-c-r gives c_R = 1" in text
    assert "records 0.3502 m (wheelbase 0.34 m times wheel_separation_multiplier 1.03)" in text
    # The same parameters as recorded: nothing to say.
    first = json.loads((passes / "r1.json").read_text())
    same = umbmark.calibrate(passes / "pass2.csv", side_length=4, current_params=passes / "r1.json")
    assert not [n for n in same.notes + same.warnings if "records" in n or "active param" in n]
    assert _new(same) == pytest.approx(_new(umbmark.calibrate(passes / "pass2.csv", side_length=4)))
    assert first["new"]["c_L"] == pytest.approx(same.calibration.active.c_left, rel=1e-9)


def test_header_round_trip_and_defaults(tmp_path):
    active = ActiveParams(wheelbase=0.5, c_left=1.01, c_right=0.99, separation_multiplier=1.6)
    assert format_active(active) == (
        "umbmark-active: wheelbase=0.5 c_L=1.01 c_R=0.99 wheel_separation_multiplier=1.6"
    )
    path = tmp_path / "runs.csv"
    umbmark.example(tmp_path / "ex.csv")
    runs = umbmark.read_runs_table(tmp_path / "ex.csv", unit="mm")
    write_runs_table(path, runs, comment="made by a test", active=active)
    assert path.read_text().splitlines()[:2] == ["# made by a test", f"# {format_active(active)}"]
    recorded = read_table_active(path)
    assert (recorded.wheelbase, recorded.c_left, recorded.c_right) == (0.5, 1.01, 0.99)
    assert recorded.separation_multiplier == 1.6
    assert recorded.wheel_diameter is None
    # A table without the line: nothing recorded, --wheelbase still required.
    write_runs_table(path, runs)
    assert read_table_active(path) is None
    assert "wheelbase is required" in api_error(umbmark.calibrate, path, side_length=4)


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("c_L=1.0", "has no c_R"),
        ("c_L=1.0 c_R=1.0 c_L=1.0", "gives c_L twice"),
        ("c_L=1.0 c_R=x", "c_R 'x' is not a number"),
        ("c_L=1.0 c_R=1e300", "c_R = 1e+300 is outside 0.2 to 5"),
        ("c_L=1.0 c_R=1.0 wheelbase=340", "wheelbase = 340 m is outside 0.001 to 10 m"),
        ("c_L=1.0 c_R=1.0 speed=3", "'speed=3' is not one of"),
    ],
)
def test_a_malformed_header_is_one_line_naming_the_row(tmp_path, line, message):
    path = tmp_path / "runs.csv"
    path.write_text(f"# a table\n#umbmark-active: {line}\ndirection,x_abs,y_abs,x_odo,y_odo\n")
    text = api_error(umbmark.calibrate, path, side_length=4, wheelbase=0.34)
    assert text.startswith(f"{path}, row 2: umbmark-active: ")
    assert message in text


def test_a_wheelbase_from_a_header_or_parameter_file_is_named_by_file_and_field(tmp_path):
    # A wheelbase not below half the 4 m side that came from the table's header, or from
    # a controller file: the refusal names that file and field, not --wheelbase.
    source = tmp_path / "ex.csv"
    umbmark.example(source)
    rows = source.read_text()
    path = tmp_path / "runs.csv"
    path.write_text(f"# umbmark-active: wheelbase=2.5 c_L=1.0 c_R=1.0\n{rows}")
    message = api_error(umbmark.calibrate, path, side_length=4, unit="mm")
    assert message.startswith(
        f"{path}: the odometry's wheelbase 2.5 m (umbmark-active: wheelbase) is not smaller"
    )
    assert "(side_length=4 m, so b < 2 m)" in message
    assert "--wheelbase" not in message
    params = tmp_path / "controller.yaml"
    params.write_text(
        "diff_drive_controller:\n  ros__parameters:\n    wheel_separation: 2.5\n"
        "    wheel_separation_multiplier: 1.0\n"
    )
    message = api_error(umbmark.calibrate, source, side_length=4, unit="mm", current_params=params)
    assert message.startswith(f"{params}: the odometry's wheelbase 2.5 m (wheel_separation)")
    assert "--wheelbase" not in message


def test_a_multiplier_from_a_header_is_named_with_the_wheelbase(tmp_path):
    # --wheelbase 0.34 m times the header's wheel_separation_multiplier 4: 1.36 m, not
    # below half a 2 m side. Both are named, each by where it came from.
    source = tmp_path / "ex.csv"
    umbmark.example(source)
    path = tmp_path / "runs.csv"
    path.write_text(
        "# umbmark-active: c_L=1.0 c_R=1.0 wheel_separation_multiplier=4\n" + source.read_text()
    )
    message = api_error(umbmark.calibrate, path, side_length=2, wheelbase=0.34, unit="mm")
    assert message.startswith(
        f"{path}: the odometry's wheelbase 1.36 m (wheelbase times umbmark-active: "
        "wheel_separation_multiplier 4) is not smaller than the square"
    )

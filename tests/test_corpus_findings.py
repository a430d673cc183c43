"""What the hostile-input corpus (tests/corpus/) found wrong with exit 0, each refused or
warned of now.

The bundled table (millimetres, 4 m square, odometry ends at the origin) has its cw
runs at about (69, 36), (97, 89), (26, 45), (106, 69), (46, 47) mm: their return errors
are 52 to 132 mm, median 96.3 mm without the first. Its ccw runs sit at about
(230, -210) mm.
"""

from __future__ import annotations

import math
import shutil
from importlib import resources
from pathlib import Path

import pytest

import umbmark

from helpers import cli_error

EXAMPLE = Path(str(resources.files("umbmark.data").joinpath("labmate_runs_mm.csv")))


def _edited(tmp_path: Path, old: str, new: str) -> str:
    text = EXAMPLE.read_text()
    assert text.count(old) == 1
    path = tmp_path / "runs.csv"
    path.write_text(text.replace(old, new))
    return str(path)


def _calibrate(path: str, **options: object) -> umbmark.CalibrationReport:
    return umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit="mm", **options)


def test_one_row_in_metres_in_a_millimetre_table_is_named(tmp_path):
    clean = _calibrate(str(EXAMPLE))
    assert not [n for n in clean.notes + clean.warnings if "is this row in" in n]
    report = _calibrate(_edited(tmp_path, "cw,69.3,36.4,", "cw,0.0693,0.0364,"))
    (note,) = [n for n in report.warnings if "is this row in" in n]
    # hypot(0.0693, 0.0364) = 0.0783 mm against the median 96.3 mm of the other cw rows:
    # 1231 times smaller; in metres it would be 78.3 mm, among them.
    assert math.hypot(0.0693, 0.0364) == pytest.approx(0.07828, abs=1e-5)
    assert note.startswith("row 7: its return error (0.0783 mm) is 1231 times smaller")
    assert "is this row in m, not mm?" in note


def test_a_swapped_label_is_named_by_row_with_the_default_method(tmp_path):
    clean = _calibrate(str(EXAMPLE))
    assert not [w for w in clean.warnings if "direction label" in w]
    path = _edited(tmp_path, "ccw,219.6,-165.0,", "cw,219.6,-165.0,")
    report = _calibrate(path)  # method exact
    (warning,) = [w for w in report.warnings if "direction label" in w]
    assert warning.startswith("row 12, labelled cw, sits in the ccw cluster")


def _loops(tmp_path: Path, sign_cw: float = -1.0) -> str:
    """Three cw and three ccw runs ending near the origin, headings unwrapped in radians."""
    rows = ["direction,x_abs,y_abs,theta_abs,x_odo,y_odo,theta_odo"]
    for direction, sign in (("cw", sign_cw), ("ccw", -sign_cw)):
        for k in range(3):
            rows.append(
                f"{direction},{0.001 * k:.4f},{0.002:.4f},{sign * (6.2832 + 0.001 * k):.5f},"
                f"0,0,{sign * 6.28319:.5f}"
            )
    path = tmp_path / "loops.csv"
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def test_headings_in_radians_read_as_degrees_are_warned_of(tmp_path):
    path = _loops(tmp_path)
    as_rad = umbmark.calibrate(path, side_length=1, wheelbase=0.34, method="heading")
    assert not [n for n in as_rad.notes + as_rad.warnings if "--angle-unit" in n]
    as_deg = umbmark.calibrate(
        path, side_length=1, wheelbase=0.34, method="heading", angle_unit="deg"
    )
    (note,) = [n for n in as_deg.warnings if "--angle-unit" in n]
    assert note.startswith("theta_odo is about 6.28 deg in every run")
    assert note.endswith("are the headings in radians? (--angle-unit rad)")


def _run_log(tmp_path: Path) -> Path:
    logs = tmp_path / "logs"
    umbmark.simulate(runs=2, dt=0.05, speed=1.0, logs=logs)
    return logs


def test_a_run_file_that_cannot_be_read_stops_the_run_log(tmp_path):
    logs = _run_log(tmp_path)
    first = sorted(logs.glob("*.csv"))[0]
    first.write_text(first.read_text(), encoding="utf-16")
    line = cli_error("calibrate", str(logs))
    assert first.name in line


def test_a_misspelt_run_file_header_is_named(tmp_path):
    logs = _run_log(tmp_path)
    first = sorted(logs.glob("*.csv"))[0]
    first.write_text(first.read_text().replace("theta", "theat", 1))
    line = cli_error("calibrate", str(logs))
    assert f"{first.name}, row 5: missing column theta" in line


def test_a_file_of_another_kind_in_a_run_log_folder_is_named(tmp_path):
    logs = _run_log(tmp_path)
    (logs / "notes.csv").write_text("what,when\ntyres,monday\n")
    line = cli_error("calibrate", str(logs))
    assert "notes.csv, row 1: is not a run file: its header 'what,when'" in line


def test_a_runs_table_beside_the_run_files_is_left_alone(tmp_path):
    logs = _run_log(tmp_path)
    alone = umbmark.calibrate(logs)
    shutil.copy(EXAMPLE, logs / "table.csv")
    beside = umbmark.calibrate(logs)
    assert len(beside.runs) == len(alone.runs)
    assert beside.estimate.E_b == alone.estimate.E_b

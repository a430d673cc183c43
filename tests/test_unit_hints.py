"""Unit hints: a runs table whose numbers are implausible for its unit and the square.

The bundled table is in millimetres: five cw and five ccw runs on a 4 m square, with the
odometry ends at (0, 0). Its farthest end point is row 16, (231.5, -227.6) mm:
sqrt(231.5^2 + 227.6^2) = 324.6 mm, 8 % of the side. Read as centimetres it reaches
3.246 m (81 % of the side: a warning naming mm); read as metres 324.6 m, more than the
side (an error naming mm). A table in metres read as millimetres reaches micrometres.
"""

from __future__ import annotations

from importlib import resources

import pytest

import umbmark

from helpers import api_error, cli_error, run_cli, write_table

EXAMPLE = str(resources.files("umbmark.data").joinpath("labmate_runs_mm.csv"))


def _unit_notes(report: umbmark.CalibrationReport) -> list[str]:
    return [note for note in report.notes if "(--unit " in note]


def test_millimetres_as_millimetres_say_nothing():
    report = umbmark.calibrate(EXAMPLE, side_length=4, wheelbase=0.34, unit="mm")
    assert _unit_notes(report) == []


def test_millimetres_as_centimetres_are_warned_of():
    report = umbmark.calibrate(EXAMPLE, side_length=4, wheelbase=0.34, unit="cm")
    (note,) = _unit_notes(report)
    assert "reach 3.246 m, 81 % of the 4 m side" in note
    assert "read as mm, they would reach 0.3246 m" in note
    assert note.endswith("are these mm, not cm? (--unit mm)")
    proc = run_cli("calibrate", EXAMPLE, "-L", "4", "-b", "0.34", "--unit", "cm", "--json")
    assert proc.returncode == 0
    assert "are these mm, not cm? (--unit mm)" in proc.stderr


def test_millimetres_as_metres_are_refused_naming_the_unit():
    message = api_error(umbmark.calibrate, EXAMPLE, side_length=4, wheelbase=0.34, unit="m")
    # The wording of the estimators' check, and the unit the numbers look like.
    assert "the return error of row 16 (324.6 m) is larger than the square's side (4 m)" in message
    assert message.endswith('are these mm, not m? (unit="mm")')  # to a Python caller
    line = cli_error("calibrate", EXAMPLE, "-L", "4", "-b", "0.34", "--unit", "m")
    assert "(--unit mm)" in line


def test_metres_as_millimetres_are_warned_of(tmp_path):
    # Return errors of 2 to 5 cm in metres, read as mm: 20 to 54 micrometres.
    rows = [
        ("cw", 0.020, 0.010, 0, 0), ("cw", 0.030, 0.020, 0, 0),
        ("ccw", 0.050, -0.020, 0, 0), ("ccw", 0.040, -0.010, 0, 0),
    ]  # fmt: skip
    path = write_table(tmp_path / "runs.csv", rows, "direction,x_abs,y_abs,x_odo,y_odo")
    report = umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit="mm")
    (note,) = _unit_notes(report)
    # Farthest: (0.050, -0.020): sqrt(0.0025 + 0.0004) = 0.05385 mm.
    assert "reach only 0.0539 mm on a 4 m square" in note
    assert note.endswith("are these m, not mm? (--unit m)")
    assert _unit_notes(umbmark.calibrate(path, side_length=4, wheelbase=0.34)) == []


@pytest.mark.parametrize(
    ("unit", "reach", "hint"),
    [
        ("m", 0.9, None),  # 22 % of a 4 m side: a bad robot, but plausible
        ("mm", 1100.0, None),  # 27 %, and no unit smaller than mm explains it
        ("m", 1.1, "cm"),  # 27 %; as cm, 11 mm
        ("cm", 110.0, "mm"),  # 27 %; as mm, 110 mm
    ],
)
def test_the_hint_needs_an_implausible_reach_and_a_unit_that_explains_it(
    tmp_path, unit, reach, hint
):
    rows = [("cw", reach, 0, 0, 0), ("cw", 0.01 * reach, 0, 0, 0)]
    rows += [("ccw", 0.02 * reach, 0, 0, 0), ("ccw", 0.01 * reach, 0.01 * reach, 0, 0)]
    path = write_table(tmp_path / "runs.csv", rows, "direction,x_abs,y_abs,x_odo,y_odo")
    report = umbmark.calibrate(path, side_length=4, wheelbase=0.34, method="exact", unit=unit)
    notes = _unit_notes(report)
    if hint is None:
        assert notes == []
    else:
        (note,) = notes
        assert note.endswith(f"are these {hint}, not {unit}? (--unit {hint})")

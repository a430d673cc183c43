"""Checks on a hand-typed runs table (issue 30, items 2 to 4): a table in metres read as
millimetres, one row typed wrong, odometry end points in the odom frame.

The bundled table's rows (lengths in mm, 4 m square, odometry ends at (0, 0)) are the
base, written after a header line, so that the rows are the file's lines 2 to 11:

    line 2-6   cw   (69.3, 36.4) (97.2, 88.9) (26.3, 45.2) (106.4, 68.9) (46.1, 47.1)
    line 7-11  ccw  (219.6, -165.0) (241.2, -217.1) (217.5, -222.3) (229.3, -198.7)
                    (231.5, -227.6)
"""

from __future__ import annotations

import json
import math
from importlib import resources
from pathlib import Path

import pytest

import umbmark

from helpers import ROOT, api_error, cli_error, linear_cgs, run_cli, runs_around, write_table

EXAMPLE = Path(str(resources.files("umbmark.data").joinpath("labmate_runs_mm.csv")))
HEADER = "direction,x_abs,y_abs,x_odo,y_odo"
REAL = [
    *sorted((ROOT / "src/umbmark/data/optiodom/square").iterdir()),
    *sorted(Path("/work/shared/data/optiodom/square").glob("[0-9]*")),
]


def _rows(path: Path = EXAMPLE) -> list[list[str]]:
    lines = path.read_text(encoding="utf-8").splitlines()
    return [line.split(",") for line in lines if line and not line.startswith(("#", "d"))]


def _table(tmp_path: Path, rows: list[list[str]], name: str = "runs.csv") -> Path:
    return write_table(tmp_path / name, rows, HEADER)


def _calibrate(path: Path, unit: str = "mm") -> umbmark.CalibrationReport:
    return umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit=unit)


# --- no false alarm ---------------------------------------------------------------------


def test_the_bundled_table_raises_no_row_unit_or_frame_doubt():
    report = _calibrate(EXAMPLE)
    assert report.warnings == ()
    assert report.without is None
    assert report.verdict.level == "apply"


@pytest.mark.parametrize("session", REAL, ids=lambda p: f"{p.parent.parent.name}-{p.name}")
def test_real_sessions_typed_as_tables_raise_no_doubt(tmp_path, session):
    # The end poses of real runs (OptiOdom, motion capture), typed as a runs table in mm:
    # three runs each way, the odometry ends up to 23 mm from the start.
    read = umbmark.calibrate(session)
    rows = [
        [run.direction.value]
        + [
            f"{1000 * v:.1f}"
            for v in (run.true_end.x, run.true_end.y, run.odometry_end.x, run.odometry_end.y)
        ]
        for run in read.runs
    ]
    report = umbmark.calibrate(
        _table(tmp_path, rows), side_length=read.test.side_length, wheelbase=0.34, unit="mm"
    )
    assert report.without is None
    assert not [w for w in report.warnings if "row" in w or "unit" in w or "frame" in w]


# --- item 2: a table in metres read as millimetres, at every size -----------------------


@pytest.mark.parametrize(("alpha", "beta"), [(0.0005, 0.001), (0.0025, 0.005), (0.02, 0.03)])
def test_metres_read_as_millimetres_are_a_unit_mistake_at_every_size(tmp_path, alpha, beta):
    # A robot's runs in metres (first-order centres on the 4 m square, five runs each way
    # on a 20 mm circle about them: a pooled scatter of 20 sqrt(10/8) = 22.4 mm), read as
    # mm: E_max,syst of 12 mm, 85 mm and 400 mm become 0.012, 0.085 and 0.4 mm, and the
    # scatter 0.022 mm, far below what a tape measure resolves, at every size.
    rows = runs_around(linear_cgs(alpha, beta, 4.0), 0.020)
    e_max = 2 * 4.0 * (alpha + beta) * math.sqrt(2)  # the cw centre, farther out
    path = write_table(tmp_path / "runs.csv", rows, HEADER)
    report = _calibrate(path, "mm")
    (said,) = [w for w in report.warnings if "(--unit m)" in w]
    assert "scatter by only 0.0224 mm" in said
    assert f"E_max,syst {1000 * e_max:.4g} mm" in said
    assert report.verdict.level == "do-not-apply"
    assert "in another unit" in report.verdict.reasons[0]
    assert report.overlay_withheld
    # Read in metres, as written: nothing said.
    assert [w for w in _calibrate(path, "m").warnings if "unit" in w] == []


def test_the_example_in_metres_read_as_millimetres_is_not_offered(tmp_path):
    rows = [[d, *(f"{float(v) / 1000:.4f}" for v in rest)] for d, *rest in _rows()]
    path = _table(tmp_path, rows)
    proc = run_cli("calibrate", str(path), "-L", "4", "-b", "0.34", "--unit", "mm")
    assert proc.returncode == 4, proc.stderr  # do not apply
    assert "Verdict: do not apply" in proc.stdout
    assert "are these m, not mm? (--unit m)" in proc.stderr
    assert "wheel_separation_multiplier" not in proc.stdout  # no overlay offered


# --- item 3: one row typed wrong ---------------------------------------------------------


def _with(cell: tuple[int, int], text: str) -> list[list[str]]:
    rows = _rows()
    rows[cell[0]][cell[1]] = text
    return rows


def test_a_dropped_minus_is_named_with_its_row_and_the_result_without_it(tmp_path):
    # Line 8 typed (241.2, 217.1) for (241.2, -217.1): 434 mm from the ccw rows' y.
    path = _table(tmp_path, _with((6, 2), "217.1"))
    report = _calibrate(path)
    (said,) = [w for w in report.warnings if "row 8" in w]
    assert "likely a sign: y_abs 217.1 (-217.1 fits)" in said
    assert report.verdict.level == "do-not-apply"
    assert "row 8" in report.verdict.reasons[0]
    # Without it the ccw centre is the other four rows': (224.475, -203.4) mm.
    without = report.without
    assert without is not None
    assert without.rows == ("row 8",)
    assert without.e_max_syst == pytest.approx(math.hypot(0.224475, 0.2034), abs=1e-9)
    # The same as the table without the line, calibrated on its own.
    alone = _calibrate(_table(tmp_path, [r for k, r in enumerate(_rows()) if k != 6], "nine.csv"))
    assert without.E_d == pytest.approx(alone.estimate.E_d, abs=1e-12)
    assert without.E_b == pytest.approx(alone.estimate.E_b, abs=1e-12)
    assert report.to_dict()["without_rows"] == {
        "rows": ["row 8"],
        "e_max_syst": pytest.approx(without.e_max_syst),
        "E_d": pytest.approx(without.E_d),
        "E_b": pytest.approx(without.E_b),
        "verdict": alone.verdict.level,
    }


@pytest.mark.slow
def test_swapped_digits_are_named_and_the_terminal_shows_the_result_beside(tmp_path):
    # Line 11 typed 213.5 for 231.5 (x_abs): 18 mm only, inside the scatter: unnamed.
    assert _calibrate(_table(tmp_path, _with((9, 1), "213.5"))).without is None
    # Line 7 typed -615.0 for -165.0 (y_abs): 450 mm out, and -165 fits its cluster.
    path = _table(tmp_path, _with((5, 2), "-615.0"))
    proc = run_cli("calibrate", str(path), "-L", "4", "-b", "0.34", "--unit", "mm")
    assert proc.returncode == 4, proc.stderr  # do not apply
    assert "row 7 lies 18 standard deviations from the other ccw runs in y" in proc.stderr
    assert "swapped digits: y_abs -615 (-165 fits)" in proc.stderr
    assert "Verdict: do not apply: row 7 lies 18 standard deviations" in proc.stdout
    # The result without it, beside: the ccw centre of lines 8 to 11, (229.875, -216.425)
    # mm, sqrt(229.875^2 + 216.425^2) = 315.7 mm from the start.
    assert "Without row 7: E_max,syst = 315.7 mm" in proc.stdout
    shown = json.loads(
        run_cli("calibrate", str(path), "-L", "4", "-b", "0.34", "--unit", "mm", "--json").stdout
    )
    assert shown["without_rows"]["rows"] == ["row 7"]
    assert shown["without_rows"]["e_max_syst"] == pytest.approx(math.hypot(0.229875, 0.216425))
    assert shown["verdict"]["level"] == "do-not-apply"


# --- item 4: odometry in the odom frame ---------------------------------------------------


def test_odometry_in_the_odom_frame_is_named_as_an_offset(tmp_path):
    rows = [
        [d, xa, ya, f"{float(xo) + 1200:.1f}", f"{float(yo) - 800:.1f}"]
        for d, xa, ya, xo, yo in _rows()
    ]
    path = _table(tmp_path, rows)
    message = api_error(_calibrate, path)
    assert message.startswith(f"{path}: ")
    assert "(1200, -800) mm" in message
    assert "relative to each run's start" in message
    assert "wheel_separation_multiplier" not in message
    assert "wheelbase" not in message
    assert "(1200, -800) mm" in cli_error(
        "calibrate", str(path), "-L", "4", "-b", "0.34", "--unit", "mm"
    )


def test_both_columns_in_one_shifted_frame_are_taken(tmp_path):
    # Truth and odometry shifted alike: the return errors are the table's own.
    rows = [
        [d, *(f"{float(v) + s:.1f}" for v, s in zip(rest, (1200, -800, 1200, -800), strict=True))]
        for d, *rest in _rows()
    ]
    report = _calibrate(_table(tmp_path, rows))
    assert report.estimate.E_b == pytest.approx(_calibrate(EXAMPLE).estimate.E_b, abs=1e-9)


# --- the verdict's channel ----------------------------------------------------------------


def test_a_blocking_warning_makes_the_verdict_do_not_apply_and_keeps_its_flags():
    from umbmark.calibration.verdict import Evidence, judge
    from umbmark.core.errors import option
    from umbmark.core.messages import Blocking, blocking, split_messages
    from umbmark.estimators.base import ErrorEstimate, SquareTest

    said = blocking(f"the table is off: {option('unit', 'm')}", "it is off", "use the unit")
    _, (warning,) = split_messages([said])
    assert isinstance(warning, Blocking)
    assert warning == "the table is off: --unit m"
    estimate = ErrorEstimate("exact", 0.0, 0.0, 1.0, 1.0)
    verdict = judge(estimate, SquareTest(4.0, 0.34), Evidence(warnings=(warning, "shaky")))
    assert verdict.level == "do-not-apply"
    assert verdict.reasons == ("it is off", "a warning comes with the result (listed with it)")
    assert verdict.instead == "use the unit"
    plain = judge(estimate, SquareTest(4.0, 0.34), Evidence(warnings=("shaky",)))
    assert plain.level == "care"


def test_a_row_far_out_that_no_typo_explains_is_named_as_such(tmp_path):
    # Line 9 at (917.5, -922.3) for (217.5, -222.3): 700 mm out in x and in y, which no
    # one character brings back (a sign or two digits mend one coordinate only).
    rows = _with((7, 1), "917.5")
    rows[7][2] = "-922.3"
    report = _calibrate(_table(tmp_path, rows))
    (said,) = [w for w in report.warnings if "row 9" in w]
    assert "no sign or digit explains it" in said
    assert report.verdict.level == "do-not-apply"
    assert report.without is not None
    assert report.without.rows == ("row 9",)

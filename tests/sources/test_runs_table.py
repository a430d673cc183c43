"""Reading runs tables: units, formats, and every kind of bad input (one clear message)."""

from __future__ import annotations

import math

import pytest

from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError
from umbmark.sources.runs_table.reader import read_runs_table
from umbmark.sources.runs_table.writer import format_runs_table, write_runs_table

GOOD = [("cw", 10.0, 20.0, 1.0, 2.0), ("ccw", -30.0, 40.0, 0.0, 0.0)]


def test_reads_directions_and_converts_mm_to_metres(table):
    runs = read_runs_table(table(GOOD), unit="mm")
    assert [r.direction for r in runs] == [Direction.CW, Direction.CCW]
    assert runs[0].return_error == pytest.approx((0.009, 0.018))
    assert runs[1].true_end.x == pytest.approx(-0.030)
    assert runs[0].label == "row 2"


def test_reads_headings_in_degrees(table):
    path = table(
        [("CW", 0.1, 0.2, 0.0, 0.0, -359.0, -360.0)],
        header="direction,x_abs,y_abs,x_odo,y_odo,theta_abs,theta_odo",
    )
    run = read_runs_table(path, angle_unit="deg")[0]
    assert run.true_end.theta == pytest.approx(math.radians(-359.0))
    assert run.heading_error == pytest.approx(math.radians(1.0))


def test_accepts_bom_semicolons_comments_extra_columns_and_paper_names(tmp_path):
    path = tmp_path / "runs.csv"
    path.write_text(
        "\ufeff# measured 2026-11-20 with a tape\n"
        "run;Direction;X_ABS;y_abs;x_calc;y_calc;note\n"
        "\n"
        "1;ccw;0.1;0.2;0.0;0.0;dusty floor\n",
        encoding="utf-8",
    )
    (run,) = read_runs_table(path)
    assert run.direction is Direction.CCW
    assert run.return_error == pytest.approx((0.1, 0.2))
    assert run.label == "row 4"


def test_empty_heading_cells_leave_the_heading_unknown(table):
    path = table(
        [("cw", 0.1, 0.2, 0.0, 0.0, "", "")],
        header="direction,x_abs,y_abs,x_odo,y_odo,theta_abs,theta_odo",
    )
    assert read_runs_table(path)[0].heading_error is None


def test_round_trip_through_the_writer(tmp_path, table):
    runs = read_runs_table(
        table(
            [("cw", 0.1, -0.2, 0.01, 0.0, 0.05, -6.2)],
            header="direction,x_abs,y_abs,x_odo,y_odo,theta_abs,theta_odo",
        )
    )
    out = tmp_path / "out.csv"
    write_runs_table(out, runs, comment="made by a test\nsecond line")
    text = out.read_text()
    assert text.startswith("# made by a test\n# second line\ndirection,x_abs,y_abs,theta_abs,")
    back = read_runs_table(out)
    assert [(r.direction, r.true_end, r.odometry_end) for r in back] == [
        (r.direction, r.true_end, r.odometry_end) for r in runs
    ]
    assert format_runs_table(runs).count("\n") == 2


@pytest.mark.parametrize(
    ("rows", "header", "message"),
    [
        (GOOD, "direction,x_abs,y_abs,x_odo", "row 1: missing column y_odo"),
        (GOOD, "dir,x_abs,y_abs,x_odo,y_odo", "row 1: missing column direction"),
        ([("cwx", 1, 2, 3, 4)], None, "row 2: direction 'cwx' is neither cw nor ccw"),
        ([("cw", "nan", 2, 3, 4)], None, "row 2: x_abs is nan (not a finite number)"),
        ([("cw", 1, "inf", 3, 4)], None, "row 2: y_abs is inf (not a finite number)"),
        ([("cw", 1, 2, "", 4)], None, "row 2: x_odo is empty"),
        ([("cw", 1, 2, 3, "4m")], None, "row 2: y_odo '4m' is not a number"),
        ([("cw", 1, 2, 3)], None, "row 2: has 4 cells, the header has 5"),
        ([], None, "has a header but no runs"),
        (GOOD, "direction,x_abs,y_abs,x_odo,y_odo,theta_abs", "needs column theta_odo"),
        (GOOD, "direction,x_abs,x_abs,x_odo,y_odo", "column x_abs appears more than once"),
        (
            [("cw", 1, 2, 3, 4, 359.0, 0.0)],
            "direction,x_abs,y_abs,x_odo,y_odo,theta_abs,theta_odo",
            "row 2: theta_abs = 359 is not a plausible heading in radians",
        ),
        (
            [("cw", 1, 2, 3, 4, 0.1, 6.2)],
            "direction,x_abs,y_abs,x_odo,y_odo,theta_abs,theta_odo",
            "row 2: labelled cw, but theta_odo = 6.2 rad is a left (ccw) loop",
        ),
        (
            [("cw", 1, 2, 3, 4, 0.1, "")],
            "direction,x_abs,y_abs,x_odo,y_odo,theta_abs,theta_odo",
            "row 2: gives one of theta_abs and theta_odo but not the other",
        ),
    ],
)
def test_bad_tables_name_file_row_and_problem(table, rows, header, message):
    path = table(rows, header=header or "direction,x_abs,y_abs,x_odo,y_odo")
    with pytest.raises(InputError) as info:
        read_runs_table(path)
    text = str(info.value)
    assert text.startswith(str(path))
    assert message in text
    assert "\n" not in text


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "no such file"),
        (b"\xff\xfe\x00\x01binary", "is not a UTF-8 text file"),
        (b"", "is empty"),
        (b"# only a comment\n", "is empty"),
    ],
)
def test_unreadable_files(tmp_path, content, message):
    path = tmp_path / "runs.csv"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(InputError, match=message):
        read_runs_table(path)


def test_a_directory_is_not_a_table(tmp_path):
    with pytest.raises(InputError, match="is a directory"):
        read_runs_table(tmp_path)


# --- measured and odometry columns swapped (issue "What a new user meets", 3) ------------


def _swapped(path, out):
    """The table at ``path`` with x_abs, y_abs and x_odo, y_odo exchanged (comments kept)."""
    lines = []
    for line in path.read_text().splitlines():
        cells = line.split(",")
        if line.startswith("#") or cells[0] == "direction":
            lines.append(line)
        else:
            lines.append(",".join([cells[0], cells[3], cells[4], cells[1], cells[2]]))
    out.write_text("\n".join(lines) + "\n")
    return out


def test_swapped_measured_and_odometry_columns_are_refused(tmp_path):
    # The bundled table with its columns swapped: the "odometry" ends lie 203.2 mm from
    # the start (the median of the rows' ten distances, between row 10's 131.7 mm and row
    # 12's 274.7 mm) and the "measured" ones at the start: a robot steering by its
    # odometry ends the other way round.
    import umbmark

    from helpers import api_error, cli_error

    good = tmp_path / "runs.csv"
    umbmark.example(good)
    path = _swapped(good, tmp_path / "swapped.csv")
    message = api_error(umbmark.calibrate, path, side_length=4, wheelbase=0.34, unit="mm")
    assert message.startswith(f"{path}: x_odo, y_odo put the robot's end 203.2 mm from the start")
    assert "the measured and odometry columns are swapped" in message
    assert "x_abs, y_abs" in message
    assert "swapped" in cli_error("calibrate", str(path), "-L", "4", "-b", "0.34", "--unit", "mm")


def test_odometry_ends_somewhat_farther_than_the_measured_ones_are_warned_of(table):
    # Odometry ends 30 mm from the start, measured ones 5 mm (median; ratio 6): a robot
    # whose controller stops loosely could do that, so a warning, not a refusal. The
    # return errors (about 30 mm) are a robot near calibration: the calibration stands.
    import umbmark

    rows = [
        ("cw", 0.004, 0.003, 0.030, 0.000), ("cw", 0.003, 0.004, 0.000, 0.030),
        ("cw", 0.005, 0.000, -0.030, 0.000), ("ccw", -0.004, 0.003, 0.000, -0.030),
        ("ccw", 0.000, 0.005, 0.030, 0.000), ("ccw", 0.003, -0.004, -0.030, 0.000),
    ]  # fmt: skip
    report = umbmark.calibrate(table(rows), side_length=4, wheelbase=0.34)
    (note,) = [n for n in report.warnings if "swapped" in n]
    assert note.startswith("x_odo, y_odo put the robot's end 30 mm from the start (median)")
    assert note.endswith("are the measured and odometry columns swapped?")


def test_the_tables_umbmark_writes_and_ships_are_not_taken_for_swapped(tmp_path):
    # The bundled table (odometry ends at 0) and a simulated one (odometry ends within
    # micrometres of the start, true ends 0.06 to 0.5 m away) are left alone.
    import umbmark

    example = tmp_path / "runs.csv"
    umbmark.example(example)
    simulated = tmp_path / "sim.csv"
    umbmark.simulate(E_d=1.002, E_b=1.01, seed=7).write(output=simulated)
    for path, unit in ((example, "mm"), (simulated, "m")):
        report = umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit=unit)
        assert not [n for n in report.notes + report.warnings if "swapped" in n]

"""The text readers stream: memory is what they keep, every line and row count is bounded.

Runs tables, run-log CSVs and OptiOdom run files are read line by line. A line longer
than ``MAX_LINE_CHARS`` (once: ``_csv.Error: field larger than field limit``), more rows
than the documented bound, or an endless file is one error line naming the file and the
row; padding a file with text the reader does not keep (comments) does not cost memory.
"""

from __future__ import annotations

import math
import os
import time
import tracemalloc

import numpy as np
import pytest

import umbmark
from umbmark.core.errors import InputError
from umbmark.sources import optiodom
from umbmark.sources.runlog import reader as runlog
from umbmark.sources.runs_table import reader as runs_table
from umbmark.sources.text import MAX_LINE_CHARS, first_content_line, iter_content_lines

from helpers import api_error, cli_error

HEADER = "direction,x_abs,y_abs,x_odo,y_odo"
ROWS = ["cw,0.05,0.02,0,0", "cw,0.06,0.03,0,0", "ccw,0.20,-0.15,0,0", "ccw,0.21,-0.16,0,0"]


def _peak(fn):  # type: ignore[no-untyped-def]
    """Peak traced memory [bytes] while ``fn`` runs, and its result."""
    tracemalloc.start()
    try:
        result = fn()
        return tracemalloc.get_traced_memory()[1], result
    finally:
        tracemalloc.stop()


def test_a_cell_over_128_kb_is_one_line_naming_file_and_row(tmp_path):
    path = tmp_path / "runs.csv"
    big = "1" * (200 * 1024)
    path.write_text("\n".join([HEADER, ROWS[0], f"cw,{big},0,0,0", *ROWS[1:]]) + "\n")
    message = api_error(umbmark.read_runs_table, path)
    assert message.startswith(f"{path}, row 3: ")
    assert f"longer than {MAX_LINE_CHARS} characters" in message
    line = cli_error("calibrate", str(path), "-L", "4", "-b", "0.34")
    assert "row 3" in line
    assert "longer than" in line


def test_the_row_bound_is_finite_generous_and_named(tmp_path, monkeypatch):
    assert 10_000 <= runs_table.MAX_ROWS <= 1_000_000
    monkeypatch.setattr(runs_table, "MAX_ROWS", 4)
    path = tmp_path / "runs.csv"
    path.write_text("\n".join(["# five runs", HEADER, *ROWS]) + "\n")
    assert len(umbmark.read_runs_table(path)) == 4  # at the bound: read
    path.write_text("\n".join(["# five runs", HEADER, *ROWS, ROWS[0]]) + "\n")
    message = api_error(umbmark.read_runs_table, path)
    # The fifth run is on line 7 (a comment, the header, four runs before it).
    assert message.startswith(f"{path}, row 7: has more than 4 runs")
    assert "at most 4 rows" in message


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero")
def test_an_endless_table_stops_at_its_first_line():
    started = time.perf_counter()
    peak, message = _peak(lambda: api_error(umbmark.read_runs_table, "/dev/zero"))
    assert time.perf_counter() - started < 5
    assert "row 1" in message
    assert "longer than" in message
    assert peak < 4 * MAX_LINE_CHARS * 4 + 1_000_000  # a line (4 bytes a char at most), not GB


def test_comments_cost_no_memory(tmp_path):
    # 18 MB of comments around four runs: reading keeps the runs, not the text.
    path = tmp_path / "runs.csv"
    comment = "# " + "x" * 198 + "\n"
    with path.open("w") as file:
        file.write(comment * 50_000 + HEADER + "\n")
        for row in ROWS:
            file.write(row + "\n" + comment * 10_000)
    assert path.stat().st_size > 18_000_000
    peak, runs = _peak(lambda: umbmark.read_runs_table(path))
    assert [run.direction.value for run in runs] == ["cw", "cw", "ccw", "ccw"]
    assert runs[3].true_end.x == 0.21
    assert runs[3].label == f"row {50_000 + 1 + 3 * 10_001 + 1}"
    assert peak < 2_000_000  # the old reader held the whole text: over 18 MB


@pytest.mark.slow
def test_memory_per_run_of_a_long_table(tmp_path):
    # 20 000 runs: the runs themselves (a Run and two EndPoses each) and no more.
    path = tmp_path / "runs.csv"
    n = 20_000
    with path.open("w") as file:
        file.write(HEADER + ",theta_abs,theta_odo\n")
        for k in range(n):
            file.write(f"{'cw' if k % 2 else 'ccw'},{k * 1e-6:.6f},0.5,0.25,-0.125,0.1,0.2\n")
    peak, runs = _peak(lambda: umbmark.read_runs_table(path))
    assert len(runs) == n
    assert runs[-1].true_end.x == pytest.approx((n - 1) * 1e-6)
    assert runs[-1].odometry_end.theta == 0.2
    # A Run and its two EndPoses are some 560 bytes; a copy of the text, its lines
    # numbered, would add 150 more (the old reader: about 710).
    assert peak / n < 650


def test_first_content_line_reads_no_further(tmp_path):
    path = tmp_path / "x.csv"
    # A valid header, 1 MB of rows, then bytes that are no UTF-8: the header alone is read.
    path.write_bytes(b"# c\n\ntime,x\n" + b"1,2\n" * 250_000 + b"\xff" * 100)
    assert first_content_line(path) == (3, "time,x")
    with pytest.raises(InputError, match="not a UTF-8 text file"):
        list(iter_content_lines(path))


def _write_log(folder, n, extra_row=None):  # type: ignore[no-untyped-def]
    """A run-log folder with one run file of ``n`` samples: a circle of radius 1 m driven
    at 0.5 rad/s, the wheels' angles straight lines (values known in closed form)."""
    folder.mkdir()
    (folder / "metadata.yaml").write_text(
        "format: umbmark-runlog\nversion: 1\nwheel_data: angles\n"
        "wheel_diameter: 0.15\nwheelbase: 0.34\n"
    )
    t = np.arange(n) * 0.01
    with (folder / "run-01.csv").open("w") as file:
        file.write("# a comment\ntime,x,y,theta,left,right\n")
        for k in range(n):
            truth = (
                ""
                if k % 3 == 1
                else f"{math.sin(0.5 * t[k]):.6f},{1 - math.cos(0.5 * t[k]):.6f},{0.5 * t[k]:.6f}"
            )
            if not truth:
                truth = ",,"
            file.write(f"{t[k]:.2f},{truth},{6.0 * t[k]:.6f},{7.0 * t[k]:.6f}\n")
            if extra_row is not None and k == 5:
                file.write(extra_row + "\n")
    return t


@pytest.mark.slow
def test_run_log_is_read_into_compact_columns(tmp_path):
    n = 30_000
    t = _write_log(tmp_path / "log", n)
    peak, (recordings, _) = _peak(lambda: runlog.read_runlog(tmp_path / "log"))
    (rec,) = recordings
    np.testing.assert_allclose(rec.wheels.time, np.round(t, 2))
    np.testing.assert_allclose(rec.wheels.angles[:, 0], np.round(6.0 * np.round(t, 2), 6))
    np.testing.assert_allclose(rec.wheels.angles[:, 1], np.round(7.0 * np.round(t, 2), 6))
    kept = [k for k in range(n) if k % 3 != 1]  # every third row has no ground truth
    assert rec.truth is not None
    np.testing.assert_allclose(rec.truth.time, np.round(t[kept], 2))
    np.testing.assert_allclose(rec.truth.poses[:, 2], np.round(0.5 * np.round(t[kept], 2), 6))
    # What is kept: 3 wheel and 4 truth columns of 8 bytes, and the arrays made of them
    # (about 100 bytes a row); a list of Python floats per row costs 150 to 200 bytes for
    # each of the two series, before the text it came from.
    assert peak / n < 200


def test_run_log_bounds_rows_and_lines(tmp_path, monkeypatch):
    _write_log(tmp_path / "long", 20, extra_row="0.055," + "9" * (MAX_LINE_CHARS + 10))
    message = api_error(runlog.read_runlog, tmp_path / "long")
    assert message.startswith(f"{tmp_path / 'long' / 'run-01.csv'}, row 9: ")
    assert "longer than" in message
    monkeypatch.setattr(runlog, "MAX_SAMPLES", 10)
    _write_log(tmp_path / "many", 11)
    message = api_error(runlog.read_runlog, tmp_path / "many")
    # Sample 11 is on line 13 (a comment and the header before the samples).
    assert "row 13: has more than 10 samples" in message


def _write_session(folder, n):  # type: ignore[no-untyped-def]
    folder.mkdir()
    (folder / "s_metadata.csv").write_text(
        "ngear,20,\nencRes,2000,\nLi,0.34,\nDi,0.15,0.15\nN,1,\n"
    )
    with (folder / "s_run-01.csv").open("w") as file:
        for k in range(n):
            file.write(f"{k * 0.01:.2f},{k * 1e-3:.4f},0,0,10,11\n")


def test_optiodom_run_files_are_bounded(tmp_path, monkeypatch):
    _write_session(tmp_path / "ok", 50)
    (rec,), _ = optiodom.read_optiodom(tmp_path / "ok")
    # Ticks are increments: 10 and 11 per sample, summed (left is the last column).
    per_tick = 2 * math.pi / (2000 * 20)
    assert rec.wheels.angles[-1, 0] == pytest.approx(50 * 11 * per_tick)
    assert rec.wheels.angles[-1, 1] == pytest.approx(50 * 10 * per_tick)
    monkeypatch.setattr(optiodom, "MAX_SAMPLES", 49)
    message = api_error(optiodom.read_optiodom, tmp_path / "ok")
    assert "row 50: has more than 49 samples" in message
    _write_session(tmp_path / "wide", 3)
    with (tmp_path / "wide" / "s_run-01.csv").open("a") as file:
        file.write("0.5," + "1" * (MAX_LINE_CHARS + 1) + ",0,0,1,1\n")
    message = api_error(optiodom.read_optiodom, tmp_path / "wide")
    assert "row 4" in message
    assert "longer than" in message


@pytest.mark.parametrize(
    ("bad", "said"),
    [
        ("25.00,0.1,0.2,0.3,abc,1.0", "left 'abc' is not a number"),
        ("25.00,0.1,0.2,inf,1.0,1.0", "theta is inf"),
        ("25.00,0.1,0.2", "has 3 cells, the header has 6"),
        (",0.1,0.2,0.3,1.0,1.0", "time is empty"),
        ("25.00,,,,,", "has neither wheel data nor ground truth"),
    ],
)
def test_a_bad_row_deep_in_a_long_run_file_is_named(tmp_path, bad, said):
    """Rows are read a block at a time; a row with something to say is said with its own
    number wherever it falls (here after two and a half blocks of good rows)."""
    folder = tmp_path / "log"
    _write_log(folder, 0)
    good = [f"{k * 0.01:.2f},0.1,0.2,0.3,{k},{k}" for k in range(2500)]
    rows = [*good, bad, *good]
    (folder / "run-01.csv").write_text("time,x,y,theta,left,right\n" + "\n".join(rows) + "\n")
    message = api_error(runlog.read_runlog, folder)
    assert message == f"{folder / 'run-01.csv'}, row 2502: {said}"


def test_quoted_cells_read_as_csv_reads_them(tmp_path):
    folder = tmp_path / "log"
    _write_log(folder, 0)
    rows = [f'{k * 0.01:.2f},"{k * 0.001:.3f}",0.0,0.0,{k},"{2 * k}"' for k in range(3000)]
    (folder / "run-01.csv").write_text("time,x,y,theta,left,right\n" + "\n".join(rows) + "\n")
    (rec,), _ = runlog.read_runlog(folder)
    np.testing.assert_array_equal(rec.wheels.time, np.round(np.arange(3000) * 0.01, 2))
    np.testing.assert_array_equal(rec.wheels.angles[:, 1], 2.0 * np.arange(3000))
    assert rec.truth is not None
    np.testing.assert_allclose(rec.truth.poses[:, 0], np.arange(3000) * 0.001)

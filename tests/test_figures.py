"""Figures and tables people read (issue 11, item 6): the replay's zoom on where the runs
end, units and names on every figure, and one table style whose piped output never splits
a value across lines, even next to a long path."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import umbmark

from helpers import cli_json, run_cli

#: Two folder names that make every path in these tests over 200 characters long.
LONG = ("a" * 100, "b" * 100)
SQUARE = Path("square") / "230620202042"
CIRCLES = Path("circular") / "250620202104"


@pytest.fixture(scope="module")
def real(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The two shipped OptiOdom sessions, in a folder with a long path."""
    root = tmp_path_factory.mktemp("figures").joinpath(*LONG)
    root.mkdir(parents=True)
    umbmark.example(str(root / "real"), real=True)
    return root / "real"


def _title(fig) -> str:  # type: ignore[no-untyped-def]
    return str(fig._suptitle.get_text()).replace("\n", "")


def test_replay_zooms_on_every_end_point(real: Path) -> None:
    calibration = umbmark.calibrate(str(real / SQUARE))
    report = umbmark.replay(str(real / CIRCLES), calibration)
    fig = report.figure()
    shown = [ax for ax in fig.axes if ax.get_visible()]
    zooms = [ax for ax in shown if ax.get_label() == "end zoom"]
    paths = [ax for ax in shown if ax.get_label() != "end zoom"]
    assert len(zooms) == len(paths) == len(report.runs) == 6
    for zoom, path, run in zip(zooms, paths, report.runs, strict=True):
        log = run.log
        assert log is not None
        truth = log.truth[log.matched]
        ends = [truth[-1, :2]]
        ends += [log.odometry(p)[-1, :2] for p in report.parameter_sets.values()]
        x0, x1 = zoom.get_xlim()
        y0, y1 = zoom.get_ylim()
        for x, y in np.array(ends) * 1000:
            assert x0 < x < x1
            assert y0 < y < y1
        # The nominal and calibrated ends are 20 to 50 mm apart: the zoom is a small part
        # of the circles (0.75 m across) the whole path panel shows.
        extent = 1000 * float(np.ptp(truth[:, :2], axis=0).max())
        assert extent > 700
        assert max(x1 - x0, y1 - y0) < 0.15 * extent
        assert zoom.get_aspect() == 1.0
        assert zoom.get_xlabel() == "x [mm]"
        assert zoom.get_ylabel() == "y [mm]"
        assert path.get_xlabel() == "x [m]"
        assert path.get_ylabel() == "y [m]"
        assert run.label in zoom.get_title()
    assert str(real / CIRCLES) in _title(fig)


@pytest.mark.slow
def test_replay_plot_is_written(real: Path, tmp_path: Path) -> None:
    from matplotlib.image import imread

    plot = tmp_path / "replay.png"
    proc = run_cli("replay", str(real / CIRCLES), "--plot", str(plot))
    assert proc.returncode == 0, proc.stderr
    assert f"umbmark: wrote {plot}" in proc.stderr
    pixels = imread(plot)[..., :3]
    assert float(pixels.std()) > 0.05


@pytest.mark.slow
def test_every_figure_has_units_and_a_name(tmp_path: Path, demo: umbmark.DemoReport) -> None:
    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    figures = {
        "calibrate": umbmark.calibrate(str(table), side_length=4, wheelbase=0.34, unit="mm"),
        "demo": demo,
        "fig4": umbmark.reproduce_fig4(),
    }
    names = {"calibrate": str(table), "demo": "Virtual LabMate", "fig4": "Wheelbase tuned"}
    for key, report in figures.items():
        fig = report.figure()
        text = _title(fig) + " ".join(ax.get_title().replace("\n", "") for ax in fig.axes)
        assert names[key] in text, key
        for ax in fig.axes:
            for label in (ax.get_xlabel(), ax.get_ylabel()):
                assert re.search(r"\[m{1,2}\]", label), (key, label)


# One table style, and piped output that never splits a value.


def _line_with(text: str, start: str) -> str:
    """The one line of ``text`` whose content starts with ``start``."""
    (line,) = [line for line in text.splitlines() if line.strip().startswith(start)]
    return line


def _piped(*args: str) -> str:
    proc = run_cli(*args)
    assert proc.returncode == 0, proc.stderr
    assert "┏" not in proc.stdout  # the one, light, table style
    assert "│" not in proc.stdout
    return proc.stdout


@pytest.mark.slow
def test_calibrate_table_keeps_values_whole(real: Path, tmp_path: Path) -> None:
    table = real.parent / "runs.csv"
    umbmark.example(str(table))
    args = ("calibrate", str(table), "-L", "4", "-b", "0.34", "--unit", "mm")
    printed = cli_json(*args)
    out = _piped(*args)
    assert str(table) in _line_with(out, "UMBmark")  # the path whole, on the header line
    assert f"{printed['E_d']:.6f} ± " in _line_with(out, "E_d = D_R / D_L")
    assert f"{printed['E_b']:.6f} ± " in _line_with(out, "E_b = b_actual / b_nominal")
    new = printed["new"]
    row = _line_with(out, "c_L, left wheel")
    assert f"{new['c_L']:.6f}" in row
    assert "1.000000" in row  # the active value, on the same line
    assert f"E_max,syst = {printed['e_max_syst'] * 1000:.1f} mm  (the ccw cluster)" in out
    assert " ───" in out  # the rule under the headers


@pytest.mark.slow
def test_replay_info_validate_history_tables_keep_rows_whole(real: Path, tmp_path: Path) -> None:
    square, circles = str(real / SQUARE), str(real / CIRCLES)
    result = real.parent / "square.json"
    cli_json("calibrate", square, "-o", str(result))
    printed = cli_json("replay", circles, "--params", str(result))
    out = _piped("replay", circles, "--params", str(result))
    assert circles in _line_with(out, "Replay of")
    for run in printed["runs"]:
        row = _line_with(out, run["label"] + " ")
        for name in ("nominal", "calibrated"):
            assert f"{1000 * run[f'end_error_{name}']:.1f}" in row
            assert f"{1000 * run[f'rmse_{name}']:.1f}" in row
            assert f"{math.degrees(run[f'heading_error_{name}']):+.2f}" in row

    out = _piped("info", square)
    assert square in _line_with(out, square)
    for number in range(1, 7):
        assert re.search(
            r"run-0\d\s+\d{4}\s+\d{4}\s+\d+\.\d\s*$", _line_with(out, f"run-0{number}")
        )

    # Sessions whose names are longer than the 200 columns rich would fit a table into.
    long_square = real.parent / ("square-" + "c" * 200)
    long_circles = real.parent / ("circles-" + "d" * 200)
    shutil.copytree(square, long_square, dirs_exist_ok=True)
    shutil.copytree(circles, long_circles, dirs_exist_ok=True)
    args = ("validate", str(long_square), str(long_circles), "--methods", "exact")
    printed = cli_json(*args)
    out = _piped(*args)
    for fold in printed["folds"]:
        row = _line_with(out, f"{Path(fold['held_out']).name} ({fold['runs']} runs)")
        assert len(row) > 200
        assert f"{1000 * fold['end_error']['nominal']:.1f}" in row

    db = real.parent / "history.sqlite3"
    for _ in range(3):
        cli_json("calibrate", square, "--robot", "optiodom", "--history", str(db))
    printed = cli_json("history", "optiodom", "--history", str(db))
    out = _piped("history", "optiodom", "--history", str(db))
    for c in printed["calibrations"]:
        (row,) = [
            line for line in out.splitlines() if re.match(rf"\s*{c['id']}\s+{c['time'][:19]}", line)
        ]
        assert f"{c['E_d']:.6f}" in row
        assert f"{c['E_b']:.6f}" in row
        assert f"{c['e_max_syst'] * 1000:.1f}" in row
    assert printed["drift"] in out.splitlines()  # the verdict on one line


@pytest.mark.slow
def test_calibration_figure_and_page_name_the_robot_and_the_command(tmp_path: Path) -> None:
    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    history = tmp_path / "history.sqlite3"
    page = tmp_path / "page.html"
    plot = tmp_path / "clusters.svg"
    args = [str(table), "-L", "4", "-b", "0.34", "--unit", "mm", "--robot", "labmate-7"]
    proc = run_cli(
        "calibrate", *args, "--history", str(history), "--report", str(page), "--plot", str(plot)
    )
    assert proc.returncode == 0, proc.stderr
    assert "labmate-7" in plot.read_text()
    html = page.read_text()
    assert "<h1>labmate-7: " in html
    # The command as typed, quoted as a shell takes it back.
    assert f"umbmark calibrate {table} -L 4 -b 0.34 --unit mm --robot labmate-7" in html

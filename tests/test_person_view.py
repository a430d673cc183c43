"""What a person reads: the 3 x SEM verdict in words, the units of alpha and beta, the
model checks, the widths of tables on a terminal and a page, the conventions of
``simulate --params``.

Expected wordings follow from the figures printed, by hand: 27.5 mm against 3 x SEM =
26.3 mm is 1.05 times, "just above" the scatter, not "well above".
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

import umbmark
from conftest import DemoCommand

from helpers import run_cli


def test_demo_says_just_above_for_27_5_against_26_3(demo_command: DemoCommand) -> None:
    """``umbmark demo`` as a user runs it (the shared run, tests/conftest.py)."""
    printed = demo_command.stdout
    after = next(line for line in printed.splitlines() if line.startswith("After calibration"))
    assert "E_max,syst = 27.5 mm > 3 x SEM = 26.3 mm" in after
    assert "(1.05 times 3 x SEM)" in after or "(1.04 times 3 x SEM)" in after
    assert "just above the scatter" in after
    assert "well above" not in after
    # The pass before the correction: 316.9 mm against 28.5 mm, 11 times: well above.
    before = next(line for line in printed.splitlines() if "E_max,syst = 316.9 mm >" in line)
    assert "well above the scatter" in before


@pytest.mark.slow
def test_one_verdict_on_terminal_page_and_json(demo_command: DemoCommand, tmp_path: Path) -> None:
    folder = demo_command.folder
    runs = folder / "runs_after.csv"
    common = [str(runs), "-L", "4", "-b", "0.34"]
    page = tmp_path / "after.html"
    proc = run_cli("calibrate", *common, "--report", str(page))
    assert proc.returncode == 0, proc.stderr
    line = next(x for x in proc.stdout.splitlines() if x.startswith("E_max,syst = 27.5 mm >"))
    assert "just above" in line
    data = json.loads(run_cli("calibrate", *common, "--json").stdout)
    assert data["second_pass"] == line
    text = page.read_text(encoding="utf-8").replace("&gt;", ">").replace("&lt;", "<")
    assert line in text
    assert "well above" not in text


# --- study's table on a terminal ---------------------------------------------------------


def _on_terminal(args: list[str], columns: int) -> str:
    """Run ``umbmark ARGS`` with stdout on a pseudo-terminal ``columns`` wide; its text."""
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import sys
    import termios

    from helpers import umbmark_command

    main, child = pty.openpty()
    # The terminal's own size, and COLUMNS as a shell exports it.
    fcntl.ioctl(child, termios.TIOCSWINSZ, struct.pack("HHHH", 50, columns, 0, 0))
    env = {**os.environ, "COLUMNS": str(columns), "LINES": "50", "TERM": "xterm"}
    proc = subprocess.Popen(
        [umbmark_command(), *args], stdout=child, stderr=subprocess.PIPE, env=env
    )
    os.close(child)
    chunks = []
    while True:
        try:
            chunk = os.read(main, 65536)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        chunks.append(chunk)
    os.close(main)
    assert proc.wait(timeout=120) == 0, proc.stderr.read() if proc.stderr else ""
    if proc.stderr:
        proc.stderr.close()
    text = b"".join(chunks).decode(sys.getdefaultencoding(), "replace")
    return re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", text).replace("\r", "")


_STUDY = ["study", "--trials", "3", "--workers", "1", "--methods", "truth,paper"]


@pytest.fixture(scope="module")
def study_json() -> dict[str, Any]:
    proc = run_cli(*_STUDY, "--json")
    assert proc.returncode == 0, proc.stderr
    data: dict[str, Any] = json.loads(proc.stdout)
    return data


@pytest.mark.slow
@pytest.mark.parametrize("columns", [120, 40])
def test_study_table_fits_the_terminal_and_cuts_no_number(
    columns: int, study_json: dict[str, Any]
) -> None:
    """120 columns: the table in two parts, each with the grid cell and the method; 40:
    a block of lines per row."""
    printed = _on_terminal(_STUDY, columns)
    assert "…" not in printed
    assert max(len(line.rstrip()) for line in printed.splitlines()) <= columns
    data = study_json
    words = set(printed.split())
    for result in data["results"]:
        # Every figure as the table formats it (shares in %, biases signed, ppm, mm).
        shown = [
            f"{100 * result[key]:.1f}"
            for key in ("floor_after_one_pass", "floor_after_two_passes", "refused")
        ] + [
            f"{result['noise_free_bias_E_b_ppm']:+.1f}",
            f"{1e6 * result['spread_E_d']:.1f}",
            f"{1e6 * result['spread_E_b']:.1f}",
            f"{1e3 * result['scatter']:.1f}",
        ]
        for cell in shown:
            assert cell in words, (cell, printed)


# --- simulate --params: one convention per line, stated -----------------------------------


@pytest.mark.slow
def test_simulate_params_states_one_convention_per_line(tmp_path: Path) -> None:
    first, result = tmp_path / "first.csv", tmp_path / "result.json"
    umbmark.simulate(E_d=1.004, E_b=1.03, noise_free=True, output=first)
    umbmark.calibrate(first, side_length=4, wheelbase=0.34, output=result)
    second = tmp_path / "second.csv"
    args = ["--E-d", "1.002", "--E-b", "1.01", "--noise-free", "--params", str(result)]
    proc = run_cli("simulate", *args, "-o", str(second))
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    truth = next(x for x in lines if x.startswith("True errors"))
    # What was asked for, relative to the nominal wheels: both E_d and E_b as given.
    assert "relative to the nominal wheels (D_n = 150 mm, b = 340 mm)" in truth
    assert "E_d = 1.002000, E_b = 1.010000, E_s = 1.000000" in truth
    left = next(x for x in lines if x.startswith("Errors left to the odometry"))
    found = dict(re.findall(r"(E_[dbs]) = ([0-9.]+)", left))
    # Both relative to the odometry of --params: what calibrating these runs with those
    # parameters active finds (noise-free runs: to the estimator's accuracy).
    again = umbmark.calibrate(second, side_length=4, current_params=result)
    assert float(found["E_d"]) == pytest.approx(again.estimate.E_d, abs=2e-5)
    assert float(found["E_b"]) == pytest.approx(again.estimate.E_b, abs=5e-5)
    data = json.loads(run_cli("simulate", *args, "--json").stdout)
    assert data["true_E_b"] == pytest.approx(1.01, rel=1e-12)
    assert data["true_E_d"] == pytest.approx(1.002, rel=1e-12)
    assert data["odometry_E_b"] == pytest.approx(float(found["E_b"]), abs=1e-6)

"""The virtual-robot commands end to end: simulate, demo, reproduce."""

from __future__ import annotations

import csv
import json
import math

import pytest
import yaml
from typer.testing import CliRunner

from umbmark.cli.main import app

runner = CliRunner()


def _ok(*args: str) -> str:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result.stdout


def _calibrate_json(path, *extra: str) -> dict:
    return json.loads(_ok("calibrate", str(path), "-L", "4", "-b", "0.34", "--json", *extra))


def test_simulate_then_calibrate_recovers_the_errors(tmp_path):
    runs = tmp_path / "runs.csv"
    _ok("simulate", "--E-d", "1.002", "--E-b", "1.01", "--noise-free", "-o", str(runs))
    header = next(line for line in runs.read_text().splitlines() if not line.startswith("#"))
    assert header == "direction,x_abs,y_abs,theta_abs,x_odo,y_odo,theta_odo"
    exact = _calibrate_json(runs, "--method", "exact")
    assert exact["E_d"] == pytest.approx(1.002, abs=2e-6)
    assert exact["E_b"] == pytest.approx(1.01, abs=2e-5)
    heading = _calibrate_json(runs, "--method", "heading")
    # Heading errors are exact in the model; E_d then goes through Eqs. 4.21-4.22.
    assert heading["E_b"] == pytest.approx(1.01, abs=2e-5)
    assert heading["E_d"] == pytest.approx(1.002, abs=2e-5)
    paper = _calibrate_json(runs)
    assert paper["E_d"] == pytest.approx(1.002, rel=1e-3)


def test_second_pass_with_params_from_the_first(tmp_path):
    first, result, second = tmp_path / "first.csv", tmp_path / "r.json", tmp_path / "second.csv"
    opts = ("--E-d", "1.004", "--E-b", "1.03", "--noise-free")
    _ok("simulate", *opts, "-o", str(first))
    before = _calibrate_json(first, "-o", str(result))
    _ok("simulate", *opts, "--params", str(result), "-o", str(second))
    # The second runs were driven with the first pass's wheelbase and wheel factors.
    after = json.loads(
        _ok(
            "calibrate",
            str(second),
            "-L",
            "4",
            "-b",
            str(before["wheelbase"]),
            "--json",
            "--current-c-l",
            str(before["new"]["c_L"]),
            "--current-c-r",
            str(before["new"]["c_R"]),
        )
    )
    assert after["e_max_syst"] < before["e_max_syst"] / 10
    # A previous result names what was active just as well as the flags do, and the
    # composed parameters approach the truth.
    same = json.loads(
        _ok(
            "calibrate",
            str(second),
            "-L",
            "4",
            "-b",
            "0.34",
            "--json",
            "--current-params",
            str(result),
        )
    )
    for key in ("c_L", "c_R", "wheelbase"):
        assert same["new"][key] == pytest.approx(after["new"][key], rel=1e-12)
    # Here the wheelbase change lives in the separation multiplier (b stays 0.34).
    assert same["new"]["wheel_separation_multiplier"] * 0.34 == pytest.approx(
        same["new"]["wheelbase"], rel=1e-12
    )
    assert same["new"]["c_R"] / same["new"]["c_L"] == pytest.approx(1.004, abs=2e-5)
    assert same["new"]["wheelbase"] == pytest.approx(0.34 * 1.03, rel=2e-4)


def test_simulate_logs_are_run_logs(tmp_path):
    logs = tmp_path / "logs"
    _ok("simulate", "--runs", "2", "--seed", "3", "--logs", str(logs), "--side-length", "1")
    meta = yaml.safe_load((logs / "metadata.yaml").read_text())
    assert meta["format"] == "umbmark-runlog"
    assert meta["wheel_data"] == "counts"
    assert meta["wheelbase"] == 0.34
    assert meta["side_length"] == 1.0
    files = sorted(p.name for p in logs.glob("run-*.csv"))
    assert files == ["run-01.csv", "run-02.csv", "run-03.csv", "run-04.csv"]
    text = (logs / "run-01.csv").read_text().splitlines()
    rows = list(csv.reader(line for line in text if not line.startswith("#")))
    assert rows[0] == ["time", "x", "y", "theta", "left", "right"]
    first, last = rows[1], rows[-1]
    assert [float(v) for v in first[:4]] == [0.0, 0.0, 0.0, 0.0]
    # A cw square: the heading ends near -2 pi; the left wheel travelled farther.
    assert float(last[3]) == pytest.approx(-2 * math.pi, abs=0.05)
    assert int(last[4]) > int(last[5]) > 0


def test_simulate_straight_line_and_turn_report_what_a_tape_measures():
    data = json.loads(
        _ok(
            "simulate",
            "--path",
            "straight",
            "--E-s",
            "1.01",
            "--noise-free",
            "--runs",
            "1",
            "--json",
        )
    )
    assert data["distance_ratio"] == pytest.approx(1.01, rel=1e-5)
    data = json.loads(
        _ok(
            "simulate",
            "--path",
            "turn",
            "--turn-angle",
            "90",
            "--E-d",
            "1.02",
            "--noise-free",
            "--runs",
            "1",
            "--json",
        )
    )
    assert data["rotation_ratio"] == pytest.approx(1.0, abs=1e-4)
    # Sec. 2.3: the centre moves by 2 d sin(tau / 2), d = (b/2)(E_d - 1)/(E_d + 1).
    d = 0.17 * 0.02 / 2.02
    assert data["centre_shift"] == pytest.approx(2 * d * math.sin(math.pi / 4), rel=1e-3)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--E-d", "0"), "--E-d must be > 0, got 0"),
        (("--E-b", "3"), "--E-b 3 is not a plausible ratio"),
        (("--runs", "1"), "--runs must be at least 2 for UMBmark"),
        (("--slip", "-1"), "--slip must be >= 0"),
        (("--path", "straight", "-o", "x.csv"), "-o writes a runs table of square runs"),
        (("--wheelbase", "340"), "--wheelbase 340 m is implausibly large"),
    ],
)
def test_simulate_refuses_bad_options(args, message):
    result = runner.invoke(app, ["simulate", *args])
    assert result.exit_code == 2
    assert message in result.stderr
    assert result.stderr.count("\n") == 1


def test_demo_json_and_files(tmp_path):
    out = tmp_path / "demo"
    data = json.loads(_ok("demo", "--json", "--out", str(out), "--seed", "4"))
    for key in ("true_E_d", "true_E_b", "E_d", "E_b", "e_max_before", "e_max_after"):
        assert isinstance(data[key], float), key
    assert data["true_E_b"] == pytest.approx(336.17 / 340.0)
    assert data["E_b"] == pytest.approx(data["true_E_b"], abs=2e-3)
    assert data["E_d"] == pytest.approx(data["true_E_d"], abs=3e-4)
    assert 0.25 < data["e_max_before"] < 0.40  # the paper: 317 mm
    assert data["e_max_after"] < data["e_max_before"] / 5
    assert (out / "clusters.png").read_bytes().startswith(b"\x89PNG")
    # The runs it wrote calibrate to the same result.
    again = _calibrate_json(out / "runs_before.csv")
    assert again["E_d"] == pytest.approx(data["E_d"], rel=1e-9)


def test_reproduce_table1_rows():
    data = json.loads(_ok("reproduce", "table1", "--json", "--seeds", "2"))
    rows = data["rows"]
    assert [r["experiment"] for r in rows] == list(range(1, 9))
    for r in rows:
        assert r["e_max_before"] == pytest.approx(r["paper_before"], rel=0.15)
        assert r["e_max_after"] < r["e_max_before"] / 5
        assert r["improvement"] > 5
    # 3, 4 and 5 share the test before correction, as in the paper.
    assert rows[2]["e_max_before"] == rows[3]["e_max_before"] == rows[4]["e_max_before"]


def test_reproduce_table1_with_physical_tape_needs_the_second_pass():
    data = json.loads(
        _ok("reproduce", "table1", "--json", "--seeds", "2", "--tape-thickness", "0.15")
    )
    seventh = data["rows"][6]
    assert seventh["second_pass_share"] == 1.0
    # The first pass leaves what the small-angle formulas missed; the second removes it.
    assert seventh["e_max_after"] > 0.05
    assert seventh["e_max_final"] < 0.75 * seventh["e_max_after"]


def test_reproduce_fig4_exposes_the_unidirectional_trap(tmp_path):
    plot = tmp_path / "fig4.svg"
    data = json.loads(_ok("reproduce", "fig4", "--json", "--plot", str(plot)))
    start, tuned, fixed = data["stages"]
    assert tuned["wheelbase"] > start["wheelbase"]  # b enlarged: turns more
    assert tuned["r_cw"] < 0.01  # cw looks excellent...
    assert tuned["r_ccw"] > 0.2  # ...and ccw is bad
    assert fixed["r_cw"] < 0.02
    assert fixed["r_ccw"] < 0.02
    assert b"<svg" in plot.read_bytes()

"""The virtual-robot jobs end to end: simulate, demo, reproduce (through the library;
the user's view of the same jobs at the end)."""

from __future__ import annotations

import csv
import math

import pytest
import yaml

import umbmark

from helpers import api_error, cli_error, run_cli


def _calibrate(path, **options) -> dict:
    return umbmark.calibrate(path, side_length=4, **{"wheelbase": 0.34, **options}).to_dict()


def test_simulate_then_calibrate_recovers_the_errors(tmp_path):
    runs = tmp_path / "runs.csv"
    sim = umbmark.simulate(E_d=1.002, E_b=1.01, noise_free=True, output=runs)
    assert len(sim.runs) == 10
    header = next(line for line in runs.read_text().splitlines() if not line.startswith("#"))
    assert header == "direction,x_abs,y_abs,theta_abs,x_odo,y_odo,theta_odo"
    exact = _calibrate(runs, method="exact")
    assert exact["E_d"] == pytest.approx(1.002, abs=2e-6)
    assert exact["E_b"] == pytest.approx(1.01, abs=2e-5)
    heading = _calibrate(runs, method="heading")
    # Heading errors are exact in the model; E_d then goes through Eqs. 4.21-4.22.
    assert heading["E_b"] == pytest.approx(1.01, abs=2e-5)
    assert heading["E_d"] == pytest.approx(1.002, abs=2e-5)
    paper = _calibrate(runs, method="paper")
    assert paper["E_d"] == pytest.approx(1.002, rel=1e-3)
    assert _calibrate(runs)["method"] == "exact"  # the default


def test_second_pass_with_params_from_the_first(tmp_path):
    first, result, second = tmp_path / "first.csv", tmp_path / "r.json", tmp_path / "second.csv"
    opts = {"E_d": 1.004, "E_b": 1.03, "noise_free": True}
    umbmark.simulate(**opts, output=first)
    before = _calibrate(first, output=result)
    umbmark.simulate(**opts, params=result, output=second)
    # The second runs were driven with the first pass's wheelbase and wheel factors.
    after = _calibrate(
        second,
        wheelbase=before["wheelbase"],
        current_c_l=before["new"]["c_L"],
        current_c_r=before["new"]["c_R"],
    )
    assert after["e_max_syst"] < before["e_max_syst"] / 10
    # A previous result names what was active just as well as the keywords do, and the
    # composed parameters approach the truth.
    same = _calibrate(second, current_params=result)
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
    umbmark.simulate(runs=2, seed=3, logs=logs, side_length=1)
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
    data = umbmark.simulate(path="straight", E_s=1.01, noise_free=True, runs=1).to_dict()
    assert data["distance_ratio"] == pytest.approx(1.01, rel=1e-5)
    turn = umbmark.simulate(
        path="turn", turn_angle=math.pi / 2, E_d=1.02, noise_free=True, runs=1
    ).to_dict()
    assert turn["rotation_ratio"] == pytest.approx(1.0, abs=1e-4)
    # Sec. 2.3: the centre moves by 2 d sin(tau / 2), d = (b/2)(E_d - 1)/(E_d + 1).
    d = 0.17 * 0.02 / 2.02
    assert turn["centre_shift"] == pytest.approx(2 * d * math.sin(math.pi / 4), rel=1e-3)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"E_d": 0}, "E_d must be > 0, got 0"),
        ({"E_b": 3}, "E_b=3 is not a plausible ratio"),
        ({"runs": 1}, "runs must be at least 2 for UMBmark"),
        ({"slip": -1}, "slip must be 0 to 0.1, got -1"),
        ({"seed": -1}, "seed must be 0 to 9223372036854775807, got -1"),
        ({"runs": 2**63}, "runs must be 1 to 1000, got 9223372036854775808"),
        ({"dt": 1e-9}, "dt must be 0.0001 to 0.1 s, got 1e-09 s"),
        ({"speed": 1e-6}, "speed must be 0.01 to 5 m/s, got 1e-06 m/s"),
        ({"bump_size": 1e308}, "bump_size must be 0 to 0.05, got 1e+308"),
        ({"encoder_resolution": 1e308}, "encoder_resolution must be 1 to 1e+07, got 1e+308"),
        ({"path": "turn", "turn_angle": math.nan}, "turn_angle=nan is not a finite number"),
        ({"path": "straight", "output": "x.csv"}, "output writes a runs table of square runs"),
        ({"wheelbase": 340}, "wheelbase=340 m is implausibly large"),
        # The command's degrees are the library's radians.
        ({"path": "turn", "turn_angle": 0.0}, "turn_angle=0 rad: give a turn of up to"),
        ({"path": "circle"}, "path='circle': use one of square, straight, turn"),
    ],
)
def test_simulate_refuses_bad_options(options, message):
    assert message in api_error(umbmark.simulate, **options)


@pytest.mark.slow
def test_simulate_logs_refuse_a_folder_with_runs_in_it(tmp_path):
    folder = tmp_path / "logs"
    umbmark.simulate(runs=2, logs=folder)
    before = sorted(p.name for p in folder.iterdir())
    message = api_error(umbmark.simulate, runs=2, E_b=1.05, logs=folder)
    assert "is not empty" in message
    assert "force=True" in message
    assert sorted(p.name for p in folder.iterdir()) == before  # nothing written
    umbmark.simulate(runs=2, logs=folder, force=True)


def test_demo_report_and_files(demo):
    """The shared demo run (tests/conftest.py: seed 1, its own folder)."""
    out = demo.files["plot"].parent
    data = demo.to_dict()
    for key in ("true_E_d", "true_E_b", "E_d", "E_b", "e_max_before", "e_max_after"):
        assert isinstance(data[key], float), key
    assert data["true_E_b"] == pytest.approx(336.17 / 340.0)
    assert data["E_b"] == pytest.approx(data["true_E_b"], abs=2e-3)
    assert data["E_d"] == pytest.approx(data["true_E_d"], abs=3e-4)
    assert 0.25 < data["e_max_before"] < 0.40  # the paper: 317 mm
    assert data["e_max_after"] < data["e_max_before"] / 5
    assert (out / "clusters.png").read_bytes().startswith(b"\x89PNG")
    # The runs it wrote calibrate to the same result.
    again = _calibrate(out / "runs_before.csv")
    assert again["E_d"] == pytest.approx(data["E_d"], rel=1e-9)
    # Without a folder the library writes nothing.
    assert umbmark.demo(seed=4, runs=2).files == {}


@pytest.mark.slow
def test_reproduce_table1_rows():
    data = umbmark.reproduce_table1(seeds=2).to_dict()
    rows = data["rows"]
    assert [r["experiment"] for r in rows] == list(range(1, 9))
    for r in rows:
        assert r["e_max_before"] == pytest.approx(r["paper_before"], rel=0.15)
        assert r["e_max_after"] < r["e_max_before"] / 5
        assert r["improvement"] > 5
    # 3, 4 and 5 share the test before correction, as in the paper.
    assert rows[2]["e_max_before"] == rows[3]["e_max_before"] == rows[4]["e_max_before"]


@pytest.mark.slow
def test_reproduce_table1_with_physical_tape_needs_the_second_pass():
    data = umbmark.reproduce_table1(seeds=2, tape_thickness=0.15e-3).to_dict()
    seventh = data["rows"][6]
    assert seventh["second_pass_share"] == 1.0
    # The first pass leaves what the small-angle formulas missed; the second removes it.
    assert seventh["e_max_after"] > 0.05
    assert seventh["e_max_final"] < 0.75 * seventh["e_max_after"]


@pytest.mark.slow
def test_reproduce_fig4_exposes_the_unidirectional_trap(tmp_path):
    plot = tmp_path / "fig4.svg"
    data = umbmark.reproduce_fig4(plot=plot).to_dict()
    start, tuned, fixed = data["stages"]
    assert data["leg_bend"] == pytest.approx(math.radians(1.0))
    assert tuned["wheelbase"] > start["wheelbase"]  # b enlarged: turns more
    assert tuned["r_cw"] < 0.01  # cw looks excellent...
    assert tuned["r_ccw"] > 0.2  # ...and ccw is bad
    assert fixed["r_cw"] < 0.02
    assert fixed["r_ccw"] < 0.02
    assert b"<svg" in plot.read_bytes()


# --- the user's view ----------------------------------------------------------------


@pytest.mark.slow
def test_simulate_command_writes_and_prints(tmp_path):
    """(That ``--json`` is the library's dictionary: tests/cli/test_main.py, for every command.)"""
    runs = tmp_path / "runs.csv"
    args = ["simulate", "--E-d", "1.002", "--seed", "7", "-o", str(runs), "--runs", "2"]
    assert run_cli(*args).returncode == 0
    assert runs.read_text().startswith("# Simulated by umbmark")
    proc = run_cli("simulate", "--path", "turn", "--turn-angle", "90", "--runs", "1")
    assert proc.returncode == 0, proc.stderr
    assert "true over odometry rotation: " in proc.stdout
    assert "--turn-angle 0 deg" in cli_error("simulate", "--path", "turn", "--turn-angle", "0")


def test_demo_command_writes_its_folder(demo_command, demo):
    """The shared ``umbmark demo --out FOLDER`` run (tests/conftest.py); it prints the
    library's figures for the same seed."""
    out = demo_command.folder
    before, after = (1000 * d.benchmark.e_max_syst for d in (demo.before, demo.after))
    line = f"E_max,syst before: {before:.1f} mm, after: {after:.1f} mm"
    assert line in demo_command.stdout
    assert f"umbmark: wrote {out / 'clusters.png'}" in demo_command.stderr
    assert sorted(p.name for p in out.iterdir()) == [
        "clusters.png",
        "overlay.yaml",
        "result.json",
        "runs_after.csv",
        "runs_before.csv",
    ]


@pytest.mark.slow
def test_reproduce_table1_command(tmp_path):
    proc = run_cli("reproduce", "table1", "--seeds", "1")
    assert proc.returncode == 0, proc.stderr
    assert "Table I on a virtual LabMate: E_max,syst [mm]" in proc.stdout
    assert "--tape-thickness 5 mm" in cli_error("reproduce", "table1", "--tape-thickness", "5")

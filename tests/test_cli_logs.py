"""Run logs through the command line: simulate --logs, calibrate and replay them, bad logs."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from umbmark.cli.main import app

from helpers import cli_error, cli_json

runner = CliRunner()


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    runs = folder / "runs.csv"
    result = runner.invoke(
        app,
        [
            "simulate",
            "--E-d",
            "1.003",
            "--E-b",
            "0.99",
            "--runs",
            "3",
            "--side-length",
            "2",
            "--seed",
            "5",
            "--logs",
            str(folder / "log"),
            "-o",
            str(runs),
        ],
    )
    assert result.exit_code == 0, result.output
    return folder


def test_logs_calibrate_like_the_runs_table_of_the_same_runs(logs):
    from_table = cli_json("calibrate", str(logs / "runs.csv"), "-L", "2", "-b", "0.34")
    from_logs = cli_json("calibrate", str(logs / "log"))
    assert from_logs["format"] == "log"
    assert from_logs["side_length"] == 2.0  # from metadata.yaml
    # The logs keep micrometres and whole counts: the same centres to a few micrometres.
    assert from_logs["cg_cw"] == pytest.approx(from_table["cg_cw"], abs=5e-6)
    assert from_logs["cg_ccw"] == pytest.approx(from_table["cg_ccw"], abs=5e-6)
    assert from_logs["E_d"] == pytest.approx(from_table["E_d"], abs=1e-6)
    assert from_logs["wheel_diameter_left"] == pytest.approx(0.15 * from_logs["new"]["c_L"])
    association = from_logs["time_association"]
    assert len(association) == 6
    assert all(a["matched"] == a["total"] for a in association.values())


def test_one_csv_of_a_log_is_one_recording(logs):
    data = cli_json("calibrate", str(logs / "log" / "run-01.csv"), "--method", "trajectory")
    assert data["n_runs"] == 1
    assert data["e_max_syst"] is None  # one direction only: no UMBmark figures
    # A 2 m square's wheel data pins the wheels down to a fraction of a per mille.
    assert data["E_d"] == pytest.approx(1.003, abs=5e-4)


def test_replay_of_logs_with_and_without_parameters(logs, tmp_path):
    result = tmp_path / "r.json"
    cli_json("calibrate", str(logs / "log"), "--method", "trajectory", "-o", str(result))
    replay = cli_json("replay", str(logs / "log"), "--params", str(result))
    assert replay["mean_end_error"] < replay["mean_end_error_nominal"] / 3
    nominal = cli_json("replay", str(logs / "log"))
    assert nominal["mean_end_error"] == pytest.approx(replay["mean_end_error_nominal"])
    assert "mean_end_error_calibrated" not in nominal


def test_overriding_the_wheel_parameters_changes_the_odometry(logs):
    base = cli_json("replay", str(logs / "log"))
    wider = cli_json("replay", str(logs / "log"), "--wheelbase", "0.35")
    assert wider["parameters"]["nominal"]["wheelbase"] == 0.35
    assert wider["mean_end_error"] != pytest.approx(base["mean_end_error"])


def test_a_runs_table_beside_the_logs_is_left_alone(logs, tmp_path):
    import shutil

    folder = tmp_path / "log"
    shutil.copytree(logs / "log", folder)
    shutil.copy(logs / "runs.csv", folder / "runs.csv")
    assert cli_json("calibrate", str(folder), "--format", "log")["n_runs"] == 6


def test_bad_logs(tmp_path, logs):
    folder = tmp_path / "log"
    folder.mkdir()
    (folder / "run.csv").write_text("time,x,y,theta,left,right\n0,0,0,0,0,0\n1,0,0,0,1,1\n")
    err = cli_error("calibrate", str(folder / "run.csv"), "--format", "log")
    assert "has no metadata.yaml beside it" in err
    (folder / "metadata.yaml").write_text(
        "wheel_diameter: 150\nwheelbase: 0.34\nencoder_resolution: 100\n"
    )
    err = cli_error("calibrate", str(folder), "--format", "log")
    assert "metadata.yaml: wheel_diameter and wheelbase are in metres" in err
    (folder / "metadata.yaml").write_text("wheel_diameter: 0.15\nwheelbase: 0.34\n")
    assert "metadata.yaml: has no encoder_resolution" in cli_error("calibrate", str(folder))
    (folder / "metadata.yaml").write_text(
        "wheel_data: angles\nwheel_diameter: 0.15\nwheelbase: 0.34\n"
    )
    (folder / "run.csv").write_text("time,x,y,left,right\n0,0,0,0,0\n")
    err = cli_error("calibrate", str(folder))
    assert "run.csv, row 1: missing column theta" in err
    (folder / "run.csv").write_text("time,x,y,theta,left,right\n0,0,0,0,0,0\n0,0,0,0,1,1\n")
    assert "run.csv: wheel time does not increase" in cli_error("calibrate", str(folder))
    (folder / "run.csv").write_text(
        "time,x,y,theta,left,right\n0,,,,0,0\n1,,,,1,1\n5,0,0,0,,\n6,0,0,0,,\n"
    )
    err = cli_error("calibrate", str(folder))
    assert (
        "run.csv: wheel data (0.000 to 1.000 s) and ground truth (5.000 to 6.000 s) do not "
        "overlap in time" in err
    )
    err = cli_error("calibrate", str(logs / "log"), "--windows", "500:600")
    assert "run-01.csv: time window 500:600 s holds 0 wheel sample(s)" in err
    err = cli_error("calibrate", str(logs / "log"), "--windows", "ten:20")
    assert "--windows 'ten:20': write start:end pairs" in err
    err = cli_error("replay", str(logs / "runs.csv"))
    assert "replay needs recorded wheel data" in err

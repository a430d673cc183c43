"""Run logs as a user's Python code sees them: simulate logs, calibrate and replay them,
bad logs."""

from __future__ import annotations

import pytest

import umbmark

from helpers import api_error


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    umbmark.simulate(
        E_d=1.003,
        E_b=0.99,
        runs=3,
        side_length=2,
        seed=5,
        logs=folder / "log",
        output=folder / "runs.csv",
    )
    return folder


def _calibrate(*sources, **options) -> dict:
    return umbmark.calibrate(*sources, **options).to_dict()


def _replay(source, **options) -> dict:
    return umbmark.replay(source, **options).to_dict()


def test_logs_calibrate_like_the_runs_table_of_the_same_runs(logs):
    from_table = _calibrate(logs / "runs.csv", side_length=2, wheelbase=0.34)
    from_logs = _calibrate(logs / "log")
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


def test_simulated_runs_in_memory_carry_their_time_series(logs):
    sim = umbmark.simulate(E_d=1.003, E_b=0.99, runs=3, side_length=2, seed=5, record=True)
    from_memory = _calibrate(list(sim.runs), side_length=2, wheelbase=0.34)
    from_table = _calibrate(logs / "runs.csv", side_length=2, wheelbase=0.34)
    # The table keeps micrometres; the runs in memory every bit.
    assert from_memory["cg_cw"] == pytest.approx(from_table["cg_cw"], abs=1e-6)
    log = sim.runs[0].log
    assert log is not None
    assert log.wheel_angles[0].tolist() == [0.0, 0.0]
    assert log.truth[-1, :2] == pytest.approx(
        [sim.runs[0].true_end.x, sim.runs[0].true_end.y], abs=1e-12
    )


def test_one_csv_of_a_log_is_one_recording(logs):
    data = _calibrate(logs / "log" / "run-01.csv", method="trajectory")
    assert data["n_runs"] == 1
    assert data["e_max_syst"] is None  # one direction only: no UMBmark figures
    # A 2 m square's wheel data pins the wheels down to a fraction of a per mille.
    assert data["E_d"] == pytest.approx(1.003, abs=5e-4)


@pytest.mark.slow
def test_replay_of_logs_with_and_without_parameters(logs, tmp_path):
    result = tmp_path / "r.json"
    umbmark.calibrate(logs / "log", method="trajectory", output=result)
    replay = umbmark.replay(logs / "log", params=result)
    assert replay.mean_end_error < replay.mean_end_error_nominal / 3
    assert replay.end_errors["calibrated"].shape == (6,)
    assert replay.to_dict()["mean_end_error"] == replay.mean_end_error
    nominal = _replay(logs / "log")
    assert nominal["mean_end_error"] == pytest.approx(replay.mean_end_error_nominal)
    assert "mean_end_error_calibrated" not in nominal


def test_overriding_the_wheel_parameters_changes_the_odometry(logs):
    base = _replay(logs / "log")
    wider = _replay(logs / "log", wheelbase=0.35)
    assert wider["parameters"]["nominal"]["wheelbase"] == 0.35
    assert wider["mean_end_error"] != pytest.approx(base["mean_end_error"])


def test_a_runs_table_beside_the_logs_is_left_alone(logs, tmp_path):
    import shutil

    folder = tmp_path / "log"
    shutil.copytree(logs / "log", folder)
    shutil.copy(logs / "runs.csv", folder / "runs.csv")
    assert _calibrate(folder, format="log")["n_runs"] == 6


def test_bad_logs(tmp_path, logs):
    def bad(*sources, **options) -> str:
        return api_error(umbmark.calibrate, *sources, **options)

    folder = tmp_path / "log"
    folder.mkdir()
    (folder / "run.csv").write_text("time,x,y,theta,left,right\n0,0,0,0,0,0\n1,0,0,0,1,1\n")
    assert "has no metadata.yaml beside it" in bad(folder / "run.csv", format="log")
    (folder / "metadata.yaml").write_text(
        "wheel_diameter: 150\nwheelbase: 0.34\nencoder_resolution: 100\n"
    )
    err = bad(folder, format="log")
    # The bound of --wheel-diameter: lengths in metres, at most 10 m.
    assert err == (
        f"{folder / 'metadata.yaml'}: wheel_diameter 150 m is implausibly large: lengths are "
        "in metres (at most 10 m here; plausible: 0.001 to 10 m)"
    )
    (folder / "metadata.yaml").write_text("wheel_diameter: 0.15\nwheelbase: 0.34\n")
    assert "metadata.yaml: has no encoder_resolution" in bad(folder)
    (folder / "metadata.yaml").write_text(
        "wheel_data: angles\nwheel_diameter: 0.15\nwheelbase: 0.34\n"
    )
    (folder / "run.csv").write_text("time,x,y,left,right\n0,0,0,0,0\n")
    assert "run.csv, row 1: missing column theta" in bad(folder)
    (folder / "run.csv").write_text("time,x,y,theta,left,right\n0,0,0,0,0,0\n0,0,0,0,1,1\n")
    assert "run.csv: wheel time does not increase" in bad(folder)
    (folder / "run.csv").write_text(
        "time,x,y,theta,left,right\n0,,,,0,0\n1,,,,1,1\n5,0,0,0,,\n6,0,0,0,,\n"
    )
    assert (
        "run.csv: wheel data (0.000 to 1.000 s) and ground truth (5.000 to 6.000 s) do not "
        "overlap in time" in bad(folder)
    )
    err = bad(logs / "log", windows="500:600")
    assert "run-01.csv: time window 500:600 s holds 0 wheel sample(s)" in err
    assert "windows='ten:20': write start:end pairs" in bad(logs / "log", windows="ten:20")
    err = api_error(umbmark.replay, logs / "runs.csv")
    assert "replay needs recorded wheel data" in err

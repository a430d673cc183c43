"""Real runs with motion-capture ground truth: the OptiOdom sessions in ../shared/data.

Figures the paper's method must reach here were measured independently of this code in
the issue that asked for it: replaying circular/250620202104 gives about 42 mm of mean
end error with the nominal parameters and about 20 mm with the paper's calibration from
square/230620202042.
"""

from __future__ import annotations

import math
import re
import shutil

import numpy as np
import pytest

import umbmark
from umbmark.core.errors import InputError
from umbmark.runs.load import detect_format
from umbmark.sources.optiodom import read_optiodom

from helpers import OPTIODOM, api_error, cli_error

SQUARE = OPTIODOM / "square" / "230620202042"
SQUARE2 = OPTIODOM / "square" / "231220200029"
CIRCLE = OPTIODOM / "circular" / "250620202104"

pytestmark = pytest.mark.skipif(not SQUARE.is_dir(), reason="no OptiOdom data")
#: The second square session is only in the shared data (the package ships the first).
needs_second = pytest.mark.skipif(not SQUARE2.is_dir(), reason="../shared/data is not here")


def test_session_metadata_and_runs_are_read_as_published():
    recordings, session = read_optiodom(SQUARE)
    assert len(recordings) == 6
    params = session.params
    assert params.wheelbase == 0.2
    assert params.wheel_diameter == 0.084
    # c_m = pi D / (n C_e) with the session's gear ratio 43.7 and 64 pulses.
    assert params.conversion_factor == pytest.approx(math.pi * 0.084 / (43.7 * 64))
    assert session.side_length == 0.75
    first = recordings[0]
    np.testing.assert_allclose(first.truth.poses[0], [0, 0, 0], atol=1e-12)
    # Ticks are increments per 50 ms cycle: the angles are their running sums.
    raw = np.loadtxt(SQUARE / "230620202042_run-01.csv", delimiter=",", encoding="utf-8-sig")
    assert first.wheels.angles[-1, 0] == pytest.approx(raw[:, 5].sum() * params.radians_per_pulse)
    assert first.wheels.angles[-1, 1] == pytest.approx(raw[:, 4].sum() * params.radians_per_pulse)


def test_directions_come_from_the_heading_not_the_file_order():
    data = umbmark.calibrate(SQUARE).to_dict()
    assert [r["direction"] for r in data["runs"]] == ["cw"] * 3 + ["ccw"] * 3
    assert data["format"] == "optiodom"
    assert data["side_length"] == 0.75
    assert data["n_cw"] == data["n_ccw"] == 3


@pytest.mark.slow
def test_paper_calibration_lowers_the_error_on_circles(tmp_path):
    result = tmp_path / "square.json"
    data = umbmark.calibrate(SQUARE, output=result).to_dict()
    assert 0.19 < data["wheelbase"] < 0.21
    assert data["wheel_diameter_left"] == pytest.approx(0.084 * data["new"]["c_L"])
    plot = tmp_path / "replay.svg"
    replay = umbmark.replay(CIRCLE, params=result, plot=plot)
    assert replay.mean_end_error_nominal == pytest.approx(0.042, abs=0.002)
    assert replay.mean_end_error == pytest.approx(0.020, abs=0.003)
    assert len(replay.runs) == 6
    svg = plot.read_text()
    # six runs, the nominal and the calibrated path's legend entry in each
    assert len(re.findall(r"ends \d+ mm off", svg)) == 12


def test_a_report_replays_like_its_result_file(tmp_path):
    from dataclasses import replace

    from umbmark.sources.params.reader import read_calibrated_params

    result = tmp_path / "square.json"
    report = umbmark.calibrate(SQUARE, output=result)
    assert report.new_params() == replace(read_calibrated_params(result), source=report.source)
    from_report = umbmark.replay(CIRCLE, report)
    from_file = umbmark.replay(CIRCLE, result)
    assert from_report.mean_end_error == from_file.mean_end_error


@pytest.mark.slow
@pytest.mark.parametrize("method", ["exact", "heading", "trajectory"])
def test_other_estimators_also_help_on_circles(tmp_path, method):
    result = tmp_path / f"{method}.json"
    umbmark.calibrate(SQUARE, method=method, output=result)
    replay = umbmark.replay(CIRCLE, params=result)
    assert replay.mean_end_error < 0.6 * replay.mean_end_error_nominal


@pytest.mark.slow
def test_trajectory_method_reports_the_scale_error_with_standard_errors():
    data = umbmark.calibrate(CIRCLE, method="trajectory").to_dict()
    assert data["method"] == "trajectory"
    assert 0.98 < data["E_s"] < 1.02
    for key in ("E_d", "E_b", "E_s", "r_left", "r_right", "wheelbase"):
        assert 0 < data["standard_errors"][key] < 0.01, key
    # The fitted absolute diameters are what the result says to configure.
    assert data["wheel_diameter_left"] == pytest.approx(2 * data["components"]["r_left"])
    assert data["wheel_diameter_right"] == pytest.approx(2 * data["components"]["r_right"])
    assert data["wheelbase"] == pytest.approx(data["components"]["wheelbase"])


def test_tum_files_for_evo(tmp_path):
    out = tmp_path / "tum"
    umbmark.calibrate(SQUARE, tum=out)
    files = sorted(p.name for p in out.iterdir())
    assert len(files) == 18
    assert "run-01_truth.tum" in files
    assert "run-01_calibrated.tum" in files
    rows = np.loadtxt(out / "run-04_truth.tum")
    assert rows.shape[1] == 8
    np.testing.assert_allclose(np.linalg.norm(rows[:, 4:8], axis=1), 1.0, atol=1e-12)
    # qz, qw encode the heading: a ccw run ends near +2 pi, i.e. a quaternion near -1 (w).
    yaw = 2 * np.arctan2(rows[:, 6], rows[:, 7])
    assert abs(np.unwrap(yaw)[-1] - 2 * math.pi) < 0.2
    nominal = np.loadtxt(out / "run-04_nominal.tum")
    assert nominal[0, 0] == 0.0
    assert nominal[-1, 0] == pytest.approx(rows[-1, 0])


def test_ros1_and_ros2_parameter_files(tmp_path):
    import yaml

    ros1, ros2 = tmp_path / "ros1.yaml", tmp_path / "ros2.yaml"
    data = umbmark.calibrate(SQUARE, ros1_yaml=ros1, yaml=ros2, controller="base").to_dict()
    one = yaml.safe_load(ros1.read_text())["base"]
    two = yaml.safe_load(ros2.read_text())["base"]["ros__parameters"]
    assert one == two
    assert one["left_wheel_radius_multiplier"] == pytest.approx(data["new"]["c_L"], rel=1e-9)


def test_format_is_detected():
    assert detect_format(SQUARE) == "optiodom"
    with pytest.raises(InputError, match="no such file or folder"):
        detect_format(OPTIODOM / "nothing")
    with pytest.raises(InputError, match="is a folder of no known layout"):
        detect_format(OPTIODOM)


def test_a_broken_session_gives_one_line(tmp_path):
    broken = tmp_path / "session"
    shutil.copytree(SQUARE, broken)
    run = broken / "230620202042_run-02.csv"
    lines = run.read_text(encoding="utf-8-sig").splitlines()
    lines[10] = "0.5,abc,0,0,1,1"
    run.write_text("\n".join(lines) + "\n")
    err = api_error(umbmark.calibrate, broken, format="optiodom")
    assert err == f"{run}, row 11: has a cell that is not a number"
    (broken / "230620202042_metadata.csv").unlink()
    err = api_error(umbmark.calibrate, broken, format="optiodom")
    assert "has no *_metadata.csv: not an OptiOdom session" in err


@needs_second
def test_second_session_longer_square():
    data = umbmark.calibrate(SQUARE2).to_dict()
    assert data["side_length"] == 1.7
    assert data["e_max_syst"] > 0.05
    assert data["second_pass_recommended"] is True


@pytest.mark.slow
@needs_second
def test_sessions_pool_for_the_trajectory_fit_but_not_across_squares():
    pooled = umbmark.calibrate(SQUARE, CIRCLE, method="trajectory")
    assert len(pooled.runs) == 12
    assert pooled.sources == (str(SQUARE), str(CIRCLE))
    assert pooled.runs[6].label == "250620202104 run-01"
    # Two sessions of one day pin the wheels down better than either alone.
    circles = OPTIODOM / "circular" / "250620202251"
    same_day = umbmark.calibrate(CIRCLE, circles, method="trajectory")
    alone = umbmark.calibrate(CIRCLE, method="trajectory")
    assert same_day.estimate.standard_errors["E_d"] < alone.estimate.standard_errors["E_d"]
    # Sessions of one day agree; a square of another day wants another wheelbase
    # (200.7 against 201.7 mm, each to 0.1 mm): the calibration says so.
    assert same_day.notes == ()
    assert same_day.warnings == ()
    (warning,) = [n for n in pooled.warnings if "want different" in n]
    assert warning.startswith(f"{SQUARE} and {CIRCLE} want different wheelbases: 200.")
    assert "not a square of known side" in api_error(umbmark.calibrate, SQUARE, CIRCLE)
    err = api_error(umbmark.calibrate, SQUARE, SQUARE2)
    assert "squares of different sides (0.75 m, 1.7 m)" in err
    twice = umbmark.calibrate(SQUARE, SQUARE)
    assert twice.e_max_syst == pytest.approx(umbmark.calibrate(SQUARE).e_max_syst, rel=1e-12)


def test_real_sessions_ship_with_the_package(tmp_path):
    """``umbmark example --real DIR`` writes two sessions identical to the data set's."""
    written = umbmark.example_sessions(tmp_path / "real")
    assert [p.relative_to(tmp_path / "real").as_posix() for p in written] == [
        "square/230620202042",
        "circular/250620202104",
    ]
    for session in written:
        original = OPTIODOM / session.relative_to(tmp_path / "real")
        names = sorted(p.name for p in session.iterdir())
        assert names == sorted(
            p.name
            for p in original.iterdir()
            if p.name.endswith("_metadata.csv") or re.fullmatch(r".*_run-\d+\.csv", p.name)
        )
        for name in names:
            assert (session / name).read_bytes() == (original / name).read_bytes()
    assert "MIT License" in (tmp_path / "real" / "LICENSE").read_text()
    assert "Sousa" in (tmp_path / "real" / "README.md").read_text()
    message = api_error(umbmark.example_sessions, tmp_path / "real")
    assert "is not empty" in message
    line = cli_error("example", "--real", str(tmp_path / "real"))
    assert "--force" in line


def test_a_session_is_dated_by_its_id(tmp_path):
    """The data set names each session by its capture's day and time (DDMMYYYYhhmm)."""
    import datetime as dt

    from umbmark.sources.optiodom import session_start

    assert (
        session_start(SQUARE)
        == dt.datetime(2020, 6, 23, 20, 42, tzinfo=dt.timezone.utc).timestamp()
    )
    for name in ("991399990000", "lab_a"):  # month 13; no time at all
        odd = tmp_path / name
        shutil.copytree(SQUARE, odd)
        for f in odd.iterdir():
            f.rename(odd / f.name.replace(SQUARE.name, name))
        assert session_start(odd) is None


def _li(session) -> float:  # type: ignore[no-untyped-def]
    """The session's nominal wheelbase, read here from its metadata's ``Li`` row."""
    (meta,) = session.glob("*_metadata.csv")
    for line in meta.read_text(encoding="utf-8-sig").splitlines():
        cells = line.split(",")
        if cells[0] == "Li":
            return float(cells[1])
    raise AssertionError(f"{meta} has no Li")


@needs_second
@pytest.mark.slow
def test_a_fleet_of_real_sessions_finds_the_robot_unchanged(tmp_path):
    """Every OptiOdom session of the shared data as one robot's fleet recordings: each
    calibrated by a trajectory fit and dated by its id; the sessions whose nominal
    wheelbase was set off on purpose are compared on the latest nominal, and the robot,
    which the data set's authors say did not change, is not flagged."""
    import datetime as dt

    pytest.importorskip("distributed")
    report = umbmark.fleet(OPTIODOM, history=tmp_path / "h.sqlite3", workers=1)
    sessions = {p.name: p for p in OPTIODOM.glob("*/*") if p.is_dir()}
    assert len(report.done) == len(sessions) >= 10
    assert all(o.calibrated and o.method == "trajectory" for o in report.done)
    (robot,) = report.summary.robots
    assert robot.robot == "unnamed"
    assert robot.flags == ()
    when = {
        name: dt.datetime.strptime(name, "%d%m%Y%H%M").replace(tzinfo=dt.timezone.utc).timestamp()
        for name in sessions
    }
    assert {o.path: o.start for o in report.done} == {str(sessions[n]): when[n] for n in sessions}
    latest = max(sessions, key=lambda n: when[n])
    li = {n: _li(p) for n, p in sessions.items()}
    assert {li[n] for n in sessions} == {0.2, 0.205}  # set off on purpose in some
    track = robot.tracks["E_b"]
    shown = dict(zip(track.paths, track.values, strict=True))
    used = [o for o in report.done if o.verdict != "do-not-apply"]
    assert len(used) >= 8
    for o in report.done:  # a calibration that failed its checks is no part of the course
        if o.verdict == "do-not-apply":
            assert o.path not in shown
            assert any(n.startswith(f"not used: {o.path}") for n in robot.notes)
    for o in used:
        name = o.path.rsplit("/", 1)[-1]
        assert shown[o.path] == pytest.approx(
            o.figures["E_b"][0] * li[name] / li[latest], rel=1e-12
        )
    # Same day, same circles, nominal 0.2 m and 0.205 m: the same actual wheelbase.
    a, b = (f"{OPTIODOM}/circular/{n}" for n in ("250620202104", "250620202119"))
    (ea,), (eb,) = (
        [e for p, e in zip(track.paths, track.errors, strict=True) if p == x] for x in (a, b)
    )
    assert abs(shown[a] - shown[b]) < 3 * math.hypot(ea, eb)
    assert any("nominal wheelbase 0.2 m, then 0.205 m" in n for n in robot.notes)

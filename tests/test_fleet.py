"""``umbmark fleet`` end to end on a small fleet of simulated recordings (ROS 1 bags with
wheels and motion capture): the robots named from the folder layout, each recording
calibrated by what it holds, the wheel changed on one robot found at the right day and
no steady robot flagged, an unreadable recording failed with its reason while the rest go
on, a second (nightly) run doing only the new recordings, and the same work on an
existing Dask cluster (a scheduler and workers started as processes) giving the same
results as the local run."""

from __future__ import annotations

import datetime as dt
import json
import sqlite3
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

import umbmark

from dask_cluster import Cluster
from helpers import run_cli

DAYS = 6
#: Each robot's true E_d before and from the day its wheel was changed.
ROBOTS = {"steady": (1.002, None, None), "wheel": (1.002, 3, 0.996)}
GEOMETRY = {"wheelbase": 0.34, "wheel_diameter": 0.15}


def _day(d: int) -> str:
    return f"2026-11-{d + 1:02d}"


@pytest.fixture(scope="module")
def recordings(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("fleet") / "fleet"
    for k, (robot, (e_d, step_day, after)) in enumerate(ROBOTS.items()):
        for d in range(DAYS):
            folder = root / robot / _day(d)
            folder.mkdir(parents=True)
            true_e_d = after if step_day is not None and d >= step_day else e_d
            umbmark.simulate(E_d=true_e_d, E_b=1.01, seed=100 * k + d, dt=0.05,
                             side_length=1.0, runs=2, bag=str(folder / "drive.bag"))  # fmt: skip
    broken = root / "broken" / _day(0)
    broken.mkdir(parents=True)
    (broken / "drive.bag").write_bytes(b"#ROSBAG V2.0\n" + b"\0" * 64)
    return root


def _run(recordings: Path, history: Path, *extra: str) -> dict:  # type: ignore[type-arg]
    proc = run_cli("fleet", str(recordings), "--robot-from", "{robot}/{date}/*.bag",
                   "-b", "0.34", "--wheel-diameter", "0.15", "--history", str(history),
                   "--json", *extra, timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    return dict(json.loads(proc.stdout))


@pytest.mark.slow
def test_a_fleet_is_calibrated_flagged_and_done_once(recordings: Path, tmp_path: Path):
    history = tmp_path / "h.sqlite3"
    page = tmp_path / "fleet.html"
    first = _run(recordings, history, "--workers", "2", "--report", str(page))
    assert first["recordings_found"] == 2 * DAYS + 1
    assert first["recordings_done"] == 2 * DAYS + 1
    assert [f["path"].endswith("broken/2026-11-01/drive.bag") for f in first["failed"]] == [True]
    by = {r["robot"]: r for r in first["robots"]}
    assert set(by) == {"steady", "wheel", "broken"}
    assert first["drifted"] == ["wheel"]
    assert first["unusable"] == ["broken"]
    e_d = by["wheel"]["figures"]["E_d"]
    assert e_d["change"] == "step"
    assert e_d["since"].endswith(f"wheel/{_day(3)}/drive.bag")
    assert e_d["size"] == pytest.approx(0.996 - 1.002, abs=3e-4)
    assert all(f["change"] == "steady" for f in by["steady"]["figures"].values())
    # The steady robot's E_d, 0.002 from nominal, within 3e-4 of its truth (its six
    # short recordings' trajectory fits each carry a bias of about 1e-4 at this dt).
    assert by["steady"]["figures"]["E_d"]["value"] == pytest.approx(1.002, abs=3e-4)
    assert by["wheel"]["figures"]["E_d"]["value"] == pytest.approx(0.996, abs=3e-4)
    shown = page.read_text(encoding="utf-8")
    assert shown.count('<section class="robot changed"') == 1  # the wheel's row
    assert "Failed recordings (1)" in shown
    assert "1 with no usable recording; 13 recordings: 12 calibrated, 1 failed" in shown
    # Every calibration is in the history with the recording's time and digest.
    with sqlite3.connect(history) as db:
        rows = db.execute("SELECT time, inputs FROM calibrations WHERE robot = 'wheel'").fetchall()
    assert sorted(r[0][:10] for r in rows) == [_day(d) for d in range(DAYS)]
    assert all(len(json.loads(r[1])[0]["sha256"]) == 64 for r in rows)
    # The nightly run: nothing new but the failed recording, which is tried again.
    again = _run(recordings, history, "--workers", "1")
    assert (again["recordings_done"], again["recordings_skipped"]) == (1, 2 * DAYS)
    assert again["drifted"] == ["wheel"]
    # umbmark history reads the same records.
    listed = run_cli("history", "wheel", "--history", str(history), "--json")
    assert len(json.loads(listed.stdout)["calibrations"]) == DAYS
    # ... and dates the robots by their recordings' days, not by the day the fleet ran.
    robots = json.loads(run_cli("history", "--history", str(history), "--json").stdout)
    dated = {r["name"]: (r["first_calibration"][:10], r["last_calibration"][:10])
             for r in robots["robots"]}  # fmt: skip
    assert dated == {"steady": (_day(0), _day(DAYS - 1)), "wheel": (_day(0), _day(DAYS - 1))}


@pytest.mark.slow
def test_an_existing_cluster_gives_the_local_results(recordings: Path, tmp_path: Path):
    local = _run(recordings, tmp_path / "local.sqlite3", "--workers", "1")
    cluster = Cluster(tmp_path, workers=2)
    try:
        remote = _run(recordings, tmp_path / "remote.sqlite3", "--scheduler", cluster.address)
    finally:
        cluster.close()

    def figures(data: dict) -> dict:  # type: ignore[type-arg]
        return {
            r["robot"]: {n: (f["value"], f["change"]) for n, f in r["figures"].items()}
            for r in data["robots"]
        }

    assert figures(remote) == figures(local)
    assert remote["drifted"] == local["drifted"] == ["wheel"]


@pytest.mark.slow
def test_a_robot_named_by_its_recording_gets_its_own_options(tmp_path: Path):
    """Without a pattern the robots are named by their recordings' robot descriptions,
    yet each gets its entry of --robot-options; a nightly run redoes a recording only
    when its own robot's entry changed."""
    fleet = tmp_path / "fleet"
    umbmark.simulate_fleet(fleet, fleet=2, days=1, minutes=0.5, seed=3)
    options, history = tmp_path / "robots.yaml", tmp_path / "h.sqlite3"

    def run(entries: str) -> umbmark.FleetReport:
        options.write_text(entries, encoding="utf-8")
        return umbmark.fleet(fleet, robot_options=options, history=history, workers=1)

    first = run("robot02:\n  scan_topic: /front/scan\n")
    by = {o.robot: o for o in first.done}
    assert set(by) == {"robot01", "robot02"}
    assert by["robot01"].calibrated
    assert not by["robot02"].calibrated
    assert "/front/scan" in str(by["robot02"].reason)
    again = run("robot02:\n  scan_topic: /front/scan\n")
    assert (len(again.done), again.skipped) == (0, 2)
    # robot02's entry changes (to its real topic): only its recording is done again.
    fixed = run("robot02:\n  scan_topic: /scan\nrobot03:\n  scan_topic: /x\n")
    assert ([o.robot for o in fixed.done], fixed.skipped) == (["robot02"], 1)
    assert fixed.done[0].calibrated


@pytest.mark.slow
def test_run_logs_are_recordings_of_a_fleet(tmp_path: Path):
    """umbmark's own run logs (wheels and motion capture by format) are calibrated by a
    trajectory fit: the simulated truth recovered, the day from the pattern."""
    root = tmp_path / "labs"
    for d, e_d in enumerate((1.003, 1.003, 1.003)):
        umbmark.simulate(E_d=e_d, E_b=1.01, seed=40 + d, dt=0.05, side_length=1.0, runs=2,
                         logs=str(root / "amr9" / _day(d) / "log"))  # fmt: skip
    report = umbmark.fleet(root, robot_from="{robot}/{date}/log", history=tmp_path / "h.sqlite3",
                           workers=1)  # fmt: skip
    assert [(o.robot, o.method) for o in report.done] == [("amr9", "trajectory")] * 3
    assert sorted(o.start for o in report.done) == [
        dt.datetime.fromisoformat(_day(d) + "T00:00:00+00:00").timestamp() for d in range(3)
    ]
    for o in report.done:
        value, se = o.figures["E_d"]
        assert value == pytest.approx(1.003, abs=max(4 * (se or 0.0), 3e-4))
        assert o.hours > 0.0


@pytest.mark.slow
def test_the_command_and_the_library_know_each_others_recordings(tmp_path: Path):
    """The command passes every reading option's default, the library none: the same
    options all the same, so a library run after a command's run does nothing again (it
    redid every recording, and each calibration counted twice in the robot's course)."""
    fleet = tmp_path / "fleet"
    umbmark.simulate_fleet(fleet, fleet=1, days=2, minutes=0.5, seed=5)
    history = tmp_path / "h.sqlite3"
    proc = run_cli("fleet", str(fleet), "--robot-from", "{robot}/{date}/*", "--history",
                   str(history), "--workers", "1", "--json", timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["recordings_done"] == 2
    again = umbmark.fleet(fleet, robot_from="{robot}/{date}/*", history=history, workers=1)
    assert (len(again.done), again.skipped) == (0, 2)
    assert [r.recordings for r in again.summary.robots] == [2]

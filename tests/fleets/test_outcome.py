"""One recording of a fleet calibrated by what it holds, as a plain function: a bag with
motion capture by a trajectory fit (the simulated truth recovered), a bag with neither a
laser nor a reference left out with the reason, an unreadable file failed with its line."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import pytest

from umbmark.core.conventions import Direction
from umbmark.fleets.outcome import RecordingTask, calibrate_recording
from umbmark.model.square import square_run_end

from helpers import run_cli

E_D, E_B = 1.002, 1.01
GEOMETRY = {"wheelbase": 0.34, "wheel_diameter": 0.15}


@pytest.fixture(scope="module")
def bag(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("fleet") / "r1.bag"
    made = run_cli("simulate", "--E-d", str(E_D), "--E-b", str(E_B), "--seed", "7",
                   "--dt", "0.02", "-L", "2", "--bag", str(path))  # fmt: skip
    assert made.returncode == 0, made.stderr
    return path


@pytest.mark.slow
def test_a_bag_with_motion_capture_is_fitted_to_the_truth(bag: Path):
    task = RecordingTask(str(bag), robot="amr1", day=dt.date(2026, 11, 2), options=GEOMETRY)
    out = calibrate_recording(task)
    assert (out.method, out.robot, out.failed, out.reason) == ("trajectory", "amr1", False, None)
    assert out.start == dt.datetime(2026, 11, 2, tzinfo=dt.timezone.utc).timestamp()
    for name, truth in (("E_d", E_D), ("E_b", E_B), ("E_s", 1.0)):
        value, se = out.figures[name]
        assert se is not None, name
        assert abs(value - truth) < 4 * se, name
    # E_max,syst on the standard 4 m square, from the closed form of the square's end
    # (model.square) with the true errors: within the estimate's reach of it.
    worst = max(
        math.hypot(*square_run_end(E_D, E_B, 1.0, 4.0, 0.34, d)[:2])
        for d in (Direction.CW, Direction.CCW)
    )
    assert out.e_max_syst == pytest.approx(worst, rel=0.05)
    sep, left, right = out.multipliers
    assert sep == pytest.approx(E_B, abs=1e-3)
    assert right / left == pytest.approx(E_D, abs=2e-4)
    assert out.hours > 0
    assert len(out.digest) == 64


@pytest.mark.slow
def test_without_geometry_or_reference_it_is_left_out_or_failed(bag: Path, tmp_path: Path):
    out = calibrate_recording(RecordingTask(str(bag), options={"truth_topic": "/nothing"}))
    assert not out.calibrated
    assert not out.failed
    assert out.reason
    garbage = tmp_path / "broken.bag"
    garbage.write_bytes(b"#ROSBAG V2.0\n" + b"\0" * 100)
    failed = calibrate_recording(RecordingTask(str(garbage)))
    assert failed.failed
    assert not failed.calibrated
    assert failed.reason
    assert "broken.bag" in failed.reason


@pytest.mark.slow
def test_without_a_pattern_the_robot_is_named_by_its_description(tmp_path: Path):
    """Topics without a namespace: the robot is the name its recorded robot description
    gives (the simulated fleet names each robot's URDF)."""
    import umbmark

    umbmark.simulate_fleet(tmp_path / "f", fleet=2, days=1, minutes=0.5)
    (path,) = (tmp_path / "f").glob("robot02/*/drive")
    out = calibrate_recording(RecordingTask(str(path)))
    assert out.robot == "robot02"
    # A robot named only inside its recording gets its own options all the same.
    own = {"robot02": {"scan_topic": "/front/scan"}, "robot01": {"scan_topic": "/scan"}}
    moved = calibrate_recording(RecordingTask(str(path), per_robot=own))
    assert (moved.robot, moved.calibrated) == ("robot02", False)
    assert "/front/scan" in str(moved.reason)
    others = calibrate_recording(RecordingTask(str(path), per_robot={"robot01": own["robot02"]}))
    assert others.calibrated  # another robot's options are not its own


@pytest.mark.slow
def test_a_recording_at_a_url_is_copied_calibrated_and_named_by_its_url(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """A simulated ROS 2 bag (a folder, MCAP and SQLite), its MCAP file alone and a ROS 1
    bag, served over HTTP: the outcome of each is the local one's but for the path (the
    URL), with the local digest; a broken bag's reason names its URL, not the copy; a URL
    that 404s fails with one line; no copy is left in the temporary folder."""
    pytest.importorskip("fsspec", reason="the remote extra: pip install '.[remote]'")
    pytest.importorskip("aiohttp", reason="the remote extra: pip install '.[remote]'")
    import tempfile
    from dataclasses import replace

    import umbmark

    from http_served import Served

    recordings = []
    for storage in ("mcap", "sqlite3", "ros1"):
        umbmark.simulate_fleet(tmp_path / "f" / storage, fleet=1, days=1, minutes=0.5,
                               bag_storage=storage)  # fmt: skip
        (recording,) = (tmp_path / "f" / storage).glob("robot01/*/drive*")
        recordings.append(recording)
    recordings.append(recordings[0] / "drive.mcap")
    assert [p.suffix for p in recordings] == ["", "", ".bag", ".mcap"]
    assert {p.suffix for p in recordings[1].iterdir()} == {".db3", ".yaml"}
    (tmp_path / "f" / "broken.bag").write_bytes(b"#ROSBAG V2.0\n" + b"\0" * 100)
    # The copies go where tempfile puts them: a folder of this test's own (others on the
    # machine make and delete theirs in the shared one meanwhile).
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    before = {p.name for p in scratch.glob("umbmark-remote-*")}
    with Served(tmp_path / "f", tmp_path / "http.log") as server:
        for local in recordings:
            url = f"{server.url}/{local.relative_to(tmp_path / 'f').as_posix()}"
            expected = calibrate_recording(RecordingTask(str(local)))
            assert expected.calibrated
            got = calibrate_recording(RecordingTask(url))
            assert got.path == url
            assert replace(got, path=str(local), record={}) == replace(expected, record={})
            theirs, ours = dict(got.record), dict(expected.record)
            assert theirs.pop("overlay").count(url) == 1  # the overlay's provenance: the URL
            assert ours.pop("overlay").count(str(local)) == 1
            assert theirs == ours
        broken = calibrate_recording(RecordingTask(f"{server.url}/broken.bag"))
        gone = calibrate_recording(RecordingTask(f"{server.url}/robot01/gone.mcap", "robot01"))
    assert broken.failed
    assert broken.reason.startswith(f"{server.url}/broken.bag")
    assert "umbmark-remote-" not in broken.reason
    assert (gone.failed, gone.robot, gone.digest) == (True, "robot01", None)
    assert (
        gone.reason == f"{server.url}/robot01/gone.mcap: cannot be read (HTTP 404 File not found)"
    )
    assert {p.name for p in scratch.glob("umbmark-remote-*")} == before

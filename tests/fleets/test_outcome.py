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


# --- the user's reference over the one suggested (issue 35, item 7) -----------------------

#: This robot's true E_d, E_b, and those of the other robot the motion capture tracks.
MINE, OTHER = (1.004, 0.985), (0.996, 1.02)
#: How near the truth a fit against noiseless motion capture comes: the poses are the
#: simulator's exact ones and the wheel angles its own (TurtleBot3 encoders of 4096
#: counts), so only the fit's convergence and the 100 Hz sampling are left; 1e-4 is the
#: precision the issue asks of a fleet's figures and 80 times less than the two robots'
#: difference in E_d (0.008; 0.035 in E_b).
CLOSE = 1e-4
#: The two-bodies bag's topics as the reader lists them.
TOPICS = (
    "/joint_states (sensor_msgs/msg/JointState), /mocap/amr0/pose "
    "(geometry_msgs/msg/PoseStamped), /mocap/amr1/pose (geometry_msgs/msg/PoseStamped), "
    "/odom (nav_msgs/msg/Odometry), /robot_description (std_msgs/msg/String), "
    "/tf (tf2_msgs/msg/TFMessage)"
)


@pytest.fixture(scope="module")
def two_bodies(tmp_path_factory) -> Path:
    """A TurtleBot3's recording in a lab whose motion capture also tracks another robot
    (``tests/robot_bags.two_bodies_bag``): the look into it suggests the other's topic."""
    from robot_bags import TB3, drive, two_bodies_bag

    folder = tmp_path_factory.mktemp("lab") / "amr1"
    folder.mkdir()
    return two_bodies_bag(folder / "drive", "mcap", drive(TB3, *MINE), drive(TB3, *OTHER))


def _errors(out) -> tuple[float, float]:  # type: ignore[no-untyped-def]
    assert (out.method, out.reason) == ("trajectory", None)
    return out.figures["E_d"][0], out.figures["E_b"][0]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("options", "per_robot"),
    [
        ({"truth_topic": "/mocap/amr1/pose"}, {}),
        ({"tf_parent": "world", "tf_child": "amr1"}, {}),  # the user's pair, no topic mixed in
        ({"truth_topic": "/mocap/amr0/pose"}, {"amr1": {"truth_topic": "/mocap/amr1/pose"}}),
    ],
    ids=["truth-topic", "tf-pair", "robot-options"],
)
def test_the_reference_given_wins_over_the_one_the_look_suggests(two_bodies, options, per_robot):
    """Left to itself the look takes the other robot's topic, first by name, and the fit
    finds that robot's errors (the same squares driven: its wheels turn alike); the
    reference given (a topic, a TF pair, or the robot's own entry over the fleet's) gives
    this robot's, and nothing of the suggested one is mixed in (a TF pair beside the
    suggested topic was left out, "not both")."""
    suggested = calibrate_recording(RecordingTask(str(two_bodies), robot="amr1"))
    assert _errors(suggested) == pytest.approx(OTHER, abs=CLOSE)
    task = RecordingTask(str(two_bodies), robot="amr1", options=options, per_robot=per_robot)
    assert _errors(calibrate_recording(task)) == pytest.approx(MINE, abs=CLOSE)


@pytest.mark.slow
def test_a_truth_topic_not_in_the_recording_is_its_reason_for_being_left_out(two_bodies, tmp_path):
    """Named with the topics there, as the reader says it; also where the recording holds
    a laser and is calibrated by scan matching, which reads no reference (before, such a
    recording was calibrated and the wrong topic never said)."""
    import umbmark

    out = calibrate_recording(
        RecordingTask(str(two_bodies), options={"truth_topic": "/mocap/amr2"})
    )
    assert (out.calibrated, out.failed) == (False, False)
    assert out.reason == (
        f"{two_bodies}: no topic /mocap/amr2 (ground truth) in the bag; topics present: {TOPICS}"
    )
    umbmark.simulate_fleet(tmp_path / "f", fleet=1, days=1, minutes=0.5)
    (laser,) = (tmp_path / "f").glob("robot01/*/drive")
    # its laser and its IMU: the gyro and the laser together
    assert calibrate_recording(RecordingTask(str(laser))).method == "gyro"
    wrong = calibrate_recording(RecordingTask(str(laser), options={"truth_topic": "/mocap/amr2"}))
    assert (wrong.calibrated, wrong.failed) == (False, False)
    assert wrong.reason is not None
    assert wrong.reason.startswith(
        f"{laser}: no topic /mocap/amr2 (ground truth) in the bag; topics present: "
        "/imu (sensor_msgs/msg/Imu), /joint_states (sensor_msgs/msg/JointState), /mocap/robot/pose "
        "(geometry_msgs/msg/PoseStamped), /odom (nav_msgs/msg/Odometry), "
    ), wrong.reason
    assert "/scan (sensor_msgs/msg/LaserScan)" in wrong.reason


@pytest.mark.slow
def test_a_reference_given_is_fitted_where_the_look_found_none_independent(tmp_path: Path):
    """A Husky's recording (``tests/robot_bags.husky_bag``): its GNSS fixes scatter by
    0.5 m and its other pose topic is robot_localization's fused odometry, so the look
    finds no independent reference and leaves it out; the user who names the fused topic
    as the reference (knowing what it holds: here the IMU's heading) gets it fitted."""
    from robot_bags import HUSKY, drive, husky_bag

    bag = husky_bag(tmp_path / "husky", "mcap", drive(HUSKY, *MINE), gps_sigma=0.5)
    geometry = {"wheelbase": 0.555, "wheel_diameter": 0.33}
    alone = calibrate_recording(RecordingTask(str(bag), options=geometry))
    assert (alone.calibrated, alone.failed) == (False, False)
    assert alone.reason == (  # its IMU, robot_localization's input, gives orientation only
        "neither a laser scan, a usable IMU nor an independent reference (motion capture): "
        f"{bag}: /imu/data: its messages give no angular velocity "
        "(angular_velocity_covariance[0] = -1, or exactly 0): no gyro"
    )
    given = {**geometry, "truth_topic": "/odometry/filtered"}
    out = calibrate_recording(RecordingTask(str(bag), options=given))
    assert (out.method, out.reason) == ("trajectory", None)

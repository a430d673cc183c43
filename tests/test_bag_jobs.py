"""ROS bags calibrated and replayed: real bags written with rosbags, then read back.

A simulated session (two cw and two ccw runs with rests between) is written as
``sensor_msgs/JointState`` at 100 Hz and ``geometry_msgs/PoseStamped`` ground truth at
50 Hz into ROS 1, ROS 2 sqlite3 and ROS 2 MCAP bags. The bag must calibrate exactly like
the same session handed over directly, through the library and through the command.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.model.kinematics import WheelParams
from umbmark.sim.robot import SimRobot

from helpers import api_error, cli_error, simulated_session

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.rosbag2.enums import StoragePlugin  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

ODO = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
ROBOT = SimRobot.with_errors(ODO, E_d=1.002, E_b=1.01)
T0 = 1_750_000_000
BAG = {"wheelbase": 0.34, "wheel_diameter": 0.15, "side_length": 1.0, "truth_topic": "/mocap/pose"}
BAG_ARGS = ["-b", "0.34", "--wheel-diameter", "0.15", "-L", "1", "--truth-topic", "/mocap/pose"]


@pytest.fixture(scope="module")
def session():
    return simulated_session(ROBOT, ["cw", "cw", "ccw", "ccw"], side=1.0, rest=3.0)


def _write(path: Path, fmt: str, session, truth_shift: float = 0.0) -> Path:
    times, counts, poses, _ = session
    ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
    types = ts.types
    if fmt == "ros1":
        path = path.with_suffix(".bag")
        writer = Writer1(path)
    else:
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    serialize = ts.serialize_ros1 if fmt == "ros1" else ts.serialize_cdr

    def header(t: float):
        sec, nsec = divmod(round((T0 + t) * 1e9), 1_000_000_000)
        stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        if fmt == "ros1":
            return types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="base")
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id="base")

    angles = counts * ODO.radians_per_pulse
    with writer:
        js = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
        gt = writer.add_connection("/mocap/pose", "geometry_msgs/msg/PoseStamped", typestore=ts)
        for k, t in enumerate(times):
            msg = types["sensor_msgs/msg/JointState"](
                header=header(t),
                name=["right_wheel_joint", "left_wheel_joint"],
                position=np.array([angles[k, 1], angles[k, 0]]),
                velocity=np.array([], np.float64),
                effort=np.array([], np.float64),
            )
            stamp = round((T0 + t) * 1e9)
            writer.write(js, stamp, serialize(msg, "sensor_msgs/msg/JointState"))
            if k % 2 == 0:
                x, y, th = poses[k]
                pose = types["geometry_msgs/msg/PoseStamped"](
                    header=header(t + truth_shift),
                    pose=types["geometry_msgs/msg/Pose"](
                        position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                        orientation=types["geometry_msgs/msg/Quaternion"](
                            x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2)
                        ),
                    ),
                )
                writer.write(gt, stamp, serialize(pose, "geometry_msgs/msg/PoseStamped"))
    return path


@pytest.fixture(scope="module")
def log_result(session, tmp_path_factory):
    """The same session as a run log: the reference the bags must match."""
    from umbmark.sources.runlog.reader import LogMetadata
    from umbmark.sources.runlog.writer import write_log_csv, write_metadata

    folder = tmp_path_factory.mktemp("log")
    times, counts, poses, _ = session
    write_metadata(
        folder,
        LogMetadata(
            wheel_diameter=0.15,
            wheelbase=0.34,
            encoder_resolution=2000,
            gear_ratio=20,
            side_length=1.0,
        ),
    )
    # Ground truth on every other row, as in the bags.
    keep = np.arange(times.size) % 2 == 0
    truth = np.where(keep[:, None], poses, np.nan)
    write_log_csv(folder / "session.csv", times, truth, counts)
    return umbmark.calibrate(folder).to_dict()


@pytest.mark.slow
@pytest.mark.parametrize("fmt", ["ros1", "sqlite3", "mcap"])
def test_bag_calibrates_like_the_same_session_as_a_log(tmp_path, session, log_result, fmt):
    bag = _write(tmp_path / "session", fmt, session)
    data = umbmark.calibrate(bag, **BAG).to_dict()
    assert data["format"] == "bag"
    assert [r["direction"] for r in data["runs"]] == ["cw", "cw", "ccw", "ccw"]
    assert data["cg_cw"] == pytest.approx(log_result["cg_cw"], abs=5e-6)
    assert data["cg_ccw"] == pytest.approx(log_result["cg_ccw"], abs=5e-6)
    assert data["E_d"] == pytest.approx(log_result["E_d"], abs=1e-6)
    assert data["E_b"] == pytest.approx(log_result["E_b"], abs=1e-6)
    (assoc,) = data["time_association"].values()
    assert assoc["matched"] >= assoc["total"] - 1
    assert assoc["largest_gap"] == pytest.approx(0.02, abs=1e-6)


@pytest.mark.slow
def test_bag_replay_and_trajectory_fit(tmp_path, session):
    bag = _write(tmp_path / "session", "sqlite3", session)
    result = tmp_path / "fit.json"
    fit = umbmark.calibrate(bag, **BAG, method="trajectory", output=result).to_dict()
    # Ground truth at half the wheel rate is interpolated linearly; while the robot speeds
    # up and slows down that costs about 1e-4 of the wheelbase (at full rate: 1e-6).
    assert fit["components"]["wheelbase"] == pytest.approx(ROBOT.wheelbase, rel=3e-4)
    assert 2 * fit["components"]["r_right"] == pytest.approx(ROBOT.diameter_right, rel=1e-4)
    replay = umbmark.replay(
        bag, params=result, wheelbase=0.34, wheel_diameter=0.15, truth_topic="/mocap/pose"
    )
    assert replay.mean_end_error < 0.002
    assert replay.mean_end_error_nominal > 0.02


@pytest.mark.slow
def test_the_command_names_the_bag_in_its_errors(tmp_path, session):
    """(That ``--json`` is the library's dictionary: tests/cli/test_main.py, for every command.)"""
    bag = _write(tmp_path / "session", "ros1", session)
    err = cli_error("calibrate", str(bag), *BAG_ARGS, "--left-joint", "wheel_l")
    assert err.startswith(f"umbmark: error: {bag}: ")


@pytest.mark.slow
def test_bad_recordings_give_one_line(tmp_path, session):
    def bad(source, **options) -> str:
        return api_error(umbmark.calibrate, source, **options)

    bag = _write(tmp_path / "session", "mcap", session)
    err = bad(bag, **{**BAG, "truth_topic": "/vicon/pose"})
    assert str(bag) in err
    assert "/vicon/pose" in err
    err = bad(bag, **BAG, left_joint="wheel_l")
    assert "wheel_l" in err
    assert "left_wheel_joint" in err  # the joints that are there
    shifted = _write(tmp_path / "shifted", "mcap", session, truth_shift=1000.0)
    assert "do not overlap in time" in bad(shifted, **BAG)
    assert "holds 0 wheel sample(s)" in bad(bag, **BAG, windows="900:950")
    err = bad(bag, side_length=1, truth_topic="/mocap/pose")
    assert "a bag needs the wheel parameters" in err
    not_a_bag = tmp_path / "fake.bag"
    not_a_bag.write_text("hello")
    assert str(not_a_bag) in bad(not_a_bag, **BAG)

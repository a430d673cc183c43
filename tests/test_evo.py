"""TUM exports that evo reads, matches and scores as umbmark does.

The real ``evo_ape`` command (``pip install evo``, in the ``dev`` extra) scores the TUM
files umbmark writes: its APE RMSE (translation, no alignment) must equal the replay's
whole-trajectory RMSE, and it must associate umbmark's files with each other (identical
timestamps) and, by the recording's own timestamps, with a TUM file the test writes
itself from the bag's ground-truth messages. evo, not umbmark, computes every expected
figure here.
"""

from __future__ import annotations

import gc
import json
import math
import os
import shutil
import subprocess
import sys
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.model.kinematics import WheelParams
from umbmark.sim.robot import SimRobot

from helpers import api_error, run_cli, simulated_session

pytestmark = pytest.mark.slow

ODO = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
ROBOT = SimRobot.with_errors(ODO, E_d=1.002, E_b=1.01)
T0 = 1_750_000_000  # epoch seconds of the bag's first stamp
BAG = {"wheelbase": 0.34, "wheel_diameter": 0.15, "truth_topic": "/mocap/pose"}
POSE = "geometry_msgs/msg/PoseStamped"
JS = "sensor_msgs/msg/JointState"


def evo_ape_command() -> str | None:
    """The ``evo_ape`` of this Python environment, else the one on PATH."""
    beside = Path(sys.executable).with_name("evo_ape")
    return str(beside) if beside.exists() else shutil.which("evo_ape")


@pytest.fixture(scope="module")
def evo_ape(tmp_path_factory):
    """``evo_ape tum REF EST [ARGS]``; returns ``(stats, timestamps)`` from its
    ``--save_results`` archive.

    evo_ape's own entry point (``evo.cli.ape``: its argument parser and ``run``) runs in
    this process, which saves a second of start-up per call; ``check=False`` runs the
    installed command in a process of its own instead and returns it, to see it fail as a
    user would. evo keeps its settings in ``$HOME/.evo``: a fresh one, for both."""
    command = evo_ape_command()
    if command is None:
        pytest.skip("the evo_ape command is missing: pip install evo (in umbmark's dev extra)")
    home = tmp_path_factory.mktemp("evo_home")
    results = tmp_path_factory.mktemp("evo_results")
    env = {**os.environ, "HOME": str(home), "MPLBACKEND": "Agg"}
    saved = os.environ.get("HOME")
    os.environ["HOME"] = str(home)  # evo reads its settings' place when first imported
    try:
        # evo's settings module leaves two files open on import (evo 1.38): not ours
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ResourceWarning)
            from evo.cli import ape, ape_parser

            gc.collect()
    finally:
        if saved is None:
            del os.environ["HOME"]
        else:
            os.environ["HOME"] = saved
    calls = [0]

    def run(ref: Path, est: Path, *args: str, check: bool = True):
        calls[0] += 1
        out = results / f"ape{calls[0]}.zip"
        argv = ["tum", str(ref), str(est), *args, "--save_results", str(out), "--no_warnings"]
        if not check:
            return subprocess.run(
                [command, *argv], capture_output=True, text=True, env=env, timeout=120,
                check=False,
            )  # fmt: skip
        ape.run(ape_parser.parser().parse_args([*argv, "--silent"]))
        with zipfile.ZipFile(out) as archive:
            stats = json.loads(archive.read("stats.json"))
            with archive.open("timestamps.npy") as file:
                stamps = np.load(file)
        return stats, stamps

    return run


def tum_stamps(path: Path) -> np.ndarray:
    return np.loadtxt(path, ndmin=2)[:, 0]


# --- a run log ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logged")
    umbmark.simulate(E_d=1.003, E_b=0.99, runs=2, side_length=2, seed=5, logs=folder / "log")
    umbmark.calibrate(folder / "log", output=folder / "result.json")
    report = umbmark.replay(folder / "log", params=folder / "result.json", tum=folder / "tum")
    return folder, report


def test_evo_scores_a_run_log_replay_as_umbmark_does(logged, evo_ape):
    folder, report = logged
    tum = folder / "tum"
    truths = sorted(tum.glob("*_truth.tum"))
    assert len(truths) == len(report.runs) == 4
    for i, truth in enumerate(truths):
        stem = truth.name.removesuffix("_truth.tum")
        assert stem in report.runs[i].label or report.runs[i].label.startswith(stem)
        for name in ("nominal", "calibrated"):
            stats, stamps = evo_ape(truth, tum / f"{stem}_{name}.tum")
            assert stats["rmse"] == pytest.approx(report.rmse[name][i], abs=1e-8), (stem, name)
            # every truth sample found its odometry sample: identical timestamps
            np.testing.assert_array_equal(stamps, tum_stamps(truth))
    assert report.mean_rmse < report.to_dict()["mean_rmse_nominal"] / 3


def test_run_log_tum_files_carry_the_logs_own_time(logged):
    folder, report = logged
    for i, truth in enumerate(sorted((folder / "tum").glob("*_truth.tum"))):
        lines = (folder / "log" / f"run-{i + 1:02d}.csv").read_text().splitlines()
        rows = [line for line in lines if not line.startswith("#")][1:]
        csv_time = np.array([float(row.split(",")[0]) for row in rows])
        stamps = tum_stamps(truth)
        # consecutive rows of the CSV, by its own time column
        first = int(np.argmin(np.abs(csv_time - stamps[0])))
        np.testing.assert_allclose(stamps, csv_time[first : first + stamps.size], atol=1e-9)
        assert report.runs[i].log is not None
        assert report.runs[i].log.start == pytest.approx(csv_time[first], abs=1e-12)


# --- a bag ----------------------------------------------------------------------------------


def write_bag(path: Path, session, truth_every: int) -> Path:
    """Joint states at 100 Hz and PoseStamped ground truth on every ``truth_every``-th
    of their stamps, stamped from ``T0``, in a ROS 2 sqlite3 bag."""
    from rosbags.rosbag2 import Writer
    from rosbags.rosbag2.enums import StoragePlugin
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.LATEST)
    types = ts.types
    times, counts, poses, _ = session
    angles = counts * ODO.radians_per_pulse

    def header(k: int):
        sec, nsec = divmod(T0 * 1_000_000_000 + 10_000_000 * k, 1_000_000_000)
        stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id="world")

    with Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
        js = writer.add_connection("/joint_states", JS, typestore=ts)
        gt = writer.add_connection("/mocap/pose", POSE, typestore=ts)
        for k in range(times.size):
            assert times[k] == pytest.approx(0.01 * k)
            bag_ns = T0 * 1_000_000_000 + 10_000_000 * k + 2_000_000  # received 2 ms later
            msg = types[JS](
                header=header(k),
                name=["left_wheel_joint", "right_wheel_joint"],
                position=np.array(angles[k]),
                velocity=np.array([], np.float64),
                effort=np.array([], np.float64),
            )
            writer.write(js, bag_ns, ts.serialize_cdr(msg, JS))
            if k % truth_every == 0:
                x, y, th = poses[k]
                pose = types[POSE](
                    header=header(k),
                    pose=types["geometry_msgs/msg/Pose"](
                        position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                        orientation=types["geometry_msgs/msg/Quaternion"](
                            x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2)
                        ),
                    ),
                )
                writer.write(gt, bag_ns, ts.serialize_cdr(pose, POSE))
    return path


def truth_tum_from_bag(bag: Path, out: Path) -> Path:
    """A TUM file of the bag's ground-truth messages, written here from rosbags: header
    stamps as ``sec.nanosec``, the pose as recorded (in the world frame)."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    lines = ["# timestamp tx ty tz qx qy qz qw"]
    with AnyReader([bag], default_typestore=get_typestore(Stores.LATEST)) as reader:
        conns = [c for c in reader.connections if c.topic == "/mocap/pose"]
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            p, q = msg.pose.position, msg.pose.orientation
            stamp = f"{msg.header.stamp.sec}.{msg.header.stamp.nanosec:09d}"
            lines.append(f"{stamp} {p.x!r} {p.y!r} {p.z!r} {q.x!r} {q.y!r} {q.z!r} {q.w!r}")
    out.write_text("\n".join(lines) + "\n")
    return out


@pytest.fixture(scope="module")
def session():
    return simulated_session(ROBOT, ["cw", "cw", "ccw", "ccw"], side=1.0, rest=3.0)


@pytest.fixture(scope="module", params=[1, 2], ids=["mocap-100Hz", "mocap-50Hz"])
def bagged(request, session, tmp_path_factory):
    """The bag calibrated, replayed with TUM exports, and the mocap as a TUM file of its
    own; ground truth at the wheels' 100 Hz or at 50 Hz."""
    pytest.importorskip("rosbags")
    folder = tmp_path_factory.mktemp("bagged")
    bag = write_bag(folder / "session", session, truth_every=request.param)
    umbmark.calibrate(bag, side_length=1.0, output=folder / "result.json", **BAG)
    report = umbmark.replay(bag, params=folder / "result.json", tum=folder / "tum", **BAG)
    independent = truth_tum_from_bag(bag, folder / "mocap.tum")
    return folder, bag, report, independent, request.param


def test_evo_scores_a_bag_replay_as_umbmark_does(bagged, evo_ape):
    folder, _, report, _, _ = bagged
    tum = folder / "tum"
    truths = sorted(tum.glob("*_truth.tum"))
    assert len(truths) == len(report.runs) == 4
    for i, truth in enumerate(truths):
        stem = truth.name.removesuffix("_truth.tum")
        for name in ("nominal", "calibrated"):
            stats, stamps = evo_ape(truth, tum / f"{stem}_{name}.tum")
            assert stats["rmse"] == pytest.approx(report.rmse[name][i], abs=1e-8), (stem, name)
            np.testing.assert_array_equal(stamps, tum_stamps(truth))


def test_bag_tum_files_carry_the_bags_header_stamps(bagged):
    folder, _, report, _, _ = bagged
    written = T0 + 0.01 * np.arange(200_000)  # every wheel stamp the bag could hold
    for i, truth in enumerate(sorted((folder / "tum").glob("*_truth.tum"))):
        stamps = tum_stamps(truth)
        k = np.round((stamps - T0) / 0.01).astype(int)
        np.testing.assert_allclose(stamps, written[k], rtol=0, atol=1e-6)
        assert np.all(np.diff(k) == 1)  # one row per wheel sample
        log = report.runs[i].log
        assert log is not None
        assert log.start == pytest.approx(stamps[0], abs=1e-6)
        for name in ("nominal", "calibrated"):
            other = truth.with_name(truth.name.replace("_truth.tum", f"_{name}.tum"))
            np.testing.assert_array_equal(tum_stamps(other), stamps)


def test_evo_matches_the_export_with_the_bags_own_ground_truth(bagged, evo_ape):
    """By timestamps alone: a TUM file written independently from the bag's mocap
    messages (world frame) lines up with umbmark's exports (each run's start frame).

    ``--align_origin`` moves umbmark's start frame onto the first matched mocap pose;
    ``--t_max_diff 0.001`` matches only equal stamps (the samples are 10 ms apart)."""
    folder, _, report, independent, truth_every = bagged
    mocap_stamps = tum_stamps(independent)
    tum = folder / "tum"
    for i, truth in enumerate(sorted(tum.glob("*_truth.tum"))[:2]):
        stem = truth.name.removesuffix("_truth.tum")
        stamps = tum_stamps(truth)
        inside = mocap_stamps[
            (mocap_stamps >= stamps[0] - 1e-6) & (mocap_stamps <= stamps[-1] + 1e-6)
        ]
        # umbmark's ground truth, moved onto the first matched mocap pose, is the mocap:
        # the same instants, the same poses.
        stats, matched = evo_ape(independent, truth, "--align_origin", "--t_max_diff", "0.001")
        assert matched.size == inside.size > 100
        np.testing.assert_allclose(matched, inside, rtol=0, atol=1e-6)
        assert stats["max"] < 1e-6
        for name in ("nominal", "calibrated"):
            stats, matched = evo_ape(
                independent, tum / f"{stem}_{name}.tum", "--align_origin", "--t_max_diff", "0.001"
            )
            assert matched.size == inside.size
            assert (inside.size == stamps.size) == (truth_every == 1)
            if truth_every == 1:  # mocap on every wheel sample: the same RMSE
                assert stats["rmse"] == pytest.approx(report.rmse[name][i], abs=1e-8)
            elif name == "nominal":  # on every other sample: nearly the same
                assert stats["rmse"] == pytest.approx(report.rmse[name][i], rel=0.01)


def test_seconds_from_the_run_start_do_not_match_the_bag(bagged, evo_ape, tmp_path):
    folder, bag, _, independent, _ = bagged
    out = tmp_path / "tum_run"
    args = ["-b", "0.34", "--wheel-diameter", "0.15", "--truth-topic", "/mocap/pose"]
    proc = run_cli("replay", str(bag), *args, "--params", str(folder / "result.json"),
                   "--tum", str(out), "--tum-time", "run")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    truth = sorted(out.glob("*_truth.tum"))[0]
    assert tum_stamps(truth)[0] == 0.0
    stats, _ = evo_ape(truth, truth.with_name(truth.name.replace("_truth", "_calibrated")))
    assert stats["rmse"] > 0
    proc = evo_ape(independent, truth, check=False)
    assert proc.returncode != 0
    assert "matching timestamps" in proc.stdout + proc.stderr


# --- the replay's RMSE as the user sees it ------------------------------------------------


def test_replay_reports_the_rmse_per_run_and_its_mean(bagged):
    folder, bag, report, _, _ = bagged
    data = report.to_dict()
    for i, run in enumerate(data["runs"]):
        assert run["rmse_nominal"] == float(report.rmse["nominal"][i])
        assert run["rmse_calibrated"] == float(report.rmse["calibrated"][i])
        assert run["rmse_calibrated"] > 0
    assert data["mean_rmse_nominal"] == pytest.approx(np.mean(report.rmse["nominal"]))
    assert data["mean_rmse_calibrated"] == pytest.approx(np.mean(report.rmse["calibrated"]))
    assert report.mean_rmse == data["mean_rmse_calibrated"]
    assert data["mean_rmse_calibrated"] < data["mean_rmse_nominal"]
    args = ["-b", "0.34", "--wheel-diameter", "0.15", "--truth-topic", "/mocap/pose"]
    proc = run_cli("replay", str(bag), *args, "--params", str(folder / "result.json"))
    assert proc.returncode == 0, proc.stderr
    assert "RMSE [mm]" in proc.stdout
    assert f"{1000 * data['mean_rmse_calibrated']:.1f}" in proc.stdout


def test_a_bad_tum_time(logged):
    folder, _ = logged
    err = api_error(umbmark.replay, folder / "log", tum=folder / "x", tum_time="utc")
    assert err == "tum_time='utc': use recording or run"
    err = api_error(umbmark.calibrate, folder / "log", tum=folder / "x", tum_time="utc")
    assert err == "tum_time='utc': use recording or run"
    assert not (folder / "x").exists()

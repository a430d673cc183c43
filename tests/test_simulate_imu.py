"""``umbmark simulate --bag --imu`` (``jobs/simulate.py``): the IMU's options go with
``--imu`` and ``--bag``, its truth is in the report, and the bag holds its topic and its
mounting on ``/tf_static`` and in ``/robot_description`` (beside the laser's, with
``--scan``)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.sim.imu import ImuSetup

from helpers import api_error, cli_error, run_cli

DEG = math.pi / 180.0
SMALL = {"runs": 2, "side_length": 1.0, "speed": 0.4, "dt": 0.02}


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (["--imu"], "--imu writes an IMU into --bag: give --bag too"),
        (["--bag", "x", "--gyro-bias", "0.1"], "--gyro-bias sets the IMU of --imu: give it too"),
        (["--imu", "--bag", "x", "--imu-roll", "200"],
         "--imu-roll must be -180 to 180 deg, got 200 deg"),
        (["--fleet", "2", "--imu"], "--fleet records an IMU on every robot, each with errors of "
         "its own (truth.json): leave out --imu and its options"),
    ],
)  # fmt: skip
@pytest.mark.slow
def test_the_imus_options_are_refused_where_they_do_nothing(tmp_path, args, line):
    assert cli_error("simulate", *args) == f"umbmark: error: {line}\n"


def test_the_library_says_so_too():
    assert api_error(umbmark.simulate, imu=True) == "imu=True writes an IMU into bag: give bag too"
    assert "imu='yes': give True, False or an ImuSetup" in api_error(
        umbmark.simulate, imu="yes", bag="x"
    )


pytest.importorskip("rosbags")

from umbmark.sources.bag import reader as bag_reader  # noqa: E402
from umbmark.sources.bag.urdf import bag_robot_description, description_text, fixed_joints  # noqa: E402


@pytest.mark.slow
def test_the_imus_truth_and_its_mounting_beside_the_lasers(tmp_path: Path):
    setup = ImuSetup(imu_rate=50.0, gyro_scale=0.98, imu_pitch=-2.0 * DEG, imu_yaw=180.0 * DEG)
    path = tmp_path / "b.bag"
    report = umbmark.simulate(**SMALL, bag=path, imu=setup, scan=True)
    truth = report.to_dict()["imu"]
    assert truth["k_g"] == 0.98
    assert truth["rate"] == 50.0
    assert truth["topic"] == "/imu"
    assert truth["mounting"]["rpy"] == [0.0, -2.0 * DEG, 180.0 * DEG]
    with bag_reader.open_bag(path, str(path)) as reader:
        topics = bag_reader.topic_types(reader)
        assert topics["/imu"] == "sensor_msgs/msg/Imu"
        conns = [c for c in reader.connections if c.topic == "/tf_static"]
        ((_, raw),) = list(bag_reader.messages(reader, conns, "/tf_static", str(path)))
        msg = reader.deserialize(raw, topics["/tf_static"])
        _, text = description_text(reader, topics, str(path))
    children = {tf.child_frame_id: tf.transform.rotation for tf in msg.transforms}
    assert set(children) == {"laser", "imu_link"}
    q = children["imu_link"]
    np.testing.assert_allclose([q.x, q.y, q.z, q.w], truth["mounting"]["quaternion"])
    parent, rotation = fixed_joints(text)["imu_link"]
    assert parent == "base_link"
    # Rz(180) Ry(-2 deg): x backwards and tilted, y to the right, z up and tilted
    c, s = math.cos(2.0 * DEG), math.sin(2.0 * DEG)
    np.testing.assert_allclose(rotation, [[-c, 0, s], [0, -1, 0], [s, 0, c]], atol=1e-12)
    described, _ = bag_robot_description(path)
    assert described is not None
    assert described.wheelbase == pytest.approx(0.34)
    done = run_cli("info", str(path), "--json")
    assert json.loads(done.stdout)["suggested_options"].endswith("--imu-topic /imu")

"""``umbmark fleet --truth-topic``: the reference given is the one every recording is
fitted against, over the one a look into it suggests, and a recording that does not hold
it is left out, the topic and the topics there said (issue 35, item 7)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

import umbmark

from helpers import run_cli

pytest.importorskip("rosbags")

from robot_bags import TB3, drive, two_bodies_bag

#: The TurtleBot3's true E_d, E_b, and those of the other robot its lab's motion capture
#: tracks (on the topic first by name); the closeness of a noiseless fit
#: (``tests/fleets/test_outcome.py``: CLOSE).
MINE, OTHER, CLOSE = (1.004, 0.985), (0.996, 1.02), 1e-4


@pytest.mark.slow
def test_the_truth_topic_given_is_every_recordings_reference(tmp_path: Path):
    """Two robots: ``amr1`` in the motion-capture lab (the look would take the other
    robot's topic), ``robot01`` with a laser and motion capture on another topic. With
    ``--truth-topic /mocap/amr1/pose`` amr1 is fitted to its own truth, and robot01,
    which does not hold that topic, is left out saying so (before, it was calibrated by
    scan matching and the topic never said), listed as a robot with no usable
    recording."""
    lab = tmp_path / "lab"
    (lab / "amr1").mkdir(parents=True)
    two_bodies_bag(lab / "amr1" / "drive", "mcap", drive(TB3, *MINE), drive(TB3, *OTHER))
    umbmark.simulate_fleet(tmp_path / "sim", fleet=1, days=1, minutes=0.5)
    (laser,) = (tmp_path / "sim").glob("robot01/*/drive")
    (lab / "robot01").mkdir()
    shutil.move(laser, lab / "robot01" / "drive")
    proc = run_cli("fleet", str(lab), "--robot-from", "{robot}/*", "--truth-topic",
                   "/mocap/amr1/pose", "--history", str(tmp_path / "h.sqlite3"),
                   "--workers", "1", "--json", timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    by = {r["robot"]: r for r in data["robots"]}
    figures = by["amr1"]["figures"]
    assert (figures["E_d"]["value"], figures["E_b"]["value"]) == pytest.approx(MINE, abs=CLOSE)
    assert by["amr1"]["latest"]["method"] == "trajectory"
    assert data["unusable"] == ["robot01"]
    (left,) = by["robot01"]["left_out"]
    assert left["path"] == str(lab / "robot01" / "drive")
    assert left["reason"].startswith(
        f"{lab / 'robot01' / 'drive'}: no topic /mocap/amr1/pose (ground truth) in the bag; "
        "topics present: /imu (sensor_msgs/msg/Imu), /joint_states (sensor_msgs/msg/JointState), "
        "/mocap/robot/pose "
        "(geometry_msgs/msg/PoseStamped), "
    ), left["reason"]
    assert "1 with no usable recording" in data["summary"]

"""A world reset while the recording pauses (issue 30, item 5).

As in a public recording of four UMBmark squares in a simulator: between squares the
person resets the world, every topic stops for about 2.6 s, the ground truth comes back
at the start (0, 0, 0) while the wheel joints keep their angles (a wheel creeps by
0.14 rad, 5 mm, meanwhile); the controller's ``/odom`` resets with the world or not. The
robot does not rest on either side of the pause. The squares are the package's
simulator's (a TurtleBot3-like robot, E_d = 1.002, E_b = 1.01), the expected runs its
squares, their ends its true ends.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import umbmark
from driven import EVERY, TB3, controller_odometry, squares
from umbmark.model.recording import PoseSeries, Recording, WheelSeries
from umbmark.runs.logged import runs_from_recordings
from umbmark.sim.robot import SimRobot

from helpers import cli_json

pytest.importorskip("rosbags")

from test_bag import JS, LEFT, ODOM, RIGHT, joint_state, ns, pose_msg, write_bag
from test_bag import split as stamp

E_D, E_B = 1.005, 1.03
ROBOT = SimRobot.with_errors(TB3, E_d=E_D, E_b=E_B)
DIRS = ["ccw", "ccw", "cw", "cw"]
PAUSE = 2.8  # [s] between squares; every message in all but its first and last 0.1 s lost
CREEP = 0.14  # [rad] the left wheel turns in the pause, before the reset


@pytest.fixture(scope="module")
def session():
    pauses = [2.0, PAUSE, PAUSE, PAUSE, 2.0]
    return squares(ROBOT, DIRS, side=1.0, pauses=pauses, reset=True, twitch=CREEP)


def _write(path, fmt, session, *, odom_resets: bool):
    """The bag: ``/joint_states``, ``/ground_truth`` and ``/odom`` at 33 Hz, none of them
    inside the pauses between squares but for their first and last 0.1 s."""
    lost = _lost(session)
    odom = controller_odometry(session.angles, TB3)
    if odom_resets:  # the controller's odometry starts again at zero after each reset
        for _, end in lost:
            k = int(np.searchsorted(session.time, end))
            odom[k:] = controller_odometry(session.angles[k:] - session.angles[k], TB3)
    messages = []
    for k in np.arange(0, session.time.size, EVERY):
        t = float(session.time[k])
        if any(a <= t <= b for a, b in lost):
            continue
        sec, nsec = stamp(t)
        messages.append(
            ("/joint_states", ns(t), joint_state(fmt, sec, nsec, [LEFT, RIGHT], session.angles[k]))
        )
        messages.append(("/odom", ns(t + 0.0005), pose_msg(fmt, ODOM, sec, nsec, *odom[k])))
        messages.append(
            ("/ground_truth", ns(t + 0.001), pose_msg(fmt, ODOM, sec, nsec, *session.truth[k]))
        )
    topics = {"/joint_states": JS, "/odom": ODOM, "/ground_truth": ODOM}
    return write_bag(path.parent, fmt, topics, messages, name=path.name)


OPTIONS = [
    "--wheelbase", str(TB3.wheelbase), "--wheel-diameter", str(TB3.wheel_diameter),
    "--side-length", "1", "--truth-topic", "/ground_truth",
    "--left-joint", LEFT, "--right-joint", RIGHT,
]  # fmt: skip


KEYWORDS = {
    "wheelbase": TB3.wheelbase, "wheel_diameter": TB3.wheel_diameter, "side_length": 1.0,
    "truth_topic": "/ground_truth", "left_joint": LEFT, "right_joint": RIGHT,
}  # fmt: skip


def _lost(session):
    """The pauses between squares but for their first and last 0.1 s [s]."""
    pauses = zip(session.stops[:-1], session.starts[1:], strict=True)
    return [(stop + 0.1, start - 0.1) for stop, start in pauses]


@pytest.mark.parametrize("split", ["rests", "none"])
def test_the_recording_in_memory_gives_four_runs(session, split):
    """The same recording without a bag (fast): the four squares are the runs."""
    keep = np.arange(0, session.time.size, EVERY)
    t = session.time[keep]
    keep = keep[~np.any([(a <= t) & (t <= b) for a, b in _lost(session)], axis=0)]
    t, angles, truth = session.time[keep], session.angles[keep], session.truth[keep]
    recording = Recording("world.csv", WheelSeries(t, angles), PoseSeries(t.copy(), truth), TB3)
    loaded = runs_from_recordings([recording], TB3, split=split)
    assert [run.direction.value for run in loaded.runs] == DIRS
    for run, (x, y, theta) in zip(loaded.runs, session.ends, strict=True):
        assert run.true_end.x == pytest.approx(x, abs=1e-3)
        assert run.true_end.y == pytest.approx(y, abs=1e-3)
        assert run.true_end.theta == pytest.approx(theta, abs=1e-3)
    assert not [n for n in loaded.notes if "left out" in n]


@pytest.mark.parametrize(
    ("fmt", "odom_resets", "wheels"),
    [
        ("sqlite3", False, "joints"),
        pytest.param("ros1", True, "joints", marks=pytest.mark.slow),
        ("mcap", True, "odom"),
    ],
)
@pytest.mark.parametrize("split", ["rests", "none"])
def test_a_reset_in_a_pause_of_the_recording_starts_a_new_run(
    tmp_path, session, fmt, odom_resets, wheels, split
):
    """The wheels from the joints (``/odom`` reset with the world or not), or from a
    controller's ``/odom`` that starts again at zero after each reset."""
    # the truth comes back to the start: 4.4, 4.4 and 22.3 cm from where the squares ended
    assert [round(math.hypot(e[0], e[1]), 3) for e in session.ends[:3]] == [0.044, 0.044, 0.223]
    bag = _write(tmp_path / "world", fmt, session, odom_resets=odom_resets)
    keywords = dict(KEYWORDS)
    if wheels == "odom":
        del keywords["left_joint"], keywords["right_joint"]
        keywords["odom_topic"] = "/odom"
    report = umbmark.calibrate(bag, **keywords, split=split, method="exact")
    assert [run.direction.value for run in report.runs] == DIRS
    for run, (x, y, theta) in zip(report.runs, session.ends, strict=True):
        # the truth at 33 Hz: the last sample before the pause is up to 30 ms early
        assert run.true_end.x == pytest.approx(x, abs=1e-3)
        assert run.true_end.y == pytest.approx(y, abs=1e-3)
        assert run.true_end.theta == pytest.approx(theta, abs=1e-3)
    assert not [n for n in report.notes if "left out" in n]
    estimate, se = report.estimate, report.estimate.standard_errors
    assert abs(estimate.E_d - E_D) <= 3 * se["E_d"] + 2e-4, (estimate.E_d, se)
    assert abs(estimate.E_b - E_B) <= 3 * se["E_b"] + 1e-3, (estimate.E_b, se)


@pytest.mark.slow
def test_the_command_finds_the_four_runs(tmp_path, session):
    bag = _write(tmp_path / "world", "mcap", session, odom_resets=True)
    data = cli_json("calibrate", str(bag), *OPTIONS, "--split", "none")
    assert [run["direction"] for run in data["runs"]] == DIRS

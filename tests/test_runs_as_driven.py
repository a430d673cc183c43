"""Runs as a person drove them: put back at the start between squares, wheels creeping and
twitching in the pauses, squares driven back to back.

The recordings come from the package's simulator (a TurtleBot3-like robot, known truth)
or closed-form kinematics, written as real bags and run logs; the expected runs are the
simulator's squares, their ends its true ends, never figures of the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import umbmark
from driven import TB3, squares, write_session_bag
from umbmark.model.recording import PoseSeries, Recording, WheelSeries
from umbmark.runs.logged import runs_from_recordings
from umbmark.runs.segmentation import split_by_rests
from umbmark.sim.robot import SimRobot
from umbmark.sources.runlog.reader import LogMetadata
from umbmark.sources.runlog.writer import write_log_csv, write_metadata

from helpers import cli_json

pytest.importorskip("rosbags")

from test_bag import LEFT, RIGHT, T0

#: Large errors, as a simulated robot driven by timed commands has: the squares end 0.3
#: to 0.5 m from where they started, and the robot is put back.
SLOPPY = SimRobot.with_errors(TB3, E_d=1.005, E_b=1.1)
DIRS = ["cw", "cw", "ccw", "ccw"]
REST = 2.0


@pytest.fixture(scope="module")
def reset_session():
    return squares(SLOPPY, DIRS, side=1.0, rest=REST, reset=True, creep=0.003, twitch=0.2)


def _assert_ends(runs, session, which, within: float = 1e-6) -> None:
    for run, k in zip(runs, which, strict=True):
        x, y, theta = session.ends[k]
        assert run.true_end.x == pytest.approx(x, abs=within)
        assert run.true_end.y == pytest.approx(y, abs=within)
        assert run.true_end.theta == pytest.approx(theta, abs=within)


def test_four_squares_with_the_robot_put_back_between_them_are_four_runs(tmp_path, reset_session):
    session = reset_session
    # the truth jumps 0.34 to 0.52 m at each reset, while the wheels stand still
    assert [round(math.hypot(e[0], e[1]), 2) for e in session.ends] == [0.52, 0.52, 0.34, 0.34]
    bag = write_session_bag(tmp_path / "tb3", "sqlite3", session, wheels="joints")
    report = umbmark.calibrate(
        bag,
        wheelbase=TB3.wheelbase,
        wheel_diameter=TB3.wheel_diameter,
        side_length=1.0,
        truth_topic="/ground_truth",
        left_joint=LEFT,
        right_joint=RIGHT,
        method="exact",
    )
    assert [run.direction.value for run in report.runs] == DIRS
    _assert_ends(report.runs, session, range(4))
    resets = [n for n in report.notes if "reset" in n]
    assert len(resets) == 4  # one in each pause after a square
    for note, stop in zip(resets, session.stops, strict=True):
        # put back in the middle of the pause; the truth at 33 Hz sees it within 30 ms
        at = float(note.split("reset at ", 1)[1].split(" s", 1)[0])
        assert stop + REST / 2 - 0.01 <= at <= stop + REST / 2 + 0.04, note
    assert all("while the wheels stood still): a run ends there" in n for n in resets)
    # The JSON gives each run's start and end on the bag's clock: from the pause before
    # the square (after the robot was put back) to the pause after it.
    runs = report.to_dict()["runs"]
    for k, run in enumerate(runs):
        start, end = run["start_time"] - T0, run["end_time"] - T0
        earliest = 0.0 if k == 0 else session.stops[k - 1] + REST / 2
        assert earliest <= start <= session.starts[k], (k, start)
        assert session.stops[k] - 0.05 <= end <= session.stops[k] + REST / 2, (k, end)


@pytest.mark.parametrize(
    ("creep", "twitch", "rest"), [(0.003, 0.0, REST), (0.0, 0.2, 1.8), (0.003, 0.2, REST)]
)
def test_creep_and_twitches_in_the_pauses_are_rests(creep, twitch, rest):
    # Not put back: each square starts where the last ended, near its start. The wheels
    # jitter by 3 mrad (0.14 rad/s from sample to sample at 33 Hz, over the 0.05 rad/s
    # of a rest) and drift, or the left one twitches by 0.2 rad in 0.15 s in the middle
    # of a 1.8 s pause (leaving two stops shorter than the 1 s of a rest), or both.
    session = squares(
        SimRobot.with_errors(TB3, E_d=1.002, E_b=1.01),
        DIRS,
        side=1.0,
        rest=rest,
        creep=creep,
        twitch=twitch,
    )
    every = slice(None, None, 3)
    time, angles, poses = session.time[every], session.angles[every], session.truth[every]
    runs = split_by_rests(time, angles, poses)
    assert len(runs) == 4
    for (a, b), start, stop in zip(runs, session.starts, session.stops, strict=True):
        assert start - rest <= time[a] <= start
        assert stop - 0.05 <= time[b] <= stop + rest


def _recording(session, every: int = 3) -> Recording:
    t, angles, truth = session.time[::every], session.angles[::every], session.truth[::every]
    return Recording("tb3.csv", WheelSeries(t, angles), PoseSeries(t.copy(), truth), TB3)


def test_two_squares_with_only_a_short_stop_between_are_two_runs():
    # 0.4 s between the two squares: a stop, not a rest (1 s); one run would turn 4 pi.
    session = squares(
        SimRobot.with_errors(TB3, E_d=1.002, E_b=1.01),
        ["cw", "cw", "ccw", "ccw"],
        side=1.0,
        pauses=[REST, 0.4, REST, 0.4, REST],
    )
    loaded = runs_from_recordings([_recording(session)], TB3)
    assert [run.direction.value for run in loaded.runs] == DIRS
    # A square after a short stop starts at the last sample still by the rest speed: the
    # robot, speeding up, has crept 0.05 mm by then.
    _assert_ends(loaded.runs, session, range(4), within=1e-4)


def _circles(turns: float, rest: float = 2.0):
    """Closed form: standing ``rest`` s, driving a circle of radius 0.5 m ``turns`` times
    round at 0.2 m/s with no stop, standing again. Returns time, wheel angles, poses."""
    dt, radius, speed = 0.01, 0.5, 0.2
    omega = speed / radius
    duration = turns * 2 * math.pi / omega
    t = np.arange(0.0, 2 * rest + duration, dt)
    moving = np.clip(t - rest, 0.0, duration)
    heading = omega * moving
    x, y = radius * np.sin(heading), radius * (1 - np.cos(heading))
    wheel = 0.5 * TB3.wheel_diameter
    left = (speed - omega * TB3.wheelbase / 2) * moving / wheel
    right = (speed + omega * TB3.wheelbase / 2) * moving / wheel
    return t, np.column_stack([left, right]), np.column_stack([x, y, heading])


def test_a_loop_closed_twice_without_a_stop_is_refused_by_name():
    t, angles, poses = _circles(2.0)
    recording = Recording("circles.csv", WheelSeries(t, angles), PoseSeries(t.copy(), poses), TB3)
    with pytest.raises(umbmark.InputError) as caught:
        runs_from_recordings([recording], TB3)
    message = str(caught.value)
    # the circle runs from 2.00 s to 2 + 31.42 s
    assert message.startswith("circles.csv: left out the motion from 2.00 to 33.42 s: ")
    assert "it closes its square 2 times (it turns 4.00 pi rad) with no stop near its start" in (
        message
    )
    # once round is one run, as before
    t, angles, poses = _circles(1.0)
    once = Recording("circle.csv", WheelSeries(t, angles), PoseSeries(t.copy(), poses), TB3)
    (run,) = runs_from_recordings([once], TB3).runs
    assert run.true_end.theta == pytest.approx(2 * math.pi, abs=1e-9)


def test_a_window_across_a_reset_is_left_out(reset_session):
    session = reset_session
    recording = _recording(session)
    around = [
        (session.starts[0] - 1.0, session.stops[1] + 0.5),  # squares 1 and 2, a reset
        (session.starts[2] - 0.5, session.stops[2] + 0.5),
        (session.starts[3] - 0.5, session.stops[3] + 0.5),
    ]
    loaded = runs_from_recordings([recording], TB3, split="windows", windows=around)
    assert [run.direction.value for run in loaded.runs] == ["ccw", "ccw"]
    _assert_ends(loaded.runs, session, (2, 3))
    (note,) = [n for n in loaded.notes if "left out" in n]
    at = float(note.split("reset at ", 1)[1].split(" s", 1)[0])
    assert session.stops[0] + REST / 2 <= at <= session.stops[0] + REST / 2 + 0.04
    assert "(it moved 0.52 m and turned 0.68 rad while the wheels stood still)" in note
    assert note.endswith("a run cannot go on across it; split the runs there (--split rests)")


@pytest.mark.slow
def test_a_reset_farther_than_a_corrupt_jump_splits_the_runs(tmp_path):
    # Squares of 2 m, the cw ones ending 1.23 m from their start: their resets jump
    # farther than the 1 m a tracker may not jump between two samples, but while the
    # wheels stand still. Their turns fall 8 degrees short each: 5.49 rad in all, under
    # the 1.75 pi (5.50 rad) that ends a run at a rest; at a reset, that is a square.
    session = squares(SLOPPY, DIRS, side=2.0, rest=REST, reset=True)
    assert [round(math.hypot(e[0], e[1]), 2) for e in session.ends] == [1.23, 1.23, 0.51, 0.51]
    assert [round(abs(e[2]), 2) for e in session.ends] == [5.49, 5.49, 5.94, 5.94]
    folder = tmp_path / "log"
    folder.mkdir()
    write_metadata(
        folder,
        LogMetadata(
            wheel_diameter=TB3.wheel_diameter,
            wheelbase=TB3.wheelbase,
            wheel_data="angles",
            side_length=2.0,
        ),
    )
    write_log_csv(folder / "tb3.csv", session.time + 1000.0, session.truth, session.angles)
    data = cli_json("calibrate", str(folder), "--method", "exact")
    assert [run["direction"] for run in data["runs"]] == DIRS
    for k, run in enumerate(data["runs"]):
        # on the run log's own clock, which starts at 1000 s; the robot's last creep to
        # its stop may be under the rest speed
        start, end = run["start_time"] - 1000.0, run["end_time"] - 1000.0
        assert session.starts[k] - REST <= start <= session.starts[k] + 1e-6
        assert session.stops[k] - 0.05 <= end <= session.stops[k] + REST


@pytest.mark.slow
def test_the_json_gives_each_runs_start_and_end_on_the_recordings_clock(tmp_path):
    session = squares(SimRobot.with_errors(TB3, E_d=1.002, E_b=1.01), DIRS, rest=REST)
    folder = tmp_path / "log"
    folder.mkdir()
    write_metadata(
        folder,
        LogMetadata(
            wheel_diameter=TB3.wheel_diameter,
            wheelbase=TB3.wheelbase,
            wheel_data="angles",
            side_length=1.0,
        ),
    )
    write_log_csv(folder / "tb3.csv", session.time + 500.0, session.truth, session.angles)
    data = cli_json("calibrate", str(folder))
    for k, run in enumerate(data["runs"]):
        # from the pause before the square to the pause after it, on the log's clock
        start, end = run["start_time"] - 500.0, run["end_time"] - 500.0
        assert session.starts[k] - REST <= start <= session.starts[k] + 1e-6
        assert session.stops[k] - 0.05 <= end <= session.stops[k] + REST


@pytest.mark.slow
@pytest.mark.parametrize("pause", [0.3, 0.05])
def test_a_simulators_world_reset_between_squares_splits_them(tmp_path, pause):
    """A simulator's world reset: put back at the start between squares with no rest (a
    0.3 s or 0.05 s pause, shorter than the 1 s of a rest), the truth jumping by the
    return error (8 to 9 cm), under the 0.1 m a stop's reset needs. Before: one run of
    four squares (their turns cancel: cw, cw, ccw, ccw). Now the jumps, which the wheels
    standing still cannot explain, end the runs."""
    robot = SimRobot.with_errors(TB3, E_d=1.002, E_b=1.01)
    pauses = [REST, pause, pause, pause, REST]
    session = squares(robot, ["cw", "cw", "ccw", "ccw"], side=1.0, pauses=pauses, reset=True)
    jumps = [math.hypot(e[0], e[1]) for e in session.ends]
    assert 0.07 < jumps[0] < 0.09  # the resets after the cw squares
    assert 0.07 < jumps[1] < 0.09
    bag = write_session_bag(tmp_path / "tb3", "mcap", session, wheels="joints")
    report = umbmark.calibrate(
        bag, wheelbase=TB3.wheelbase, wheel_diameter=TB3.wheel_diameter, side_length=1.0,
        truth_topic="/ground_truth", left_joint=LEFT, right_joint=RIGHT, method="exact",
    )  # fmt: skip
    assert [run.direction.value for run in report.runs] == DIRS
    # the third square's end: 0.05 s before an 8 mm reset the 33 Hz truth half sees
    _assert_ends(report.runs, session, range(4), within=1e-6 if pause > 0.1 else 1e-4)
    resets = [n for n in report.notes if "reset at" in n]
    assert len(resets) == 2  # the third jump, 8 mm, is under MIN_JUMP: a stop ends that run
    for note, stop, jump in zip(resets, session.stops[:2], jumps[:2], strict=True):
        at = float(note.split("reset at ", 1)[1].split(" s", 1)[0])
        assert stop <= at <= stop + pause + 0.04, note
        assert f"(it jumped {jump:.3f} m in " in note
        assert note.endswith("where the wheels allow 0.000 m): a run ends there")
    # the simulated robot's errors come back (noise-free: quantization only)
    assert report.estimate.E_d == pytest.approx(1.002, abs=1e-4)
    assert report.estimate.E_b == pytest.approx(1.01, abs=1e-3)


def test_a_jump_while_the_wheels_turn_is_a_reset():
    """Closed form: driving straight at 0.2 m/s, the truth put back 0.3 m between two
    samples at 5 s; the wheels allow 2 x 4 mm there. A tracker's millimetre of noise,
    AMCL-like 2 cm corrections every half second, and a tracker that jumps aside and back
    are no resets."""
    from umbmark.runs.rests import find_resets

    dt, speed, wheel = 0.01, 0.2, 0.5 * TB3.wheel_diameter
    t = np.arange(0.0, 10.0, dt)
    angles = np.column_stack([speed * t / wheel, speed * t / wheel])
    x = speed * t - 0.3 * (t >= 5.0)
    rng = np.random.default_rng(3)
    poses = np.column_stack([x + rng.normal(0, 1e-3, t.size), 0 * t, 0 * t])
    (reset,) = find_resets(t, angles, poses, 0.05, wheel)
    assert t[reset.at] == pytest.approx(5.0)
    assert reset.allowed == pytest.approx(2 * 2 * speed * dt, rel=1e-6)
    assert reset.describe(t).startswith("the ground truth was reset at 5.00 s (it jumped 0.29")
    assert find_resets(t, angles, poses, 0.05) == []  # without the wheel radius: stops only
    amcl = np.column_stack([speed * t + 0.02 * np.floor(t / 0.5) % 2, 0 * t, 0 * t])
    assert find_resets(t, angles, amcl, 0.05, wheel) == []
    # a tracker on a reflection 0.6 m aside from 3 to 4 s, and back: no reset
    lost = poses.copy()
    lost[(t >= 3.0) & (t < 4.0), 1] += 0.6
    assert [t[r.at] for r in find_resets(t, angles, lost, 0.05, wheel)] == [pytest.approx(5.0)]

"""Logged runs: splitting recordings, run logs, start frames, replay.

Recordings come from the closed-loop simulator, whose truth is known; expected values are
the simulator's own run results or hand-derived quantities, never the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.errors import InputError
from umbmark.kinematics import WheelParams
from umbmark.outputs.runlog import write_log_csv, write_metadata
from umbmark.recording import PoseSeries, Recording, WheelSeries
from umbmark.runs import end_errors
from umbmark.sim.robot import VirtualRobot
from umbmark.sources.logged import runs_from_recordings, to_start_frame
from umbmark.sources.runlog import LogMetadata, read_runlog
from umbmark.sources.segmentation import split_by_rests, split_by_windows

from helpers import simulated_session

ODO = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
ROBOT = VirtualRobot.with_errors(ODO, E_d=1.002, E_b=1.01)
DIRS = ["cw", "cw", "ccw", "ccw"]


@pytest.fixture(scope="module")
def session():
    return simulated_session(ROBOT, DIRS, side=1.0, rest=3.0)


def _recording(session, name="session.csv") -> Recording:
    t, counts, poses, _ = session
    return Recording(
        name=name,
        wheels=WheelSeries(t, counts * ODO.radians_per_pulse),
        truth=PoseSeries(t.copy(), poses.copy()),
        params=ODO,
    )


def test_rests_near_the_start_split_the_runs(session):
    t, counts, poses, _ = session
    segments = split_by_rests(t, counts * ODO.radians_per_pulse, poses)
    assert len(segments) == 4
    # Each run: 4 legs of 1 m at up to 0.2 m/s and 4 turns, about 28.5 s, bracketed by
    # the 3 s rests (no corner stop is taken for the end of a run).
    durations = [t[b] - t[a] for a, b in segments]
    assert all(25 < d < 32 for d in durations)
    assert all(segments[k][1] < segments[k + 1][0] for k in range(3))


def test_runs_from_a_recording_match_the_simulator(session):
    loaded = runs_from_recordings([_recording(session)], ODO)
    _, _, _, ends = session
    assert [r.direction.value for r in loaded.runs] == DIRS
    for run, (x, y, _) in zip(loaded.runs, ends, strict=True):
        # True end in the run's start frame, as the simulator had it.
        assert run.true_end.x == pytest.approx(x, abs=1e-9)
        assert run.true_end.y == pytest.approx(y, abs=1e-9)
        # The odometry believes it came home (to within the stop tolerance).
        assert math.hypot(run.odometry_end.x, run.odometry_end.y) < 2e-4
    assert loaded.associations[0][1].matched == loaded.associations[0][1].total


def test_windows_cut_runs_by_time(session):
    t = session[0]
    assert split_by_windows(t, [(3.0, 10.0)]) == [(300, 1000)]
    with pytest.raises(InputError, match="time window 5:2 s is empty"):
        split_by_windows(t, [(5.0, 2.0)], "x.csv")
    with pytest.raises(InputError, match="holds 0 wheel sample"):
        split_by_windows(t, [(500.0, 600.0)], "x.csv")


def test_start_frame_puts_the_first_pose_at_the_origin_facing_x():
    poses = np.array([[1.0, 2.0, math.pi / 2], [1.0, 3.0, math.pi / 2], [0.0, 3.0, math.pi]])
    np.testing.assert_allclose(
        to_start_frame(poses), [[0, 0, 0], [1, 0, 0], [1, 1, math.pi / 2]], atol=1e-12
    )


def test_run_log_round_trip_and_calibration(tmp_path, session):
    t, counts, poses, _ = session
    write_metadata(
        tmp_path,
        LogMetadata(
            wheel_diameter=0.15,
            wheelbase=0.34,
            encoder_resolution=2000,
            gear_ratio=20,
            side_length=1.0,
        ),
    )
    write_log_csv(tmp_path / "session.csv", t, poses, counts)
    recordings, meta = read_runlog(tmp_path)
    assert meta.side_length == 1.0
    assert len(recordings) == 1
    loaded = runs_from_recordings(recordings, meta.params)
    direct = runs_from_recordings([_recording(session)], ODO)
    assert len(loaded.runs) == 4
    for a, b in zip(loaded.runs, direct.runs, strict=True):
        # The CSV keeps micrometres and whole counts.
        assert a.true_end.x == pytest.approx(b.true_end.x, abs=2e-6)
        assert a.odometry_end.y == pytest.approx(b.odometry_end.y, abs=1e-9)


def test_ground_truth_and_wheels_on_separate_rows(tmp_path):
    # Wheels at 50 Hz, ground truth at 20 Hz on rows of their own: a straight 1 m at 0.5 m/s.
    write_metadata(tmp_path, LogMetadata(wheel_diameter=0.1, wheelbase=0.3, wheel_data="angles"))
    lines = ["time,x,y,theta,left,right"]
    for k in range(101):
        t = k * 0.02
        lines.append(f"{t:.3f},,,,{t * 10:.6f},{t * 10:.6f}")  # 10 rad/s x 0.05 m = 0.5 m/s
    for k in range(41):
        t = k * 0.05 + 0.001
        lines.append(f"{t:.3f},{0.5 * t:.6f},0,0,,")
    lines = [lines[0], *sorted(lines[1:], key=lambda r: float(r.split(",")[0]))]
    (tmp_path / "line.csv").write_text("\n".join(lines) + "\n")
    (recording,), meta = read_runlog(tmp_path / "line.csv")
    loaded = runs_from_recordings([recording], meta.params, split="none")
    (run,) = loaded.runs
    assoc = loaded.associations[0][1]
    assert assoc.total == 101
    assert assoc.matched == 100  # the first wheel sample precedes the first ground truth
    # From the first matched sample (t = 0.02) to the last (t = 2.0): 0.99 m both ways.
    assert run.true_end.x == pytest.approx(0.99, abs=1e-6)
    assert run.odometry_end.x == pytest.approx(0.99, abs=1e-9)


def test_replay_with_the_true_parameters_removes_the_systematic_error(session):
    loaded = runs_from_recordings([_recording(session)], ODO)
    truth = ODO.with_corrections(
        c_left=ROBOT.diameter_left / 0.15,
        c_right=ROBOT.diameter_right / 0.15,
        wheelbase=ROBOT.wheelbase,
    )
    before = end_errors(loaded.runs)
    after = end_errors([run.reintegrated(truth) for run in loaded.runs])
    assert before.min() > 0.02
    assert after.max() < 2e-4  # what is left is encoder quantization and stop tolerance


def test_recording_without_ground_truth_is_refused():
    t = np.linspace(0, 1, 11)
    rec = Recording("odo.csv", WheelSeries(t, np.column_stack([t, t])))
    with pytest.raises(InputError, match=r"odo\.csv: has no ground truth"):
        runs_from_recordings([rec], ODO)

"""Logged runs: splitting recordings, run logs, start frames, replay.

Recordings come from the closed-loop simulator, whose truth is known; expected values are
the simulator's own run results or hand-derived quantities, never the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.core.geometry import to_start_frame
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import PoseSeries, Recording, WheelSeries
from umbmark.model.run import end_errors
from umbmark.runs.logged import runs_from_recordings
from umbmark.runs.segmentation import split_by_rests, split_by_windows
from umbmark.sim.robot import SimRobot
from umbmark.sources.runlog.reader import LogMetadata, read_runlog
from umbmark.sources.runlog.writer import write_log_csv, write_metadata

from helpers import simulated_session

ODO = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
ROBOT = SimRobot.with_errors(ODO, E_d=1.002, E_b=1.01)
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


# --- parameters from a source's metadata: bounds and provenance in messages ---------------


@pytest.fixture(scope="module")
def log_folder(tmp_path_factory):
    """A run log of a virtual robot: 2 + 2 runs on a 4 m square, b = 0.34 m."""
    import umbmark

    folder = tmp_path_factory.mktemp("log") / "log"
    umbmark.simulate(E_d=1.002, E_b=1.01, runs=2, dt=0.02, logs=folder)
    return folder


def _edited_log(log_folder, tmp_path, old, new):
    import shutil

    folder = tmp_path / "log"
    shutil.copytree(log_folder, folder)
    meta = folder / "metadata.yaml"
    text = meta.read_text()
    assert old in text
    meta.write_text(text.replace(old, new))
    return folder, meta


@pytest.mark.parametrize(
    ("old", "new", "message", "option"),
    [
        ("c_right: 1.0\n", "c_right: 1.0e-300\n",
         "c_right 1e-300 is not a plausible factor: it must be within 0.2 to 5",
         {"current_c_r": 1e-300}),
        ("wheel_separation_multiplier: 1.0\n", "wheel_separation_multiplier: 1.0e+300\n",
         "wheel_separation_multiplier 1e+300 is not a plausible factor: it must be within 0.2 to 5",
         {"current_separation_multiplier": 1e300}),
        ("side_length: 4.0\n", "side_length: 1.0e+308\n",
         "side_length 1e+308 m is implausibly large: lengths are in metres (at most 100 m here",
         {"side_length": 1e308}),
        ("side_length: 4.0\n", "side_length: 500.0\n",
         "side_length 500 m is implausibly large", {"side_length": 500.0}),
        ("wheelbase: 0.34\n", "wheelbase: 1.0e-300\n",
         "wheelbase 1e-300 m is implausibly small", {"wheelbase": 1e-300}),
        ("wheel_diameter: 0.15\n", "wheel_diameter: 340.0\n",
         "wheel_diameter 340 m is implausibly large", {"wheel_diameter": 340.0}),
        ("encoder_resolution: 2000.0\n", "encoder_resolution: 1.0e-300\n",
         "encoder_resolution must be 1 to 1e+07, got 1e-300", None),
        ("gear_ratio: 20.0\n", "gear_ratio: 1.0e+300\n",
         "gear_ratio must be 0.001 to 10000, got 1e+300", None),
    ],
)  # fmt: skip
def test_metadata_gets_the_bounds_of_the_options(log_folder, tmp_path, old, new, message, option):
    # Before: c_R = 1e-300 was taken with a warning, a side of 1e308 ended in NaN. Now the
    # metadata's values are refused as the option giving the same value is, naming the
    # file and the field; the bound is the option's (its message says the same range).
    import umbmark

    from helpers import api_error

    folder, meta = _edited_log(log_folder, tmp_path, old, new)
    line = api_error(umbmark.calibrate, folder)
    assert line.startswith(f"{meta}: {message}")
    if option is not None:
        keyword = next(iter(option))
        said = api_error(umbmark.calibrate, log_folder, **option)
        assert said.startswith(f"{keyword}=")
        # The same bound: the lines differ only in the file and the name before the value.
        assert said.split("=", 1)[1] == line.removeprefix(f"{meta}: ").split(" ", 1)[1]


def test_a_wheelbase_from_the_metadata_is_named_by_file_and_field(log_folder, tmp_path):
    # The metadata's wheelbase (2.5 m) is not below half its side (4 m): the refusal names
    # the file and both fields, not --wheelbase, which was not given.
    import umbmark

    from helpers import api_error

    folder, meta = _edited_log(log_folder, tmp_path, "wheelbase: 0.34\n", "wheelbase: 2.5\n")
    message = api_error(umbmark.calibrate, folder)
    assert message.startswith(f"{meta}: the odometry's wheelbase 2.5 m (wheelbase) is not ")
    assert "(side_length 4 m, so b < 2 m)" in message
    assert "--wheelbase" not in message
    # With the side given: the option is named, the wheelbase still by its file.
    # (4.3 m: within a tenth of the 4 m legs the reference measures, not refused for it)
    message = api_error(umbmark.calibrate, folder, side_length=4.3)
    assert message.startswith(f"{meta}: the odometry's wheelbase 2.5 m (wheelbase)")
    assert "(side_length=4.3 m, so b < 2.15 m)" in message
    assert "--wheelbase" not in message


def test_optiodom_parameters_and_runs_are_named_by_their_files(tmp_path):
    # The bundled real session (L = 0.75 m, Li = 0.2 m) with Li set to 2 m: the refusal
    # names the metadata file and Li; with one run's ground truth frozen, the refusal names
    # that run's file inside the session folder, not only "run-02".
    import shutil

    import umbmark

    from helpers import api_error

    sessions = umbmark.example_sessions(tmp_path / "real")
    session = next(p for p in sessions if p.parent.name == "square")
    meta = next(session.glob("*_metadata.csv"))
    text = meta.read_text()
    meta.write_text(text.replace("\nLi,0.2,", "\nLi,2.0,"))
    message = api_error(umbmark.calibrate, session)
    assert message.startswith(f"{meta}: the odometry's wheelbase 2 m (Li) is not smaller")
    assert "(L 0.75 m, so b < 0.375 m)" in message
    assert "--wheelbase" not in message
    meta.write_text(text.replace("\nLi,0.2,", "\nLi,1.0e-9,"))
    assert api_error(umbmark.calibrate, session) == (
        f"{meta}: Li 1e-09 m is implausibly small: lengths are in metres (plausible: 0.001 to 10 m)"
    )
    meta.write_text(text)
    run = next(session.glob("*_run-02.csv"))
    rows = [line.split(",") for line in run.read_text(encoding="utf-8-sig").splitlines()]
    run.write_text("\n".join(",".join([r[0], "0", "0", "0", *r[4:]]) for r in rows) + "\n")
    message = api_error(umbmark.calibrate, session)
    assert message.startswith(f"{run}: the ground truth never moves")
    shutil.rmtree(session)


@pytest.mark.parametrize("session", ["square/230620202042", "circular/250620202104"])
def test_motion_capture_is_no_reproduced_odometry(session):
    """The bundled OptiOdom sessions (OptiTrack): the best-fitting wheel odometry follows
    their heading to 4e-4 to 1e-3 rad per radian turned, five orders of magnitude above
    rounding; they are read, never refused as the odometry itself."""
    from importlib.resources import files

    from umbmark.runs.load import LoadOptions, load_runs
    from umbmark.runs.reproduced import EXACT, reproduction

    folder = files("umbmark.data") / "optiodom" / session
    loaded = load_runs(str(folder), "optiodom", LoadOptions())
    assert len(loaded.runs) == 6
    params = loaded.params
    assert params is not None
    for run in loaded.runs:
        assert run.log is not None
        times = run.log.start + run.log.time  # the session's truth shares the wheels' stamps
        found = reproduction([run.log], times, params)
        assert found is not None
        assert found.heading_rms > 1e4 * EXACT * found.turned
        assert not found.exact


def test_a_fit_with_negative_radii_is_no_robots_odometry():
    """A reference matched exactly by a degenerate fit (radii of opposite signs, a negative
    wheelbase: what a selfcal run log's few shared samples once gave, 10.9 and -18.8 mm,
    -260 mm) is no controller's odometry and is not refused; the same residuals with a
    robot's geometry are."""
    from umbmark.runs.reproduced import Reproduction

    exact = {"heading_rms": 3e-15, "position_rms": 6e-6, "turned": 6.5, "driven": 0.2}
    degenerate = Reproduction(**exact, r_left=0.010877, r_right=-0.018795, wheelbase=-0.26,
                              samples=40)  # fmt: skip
    lopsided = Reproduction(**exact, r_left=0.03, r_right=0.075, wheelbase=0.34, samples=40)
    robot = Reproduction(**exact, r_left=0.075, r_right=0.0751, wheelbase=0.34, samples=40)
    assert not degenerate.physical
    assert not degenerate.exact
    assert not lopsided.exact  # radii 2.5 times apart: no controller's wheels
    assert robot.physical
    assert robot.exact

"""A gap in the messages is a gap, not a jump.

Public bags of simulated robots drop the controller's ``/odom`` for a second or two while
the robot drives on: the wheel angles recovered from it then step by the whole way driven
meanwhile. Such a gap is bridged when the wheels turned steadily across it, or leaves its
run out with a note; it never makes the whole recording unreadable. Time windows apply
before any check. Expected figures come from the simulator and from the messages the test
wrote, never from the code under test.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import umbmark
from driven import EVERY, TB3, controller_odometry, squares, write_session_bag
from umbmark.model.kinematics import OdometryGeometry
from umbmark.runs.load import LoadOptions, load_runs
from umbmark.runs.logged import check_motion
from umbmark.sim.robot import SimRobot
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.runlog.reader import LogMetadata
from umbmark.sources.runlog.writer import write_log_csv, write_metadata

pytest.importorskip("rosbags")

from test_bag import T0

ROBOT = SimRobot.with_errors(TB3, E_d=1.002, E_b=1.01)
DIRS = ["cw", "cw", "ccw", "ccw", "ccw"]
GAP = 1.76  # [s] of /odom messages dropped, as in the bag that asked for this


@pytest.fixture(scope="module")
def session():
    return squares(ROBOT, DIRS, side=2.0, rest=2.0)


def _speeds(session):
    """Wheel speeds [rad/s], shape (n - 1, 2), and the interval start times."""
    return np.diff(session.angles, axis=0) / np.diff(session.time)[:, None], session.time[:-1]


def _cruise(session, square: int, length: float) -> float:
    """The start [s] of the first stretch of ``square`` at least ``length`` s long where
    both wheels turn forward at the cruise speed (a straight leg)."""
    speed, t = _speeds(session)
    top = 0.35 / (0.5 * TB3.wheel_diameter)  # the cruise speed [rad/s]
    inside = (t >= session.starts[square]) & (t < session.stops[square])
    steady = inside & np.all(np.abs(speed - top) < 0.03 * top, axis=1)  # counts: 1.5 %
    edges = np.flatnonzero(np.diff(np.concatenate([[0], steady.astype(int), [0]])))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if t[b - 1] - t[a] >= length:
            return float(t[a])
    raise AssertionError("no straight leg that long")


def _turn(session, square: int) -> float:
    """When the first spot turn of ``square`` starts [s]."""
    speed, t = _speeds(session)
    inside = (t >= session.starts[square]) & (t < session.stops[square])
    turning = inside & (speed[:, 0] * speed[:, 1] < 0) & (np.abs(speed[:, 0]) > 0.5)
    return float(t[np.argmax(turning)])


def _gap_seen(session, start: float, end: float) -> tuple[float, float, float]:
    """The gap a reader sees when no message is written from ``start`` to ``end`` [s]:
    its start, length [s], and the wheels' mean travel [m] across it as the odometry
    tells it: one arc from the pose before the gap, as long as the displacement along the
    mid-gap heading, turning as the headings do (the controller's update, inverted)."""
    kept = session.time[::EVERY]
    before = kept[kept < start][-1]
    after = kept[kept > end][0]
    k0, k1 = (int(np.flatnonzero(session.time == v)[0]) for v in (before, after))
    odom = controller_odometry(session.angles, TB3)
    (x0, y0, h0), (x1, y1, h1) = odom[k0], odom[k1]
    turn = h1 - h0
    along = (x1 - x0) * math.cos(h0 + turn / 2) + (y1 - y0) * math.sin(h0 + turn / 2)
    arc = along if abs(turn) < 1e-12 else along * (turn / 2) / math.sin(turn / 2)
    sides = (arc - TB3.wheelbase * turn / 2, arc + TB3.wheelbase * turn / 2)
    return before, after - before, 0.5 * (abs(sides[0]) + abs(sides[1]))


def _calibrate(bag: Path, **options: object) -> umbmark.CalibrationReport:
    return umbmark.calibrate(
        bag,
        wheelbase=TB3.wheelbase,
        wheel_diameter=TB3.wheel_diameter,
        side_length=2.0,
        odom_topic="/odom",
        truth_topic="/ground_truth",
        **options,
    )


def test_a_gap_between_samples_is_no_wheel_jump():
    # 0.35 m/s on 33 mm wheels (10.6 rad/s), sampled at 30 Hz, nothing for 1.76 s:
    # 18.7 rad in one step, at the speed of every other step.
    time = np.arange(0.0, 20.0, 1.0 / 30.0)
    time = time[(time < 8.0) | (time > 8.0 + GAP)]
    angles = np.column_stack([time * 10.6, time * 10.6])
    truth = np.column_stack([time * 0.35, 0 * time, 0 * time])
    check_motion("drive.bag", time, angles, truth)
    # One corrupt sample among steady ones is still refused, as before.
    angles[300:, 0] += 20.0
    with pytest.raises(umbmark.InputError, match=r"left wheel jumps by 20\.\d+ rad in one"):
        check_motion("drive.bag", time, angles, truth)


@pytest.mark.parametrize("fmt", [pytest.param("ros1", marks=pytest.mark.slow), "mcap"])
def test_dropped_odom_is_bridged_on_a_straight_and_leaves_a_turning_run_out(tmp_path, session, fmt):
    straight = _cruise(session, 1, GAP + 1.5) + 0.6  # in square 2, at cruise speed
    turning = _turn(session, 2) - 0.5  # square 3: stopping, then turning
    drops = [(straight, straight + GAP), (turning, turning + GAP)]
    bag = write_session_bag(tmp_path / "tb3", fmt, session, drop=drops)
    report = _calibrate(bag)

    assert [run.direction.value for run in report.runs] == ["cw", "cw", "ccw", "ccw"]
    for run, k in zip(report.runs, (0, 1, 3, 4), strict=True):
        x, y, _ = session.ends[k]
        assert run.true_end.x == pytest.approx(x, abs=1e-6)
        assert run.true_end.y == pytest.approx(y, abs=1e-6)
        # the robot's own odometry came home; across the bridged gap too
        assert math.hypot(run.odometry_end.x, run.odometry_end.y) < 1e-3
    (bridged,) = [n for n in report.notes if "bridged" in n]
    at, length, travel = _gap_seen(session, *drops[0])
    assert bridged == (
        f"{bag.name} run 2: no /odom message for {length:.2f} s from {at:.2f} s (the wheels "
        f"moved {travel:.2f} m meanwhile): bridged, the wheels turned across it at the "
        "speeds they had before and after it"
    )
    assert 0.6 < travel < 0.65  # 0.35 m/s for 1.76 to 1.82 s
    (left,) = [n for n in report.warnings if "left out" in n]
    at, length, travel = _gap_seen(session, *drops[1])
    assert left.startswith(f"{bag.name}: left out the motion from ")
    assert (
        f"s: no /odom message for {length:.2f} s from {at:.2f} s (the wheels moved "
        f"{travel:.2f} m meanwhile): the wheels changed speed (before, across, after it: "
    ) in left
    assert left.endswith("rad/s): the path across it is unknown")
    # the run left out is square 3, from the pause before it to the pause after it
    start, end = (float(v) for v in left.split("from ", 1)[1].split(" s:", 1)[0].split(" to "))
    assert session.starts[2] - 2.0 <= start <= session.starts[2]
    assert session.stops[2] <= end <= session.stops[2] + 2.0


@pytest.mark.slow
def test_windows_leave_a_gap_out_before_any_check(tmp_path, session):
    turning = _turn(session, 2) - 0.5
    bag = write_session_bag(tmp_path / "tb3", "sqlite3", session, drop=[(turning, turning + 4)])
    # The 4 s gap in square 3 would leave it out; windows around the others need no note.
    windows = [(session.starts[k] - 1.0, session.stops[k] + 1.0) for k in (0, 1, 3, 4)]
    report = _calibrate(bag, windows=windows)
    assert [run.label for run in report.runs] == [f"{bag.name} run {k}" for k in (1, 2, 3, 4)]
    assert not [n for n in (*report.notes, *report.warnings) if "gap" in n or "message" in n]
    for run, k in zip(report.runs, (0, 1, 3, 4), strict=True):
        assert run.true_end.x == pytest.approx(session.ends[k][0], abs=1e-6)
        assert run.true_end.y == pytest.approx(session.ends[k][1], abs=1e-6)


@pytest.mark.slow
def test_one_run_broken_by_a_gap_is_refused_with_what_was_seen(tmp_path, session):
    turning = _turn(session, 2) - 0.5
    bag = write_session_bag(tmp_path / "tb3", "sqlite3", session, drop=[(turning, turning + 4)])
    window = [(session.starts[2] - 1.0, session.stops[2] + 1.0)]
    with pytest.raises(umbmark.InputError) as caught:
        _calibrate(bag, windows=window)
    message = str(caught.value)
    at, length, travel = _gap_seen(session, turning, turning + 4)
    assert message.startswith(f"{bag.name}: left out the motion from ")
    assert (
        f"no /odom message for {length:.2f} s from {at:.2f} s (the wheels moved {travel:.2f} "
        "m meanwhile): longer than 2 s while the wheels turned; no run is left"
    ) in message


def _log(folder: Path, session, offset: float = 0.0) -> Path:
    """``session`` as a run log: wheel angles [rad], ground truth, the clock from
    ``offset`` [s]."""
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
    write_log_csv(folder / "tb3.csv", session.time + offset, session.truth, session.angles)
    return folder


def test_windows_leave_a_corrupt_stretch_out(tmp_path, session):
    angles = session.angles.copy()
    k = int(np.searchsorted(session.time, _turn(session, 2)))
    angles[k : k + 5, 0] += 40.0  # five corrupt samples in square 3: 40 rad in 10 ms
    truth = session.truth.copy()
    truth[np.searchsorted(session.time, session.starts[2] + 3.0), 0] = 1000.0  # a cell in mm
    folder = _log(tmp_path / "log", replace(session, angles=angles, truth=truth))
    with pytest.raises(umbmark.InputError) as caught:
        umbmark.calibrate(folder)
    whole = str(caught.value)
    assert "tb3.csv: the left wheel jumps by 40.0" in whole
    assert "rad in one sample at " in whole
    windows = [(session.starts[k] - 1.0, session.stops[k] + 1.0) for k in (0, 1, 3, 4)]
    report = umbmark.calibrate(folder, windows=windows)
    assert [run.direction.value for run in report.runs] == ["cw", "cw", "ccw", "ccw"]
    for run, k in zip(report.runs, (0, 1, 3, 4), strict=True):
        assert run.true_end.x == pytest.approx(session.ends[k][0], abs=2e-6)
        assert run.true_end.y == pytest.approx(session.ends[k][1], abs=2e-6)


@pytest.mark.slow
def test_a_gap_in_odom_is_no_sign_of_a_filtered_odometry(tmp_path):
    # Two squares of 8 m; 4 s without /odom from the end of a leg through a corner turn.
    # One arc across the gap cannot follow the corner: 0.49 m sideways, 31 mm per metre
    # driven over the recording, more than a filtered odometry's 20 mm/m; but it is one
    # gap, and the run it breaks is left out, not the recording.
    pair = squares(ROBOT, ["cw", "ccw"], side=2.0, rest=2.0)
    turning = _turn(pair, 1) - 0.5
    bag = write_session_bag(tmp_path / "tb3", "sqlite3", pair, drop=[(turning, turning + 4)])
    odom = BagOptions(
        odom_topic="/odom",
        odom_geometry=OdometryGeometry(0.033, 0.033, TB3.wheelbase),
        truth_topic="/ground_truth",
    )
    loaded = load_runs(bag, "bag", LoadOptions(params=TB3, bag=odom))
    (run,) = loaded.runs
    assert run.direction.value == "cw"
    assert run.true_end.x == pytest.approx(pair.ends[0][0], abs=1e-6)
    (left,) = [n for n in loaded.notes if "left out" in n]
    assert "no /odom message for 4.05 s from " in left


@pytest.mark.slow
def test_a_recorders_hiccup_while_the_robot_speeds_up_is_bridged(tmp_path, session):
    # A quarter second without /joint_states as the robot sets off on a leg, and as it
    # starts a spot turn: the speeds change across it, but the robot barely turns while
    # it drives (and barely drives while it turns), so one arc is the path. No run is
    # lost, as none was before.
    drops = [
        (session.starts[1] - 0.05, session.starts[1] + 0.2),
        (_turn(session, 2) - 0.05, _turn(session, 2) + 0.2),
    ]
    bag = write_session_bag(tmp_path / "tb3", "mcap", session, wheels="joints", drop=drops)
    report = umbmark.calibrate(
        bag,
        wheelbase=TB3.wheelbase,
        wheel_diameter=TB3.wheel_diameter,
        side_length=2.0,
        truth_topic="/ground_truth",
        left_joint="left_wheel_joint",
        right_joint="right_wheel_joint",
    )
    assert [run.direction.value for run in report.runs] == DIRS
    for run, (x, y, _) in zip(report.runs, session.ends, strict=True):
        assert run.true_end.x == pytest.approx(x, abs=1e-6)
        assert run.true_end.y == pytest.approx(y, abs=1e-6)
        assert math.hypot(run.odometry_end.x, run.odometry_end.y) < 1e-3
    bridged = [n for n in report.notes if "bridged" in n]
    assert len(bridged) == 2
    for note, run, drop in zip(bridged, (2, 3), drops, strict=True):
        at, length, _ = _gap_seen(session, *drop)
        assert note.startswith(
            f"{bag.name} run {run}: no /joint_states message for {length:.2f} s from {at:.2f} s"
        )
        assert "bridged, one arc across it ends at most 0." in note  # a tenth of a mm
        assert note.endswith(" mm from any path of its length and turn")


def _wander(rest: float = 2.0):
    """A drive that is no loop, as a person drives a robot about a room: four legs with
    turns of +90, -120 and +60 degrees between them (30 degrees net), standing ``rest`` s
    before and after; from the simulator, as a :class:`driven.Session` of one path."""
    from driven import CONTROL, Session
    from umbmark.core.conventions import Direction
    from umbmark.sim.engine import simulate
    from umbmark.sim.paths import Path as SimPath
    from umbmark.sim.paths import Segment

    legs = [Segment("straight", 2.0), Segment("turn", math.pi / 2)]
    legs += [Segment("straight", 1.5), Segment("turn", -2 * math.pi / 3)]
    legs += [Segment("straight", 2.0), Segment("turn", math.pi / 3), Segment("straight", 1.0)]
    result = simulate(
        ROBOT, SimPath("wander", tuple(legs)), [Direction.CCW], CONTROL,
        np.random.default_rng(0), record=True,
    )  # fmt: skip
    trace = result.trace
    dt = float(trace.time[1] - trace.time[0])
    n = int(result.samples_used[0]) + 1
    still = round(rest / dt)
    angles = trace.counts[0, :n] * ROBOT.odometry.radians_per_pulse
    angles = np.vstack([np.repeat(angles[:1], still, 0), angles, np.repeat(angles[-1:], still, 0)])
    truth = trace.true_pose[0, :n]
    truth = np.vstack([np.repeat(truth[:1], still, 0), truth, np.repeat(truth[-1:], still, 0)])
    time = dt * np.arange(angles.shape[0])
    start, stop = still * dt, (still + n - 1) * dt
    return Session(time, angles, truth, [tuple(truth[-1])], [start], [stop])


def test_a_gap_in_a_drive_of_any_shape_splits_it_into_two_runs(tmp_path):
    # No loop to tell runs apart: the drive is one run of its motion. 1.76 s without /odom
    # from half a second before the second turn, as the robot stops and turns: the path
    # across is unknown. Before: "left out the motion from 2.00 to ... s ...; no run is
    # left". Now the drive is split there, and each side is a run.
    drive = _wander()
    turning = _turn(drive, 0) - 0.5
    assert _turn(drive, 0) < turning + GAP  # the first turn starts inside it
    bag = write_session_bag(tmp_path / "tb3", "mcap", drive, drop=[(turning, turning + GAP)])
    report = _calibrate(bag, method="trajectory")
    assert [run.label for run in report.runs] == [f"{bag.name} run 1", f"{bag.name} run 2"]
    at, length, travel = _gap_seen(drive, turning, turning + GAP)
    (note,) = [n for n in report.notes if "split at the gap" in n]
    assert note.startswith(
        f"{bag.name}: split at the gap: no /odom message for {length:.2f} s from {at:.2f} s "
        f"(the wheels moved {travel:.2f} m meanwhile): the wheels changed speed (before, "
    )
    assert note.endswith(
        "the path across it is unknown; the motion before and after it are runs apart"
    )
    first, second = (run.log for run in report.runs)
    assert first.start - T0 + first.time[-1] == pytest.approx(at, abs=1e-6)  # up to the gap
    assert second.start - T0 == pytest.approx(at + length, abs=1e-6)  # on from its end
    # the robot's errors, from the two runs' whole trajectories
    assert report.estimate.E_d == pytest.approx(1.002, abs=3e-4)
    assert report.estimate.E_b == pytest.approx(1.01, abs=3e-3)
    # Only the second run turns: the wheelbase rests on it alone, on any machine, and its
    # interval is said to be too narrow (tests/estimators/test_trajectory_fit.py).
    assert [w for w in report.warnings if "wheelbase is pinned by one of the 2 runs alone" in w]

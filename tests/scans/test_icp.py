"""Scan matching and motion intervals (umbmark.scans) against simulated truth.

The sweeps are ray-cast by the virtual robot's world at poses chosen here; the truth of a
match is the relative pose of those poses (``Pose2D.relative_to``), the truth of an
interval the laser's displacement in the simulated drive (tests/scan_sim.py).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from scan_sim import LASER, PATTERN, mirrored, ramped, simulate
from umbmark.model.scans import ScanSeries
from umbmark.robot.base import Pose2D
from umbmark.robot.world import World, legs, room_world
from umbmark.scans.icp import match
from umbmark.scans.intervals import IntervalOptions, OdometryGuess, match_intervals
from umbmark.scans.points import prepare, scan_points

#: Tolerances of one match on the room's sweeps (1 cm range noise): position, yaw.
POSITION_TOL = 0.006  # m
YAW_TOL = math.radians(0.15)


def _world(beams: int, world: World | None = None) -> World:
    world = world or room_world()
    assert world.lidar is not None
    lidar = dataclasses.replace(world.lidar, beams=beams, increment=2 * math.pi / beams)
    return dataclasses.replace(world, lidar=lidar)


def _points(world: World, pose: Pose2D, rng: np.random.Generator) -> np.ndarray:
    scan = world.scan(pose, 0.0, rng)
    assert scan is not None
    return scan_points(scan.ranges, scan.angles(), scan.range_min, scan.range_max)


@pytest.mark.parametrize("beams", [360, 720])
def test_match_recovers_the_relative_pose_in_the_room(beams: int) -> None:
    world = _world(beams)
    rng = np.random.default_rng(beams)
    for _ in range(15):
        a = Pose2D(rng.uniform(-1.0, 2.5), rng.uniform(-1.0, 1.0), rng.uniform(-3.1, 3.1))
        b = a.compose(
            Pose2D(rng.uniform(-0.3, 0.3), rng.uniform(-0.1, 0.1), rng.uniform(-0.5, 0.5))
        )
        truth = b.relative_to(a)
        true = np.array([truth.x, truth.y, truth.theta])
        guess = true + rng.uniform(-0.05, 0.05, 3)  # a guess off by up to 5 cm and 3 degrees
        result = match(prepare(_points(world, a, rng)), prepare(_points(world, b, rng)), guess)
        assert result.status == "ok"
        assert math.hypot(*(result.pose[:2] - true[:2])) < POSITION_TOL
        assert abs(math.remainder(result.pose[2] - true[2], math.tau)) < YAW_TOL
        # the covariance is a covariance, and of the size of the error (mm, not m or um)
        assert np.all(np.linalg.eigvalsh(result.covariance) > 0)
        assert 1e-4 < math.sqrt(result.covariance[0, 0]) < 5e-3


def test_a_corridor_is_degenerate() -> None:
    # two walls 2 m apart, 80 m long: nothing fixes the motion along them
    corridor = World.build([[-40.0, 1.0, 40.0, 1.0], [-40.0, -1.0, 40.0, -1.0]])
    rng = np.random.default_rng(1)
    a, b = Pose2D(0.0, 0.0, 0.0), Pose2D(0.2, 0.05, 0.05)
    result = match(prepare(_points(corridor, a, rng)), prepare(_points(corridor, b, rng)))
    assert result.status == "corridor"
    assert not result.ok
    # the same two walls with an end wall in sight are not
    closed = World.build([*corridor.segments.tolist(), [5.0, -1.0, 5.0, 1.0]])
    result = match(prepare(_points(closed, a, rng)), prepare(_points(closed, b, rng)))
    assert result.status == "ok"


def test_open_space_is_degenerate() -> None:
    # a person standing in a hall bigger than the laser's 12 m range: a few returns only
    hall = World.build((), legs(1.5, 0.5))
    rng = np.random.default_rng(2)
    a, b = Pose2D(0.0, 0.0, 0.0), Pose2D(0.1, 0.0, 0.0)
    result = match(prepare(_points(hall, a, rng)), prepare(_points(hall, b, rng)))
    assert result.status == "open space"


def test_points_leave_out_what_did_not_return() -> None:
    ranges = np.array([1.0, np.nan, np.inf, -np.inf, 0.01, 30.0, 2.0, 10.0])
    angles = np.linspace(0.0, 0.7, ranges.size)
    pts = scan_points(ranges, angles, 0.05, 10.0)
    # kept: 1.0 at 0, 2.0 at 0.6, 10.0 (the range limit itself) at 0.7
    expected = [
        [1.0, 0.0],
        [2 * math.cos(0.6), 2 * math.sin(0.6)],
        [10 * math.cos(0.7), 10 * math.sin(0.7)],
    ]
    np.testing.assert_allclose(pts, expected, atol=1e-12)
    flipped = scan_points(ranges, angles, 0.05, 10.0, upside_down=True)
    np.testing.assert_allclose(flipped, np.array(expected) * [1.0, -1.0], atol=1e-12)


@pytest.fixture(scope="module")
def drive():  # type: ignore[no-untyped-def]
    return simulate()


def _truth(drive, intervals) -> np.ndarray:  # type: ignore[no-untyped-def]
    return np.array(
        [
            drive.laser_motion(s, s + t)
            for s, t in zip(intervals.start_time, intervals.duration, strict=True)
        ]
    )


def test_intervals_of_a_drive_match_the_true_laser_motion(drive) -> None:  # type: ignore[no-untyped-def]
    report = match_intervals(drive.scans, drive.wheels)
    iv = report.intervals
    # 31 s of driving, one interval every >= 0.5 s (sweeps at 10 Hz, jittered by 30 %)
    assert 45 <= len(iv) <= 62
    assert report.left_out == {}
    assert np.all(iv.duration >= 0.5)
    assert np.all(iv.duration <= 0.5 + 0.14)
    err = iv.sensor_motion - _truth(drive, iv)
    assert np.max(np.hypot(err[:, 0], err[:, 1])) < POSITION_TOL
    assert np.max(np.abs(err[:, 2])) < YAW_TOL
    # the wheels' rotation: the true wheel speeds of scan_sim over each interval
    ends = iv.start_time + iv.duration
    phi = drive.wheels.angles
    np.testing.assert_allclose(
        iv.phi_left,
        np.interp(ends, drive.wheels.time, phi[:, 0])
        - np.interp(iv.start_time, drive.wheels.time, phi[:, 0]),
        atol=1e-9,
    )
    # the covariances fit the errors: normalized errors of unit spread (0.5 .. 2)
    assert iv.sensor_covariance is not None
    sd = np.sqrt(np.einsum("kii->ki", iv.sensor_covariance))
    spread = np.sqrt(np.mean((err / sd) ** 2, axis=0))
    assert np.all((spread > 0.5) & (spread < 2.0)), spread
    # every kind of motion is there: turns on the spot both ways, straights both ways
    turning = np.sign(iv.phi_right - iv.phi_left)
    forward = np.sign(iv.phi_right + iv.phi_left)
    assert {1, -1} <= set(turning.tolist())
    assert {1, -1} <= set(forward.tolist())


def test_an_upside_down_laser_reads_the_same_motion(drive) -> None:  # type: ignore[no-untyped-def]
    scans = drive.scans
    flipped = dataclasses.replace(scans, ranges=mirrored(scans.ranges), upside_down=True)
    iv = match_intervals(flipped, drive.wheels).intervals
    err = iv.sensor_motion - _truth(drive, iv)
    assert len(iv) >= 45
    assert np.max(np.hypot(err[:, 0], err[:, 1])) < POSITION_TOL
    assert np.max(np.abs(err[:, 2])) < YAW_TOL
    # read the right way up, the mirrored sweeps give a mirrored, wrong motion
    wrong = dataclasses.replace(flipped, upside_down=False)
    bad = match_intervals(wrong, drive.wheels).intervals
    turns = np.abs(_truth(drive, bad)[:, 2]) > 0.1
    assert np.all(np.sign(bad.sensor_motion[turns, 2]) != np.sign(_truth(drive, bad)[turns, 2]))


def test_gaps_standstill_and_missing_wheels_are_left_out(drive) -> None:  # type: ignore[no-untyped-def]
    scans = drive.scans
    # a 3 s gap in the sweeps, and the wheels' record ending 5 s before the sweeps
    keep = (scans.times < 10.0) | (scans.times > 13.0)
    gappy = ScanSeries(
        scans.times[keep],
        scans.ranges[keep],
        scans.angle_min,
        scans.angle_increment,
        scans.range_min,
        scans.range_max,
    )
    wheels = dataclasses.replace(
        drive.wheels,
        time=drive.wheels.time[drive.wheels.time < drive.wheels.time[-1] - 5.0],
        angles=drive.wheels.angles[drive.wheels.time < drive.wheels.time[-1] - 5.0],
    )
    report = match_intervals(gappy, wheels)
    assert report.left_out["gap in the scans"] == 1
    assert report.left_out["no wheel data"] >= 8
    # standing still: no wheel turned
    still = simulate(((3.0, 0.0, 0.0),), seed=4)
    report = match_intervals(still.scans, still.wheels)
    assert len(report.intervals) == 0
    assert report.left_out["standing still"] >= 4


@pytest.mark.slow
def test_a_guess_from_the_wheels_agrees_and_catches_a_slipped_match(drive) -> None:  # type: ignore[no-untyped-def]
    # nominal geometry a little off, as a robot's is before calibration
    guess = OdometryGuess(0.05, 0.05, 0.35, (0.1, 0.0, 0.0))
    report = match_intervals(drive.scans, drive.wheels, IntervalOptions(guess=guess))
    err = report.intervals.sensor_motion - _truth(drive, report.intervals)
    assert report.left_out == {}
    assert len(report.intervals) >= 45
    assert np.max(np.abs(err[:, 2])) < YAW_TOL
    # the left and right wheels swapped (joints mixed up): every turn is the wrong way
    swapped = dataclasses.replace(drive.wheels, angles=drive.wheels.angles[:, ::-1].copy())
    report = match_intervals(drive.scans, swapped, IntervalOptions(guess=guess))
    assert report.left_out.get("far from the wheels' guess", 0) >= 10


def test_the_pattern_stays_in_the_room(drive) -> None:  # type: ignore[no-untyped-def]
    # the robot's centre keeps 0.5 m from everything, the laser is mounted off it
    assert room_world().clearance(drive.poses[:, :2]) > 0.5
    assert drive.scans.beams == 360
    assert len(PATTERN) == 7
    assert LASER.x > 0


@pytest.fixture(scope="module")
def rolling():  # type: ignore[no-untyped-def]
    # a 10 Hz scanner whose beams take the whole period, on a drive that accelerates
    return simulate(ramped(PATTERN), sweep_time=0.1)


@pytest.mark.slow
def test_the_motion_during_a_sweep_is_undone(rolling) -> None:  # type: ignore[no-untyped-def]
    assert rolling.scans.time_increment == pytest.approx(0.1 / 360)
    # taken as measured at once, the turns come out bent: short by the sweep's share of
    # a revolution, and more where the robot accelerates within a sweep
    at_once = dataclasses.replace(rolling.scans, time_increment=0.0)
    iv = match_intervals(at_once, rolling.wheels).intervals
    err = iv.sensor_motion - _truth(rolling, iv)
    assert np.max(np.abs(err[:, 2])) > 3 * YAW_TOL
    # undone with the motion fitted to the sweeps (no guess), or with the wheels' guess
    guess = OdometryGuess(0.05, 0.05, 0.35, (0.1, 0.0, 0.0))
    for options in (IntervalOptions(), IntervalOptions(guess=guess)):
        report = match_intervals(rolling.scans, rolling.wheels, options)
        iv = report.intervals
        assert len(iv) >= 45
        assert report.left_out == {}
        err = iv.sensor_motion - _truth(rolling, iv)
        assert np.max(np.hypot(err[:, 0], err[:, 1])) < POSITION_TOL
        assert np.max(np.abs(err[:, 2])) < YAW_TOL

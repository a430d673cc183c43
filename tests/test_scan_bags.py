"""Laser scans in ROS 1 and ROS 2 bags (sqlite3 and MCAP), written with rosbags: read back
into a ScanSeries, and motion intervals straight from a bag against the simulated truth."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore

from scan_sim import LASER, RADIUS_LEFT, RADIUS_RIGHT, WHEELBASE, mirrored, simulate
from umbmark.core.errors import InputError
from umbmark.model.kinematics import OdometryGeometry
from umbmark.model.recording import PoseSeries
from umbmark.scans.bag import intervals_from_bag, scan_intervals_from_bag
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.scans import read_scan_bag
from umbmark.sources.bag.writer import START_EPOCH, bag_target, write_bag

NAMES = {"ros1": "drive.bag", "sqlite3": "drive_sqlite", "mcap": "drive_mcap"}


@pytest.fixture(scope="module")
def drive():  # type: ignore[no-untyped-def]
    return simulate()


def _write(drive, folder: Path, fmt: str, *, upside_down: bool = False) -> Path:  # type: ignore[no-untyped-def]
    scans = drive.scans
    if upside_down:
        scans = dataclasses.replace(scans, ranges=mirrored(scans.ranges), upside_down=True)
    poses = PoseSeries(time=drive.pose_times, poses=drive.poses)
    target = bag_target(folder / NAMES[fmt], None if fmt == "ros1" else fmt)
    laser = (LASER.x, LASER.y, LASER.theta)
    return write_bag(target, drive.wheels, poses, poses, scans=scans, laser_pose=laser)


@pytest.mark.parametrize("fmt", ["ros1", "sqlite3", "mcap"])
def test_scans_round_trip(drive, tmp_path: Path, fmt: str) -> None:  # type: ignore[no-untyped-def]
    bag = _write(drive, tmp_path, fmt, upside_down=fmt == "mcap")
    read = read_scan_bag(bag, "/scan")
    scans = drive.scans
    assert read.upside_down is (fmt == "mcap")  # from the mounting on /tf_static
    assert read.frame == "laser"
    # stamps: the writer's start epoch plus the simulated times, to the nanosecond
    np.testing.assert_allclose(read.times - START_EPOCH, scans.times, atol=2e-6)
    assert np.all(np.diff(read.times) > 0)
    assert np.ptp(np.diff(read.times)) > 0.04  # irregular rate, as simulated
    expected = mirrored(scans.ranges) if fmt == "mcap" else scans.ranges
    np.testing.assert_array_equal(read.ranges, expected.astype(np.float32).astype(np.float64))
    # NaN (dropouts) and inf (beyond 12 m: the door) survive, where they were
    assert np.isnan(read.ranges).any()
    assert np.isinf(read.ranges).any()
    np.testing.assert_array_equal(np.isinf(read.ranges), np.isinf(expected))
    assert read.angle_min == pytest.approx(-math.pi)
    assert read.angle_increment == pytest.approx(2 * math.pi / 360)
    assert (read.range_min, read.range_max) == pytest.approx((0.05, 12.0))
    assert read.time_increment == 0.0  # the simulated sweeps are taken at once


def test_a_rolling_sweep_keeps_its_timing(tmp_path: Path) -> None:
    drive = simulate(((2.0, 0.0, 0.6),), sweep_time=0.1)
    poses = PoseSeries(time=drive.pose_times, poses=drive.poses)
    bag = write_bag(
        bag_target(tmp_path / "rolling.bag"), drive.wheels, poses, poses, scans=drive.scans
    )
    assert read_scan_bag(bag, "/scan").time_increment == pytest.approx(0.1 / 360, rel=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("upside_down", [False, True])
def test_intervals_from_a_bag_match_the_true_laser_motion(
    drive, tmp_path: Path, upside_down: bool
) -> None:  # type: ignore[no-untyped-def]
    bag = _write(drive, tmp_path, "sqlite3", upside_down=upside_down)
    wheels = BagOptions(left_joint="left_wheel_joint", right_joint="right_wheel_joint")
    report = scan_intervals_from_bag(bag, "/scan", wheels)
    iv = report.intervals
    assert len(iv) >= 45
    assert report.left_out == {}
    start = iv.start_time - START_EPOCH
    truth = np.array(
        [drive.laser_motion(s, s + t) for s, t in zip(start, iv.duration, strict=True)]
    )
    err = iv.sensor_motion - truth
    assert np.max(np.hypot(err[:, 0], err[:, 1])) < 0.006
    assert np.max(np.abs(err[:, 2])) < math.radians(0.15)
    assert len(intervals_from_bag(bag, "/scan", wheels)) == len(iv)


def test_bad_scan_topics_are_one_line(drive, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    bag = _write(drive, tmp_path, "ros1")
    with pytest.raises(InputError, match=r"no topic /laser \(laser scans\) in the bag") as err:
        read_scan_bag(bag, "/laser")
    assert "\n" not in str(err.value)
    assert str(bag) in str(err.value)
    with pytest.raises(InputError, match="/odom has messages of type nav_msgs/msg/Odometry"):
        read_scan_bag(bag, "/odom")
    with pytest.raises(InputError, match="more than 10 sweeps"):
        read_scan_bag(bag, "/scan", max_scans=10)
    thinned = read_scan_bag(bag, "/scan", min_period=0.5)
    assert np.all(np.diff(thinned.times) >= 0.5)
    assert len(thinned) < len(drive.scans) / 4


def test_a_scanner_that_changes_its_beams_is_refused(tmp_path: Path) -> None:
    store = get_typestore(Stores.ROS2_HUMBLE)
    t = store.types
    path = tmp_path / "changing"
    with Writer2(path, version=Writer2.VERSION_LATEST) as writer:
        conn = writer.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=store)
        for k, beams in enumerate([360, 360, 720]):
            msg = t["sensor_msgs/msg/LaserScan"](
                header=t["std_msgs/msg/Header"](
                    stamp=t["builtin_interfaces/msg/Time"](sec=100 + k, nanosec=0),
                    frame_id="laser",
                ),
                angle_min=-math.pi,
                angle_max=math.pi,
                angle_increment=2 * math.pi / beams,
                time_increment=0.0,
                scan_time=0.1,
                range_min=0.1,
                range_max=10.0,
                ranges=np.full(beams, 2.0, dtype=np.float32),
                intensities=np.empty(0, dtype=np.float32),
            )
            writer.write(conn, (100 + k) * 1_000_000_000, store.serialize_cdr(msg, conn.msgtype))
    with pytest.raises(InputError, match="/scan: sweep 3 has 720 beams") as err:
        read_scan_bag(path, "/scan")
    assert "\n" not in str(err.value)


@pytest.mark.slow
def test_wheels_from_the_controllers_odometry(drive, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    # the bag's /odom is the true motion; turned back into wheel rotation with radii of
    # 0.05 m and the true wheelbase, each wheel's angle is its true travel over 0.05 m
    bag = _write(drive, tmp_path, "mcap")
    wheels = BagOptions(odom_topic="/odom", odom_geometry=OdometryGeometry(0.05, 0.05, WHEELBASE))
    report = scan_intervals_from_bag(bag, "/scan", wheels)
    iv = report.intervals
    assert len(iv) >= 45
    start = iv.start_time - START_EPOCH
    truth = np.array(
        [drive.laser_motion(s, s + t) for s, t in zip(start, iv.duration, strict=True)]
    )
    err = iv.sensor_motion - truth
    assert np.max(np.hypot(err[:, 0], err[:, 1])) < 0.006
    assert np.max(np.abs(err[:, 2])) < math.radians(0.15)
    angles = drive.wheels.angles
    true_left = np.interp(start + iv.duration, drive.wheels.time, angles[:, 0]) - np.interp(
        start, drive.wheels.time, angles[:, 0]
    )
    true_right = np.interp(start + iv.duration, drive.wheels.time, angles[:, 1]) - np.interp(
        start, drive.wheels.time, angles[:, 1]
    )
    np.testing.assert_allclose(iv.phi_left, true_left * RADIUS_LEFT / 0.05, atol=2e-3)
    np.testing.assert_allclose(iv.phi_right, true_right * RADIUS_RIGHT / 0.05, atol=2e-3)


@pytest.mark.slow
def test_windows_give_the_intervals_of_a_whole_read(tmp_path: Path):
    """A long recording's sweeps and wheels are read a window at a time (its memory that
    of one window): the intervals a whole read gives, less the few that straddle two
    windows."""
    import umbmark
    from umbmark.scans.bag import scan_intervals_from_bag

    umbmark.simulate_fleet(tmp_path / "f", fleet=1, days=1, minutes=3.0, seed=5)
    (path,) = (tmp_path / "f").glob("robot01/*/drive")
    whole = scan_intervals_from_bag(path, "/scan", window=600.0)
    parts = scan_intervals_from_bag(path, "/scan", window=45.0)  # five windows
    assert len(whole.intervals) > 100
    lost = len(whole.intervals) - len(parts.intervals)
    assert 0 <= lost <= 5  # at most one interval across each boundary
    assert 0 <= whole.tried - parts.tried <= 5  # tried or not, across a boundary
    # The intervals kept in both are the same intervals, matched alike.
    starts = whole.intervals.start_time
    assert starts is not None
    assert parts.intervals.start_time is not None
    common = np.isin(starts, parts.intervals.start_time)
    assert np.count_nonzero(common) == len(parts.intervals)
    theirs = np.isin(parts.intervals.start_time, starts)
    np.testing.assert_allclose(
        parts.intervals.sensor_motion[theirs], whole.intervals.sensor_motion[common], atol=1e-9
    )
    # The wheels too are read a window at a time: the same rotation over each interval.
    for name in ("phi_left", "phi_right"):
        np.testing.assert_allclose(
            getattr(parts.intervals, name)[theirs], getattr(whole.intervals, name)[common],
            atol=1e-9,
        )  # fmt: skip

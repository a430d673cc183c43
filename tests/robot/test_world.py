"""The virtual robot's world: ray casting against closed forms and a plain per-beam loop,
the sensors' noise, dropouts and limits, and the standard world's layout.

Expected values are hand geometry (a ray meeting a wall or a circle) or an independent
per-beam loop written here, never the vectorized code under test.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from umbmark.robot.base import Pose2D
from umbmark.robot.world import (
    LCorner,
    Lidar,
    MotionCapture,
    RangeSensors,
    World,
    box,
    corner_world,
    legs,
    square_path,
)

EXACT = Lidar(sigma=0.0, dropout=0.0)


def _loop_cast(world: World, ox: float, oy: float, angle: float) -> float:
    """One ray, one obstacle at a time, in plain Python (the reference)."""
    dx, dy = math.cos(angle), math.sin(angle)
    best = math.inf
    for x0, y0, x1, y1 in world.segments.tolist():
        ex, ey = x1 - x0, y1 - y0
        denom = dx * ey - dy * ex
        if denom == 0.0:
            continue
        t = ((x0 - ox) * ey - (y0 - oy) * ex) / denom
        u = ((x0 - ox) * dy - (y0 - oy) * dx) / denom
        if t > 1e-9 and 0.0 <= u <= 1.0:
            best = min(best, t)
    for cx, cy, r in world.circles.tolist():
        # |o + t d - c| = r, nearest t > 0 from outside
        fx, fy = ox - cx, oy - cy
        b = fx * dx + fy * dy
        disc = b * b - (fx * fx + fy * fy - r * r)
        if disc >= 0.0:
            t = -b - math.sqrt(disc)
            if t > 1e-9:
                best = min(best, t)
    return best


def test_a_ray_meets_a_wall_at_the_hand_distance():
    world = World.build([[2.0, -1.0, 2.0, 1.0]], lidar=EXACT)
    angles = np.radians([0.0, 25.0, -20.0, 30.0, 180.0])
    got = world.cast(np.zeros(2), angles)
    # the wall x = 2 for |y| <= 1: distance 2 / cos(a) while 2 tan(a) <= 1 (not at 30 deg)
    want = [2.0, 2.0 / math.cos(math.radians(25)), 2.0 / math.cos(math.radians(20)), math.inf]
    np.testing.assert_allclose(got[:4], want, rtol=1e-12)
    assert got[4] == math.inf  # behind the origin


def test_a_ray_meets_a_circle_at_the_hand_distance():
    world = World.build(circles=[[3.0, 0.0, 0.5]])
    got = world.cast(np.zeros(2), np.array([0.0, math.asin(0.5 / 3.0) * 0.999, 0.2]))
    assert got[0] == pytest.approx(2.5, abs=1e-12)
    assert math.isfinite(got[1])  # just grazing
    assert got[2] == math.inf  # past it (sin 0.2 * 3 > 0.5)


def test_the_nearest_of_several_things_is_hit():
    world = World.build([[4.0, -1.0, 4.0, 1.0]], [[2.0, 0.0, 0.1]])
    assert world.cast(np.zeros(2), np.array([0.0]))[0] == pytest.approx(1.9, abs=1e-12)


def test_vectorized_casting_matches_a_per_beam_loop():
    world = corner_world()
    rng = np.random.default_rng(5)
    origins = rng.uniform(-1.5, 1.5, size=(200, 2))
    angles = rng.uniform(-math.pi, math.pi, size=200)
    got = world.cast(origins, angles)
    want = [_loop_cast(world, o[0], o[1], a) for o, a in zip(origins, angles, strict=True)]
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def test_a_scan_places_the_laser_by_its_mount_and_the_robot_pose():
    # the laser 0.2 m ahead and 0.1 m left on the robot, turned 90 deg; the robot at
    # (1, 2) heading 90 deg: the laser stands at (0.9, 2.2) looking along -x, so its beam
    # 0 meets the wall x = -1 after 1.9 m and its beam at +90 deg the wall y = -3 ...
    world = World.build(
        [[-1.0, -10.0, -1.0, 10.0], [-10.0, -3.0, 10.0, -3.0]],
        lidar=Lidar(
            mount=Pose2D(0.2, 0.1, math.pi / 2),
            beams=4,
            angle_min=0.0,
            increment=math.pi / 2,
            sigma=0.0,
            dropout=0.0,
        ),
    )
    scan = world.scan(Pose2D(1.0, 2.0, math.pi / 2), 7.5, np.random.default_rng(0))
    assert scan is not None
    # beam +90 deg looks along -y: from y = 2.2 to y = -3 is 5.2 m
    np.testing.assert_allclose(scan.ranges[:2], [1.9, 5.2], atol=1e-12)
    assert scan.time == 7.5
    assert scan.mount == Pose2D(0.2, 0.1, math.pi / 2)


def test_range_noise_has_the_configured_spread():
    world = World.build([[2.0, -50.0, 2.0, 50.0]], lidar=Lidar(sigma=0.01, dropout=0.0))
    rng = np.random.default_rng(1)
    exact = replace(world, lidar=EXACT).scan(Pose2D(), 0.0, rng)
    assert exact is not None
    errors = []
    for _ in range(20):
        scan = world.scan(Pose2D(), 0.0, rng)
        assert scan is not None
        ok = np.isfinite(exact.ranges)
        errors.append(scan.ranges[ok] - exact.ranges[ok])
    e = np.concatenate(errors)
    assert e.size > 5000
    assert abs(float(e.mean())) < 4 * 0.01 / math.sqrt(e.size)
    assert float(e.std()) == pytest.approx(0.01, rel=0.05)


def test_dropouts_are_the_configured_fraction_and_far_returns_are_inf():
    world = World.build(
        [[2.0, -50.0, 2.0, 50.0]], lidar=Lidar(sigma=0.0, dropout=0.3, range_max=4.0)
    )
    scan = world.scan(Pose2D(), 0.0, np.random.default_rng(2))
    assert scan is not None
    n = scan.ranges.size
    dropped = np.isnan(scan.ranges).sum()
    # binomial(720, 0.3): sd 12.3 beams
    assert abs(dropped - 0.3 * n) < 4 * math.sqrt(n * 0.3 * 0.7)
    a = scan.angles()
    seen = np.isfinite(scan.ranges)
    # within the range limit only: 2 / cos(a) <= 4 means |a| <= 60 deg
    assert np.all(np.abs(a[seen]) <= math.radians(60.0) + 1e-9)
    behind = ~np.isnan(scan.ranges) & (np.abs(a) > math.radians(61.0))
    assert np.all(np.isinf(scan.ranges[behind]))


def test_range_sensors_measure_along_their_x_axis_and_miss_as_nan():
    world = World.build(
        [[-0.5, -5.0, -0.5, 5.0]],
        sonars=RangeSensors((Pose2D(-0.2, 0.1, math.pi), Pose2D(0.0, 0.0, 0.0)), sigma=0.0),
    )
    reading = world.ranges(Pose2D(0.0, 0.0, 0.0), 1.0, np.random.default_rng(0))
    assert reading is not None
    assert reading.ranges[0] == pytest.approx(0.3, abs=1e-12)
    assert math.isnan(reading.ranges[1])  # nothing ahead
    # turned by 20 deg, the beam from (-0.2 cos 20 - 0.1 sin 20, ...) meets x = -0.5 obliquely
    t = math.radians(20.0)
    sx = -0.2 * math.cos(t) - 0.1 * math.sin(t)
    reading = world.ranges(Pose2D(0.0, 0.0, t), 1.0, np.random.default_rng(0))
    assert reading is not None
    assert reading.ranges[0] == pytest.approx((sx + 0.5) / math.cos(t), abs=1e-12)


def test_motion_capture_reports_the_true_pose_with_its_noise():
    world = World.build([], mocap=MotionCapture(sigma_xy=0.001, sigma_theta=0.002))
    rng = np.random.default_rng(4)
    truth = Pose2D(1.0, -2.0, 0.5)
    got = [world.truth(truth, 3.0, rng) for _ in range(4000)]
    xs = np.array([[g.pose.x, g.pose.y, g.pose.theta] for g in got if g is not None])
    assert xs.shape == (4000, 3)
    np.testing.assert_allclose(xs.mean(axis=0), [1.0, -2.0, 0.5], atol=1e-4)
    np.testing.assert_allclose(xs.std(axis=0), [0.001, 0.001, 0.002], rtol=0.06)


def test_a_robot_without_a_sensor_reads_none():
    world = World.build([[1.0, -1.0, 1.0, 1.0]], lidar=None)
    rng = np.random.default_rng(0)
    assert world.scan(Pose2D(), 0.0, rng) is None
    assert world.ranges(Pose2D(), 0.0, rng) is None
    assert world.truth(Pose2D(), 0.0, rng) is None


def test_the_standard_world_keeps_out_of_the_squares_way():
    world = corner_world()
    # the nearest things: the side wall ends 0.35 m behind the cw square's last leg; the
    # box's front face is 0.6 m behind the ccw square's last leg (x = 0)
    assert world.clearance(square_path(4.0, "cw")) == pytest.approx(0.35, abs=1e-12)
    assert world.clearance(square_path(4.0, "ccw")) == pytest.approx(0.6, abs=1e-12)
    assert world.corner is not None
    assert world.corner.in_corner(world.start) == Pose2D(1.6, 1.3, 0.0)


def test_clearance_is_zero_when_a_wall_crosses_the_path():
    world = World.build([[2.0, -0.5, 2.0, 0.5]])
    assert world.clearance(square_path(4.0, "ccw")) == 0.0
    assert World.build(circles=[[2.0, 0.05, 0.1]]).clearance(square_path(4.0, "cw")) == 0.0
    # a wall 0.3 m beside the first leg, parallel to it
    side = World.build([[1.0, -0.3, 3.0, -0.3]])
    assert side.clearance(square_path(4.0, "ccw")) == pytest.approx(0.3, abs=1e-12)


def test_corner_and_clutter_shapes():
    corner = LCorner(vertex=(1.0, 2.0), heading=math.pi / 2, x_length=1.0, y_length=2.0)
    np.testing.assert_allclose(
        corner.segments(), [[1.0, 2.0, 1.0, 3.0], [1.0, 2.0, -1.0, 2.0]], atol=1e-12
    )
    # the robot at (0.5, 2.5) heading pi is at x 0.5, y 0.5 in the corner, heading pi/2
    p = corner.in_corner(Pose2D(0.5, 2.5, math.pi))
    assert (p.x, p.y, p.theta) == pytest.approx((0.5, 0.5, math.pi / 2))
    sides = box(0.0, 0.0, 2.0, 1.0)
    assert sorted(np.hypot(sides[:, 2] - sides[:, 0], sides[:, 3] - sides[:, 1])) == (
        pytest.approx([1.0, 1.0, 2.0, 2.0])
    )
    feet = legs(1.0, 1.0, heading=0.0)
    assert feet[:, 1].tolist() == pytest.approx([1.1, 0.9])

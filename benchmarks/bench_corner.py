"""The corner measurement: simulated scans and the corner fit, each against a plain reference.

- Ray casting: the world's vectorized scan (720 beams against every wall and circle at
  once) against a per-beam Python loop over the same walls and circles.
- The corner fit per scan: the whole pipeline (pieces, candidate corners, the joint fit
  in range space, the walls' angle) for one scan, and for the five scans the routine
  takes; the median over many scans, and its share of a 10 Hz laser's period.
- The joint fit alone, on the same returns: closed form then Gauss-Newton with the
  analytic Jacobian, against ``scipy.optimize.least_squares`` (numerical Jacobian)
  minimizing the same range residuals; the largest difference between their poses is
  printed as a check that both solve the same problem.

With ``--accuracy`` it first prints the fixes' errors against the simulated truth: rms
over random poses near the start, for the laser (5 scans a fix, as the routine takes;
also 1 scan, and 30 % dropouts with an offset, rotated laser) and for three range sensors
(5 readings a fix; also 1).

Run: python benchmarks/bench_corner.py [--scans 200] [--accuracy] [--poses 200]
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares

from umbmark.robot.base import Pose2D, ScanSweep
from umbmark.robot.world import LCorner, Lidar, RangeSensors, World, box, corner_world, legs
from umbmark.routines.corner import fit_corner, to_frame
from umbmark.routines.corner_beams import Beams, fit_corner_ranges
from umbmark.routines.corner_lidar import fix_from_scans
from umbmark.routines.corner_pieces import scan_beams
from umbmark.routines.corner_sensors import fix_from_ranges

from _timing import best_of


def loop_scan(world: World, pose: Pose2D) -> list[float]:
    """One scan, beam by beam, obstacle by obstacle, in plain Python (no noise)."""
    lidar = world.lidar
    assert lidar is not None
    laser = pose.compose(lidar.mount)
    segments, circles = world.segments.tolist(), world.circles.tolist()
    out = []
    for k in range(lidar.beams):
        angle = laser.theta + lidar.angle_min + lidar.increment * k
        dx, dy = math.cos(angle), math.sin(angle)
        best = math.inf
        for x0, y0, x1, y1 in segments:
            ex, ey = x1 - x0, y1 - y0
            denom = dx * ey - dy * ex
            if denom != 0.0:
                t = ((x0 - laser.x) * ey - (y0 - laser.y) * ex) / denom
                u = ((x0 - laser.x) * dy - (y0 - laser.y) * dx) / denom
                if t > 1e-9 and 0.0 <= u <= 1.0:
                    best = min(best, t)
        for cx, cy, r in circles:
            fx, fy = laser.x - cx, laser.y - cy
            b = fx * dx + fy * dy
            disc = b * b - (fx * fx + fy * fy - r * r)
            if disc >= 0.0 and -b - math.sqrt(disc) > 1e-9:
                best = min(best, -b - math.sqrt(disc))
        out.append(best)
    return out


def scipy_fit(x_wall: Beams, y_wall: Beams, start: Pose2D) -> Pose2D:
    """The same joint fit (range residuals, pose parameters) by a general solver."""

    def residuals(p: np.ndarray) -> np.ndarray:
        alpha = -p[2]
        ex = np.array([math.cos(alpha), math.sin(alpha)])
        ey = np.array([-ex[1], ex[0]])
        out = []
        for beams, normal, offset in ((x_wall, ey, -p[1]), (y_wall, ex, -p[0])):
            t = (offset - beams.origins @ normal) / (beams.directions @ normal)
            out.append(beams.ranges - t)
        return np.concatenate(out)

    fit = least_squares(residuals, [start.x, start.y, start.theta], method="lm")
    return Pose2D(*map(float, fit.x))


def _cluttered(world: World) -> World:
    """The standard world with eight more boxes and six more people around."""
    rng = np.random.default_rng(1)
    boxes = [box(*rng.uniform(-6, 6, 2), 0.4, 0.3, rng.uniform(0, 3)) for _ in range(8)]
    people = [legs(*rng.uniform(-6, 6, 2), rng.uniform(0, 3)) for _ in range(6)]
    return replace(
        world,
        segments=np.vstack([world.segments, *boxes]),
        circles=np.vstack([world.circles, *people]),
    )


def _rms(errors: list[tuple[float, float, float]]) -> str:
    e = np.array(errors)
    x, y, th = np.sqrt(np.mean(e**2, axis=0))
    radial = math.sqrt(float(np.mean(e[:, 0] ** 2 + e[:, 1] ** 2)))
    return (
        f"x {x * 1e3:5.2f} mm, y {y * 1e3:5.2f} mm, position {radial * 1e3:5.2f} mm, "
        f"heading {math.degrees(th):5.3f} deg"
    )


def accuracy(poses: int) -> None:
    """Errors of fixes against the world's truth, rms over random poses near the start."""
    world = corner_world()
    assert world.corner is not None
    rng = np.random.default_rng(7)
    paper = World.build(
        corner=LCorner(vertex=(-0.6, -0.5), heading=0.0, x_length=1.5, y_length=2.0),
        lidar=None,
        sonars=RangeSensors(
            (
                Pose2D(-0.25, 0.25, math.pi),
                Pose2D(-0.25, -0.25, math.pi),
                Pose2D(0.0, -0.2, -math.pi / 2),
            )
        ),
    )
    offset = replace(world, lidar=Lidar(mount=Pose2D(0.15, -0.05, 0.5), dropout=0.3))
    cases = [
        ("laser, 5 scans", world, "lidar", 5, 0.5, 15.0),
        ("laser, 1 scan", world, "lidar", 1, 0.5, 15.0),
        ("laser, 5 scans, 30 % dropouts, offset mount", offset, "lidar", 5, 0.5, 15.0),
        ("3 ranges (standard world), 5 readings", world, "ranges", 5, 0.15, 5.0),
        ("3 ranges (paper's layout), 5 readings", paper, "ranges", 5, 0.15, 5.0),
        ("3 ranges (paper's layout), 1 reading", paper, "ranges", 1, 0.15, 5.0),
    ]
    print(f"accuracy against the truth, rms over {poses} poses near the start")
    for name, scene, method, n, radius, angle in cases:
        assert scene.corner is not None
        errors = []
        for _ in range(poses):
            r, a = radius * math.sqrt(rng.random()), rng.uniform(-math.pi, math.pi)
            pose = Pose2D(
                r * math.cos(a), r * math.sin(a), math.radians(rng.uniform(-angle, angle))
            )
            truth = scene.corner.in_corner(pose)
            if method == "lidar":
                scans = [scene.scan(pose, 0.1 * k, rng) for k in range(n)]
                fix = fix_from_scans(scans)  # type: ignore[arg-type]
            else:
                readings = [scene.ranges(pose, 0.1 * k, rng) for k in range(n)]
                fix = fix_from_ranges(readings)  # type: ignore[arg-type]
            dtheta = math.remainder(fix.pose.theta - truth.theta, 2 * math.pi)
            errors.append((fix.pose.x - truth.x, fix.pose.y - truth.y, dtheta))
        where = f"within {radius:g} m, {angle:g} deg"
        print(f"  {name} ({where}):\n    {_rms(errors)}")


def median_time(fn: object, items: list[object]) -> float:
    times = []
    for item in items:
        start = time.perf_counter()
        fn(item)  # type: ignore[operator]
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", type=int, default=200, help="scans to time the fit on")
    parser.add_argument("--accuracy", action="store_true", help="print the fixes' errors first")
    parser.add_argument("--poses", type=int, default=200, help="poses for --accuracy")
    args = parser.parse_args()
    if args.accuracy:
        accuracy(args.poses)
    world = corner_world()
    assert world.lidar is not None
    assert world.corner is not None
    rng = np.random.default_rng(0)
    poses = [
        Pose2D(*rng.uniform(-0.3, 0.3, 2), math.radians(rng.uniform(-15, 15)))
        for _ in range(args.scans)
    ]
    for name, scene in (("standard corner world", world), ("with more clutter", _cluttered(world))):
        n_things = len(scene.segments) + len(scene.circles)
        print(f"{name}: {world.lidar.beams} beams, {n_things} walls and circles")
        t_vec, _ = best_of(lambda scene=scene: [scene.scan(p, 0.0, rng) for p in poses], 1)
        t_loop, loop = best_of(lambda scene=scene: [loop_scan(scene, p) for p in poses[:20]], 1)
        per_vec, per_loop = t_vec / len(poses), t_loop / 20
        print(f"  ray cast, vectorized: {per_vec * 1e3:8.3f} ms/scan")
        print(
            f"  ray cast, plain loop: {per_loop * 1e3:8.3f} ms/scan   "
            f"ratio {per_loop / per_vec:6.1f}x"
        )
        exact = scene.cast(
            np.array([poses[0].x, poses[0].y]),
            poses[0].theta + world.lidar.angle_min + world.lidar.increment * np.arange(720),
        )
        ref = np.array(loop[0])
        hit = np.isfinite(ref)
        assert np.array_equal(hit, np.isfinite(exact))
        diff = float(np.max(np.abs(exact[hit] - ref[hit])))
        print(f"  largest range difference, loop vs vectorized: {diff:.1e} m")

    scans: list[ScanSweep] = []
    for p in poses:
        scan = world.scan(p, 0.0, rng)
        assert scan is not None
        scans.append(scan)
    one = median_time(lambda s: fix_from_scans([s]), scans)  # type: ignore[arg-type]
    groups = [[world.scan(p, 0.1 * k, rng) for k in range(5)] for p in poses[: len(poses) // 5]]
    five = median_time(fix_from_scans, groups)  # type: ignore[arg-type]
    print("corner fit (1 cm noise, 2 % dropouts)")
    print(
        f"  one scan: {one * 1e3:7.2f} ms (median over {len(scans)} scans; "
        f"{one / 0.1:.1%} of a 10 Hz laser's period)"
    )
    print(
        f"  five scans at one stop: {five * 1e3:7.2f} ms ({five / 5 * 1e3:.2f} ms per scan; "
        f"median over {len(groups)} stops)"
    )

    # the joint fit alone, on the returns the pipeline chose, from the closed-form start
    cases = []
    for group in groups[:20]:
        fix = fix_from_scans(group)
        beams = [scan_beams(s) for s in group]
        pooled = Beams(
            np.vstack([b.origins for b in beams]),
            np.vstack([b.directions for b in beams]),
            np.concatenate([b.ranges for b in beams]),
        )
        c = to_frame(fix.pose, pooled.points)
        on_x = (np.abs(c[:, 1]) < 0.03) & (c[:, 0] > 0.05) & (c[:, 0] < 0.9)
        on_y = (np.abs(c[:, 0]) < 0.03) & (c[:, 1] > 0.05) & (c[:, 1] < 3.0)
        x_wall, y_wall = pooled.take(on_x & ~on_y), pooled.take(on_y & ~on_x)
        start = fit_corner(x_wall.points, y_wall.points)
        assert start is not None
        cases.append((x_wall, y_wall, start.pose))

    def ours(case: tuple[Beams, Beams, Pose2D]) -> Pose2D:
        start = fit_corner(case[0].points, case[1].points)
        assert start is not None
        return fit_corner_ranges(case[0], case[1], start.pose).pose

    t_ours = median_time(ours, cases)  # type: ignore[arg-type]
    t_ref = median_time(lambda c: scipy_fit(*c), cases)  # type: ignore[misc]
    diff = max(
        max(abs(a.x - b.x), abs(a.y - b.y)) for a, b in ((ours(c), scipy_fit(*c)) for c in cases)
    )
    n = int(np.mean([len(c[0]) + len(c[1]) for c in cases]))
    print(f"joint fit alone (5 scans, about {n} returns on the walls)")
    print(f"  closed form + Gauss-Newton: {t_ours * 1e3:7.3f} ms")
    print(f"  scipy least_squares (lm):   {t_ref * 1e3:7.3f} ms   ratio {t_ref / t_ours:6.1f}x")
    print(f"  largest position difference between them: {diff:.1e} m")


if __name__ == "__main__":
    main()

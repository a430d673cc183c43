"""Scan matching: umbmark's point-to-line ICP against the alternatives, on one core.

Candidates, each matching the same pairs of sweeps from the same first guess:

- ``umbmark PLICP``: :func:`umbmark.scans.icp.match` (numpy, scipy's ``cKDTree``), both
  sweeps prepared (normals, KD-tree) inside the timing;
- ``point-to-point ICP``: the plain alternative, on the same KD-tree and with the same
  trimming and stopping rule, the pose solved in closed form (weighted Kabsch) each step;
- ``small_gicp GICP / PLANE_ICP / ICP`` (``pip install small_gicp``, optional): the
  C++ library's ``align`` on the sweeps lifted into 3D (each point at z = -0.2, 0 and
  0.2 m, so that walls are planes), ``num_threads=1``, 1 cm voxels.

The pairs: sweeps of the virtual robot's room (``umbmark.robot.world.room_world``: walls,
a door, a pillar, furniture, a chair and a person; 1 cm range noise, 2 % dropouts) from
random poses inside it, the second sweep moved as in a 0.5 s interval of driving (up to
0.25 m and 25 degrees), the guess off the truth by up to 5 cm and 3 degrees (uncalibrated
wheels). Errors are against the simulated truth: median and 95th percentile of the
position [mm] and yaw [deg] errors, and the pairs off by more than 2 cm or 0.5 degree
("bad"). Speed: scan pairs per second of CPU time of this process (the machine may be
shared) and of wall time, with ``OMP_NUM_THREADS=1`` and friends set before numpy loads.

The last lines time :func:`umbmark.scans.intervals.intervals_from_scans` on the tests'
simulated drive (every sweep used prepared once, matched against the one before it),
with sweeps taken at once and with rolling sweeps (``time_increment``; without a guess
they are matched twice): intervals per second, the rate that an hour of driving needs.

Run: python benchmarks/bench_scan_matching.py [--pairs 200] [--beams 360 720]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from umbmark.robot.base import Pose2D  # noqa: E402
from umbmark.robot.world import World, room_world  # noqa: E402
from umbmark.scans.icp import match  # noqa: E402
from umbmark.scans.intervals import IntervalOptions, match_intervals  # noqa: E402
from umbmark.scans.points import prepare, scan_points  # noqa: E402

Pair = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # ref, cur, guess, truth
Matcher = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray | None]


def make_pairs(beams: int, count: int, seed: int = 7) -> list[Pair]:
    """``count`` pairs of sweeps of the room, with guesses and true relative poses."""
    world = room_world()
    assert world.lidar is not None
    lidar = dataclasses.replace(world.lidar, beams=beams, increment=2 * math.pi / beams)
    world = dataclasses.replace(world, lidar=lidar)
    rng = np.random.default_rng(seed)
    pairs = []
    while len(pairs) < count:
        a = Pose2D(rng.uniform(-1.5, 3.0), rng.uniform(-1.8, 1.8), rng.uniform(-math.pi, math.pi))
        step = Pose2D(rng.uniform(-0.25, 0.25), rng.uniform(-0.03, 0.03), rng.uniform(-0.44, 0.44))
        b = a.compose(step)
        if world.clearance(np.array([[a.x, a.y], [b.x, b.y]])) < 0.3:
            continue
        truth = b.relative_to(a)
        true = np.array([truth.x, truth.y, truth.theta])
        guess = true + np.concatenate([rng.uniform(-0.05, 0.05, 2), rng.uniform(-0.052, 0.052, 1)])
        pairs.append((_points(world, a, rng), _points(world, b, rng), guess, true))
    return pairs


def _points(world: World, pose: Pose2D, rng: np.random.Generator) -> np.ndarray:
    scan = world.scan(pose, 0.0, rng)
    assert scan is not None
    return scan_points(scan.ranges, scan.angles(), scan.range_min, scan.range_max)


def plicp(ref: np.ndarray, cur: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
    result = match(prepare(ref), prepare(cur), guess)
    return result.pose if result.ok else None


def point_to_point(ref: np.ndarray, cur: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
    """Plain ICP on the KD-tree: nearest point pairs, the same trimming, Kabsch steps."""
    tree = cKDTree(ref)
    pose = guess.copy()
    distance = 0.5
    for _ in range(60):
        c, s = math.cos(pose[2]), math.sin(pose[2])
        moved = cur @ np.array([[c, s], [-s, c]]) + pose[:2]
        dist, j = tree.query(moved, k=1, distance_upper_bound=distance, workers=1)
        near = np.isfinite(dist)
        if np.count_nonzero(near) < 40:
            return None
        d = dist[near]
        scale = max(1.4826 * float(np.median(d)), 1e-4)
        keep = d <= max(3.0 * scale, 0.025)
        p, q = moved[near][keep], ref[j[near][keep]]
        w = 1.0 / (1.0 + (d[keep] / (3.0 * scale)) ** 2)
        pm, qm = np.average(p, axis=0, weights=w), np.average(q, axis=0, weights=w)
        pc, qc = p - pm, q - qm
        dth = math.atan2(
            float(np.sum(w * (pc[:, 0] * qc[:, 1] - pc[:, 1] * qc[:, 0]))),
            float(np.sum(w * (pc[:, 0] * qc[:, 0] + pc[:, 1] * qc[:, 1]))),
        )
        cd, sd = math.cos(dth), math.sin(dth)
        t = qm - np.array([cd * pm[0] - sd * pm[1], sd * pm[0] + cd * pm[1]])
        # compose the step (dth, t) onto the pose
        new = np.array(
            [cd * pose[0] - sd * pose[1] + t[0], sd * pose[0] + cd * pose[1] + t[1], pose[2] + dth]
        )
        step, pose = new - pose, new
        distance = min(distance, max(0.05, 12.0 * scale))
        if float(np.max(np.abs(step))) < 1e-4:
            return pose
    return None


def small_gicp_matcher(kind: str) -> Matcher | None:
    try:
        import small_gicp
    except ImportError:
        return None

    def lift(points: np.ndarray) -> np.ndarray:
        layers = [np.column_stack([points, np.full(len(points), z)]) for z in (-0.2, 0.0, 0.2)]
        return np.vstack(layers)

    def run(ref: np.ndarray, cur: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
        init = np.eye(4)
        c, s = math.cos(guess[2]), math.sin(guess[2])
        init[:2, :2] = [[c, -s], [s, c]]
        init[:2, 3] = guess[:2]
        result = small_gicp.align(
            lift(ref),
            lift(cur),
            init,
            registration_type=kind,
            downsampling_resolution=0.01,
            max_correspondence_distance=0.5,
            num_threads=1,
            max_iterations=40,
            rotation_epsilon=1e-4,
            translation_epsilon=1e-4,
        )
        if not result.converged:
            return None
        m = result.T_target_source
        return np.array([m[0, 3], m[1, 3], math.atan2(m[1, 0], m[0, 0])])

    return run


def evaluate(name: str, matcher: Matcher, pairs: list[Pair], base: float | None) -> float:
    """Match every pair, print one line; return the CPU time per pair [s]."""
    errors = []
    failed = 0
    cpu0, wall0 = time.process_time(), time.perf_counter()
    poses = [matcher(ref, cur, guess) for ref, cur, guess, _ in pairs]
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    for pose, (_, _, _, true) in zip(poses, pairs, strict=True):
        if pose is None:
            failed += 1
            continue
        errors.append(
            (math.hypot(*(pose[:2] - true[:2])), abs(math.remainder(pose[2] - true[2], math.tau)))
        )
    err = np.array(errors).reshape(-1, 2)
    bad = int(np.count_nonzero((err[:, 0] > 0.02) | (err[:, 1] > math.radians(0.5))))
    per = cpu / len(pairs)
    ratio = f"{per / base:5.1f}x" if base else "  1.0x"
    print(
        f"  {name:<22} {len(pairs) / cpu:7.0f} /s cpu {len(pairs) / wall:7.0f} /s wall {ratio}"
        f"  pos {np.median(err[:, 0]) * 1e3:6.2f} / {np.percentile(err[:, 0], 95) * 1e3:6.2f} mm"
        f"  yaw {math.degrees(np.median(err[:, 1])):6.3f} / "
        f"{math.degrees(np.percentile(err[:, 1], 95)):6.3f} deg"
        f"  failed {failed:3d}  bad {bad:3d}"
    )
    return per


def drive_rate(beams: int, sweep_time: float = 0.0) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from scan_sim import PATTERN, ramped, simulate  # the tests' simulated drive

    drive = simulate(ramped(PATTERN), beams=beams, sweep_time=sweep_time)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    report = match_intervals(drive.scans, drive.wheels, IntervalOptions())
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    n = report.tried
    kind = "rolling sweeps (matched twice)" if sweep_time else "sweeps taken at once"
    print(
        f"  intervals_from_scans, {beams} beams, {kind}: {n} intervals of {len(drive.scans)}"
        f" sweeps in {cpu:.2f} s cpu ({n / cpu:.0f} /s cpu, {n / wall:.0f} /s wall); "
        f"an hour at 5 Hz (9000 pairs) in {9000 * cpu / n:.0f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=200)
    parser.add_argument("--beams", type=int, nargs="+", default=[360, 720])
    args = parser.parse_args()
    candidates: list[tuple[str, Matcher]] = [
        ("umbmark PLICP", plicp),
        ("point-to-point ICP", point_to_point),
    ]
    for kind in ("GICP", "PLANE_ICP", "ICP"):
        found = small_gicp_matcher(kind)
        if found is not None:
            candidates.append((f"small_gicp {kind}", found))
    if len(candidates) == 2:
        print("(small_gicp is not installed: pip install small_gicp to compare it)")
    print(
        "pairs per second (one core), cpu and wall; time per pair against umbmark's;"
        " errors median / 95th percentile"
    )
    for beams in args.beams:
        pairs = make_pairs(beams, args.pairs)
        print(f"{beams} beams, {len(pairs)} pairs of the room:")
        base = None
        for name, matcher in candidates:
            matcher(*pairs[0][:3])  # warm up (imports, first calls)
            per = evaluate(name, matcher, pairs, base)
            base = base or per
    for beams in args.beams:
        drive_rate(beams)
        drive_rate(beams, sweep_time=0.1)


if __name__ == "__main__":
    main()

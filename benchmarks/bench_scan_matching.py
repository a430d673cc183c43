"""Scan matching: umbmark's point-to-line ICP against the alternatives, on one core.

Candidates, each matching the same pairs of sweeps from the same first guess:

- ``umbmark PLICP``: :func:`umbmark.scans.icp.match` (numpy, scipy's ``cKDTree``), both
  sweeps prepared (normals, KD-tree) inside the timing;
- ``point-to-point ICP``: the plain alternative, on the same KD-tree and with the same
  trimming and stopping rule, the pose solved in closed form (weighted Kabsch) each step;
- ``small_gicp GICP / PLANE_ICP / ICP`` (``pip install small_gicp``, optional): the
  C++ library's ``align`` on the sweeps lifted into 3D (each point at z = -0.2, 0 and
  0.2 m, so that walls are planes), ``num_threads=1``, 1 cm voxels;
- ``kiss-icp (registration)`` (``pip install kiss-icp``, optional): kiss-icp's registration
  core, ``Registration.align_points_to_map`` (point-to-point, Geman-McClure kernel), against
  a voxel map of the reference sweep (5 cm voxels), one thread, the points at z = 0; not
  its odometry pipeline (motion model, adaptive threshold, local map), which takes a
  stream of frames, not a pair from a guess.

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

Real scans (``--carmen LOG``): consecutive sweeps of a CARMEN log
(:func:`umbmark.sources.carmen.read_carmen`; the MIT Killian Court log ``killian.g2o`` of
the PyPI package ``rtb-data``, see ``tools/carmen_scans.py`` for how to fetch it), every
candidate started from the log's odometry (the laser's motion between the two sweeps,
through the stated mounting if any). Pairs further apart than ``--max-gap`` seconds are
left out; ``--pairs`` of the rest, spread evenly over the log. With no truth, accuracy is
told in four ways:

- ``odometry``: the match against the odometry's own motion over the pair, median and 95th
  percentile of the position [mm] and yaw [deg] differences: the matcher's error and the
  odometry's together (a matcher that returned its guess would score zero: read it with
  the next two);
- ``fwd-bwd``: each pair matched both ways (B against A from the odometry, A against B
  from the odometry's inverse), the two composed: its distance from the identity;
- ``kicked``: each pair matched again from the odometry moved by 5 cm and 3 degrees (the
  same random kicks for every candidate): how far that answer lies from the first, and
  the share that came back within 1 cm and 0.2 degree of it (``back``). A matcher that
  stays near its guess shows about 5 cm and 3 degrees here, however well it scores on
  the first two;
- ``refused``: no answer (refused, not converged, an exception); ``wild``: an answer off
  the odometry by more than 15 cm or 3 degrees (30 % of a 0.5 m step, which odometry does
  not drift by). The accuracy figures are over the pairs every candidate answered.

``umbmark PLICP (no checks)`` is the same matcher with its corridor and open-space
verdicts ignored (its answer whenever it has one), to compare like with like on the
pairs the checks refuse.

``--field 180 --range-step 0.05`` keeps of each simulated sweep the half ahead and rounds
its ranges to 5 cm, as the Killian log's scanner (``--beams 360``: 1 degree apart).

Run: python benchmarks/bench_scan_matching.py [--pairs 200] [--beams 360 720]
     python benchmarks/bench_scan_matching.py --beams 360 --field 180 --range-step 0.05
     python benchmarks/bench_scan_matching.py --carmen killian.g2o [--pairs 1000]
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

from umbmark.core.errors import InputError  # noqa: E402
from umbmark.robot.base import Pose2D  # noqa: E402
from umbmark.robot.world import World, room_world  # noqa: E402
from umbmark.scans.icp import match  # noqa: E402
from umbmark.scans.intervals import IntervalOptions, match_intervals  # noqa: E402
from umbmark.scans.points import prepare, scan_points  # noqa: E402
from umbmark.sources.carmen import read_carmen  # noqa: E402

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


def resample(points: np.ndarray, field: float, step: float) -> np.ndarray:
    """The returns within ``field`` [deg] ahead (centred on x), ranges rounded to ``step``
    [m] (0: as they are): a sweep of the room as a narrower, coarser scanner sees it."""
    r = np.hypot(points[:, 0], points[:, 1])
    a = np.arctan2(points[:, 1], points[:, 0])
    if step > 0:
        r = np.round(r / step) * step
    keep = np.abs(a) <= math.radians(field) / 2
    return np.column_stack([r * np.cos(a), r * np.sin(a)])[keep]


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


def plicp_unchecked(ref: np.ndarray, cur: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
    """umbmark's PLICP, its answer whatever its verdict (None only without one)."""
    result = match(prepare(ref), prepare(cur), guess)
    return None if result.status == "open space" and result.pairs == 0 else result.pose


def _matrix(pose: np.ndarray) -> np.ndarray:
    """``x, y, yaw`` as a 4 x 4 homogeneous transform (a rotation about z)."""
    m = np.eye(4)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    m[:2, :2] = [[c, -s], [s, c]]
    m[:2, 3] = pose[:2]
    return m


def _planar(m: np.ndarray) -> np.ndarray:
    return np.array([m[0, 3], m[1, 3], math.atan2(m[1, 0], m[0, 0])])


def kiss_icp_matcher(voxel: float = 0.05, kernel: float = 0.05) -> Matcher | None:
    """kiss-icp's registration of the current sweep against a voxel map of the reference.

    ``voxel`` and ``kernel`` [m] were chosen on 150 of the Killian log's pairs among 0.05 to
    0.5 m and 0.03 to 0.17 m: its own rule (voxels of a hundredth of the maximum range,
    here 0.5 m) multiplied the forward-backward disagreement's median by 9 and its 95th
    percentile by 14. Small voxels narrow the basin: kicked off its guess, it stays near
    the kick more often (the real mode's ``kicked`` columns)."""
    try:
        from kiss_icp.mapping import VoxelHashMap
        from kiss_icp.registration import Registration
    except ImportError:
        return None
    registration = Registration(
        max_num_iterations=500, convergence_criterion=1e-4, max_num_threads=1
    )

    def flat(points: np.ndarray) -> np.ndarray:
        return np.column_stack([points, np.zeros(len(points))])

    def run(ref: np.ndarray, cur: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
        voxel_map = VoxelHashMap(voxel_size=voxel, max_distance=100.0, max_points_per_voxel=20)
        voxel_map.add_points(flat(ref))
        m = registration.align_points_to_map(
            flat(cur), voxel_map, _matrix(guess), max_correspondance_distance=0.5, kernel=kernel
        )
        return _planar(np.asarray(m))

    return run


def small_gicp_matcher(kind: str) -> Matcher | None:
    try:
        import small_gicp
    except ImportError:
        return None

    def lift(points: np.ndarray) -> np.ndarray:
        layers = [np.column_stack([points, np.full(len(points), z)]) for z in (-0.2, 0.0, 0.2)]
        return np.vstack(layers)

    def run(ref: np.ndarray, cur: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
        result = small_gicp.align(
            lift(ref),
            lift(cur),
            _matrix(guess),
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
        return _planar(result.T_target_source)

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


# Real scans ----------------------------------------------------------------------------

RealPair = tuple[np.ndarray, np.ndarray, np.ndarray]  # ref points, cur points, odometry


def carmen_pairs(path: Path, count: int, max_gap: float) -> tuple[list[RealPair], str]:
    """``count`` pairs of consecutive sweeps of a CARMEN log, spread evenly over it, with
    the laser's motion from the first to the second by the odometry; and a description."""
    log = read_carmen(path)
    scans, odo = log.scans, log.odometry
    mount = Pose2D(*(log.stated_mounting or (0.0, 0.0, 0.0)))
    heading = np.unwrap(odo.poses[:, 2])
    at = np.column_stack(
        [np.interp(scans.times, odo.time, odo.poses[:, 0]),
         np.interp(scans.times, odo.time, odo.poses[:, 1]),
         np.interp(scans.times, odo.time, heading)]
    )  # fmt: skip
    usable = np.flatnonzero(np.diff(scans.times) <= max_gap)
    chosen = usable[
        np.unique(np.linspace(0, len(usable) - 1, min(count, len(usable))).round().astype(int))
    ]
    angles = scans.angles()
    pairs: list[RealPair] = []
    for i in chosen:
        a, b = Pose2D(*at[i]).compose(mount), Pose2D(*at[i + 1]).compose(mount)
        step = b.relative_to(a)
        points = [
            scan_points(scans.ranges[k], angles, scans.range_min, scans.range_max,
                        upside_down=scans.upside_down)
            for k in (i, i + 1)
        ]  # fmt: skip
        pairs.append((points[0], points[1], np.array([step.x, step.y, step.theta])))
    moved = np.array([math.hypot(*p[2][:2]) for p in pairs])
    turned = np.degrees(np.abs([p[2][2] for p in pairs]))
    text = (
        f"{path.name}: {len(pairs)} pairs of consecutive sweeps of {scans.beams} beams "
        f"(of {len(usable)} no more than {max_gap:g} s apart); odometry per pair: moved "
        f"median {np.median(moved):.2f} m (95 % {np.percentile(moved, 95):.2f} m), turned "
        f"median {np.median(turned):.1f} deg (95 % {np.percentile(turned, 95):.1f} deg)"
    )
    return pairs, text


def _inverse(pose: np.ndarray) -> np.ndarray:
    inv = Pose2D(0.0, 0.0, 0.0).relative_to(Pose2D(*pose))
    return np.array([inv.x, inv.y, inv.theta])


def _apart(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Position [m] and |yaw| [rad] of ``b`` in ``a``'s frame."""
    d = Pose2D(*b).relative_to(Pose2D(*a))
    return math.hypot(d.x, d.y), abs(math.remainder(d.theta, math.tau))


def _safe(
    matcher: Matcher, ref: np.ndarray, cur: np.ndarray, guess: np.ndarray
) -> np.ndarray | None:
    try:
        pose = matcher(ref, cur, guess)
    except Exception:  # a library's refusal or failure counts as no answer
        return None
    return None if pose is None or not np.all(np.isfinite(pose)) else np.asarray(pose)


@dataclasses.dataclass
class RealRun:
    """One candidate's answers on the real pairs (None: no answer) and its CPU time [s]."""

    forward: list[np.ndarray | None]
    backward: list[np.ndarray | None]
    kicked: list[np.ndarray | None]
    cpu: float
    wall: float


def run_real(matcher: Matcher, pairs: list[RealPair], kicks: np.ndarray) -> RealRun:
    matcher(*pairs[0])  # warm up (imports, first calls)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    forward = [_safe(matcher, ref, cur, odo) for ref, cur, odo in pairs]
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    backward = [_safe(matcher, cur, ref, _inverse(odo)) for ref, cur, odo in pairs]
    kicked = [
        _safe(matcher, ref, cur, _compose(odo, kick))
        for (ref, cur, odo), kick in zip(pairs, kicks, strict=True)
    ]
    return RealRun(forward, backward, kicked, cpu, wall)


def _compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    c = Pose2D(*a).compose(Pose2D(*b))
    return np.array([c.x, c.y, c.theta])


def _stats(values: list[tuple[float, float]]) -> str:
    v = np.array(values).reshape(-1, 2)
    if len(v) == 0:
        return "      -         -    "
    return (
        f"{np.median(v[:, 0]) * 1e3:5.1f} / {np.percentile(v[:, 0], 95) * 1e3:6.1f} mm "
        f"{math.degrees(np.median(v[:, 1])):5.2f} / "
        f"{math.degrees(np.percentile(v[:, 1], 95)):5.2f} deg"
    )


def _summary(name: str, r: RealRun, pairs: list[RealPair], common: list[int], base: float) -> str:
    """One candidate's line: speed, then its answers over the ``common`` pairs."""
    odo, fb, kick, back = [], [], [], 0
    for k in common:
        forward, backward, kicked = r.forward[k], r.backward[k], r.kicked[k]
        assert forward is not None
        assert backward is not None
        odo.append(_apart(pairs[k][2], forward))
        fb.append(_apart(np.zeros(3), _compose(forward, backward)))
        if kicked is not None:
            kick.append(_apart(forward, kicked))
            back += kick[-1][0] < 0.01 and kick[-1][1] < math.radians(0.2)
    refused = sum(p is None for p in r.forward)
    wild = 0
    for pose, (_, _, guess) in zip(r.forward, pairs, strict=True):
        if pose is not None:
            shift, turn = _apart(guess, pose)
            wild += shift > 0.15 or turn > math.radians(3)
    per = r.cpu / len(pairs)
    return (
        f"  {name:<26} {len(pairs) / r.cpu:7.0f} {len(pairs) / r.wall:7.0f} {per / base:5.1f}x"
        f"  {_stats(odo)}  {_stats(fb)}  {_stats(kick)} {100 * back / max(len(common), 1):5.1f} %"
        f"  {refused:7d}  {wild:4d}"
    )


def real_benchmark(
    path: Path, count: int, max_gap: float, candidates: list[tuple[str, Matcher]]
) -> None:
    pairs, text = carmen_pairs(path, count, max_gap)
    print(text)
    rng = np.random.default_rng(11)
    angle = rng.uniform(0, math.tau, len(pairs))
    turn = rng.choice([-1.0, 1.0], len(pairs)) * math.radians(3)
    kicks = np.column_stack([0.05 * np.cos(angle), 0.05 * np.sin(angle), turn])
    runs = {name: run_real(matcher, pairs, kicks) for name, matcher in candidates}
    common = [
        k for k in range(len(pairs))
        if all(r.forward[k] is not None and r.backward[k] is not None for r in runs.values())
    ]  # fmt: skip
    print(
        f"pairs per second (one core), cpu and wall; time per pair against umbmark's; over the"
        f" {len(common)} pairs every candidate answered both ways: median / 95th percentile"
    )
    print(
        f"  {'candidate':<26} {'cpu /s':>7} {'wall /s':>7} {'time':>6}  {'match - odometry':^32}"
        f"  {'fwd-bwd composed':^32}  {'kicked - first answer':^32} back  refused  wild"
    )
    base = runs[candidates[0][0]].cpu / len(pairs)
    for name, r in runs.items():
        print(_summary(name, r, pairs, common, base))
    # how the others fare where umbmark's checks refuse (corridors, open space)
    checked = runs[candidates[0][0]]
    refused = [k for k in range(len(pairs)) if checked.forward[k] is None]
    print(f"on the {len(refused)} pairs {candidates[0][0]} refused, the others' answers:")
    for name, r in list(runs.items())[1:]:
        odo, fb = [], []
        for k in refused:
            forward, backward = r.forward[k], r.backward[k]
            if forward is not None:
                odo.append(_apart(pairs[k][2], forward))
                if backward is not None:
                    fb.append(_apart(np.zeros(3), _compose(forward, backward)))
        print(f"  {name:<26} {len(odo):4d} answered  {_stats(odo)}  fwd-bwd {_stats(fb)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=200)
    parser.add_argument("--beams", type=int, nargs="+", default=[360, 720])
    parser.add_argument("--field", type=float, default=360.0, help="simulated: [deg] ahead kept")
    parser.add_argument(
        "--range-step", type=float, default=0.0, help="simulated: ranges rounded [m]"
    )
    parser.add_argument("--carmen", type=Path, help="a CARMEN log: match its real sweeps")
    parser.add_argument("--max-gap", type=float, default=4.0, help="[s] between real sweeps (4)")
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
    kiss = kiss_icp_matcher()
    if kiss is None:
        print("(kiss-icp is not installed: pip install kiss-icp to compare it)")
    else:
        candidates.append(("kiss-icp (registration)", kiss))
    if args.carmen is not None:
        candidates.insert(1, ("umbmark PLICP (no checks)", plicp_unchecked))
        try:
            real_benchmark(args.carmen, args.pairs, args.max_gap, candidates)
        except InputError as err:
            print(f"error: {err}", file=sys.stderr)
            sys.exit(2)
        return
    print(
        "pairs per second (one core), cpu and wall; time per pair against umbmark's;"
        " errors median / 95th percentile"
    )
    for beams in args.beams:
        pairs = make_pairs(beams, args.pairs)
        seen = ""
        if args.field < 360 or args.range_step > 0:
            field, step = args.field, args.range_step
            pairs = [
                (resample(ref, field, step), resample(cur, field, step), guess, true)
                for ref, cur, guess, true in pairs
            ]
            seen = f", seen over {args.field:g} deg ahead, ranges in steps of {args.range_step:g} m"
        print(f"{beams} beams, {len(pairs)} pairs of the room{seen}:")
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

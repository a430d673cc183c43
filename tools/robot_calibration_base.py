"""ROS robot_calibration's base calibration, reimplemented from its source, beside umbmark's
gyro estimator on the same simulated spins.

robot_calibration (github.com/mikeferguson/robot_calibration, Apache-2.0; read at commit
89d9f40, ``robot_calibration/src/base_calibration.cpp`` and ``src/nodes/base_calibration.cpp``)
spins the base in front of a wall at 0.5, 1.5 and 3.0 rad/s (2 rotations at 3.0) both ways.
For each spin it notes the wall's angle in the laser's scan (``scan_start``, before it
aligns the robot with the wall), aligns until that angle is within ``align_tolerance``
(0.2 rad), resets its integrals, spins until the odometry's integrated turn reaches
``2 pi N - v^2 / (2 a)`` (``a = accel_limit``, 2 rad/s^2), stops, waits a second, and keeps

    imu_i  = the gyro's z rate integrated (as read: bias in it),
    odom_i = the odometry's turn rate integrated,
    scan_i = scan_start + 2 pi N - (the wall's angle now)   (v > 0; - 2 pi N for v < 0).

The wall's angle is ``atan2(slope, 1)`` of a straight line fitted to the scan's points
between -0.5 and 0.5 rad, each beam as ``(sin(a) r, cos(a) r)`` (``laserCallback``). Then
(``printCalibrationData``)

    odom_scale = mean((scan_i - odom_i) / odom_i),  track_width_new = track_width (1 + odom_scale)
    imu_scale  = mean((scan_i - imu_i) / imu_i),    gyro_scale_new = gyro_scale (1 + imu_scale)

This file does exactly that on the tests' closed-form robot with a gyro
(``tests/gyro_sim.py``: the robot's true rotation for the odometry's, a wall 1.5 m ahead
ray-cast in closed form, 5 mm of range noise), and runs umbmark's gyro estimator
(:func:`umbmark.estimators.gyro.fit_gyro`) on the same recording's wheels and gyro: alone
(``E_b k_g``), and with the laser's turn of each spin as a heading reference (``k_g`` and
``E_b``). It is a tool beside the package, not part of it.

    PYTHONPATH=src python tools/robot_calibration_base.py
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from gyro_sim import Motion, Recording, Segment, Truth, record  # noqa: E402

#: The node's spins: (velocity [rad/s], rotations), in its order.
SPINS = ((0.5, 1), (1.5, 1), (3.0, 2), (-0.5, 1), (-1.5, 1), (-3.0, 2))
ACCEL_LIMIT = 2.0
ALIGN_TOLERANCE = 0.2
ALIGN_VELOCITY = 0.2
#: The scan's beams the wall is fitted to [rad], and the laser's sweep.
MIN_ANGLE, MAX_ANGLE = -0.5, 0.5
BEAMS = np.linspace(-2.0, 2.0, 721)
WALL = 1.5
RANGE_NOISE = 0.005


def wall_angle(ranges: np.ndarray, angles: np.ndarray) -> float:
    """``laserCallback``: the wall's angle from one scan, as the source computes it."""
    use = (angles >= MIN_ANGLE) & (angles <= MAX_ANGLE) & np.isfinite(ranges)
    px, py = np.sin(angles[use]) * ranges[use], np.cos(angles[use]) * ranges[use]
    px, py = px - px.mean(), py - py.mean()
    n = px.size
    x, y, xx, xy = px.sum(), py.sum(), (px * px).sum(), (px * py).sum()
    return math.atan2((n * xy - x * y) / (n * xx - x * x), 1.0)


def base_calibration(
    scan: list[float], odom: list[float], imu: list[float], track_width: float, gyro_scale: float
) -> tuple[float, float]:
    """``printCalibrationData``: the new track width and the new gyro scale."""
    odom_scale = sum((s - o) / o for s, o in zip(scan, odom, strict=True)) / len(scan)
    imu_scale = sum((s - i) / i for s, i in zip(scan, imu, strict=True)) / len(scan)
    return track_width * (1.0 + odom_scale), gyro_scale * (1.0 + imu_scale)


@dataclass(frozen=True)
class Session:
    """The spins as the node drives them: the motion, and each spin's bookkeeping times."""

    motion: Motion
    spins: tuple[tuple[float, float, float, int, float], ...]  # (before, start, end, N, sign)
    wall: float  # the robot's heading from the wall's normal at the start [rad]


def session(truth: Truth, start_angle: float = 0.05) -> Session:
    """The node's six spins on a robot of ``truth``: a spin of ``2 pi N`` by odometry
    turns it by ``2 pi N E_s / E_b``, at ``E_s / E_b`` times the commanded rate."""
    gain = truth.E_s / truth.E_b
    segments: list[Segment] = [Segment(2.0)]
    spins = []
    t, wall = 2.0, start_angle
    for v, n in SPINS:
        before = t  # scan_start: the wall's angle now, before aligning
        if abs(wall) > ALIGN_TOLERANCE:  # align: turn until within the tolerance
            turn = -(wall - math.copysign(ALIGN_TOLERANCE, wall))
            seg = Segment(abs(turn) / ALIGN_VELOCITY + 0.1, 0.0, turn, ramp=0.1)
            segments.append(seg)
            t, wall = t + seg.duration, wall + turn
        segments.append(Segment(0.25))  # the node sleeps 250 ms after aligning
        t += 0.25
        ramp = abs(v) / ACCEL_LIMIT
        total = 2 * math.pi * n * gain * math.copysign(1.0, v)
        seg = Segment(abs(total) / (abs(v) * gain) + ramp, 0.0, total, ramp=ramp)
        segments.append(seg)
        spins.append((before, t, t + seg.duration + 1.0, n, math.copysign(1.0, v)))
        segments.append(Segment(1.0))  # waits a second: the integrals go on
        t += seg.duration + 1.0
        wall = math.remainder(wall + total, 2 * math.pi)
    segments.append(Segment(2.0))
    return Session(Motion(tuple(segments)), tuple(spins), start_angle)


def _scan(rec: Recording, spins: Session, t: float, rng: np.random.Generator) -> float:
    """The wall's angle in a scan at ``t`` (the robot facing the wall within a quarter
    turn, as the node keeps it)."""
    heading = float(rec.motion.state(np.array([t]))["theta"][0]) + spins.wall
    with np.errstate(divide="ignore"):
        ranges = WALL / np.cos(heading + BEAMS)
    ranges = np.where(np.cos(heading + BEAMS) > 0.05, ranges, np.inf)
    return wall_angle(ranges + rng.normal(size=ranges.size) * RANGE_NOISE, BEAMS)


def measure(rec: Recording, spins: Session, seed: int = 0) -> dict[str, list[float]]:
    """The node's ``scan_``, ``odom_`` and ``imu_`` of each spin, and the laser's turn
    (the wall's angle at the spin's start and end, rightly placed) for umbmark's reference."""
    rng = np.random.default_rng(seed)
    truth, w, g = rec.truth, rec.wheels, rec.gyro
    r, b = 0.5 * truth.nominal_diameter, truth.nominal_wheelbase
    out: dict[str, list[float]] = {k: [] for k in ("scan", "odom", "imu", "laser", "start", "end")}
    for before, start, end, n, sign in spins.spins:
        scan_start = _scan(rec, spins, before, rng)
        angle_start, angle_end = _scan(rec, spins, start, rng), _scan(rec, spins, end, rng)
        out["scan"].append(scan_start + sign * 2 * math.pi * n - angle_end)
        out["laser"].append(sign * 2 * math.pi * n + angle_end - angle_start)
        phi = [np.interp([start, end], w.time, w.angles[:, k]) for k in (0, 1)]
        out["odom"].append(r * (float(np.diff(phi[1])[0]) - float(np.diff(phi[0])[0])) / b)
        rows = (g.time > start) & (g.time <= end)
        out["imu"].append(float(np.sum(g.rate[rows, 2] * np.diff(g.time)[rows[1:]])))
        out["start"].append(start)
        out["end"].append(end)
    return out


ROBOTS = (
    ("wheelbase 3 % long, gyro 2 % high", Truth(wheelbase=0.34 * 1.03, k_g=1.02)),
    ("wheelbase 3 % short, gyro 3 % low", Truth(wheelbase=0.34 * 0.97, k_g=0.97)),
    ("wheelbase right, gyro 3 % high", Truth(wheelbase=0.34, k_g=1.03)),
    ("wheelbase 1 % long, gyro right", Truth(wheelbase=0.34 * 1.01, k_g=1.0)),
)


def compare() -> list[dict[str, float]]:
    """Both on each of :data:`ROBOTS` (equal wheels, a bias of 0.4 deg/s that wanders, a
    1 degree tilt): the figures of the table in ``docs/estimators.md``."""
    from umbmark.estimators.gyro import fit_gyro
    from umbmark.model.kinematics import WheelParams
    from umbmark.scans.gyro_intervals import HeadingReference, gyro_intervals, gyro_reference

    rows = []
    for k, (_, robot) in enumerate(ROBOTS):
        truth = Truth(radius_left=0.05, radius_right=0.05, wheelbase=robot.wheelbase, k_g=robot.k_g)
        spins = session(truth)
        rec = record(spins.motion, truth, seed=k)
        got = measure(rec, spins, seed=k)
        track, gyro_scale = base_calibration(
            got["scan"], got["odom"], got["imu"], truth.nominal_wheelbase, 1.0
        )
        active = WheelParams(truth.nominal_wheelbase, truth.nominal_diameter)
        iv = gyro_intervals(rec.wheels, rec.gyro)
        alone = fit_gyro(iv, active)
        ref = HeadingReference(np.array(got["start"]), np.array(got["end"]), np.array(got["laser"]))
        joint = fit_gyro(iv, active, reference=gyro_reference(rec.gyro, ref))
        rows.append(
            {
                "E_b": truth.E_b / truth.E_s,
                "k_g": truth.k_z,
                "rc_E_b": track / truth.nominal_wheelbase,
                "rc_k_g": gyro_scale,
                "E_b_k_g": truth.E_b * truth.k_z / truth.E_s,
                "ours_E_b_k_g": alone.values["E_b_k_g"],
                "ours_E_b_k_g_se": alone.standard_errors["E_b_k_g"],
                "ours_E_b": joint.values["E_b"],
                "ours_E_b_se": joint.standard_errors["E_b"],
                "ours_k_g": joint.values["k_g"],
                "ours_k_g_se": joint.standard_errors["k_g"],
            }
        )
    return rows


def main() -> None:
    print(
        "| robot | true E_b | true k_g | robot_calibration E_b | robot_calibration k_g "
        "| umbmark, gyro alone: E_b k_g (true) | umbmark with the laser: E_b | k_g |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for (name, _), row in zip(ROBOTS, compare(), strict=True):
        print(
            f"| {name} | {row['E_b']:.4f} | {row['k_g']:.4f} | {row['rc_E_b']:.4f} "
            f"| {row['rc_k_g']:.4f} | {row['ours_E_b_k_g']:.5f} +- {row['ours_E_b_k_g_se']:.1g} "
            f"({row['E_b_k_g']:.5f}) | {row['ours_E_b']:.5f} +- {row['ours_E_b_se']:.1g} "
            f"| {row['ours_k_g']:.5f} +- {row['ours_k_g_se']:.1g} |"
        )


if __name__ == "__main__":
    main()

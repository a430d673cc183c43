"""A drive of a robot with a laser through a room, with its truth, from first principles.

The robot follows constant ``(v, omega)`` segments; its true pose is integrated in closed
form (exact arcs), the wheels' angles are ``(v -/+ omega b / 2) / r`` integrated over
time with the true radii and wheelbase, and the laser sweeps are ray-cast by the virtual
robot's world (``umbmark.robot.world``) at the laser's true mounting. The truth of a
scan matcher is the relative pose of the laser between two sweeps, from the true poses.
Nothing of ``umbmark.scans`` is used here.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from umbmark.model.recording import WheelSeries
from umbmark.model.scans import ScanSeries
from umbmark.robot.base import Pose2D
from umbmark.robot.world import World, room_world

#: The true geometry of the simulated robot: wheel radii [m] and wheelbase [m].
RADIUS_LEFT, RADIUS_RIGHT, WHEELBASE = 0.0505, 0.0495, 0.34
#: The laser's true mounting in the base frame.
LASER = Pose2D(0.12, -0.03, 0.05)

#: An excitation: (duration [s], v [m/s], omega [rad/s]); stays inside room_world.
PATTERN: tuple[tuple[float, float, float], ...] = (
    (4.0, 0.0, 0.6),
    (4.0, 0.0, -0.6),
    (4.0, 0.25, 0.0),
    (4.0, -0.25, 0.0),
    (6.0, 0.2, 0.35),
    (6.0, -0.2, 0.35),
    (3.0, 0.0, 0.8),
)


def ramped(
    pattern: Sequence[tuple[float, float, float]], ramp: float = 0.4, step: float = 0.01
) -> tuple[tuple[float, float, float], ...]:
    """``pattern`` with every change of ``(v, omega)`` spread linearly over ``ramp`` [s]
    (at the end of the segment before it), as a robot's controller accelerates."""
    out: list[tuple[float, float, float]] = []
    for k, (duration, v, w) in enumerate(pattern):
        nv, nw = pattern[k + 1][1:] if k + 1 < len(pattern) else (v, w)
        steady = max(duration - ramp, 0.0) if (nv, nw) != (v, w) else duration
        out.append((steady, v, w))
        n = round((duration - steady) / step)
        for i in range(n):
            f = (i + 0.5) / n
            out.append((step, v + f * (nv - v), w + f * (nw - w)))
    return tuple(out)


@dataclass(frozen=True)
class Drive:
    """The simulated recording and its truth."""

    scans: ScanSeries
    wheels: WheelSeries
    pose_times: np.ndarray  # (k,) [s]
    poses: np.ndarray  # (k, 3) true robot poses in the world
    laser: Pose2D = LASER  # the laser's true mounting

    def laser_pose(self, t: float) -> Pose2D:
        """The laser's true pose in the world at time ``t`` (nearest pose sample)."""
        i = int(np.argmin(np.abs(self.pose_times - t)))
        x, y, th = self.poses[i]
        return Pose2D(float(x), float(y), float(th)).compose(self.laser)

    def laser_motion(self, t0: float, t1: float) -> np.ndarray:
        """The laser's true displacement from ``t0`` to ``t1`` in its frame at ``t0``."""
        rel = self.laser_pose(t1).relative_to(self.laser_pose(t0))
        return np.array([rel.x, rel.y, rel.theta])


def mirrored(ranges: np.ndarray) -> np.ndarray:
    """Ranges ``(n, beams)`` of a full 360 degree sweep (``angle_min = -pi``) as the same
    scanner mounted upside down reports them: its beam at angle ``a`` looks at ``-a``."""
    beams = ranges.shape[1]
    return ranges[:, (beams - np.arange(beams)) % beams]


def simulate(
    pattern: Sequence[tuple[float, float, float]] = PATTERN,
    *,
    world: World | None = None,
    beams: int = 360,
    scan_rate: float = 10.0,
    jitter: float = 0.3,
    wheel_rate: float = 100.0,
    seed: int = 3,
    sweep_time: float = 0.0,
    radii: tuple[float, float] = (RADIUS_LEFT, RADIUS_RIGHT),
    wheelbase: float = WHEELBASE,
    laser: Pose2D = LASER,
) -> Drive:
    """Drive ``pattern`` from the world's start; sweeps at ``scan_rate`` [Hz] with their
    spacing jittered by up to ``jitter`` of a period (irregular rates).

    ``sweep_time`` [s]: a rotating scanner's beams are measured one after the other over
    this time from the sweep's stamp (``time_increment = sweep_time / beams``), each from
    the pose the robot has then (interpolated linearly between the 100 Hz poses); 0: all
    at once. ``radii``, ``wheelbase`` [m] and ``laser`` (its mounting): the truth."""
    world = world or room_world()
    assert world.lidar is not None
    lidar = dataclasses.replace(
        world.lidar, mount=laser, beams=beams, increment=2 * math.pi / beams
    )
    world = dataclasses.replace(world, lidar=lidar)
    rng = np.random.default_rng(seed)
    dt = 1.0 / wheel_rate
    x = y = th = 0.0
    phi_l = phi_r = 0.0
    t = 0.0
    times, poses, angles = [0.0], [(0.0, 0.0, 0.0)], [(0.0, 0.0)]
    for duration, v, w in pattern:
        for _ in range(round(duration * wheel_rate)):
            if abs(w) > 1e-12:
                x += v / w * (math.sin(th + w * dt) - math.sin(th))
                y -= v / w * (math.cos(th + w * dt) - math.cos(th))
            else:
                x += v * dt * math.cos(th)
                y += v * dt * math.sin(th)
            th += w * dt
            phi_l += (v - w * wheelbase / 2) / radii[0] * dt
            phi_r += (v + w * wheelbase / 2) / radii[1] * dt
            t += dt
            times.append(t)
            poses.append((x, y, th))
            angles.append((phi_l, phi_r))
    pose_times, pose_arr = np.array(times), np.array(poses)
    period = 1.0 / scan_rate
    stamps = [0.05]
    while stamps[-1] < t - period:
        stamps.append(stamps[-1] + period * (1.0 + jitter * rng.uniform(-1, 1)))
    stamps = stamps[:-1]
    # the sweeps are taken at the nearest pose sample, and stamped with its time
    index = np.unique(np.round(np.array(stamps) * wheel_rate).astype(int))
    sweeps = []
    for i in index:
        if sweep_time > 0.0:
            sweeps.append(_rolling_sweep(world, pose_times, pose_arr, i, sweep_time, rng))
            continue
        px, py, pth = pose_arr[i]
        scan = world.scan(Pose2D(float(px), float(py), float(pth)), float(pose_times[i]), rng)
        assert scan is not None
        sweeps.append(scan.ranges)
    scans = ScanSeries(
        times=pose_times[index],
        ranges=np.array(sweeps),
        angle_min=lidar.angle_min,
        angle_increment=lidar.increment,
        range_min=lidar.range_min,
        range_max=lidar.range_max,
        time_increment=sweep_time / beams,
    )
    wheels = WheelSeries(time=pose_times, angles=np.array(angles))
    return Drive(scans, wheels, pose_times, pose_arr, laser)


def _rolling_sweep(
    world: World,
    pose_times: np.ndarray,
    poses: np.ndarray,
    i: int,
    sweep_time: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """The ranges of a sweep stamped at ``pose_times[i]`` whose beam ``k`` is cast at
    ``k * sweep_time / beams`` later, from the laser's pose then."""
    lidar = world.lidar
    assert lidar is not None
    k = np.arange(lidar.beams)
    t = pose_times[i] + k * sweep_time / lidar.beams
    x = np.interp(t, pose_times, poses[:, 0])
    y = np.interp(t, pose_times, poses[:, 1])
    th = np.interp(t, pose_times, poses[:, 2])
    m = lidar.mount
    lx = x + np.cos(th) * m.x - np.sin(th) * m.y
    ly = y + np.sin(th) * m.x + np.cos(th) * m.y
    angles = th + m.theta + lidar.angle_min + lidar.increment * k
    true = world.cast(np.column_stack([lx, ly]), angles)
    ranges = true + lidar.sigma * rng.standard_normal(lidar.beams)
    ranges[~np.isfinite(true) | (ranges > lidar.range_max)] = np.inf
    ranges[rng.random(lidar.beams) < lidar.dropout] = np.nan
    return ranges

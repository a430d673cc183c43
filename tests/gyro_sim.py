"""A differential-drive robot with a gyro, in closed form, with its truth: the tests' own.

Every motion is a segment of constant curvature driven with a trapezoidal speed profile:
the path length ``s(t) = L u(t)`` and the heading ``theta(t) = theta_0 + A u(t)`` follow the
same normalised profile ``u`` (accelerate over ``ramp`` seconds, cruise, brake), so the pose
is exact: ``x = x_0 + (L / A)(sin(theta) - sin(theta_0))``, ``y = y_0 - (L / A)(cos(theta) -
cos(theta_0))`` (``x_0 + L u cos(theta_0)`` on a straight). The wheels' true angles are
``(s -/+ (theta - theta_0) b / 2) / r`` with the true radii and wheelbase, sampled at the
wheels' rate, slipping a little (a random walk of ``slip`` times each step's rotation) and
counted in encoder ticks. The gyro, sampled at its rate, reads the true yaw rate (``delay``
late) divided by
its scale ``k_g`` in its own frame, tilted on the base by ``tilt`` (roll, pitch) and read
through a stated transform that does not know it, plus a bias (a constant per axis, the
yaw's with a random walk) and white noise; its accelerometer reads gravity (and the
motion) in the same frame. A heading reference reads the true heading change between two
times with noise; a laser's scan matching the true relative pose of a laser mounted at
``laser`` with noise. Nothing of ``umbmark`` is used but its value types.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from umbmark.model.gyro_series import GyroSeries
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.recording import WheelSeries

G = 9.80665


@dataclass(frozen=True)
class Truth:
    """The simulated robot and its gyro.

    ``radius_left``, ``radius_right``, ``wheelbase``: true [m]; ``nominal_diameter``,
    ``nominal_wheelbase``: what the odometry uses [m]; ``k_g``: the gyro's scale
    (``omega_true = k_g (omega_read - bias)``); ``bias``: the yaw bias at the start [rad/s];
    ``bias_walk``: its random walk [rad/s/sqrt(s)]; ``bias_xy``: the other axes' [rad/s];
    ``noise``: white noise density [rad/s/sqrt(Hz)]; ``tilt``: the IMU's roll and pitch on
    the base [rad]; ``slip``: the wheels' slip per unit rotation; ``ticks``: encoder counts
    per wheel revolution (0: none); ``delay``: how late the gyro reads the motion [s] (a
    reading that is the mean over its period lags by half of it).
    """

    radius_left: float = 0.0505
    radius_right: float = 0.0495
    wheelbase: float = 0.345
    nominal_diameter: float = 0.1
    nominal_wheelbase: float = 0.34
    k_g: float = 1.02
    bias: float = math.radians(0.4)
    bias_walk: float = math.radians(0.0005)
    bias_xy: tuple[float, float] = (math.radians(0.2), math.radians(-0.3))
    noise: float = math.radians(0.005)
    tilt: tuple[float, float] = (math.radians(0.7), math.radians(0.7))
    slip: float = 0.002
    ticks: int = 4096
    delay: float = 0.0

    @property
    def E_d(self) -> float:
        return self.radius_right / self.radius_left

    @property
    def E_b(self) -> float:
        return self.wheelbase / self.nominal_wheelbase

    @property
    def E_s(self) -> float:
        return (self.radius_left + self.radius_right) / self.nominal_diameter

    @property
    def tilt_angle(self) -> float:
        """The angle between the IMU's z and the base's z [rad]."""
        return math.acos(float(_tilt_matrix(self.tilt)[2, 2]))

    @property
    def k_z(self) -> float:
        """The scale of the yaw rate as read through a transform that does not know the
        tilt: the z reading is ``cos(tilt) omega / k_g``, so its scale is ``k_g / cos``."""
        return self.k_g / float(_tilt_matrix(self.tilt)[2, 2])


def _tilt_matrix(tilt: tuple[float, float]) -> np.ndarray:
    """base <- imu for an IMU rolled and pitched by ``tilt``."""
    r, p = tilt
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    return ry @ rx


# --- the motion ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Segment:
    """``length`` [m] and ``turn`` [rad] over ``duration`` [s] (0, 0: a rest), its speed
    ramped up and down over ``ramp`` seconds (None: the motion's)."""

    duration: float
    length: float = 0.0
    turn: float = 0.0
    ramp: float | None = None


def rest(seconds: float) -> Segment:
    return Segment(seconds)


def straight(length: float, speed: float = 0.3, ramp: float = 0.5) -> Segment:
    return Segment(abs(length) / speed + ramp, length, 0.0)


def spin(turn: float, rate: float = math.radians(60), ramp: float = 0.5) -> Segment:
    return Segment(abs(turn) / rate + ramp, 0.0, turn)


def arc(length: float, turn: float, speed: float = 0.25, ramp: float = 0.5) -> Segment:
    return Segment(abs(length) / speed + ramp, length, turn)


def _profile(t: np.ndarray, duration, ramp) -> tuple[np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
    """The normalised profile ``u(t)`` and ``du/dt`` of segments (trapezoids of speed)."""
    ramp = np.maximum(np.minimum(ramp, 0.5 * duration), 1e-9)
    peak = 1.0 / (duration - ramp)
    t = np.clip(t, 0.0, duration)
    up, down = t < ramp, t > duration - ramp
    u = np.where(
        up, 0.5 * peak * t * t / ramp,
        np.where(down, 1.0 - 0.5 * peak * (duration - t) ** 2 / ramp, peak * (t - 0.5 * ramp)),
    )  # fmt: skip
    rate = np.where(up, peak * t / ramp, np.where(down, peak * (duration - t) / ramp, peak))
    return u, rate


@dataclass(frozen=True)
class Motion:
    """A program of segments, evaluated exactly at any times."""

    segments: tuple[Segment, ...]
    ramp: float = 0.5
    starts: tuple[float, ...] = field(init=False)
    poses: tuple[tuple[float, float, float, float], ...] = field(init=False)

    def __post_init__(self) -> None:
        starts, poses, t = [], [], 0.0
        x = y = th = s = 0.0
        for seg in self.segments:
            starts.append(t)
            poses.append((x, y, th, s))
            x, y = (float(v) for v in _advance(x, y, th, seg.length, seg.turn, 1.0))
            th, s, t = th + seg.turn, s + seg.length, t + seg.duration
        starts.append(t)
        poses.append((x, y, th, s))
        object.__setattr__(self, "starts", tuple(starts))
        object.__setattr__(self, "poses", tuple(poses))

    @property
    def duration(self) -> float:
        return self.starts[-1]

    def state(self, t: np.ndarray) -> dict[str, np.ndarray]:
        """``x, y, theta, s`` (path length), ``v``, ``omega`` at times ``t``."""
        t = np.asarray(t, dtype=float)
        k = np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0, len(self.segments) - 1)
        seg = self.segments
        duration = np.array([g.duration for g in seg])[k]
        length = np.array([g.length for g in seg])[k]
        turn = np.array([g.turn for g in seg])[k]
        ramp = np.array([self.ramp if g.ramp is None else g.ramp for g in seg])[k]
        x0, y0, th0, s0 = (np.array(p)[k] for p in zip(*self.poses[:-1], strict=True))
        u, rate = _profile(t - np.array(self.starts)[k], duration, ramp)
        resting = (length == 0.0) & (turn == 0.0)
        u, rate = np.where(resting, 0.0, u), np.where(resting, 0.0, rate)
        x, y = _advance(x0, y0, th0, length, turn, u)
        return {
            "x": x, "y": y, "theta": th0 + turn * u, "s": s0 + length * u,
            "v": length * rate, "omega": turn * rate,
        }  # fmt: skip


def _advance(x, y, th, length, turn, u):  # type: ignore[no-untyped-def]
    """Where a constant-curvature segment from ``(x, y, th)`` is after the share ``u``."""
    straight = np.abs(turn) < 1e-12
    safe = np.where(straight, 1.0, turn)
    radius = length / safe
    th1 = th + turn * u
    ax = np.where(straight, length * u * np.cos(th), radius * (np.sin(th1) - np.sin(th)))
    ay = np.where(straight, length * u * np.sin(th), -radius * (np.cos(th1) - np.cos(th)))
    return x + ax, y + ay


# --- the sensors --------------------------------------------------------------------------


@dataclass(frozen=True)
class Recording:
    motion: Motion
    truth: Truth
    wheels: WheelSeries
    gyro: GyroSeries
    bias: np.ndarray  # the true yaw bias at the gyro's samples [rad/s]

    def bias_at(self, t: np.ndarray) -> np.ndarray:
        return np.interp(t, self.gyro.time, self.bias)


def record(
    motion: Motion,
    truth: Truth = Truth(),
    *,
    wheel_rate: float = 50.0,
    gyro_rate: float = 200.0,
    seed: int = 0,
    accel: bool = True,
) -> Recording:
    """The wheels and the gyro of ``truth`` driving ``motion``."""
    rng = np.random.default_rng(seed)
    tw = np.arange(0.0, motion.duration, 1.0 / wheel_rate)
    st = motion.state(tw)
    half = 0.5 * truth.wheelbase * st["theta"]
    left, right = (st["s"] - half) / truth.radius_left, (st["s"] + half) / truth.radius_right
    angles = np.column_stack([left, right])
    steps = np.abs(np.diff(angles, axis=0))
    slip = np.vstack(
        [np.zeros((1, 2)), np.cumsum(rng.normal(size=steps.shape) * truth.slip * steps, 0)]
    )
    angles = angles + slip
    if truth.ticks:
        per = 2.0 * math.pi / truth.ticks
        angles = np.round(angles / per) * per
    tg = np.arange(0.0, motion.duration, 1.0 / gyro_rate) + 0.37 / gyro_rate
    tg = tg[tg < tw[-1]]
    sg = motion.state(tg - truth.delay)
    tilt = _tilt_matrix(truth.tilt)
    true_rate = np.column_stack([np.zeros_like(tg), np.zeros_like(tg), sg["omega"]])
    in_imu = true_rate @ tilt / truth.k_g  # R^T w, row by row
    dt = 1.0 / gyro_rate
    walk = np.cumsum(rng.normal(size=tg.size)) * truth.bias_walk * math.sqrt(dt)
    bias_z = truth.bias + walk
    bias = np.column_stack(
        [np.full(tg.size, truth.bias_xy[0]), np.full(tg.size, truth.bias_xy[1]), bias_z]
    )
    white = rng.normal(size=(tg.size, 3)) * truth.noise * math.sqrt(gyro_rate)
    rate = in_imu + bias + white
    acc = None
    if accel:
        specific = np.column_stack(
            [np.gradient(sg["v"], tg), sg["v"] * sg["omega"], np.full(tg.size, G)]
        )
        acc = specific @ tilt + rng.normal(size=(tg.size, 3)) * 0.02
    gyro = GyroSeries(tg, rate, acc, frame="imu_link", source="simulated gyro")
    return Recording(motion, truth, WheelSeries(tw, angles), gyro, bias_z)


def heading_reference(
    rec: Recording, every: float = 1.0, noise: float = math.radians(0.2), seed: int = 1
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(start, end, yaw)``: the true heading change over consecutive stretches of
    ``every`` seconds, with white noise of ``noise`` [rad] (a reference's reading)."""
    rng = np.random.default_rng(seed)
    edges = np.arange(rec.gyro.time[0] + 0.05, rec.gyro.time[-1] - 0.05, every)
    theta = rec.motion.state(edges)["theta"]
    yaw = np.diff(theta) + rng.normal(size=edges.size - 1) * noise
    return edges[:-1], edges[1:], yaw


def scan_reference(
    rec: Recording,
    laser: tuple[float, float, float] = (0.12, -0.03, 0.05),
    every: float = 1.0,
    noise: tuple[float, float, float] = (0.002, 0.002, math.radians(0.3)),
    seed: int = 2,
    moving_only: bool = True,
) -> MotionIntervals:
    """A laser's scan matching between sweeps ``every`` seconds apart: the laser's true
    relative pose with noise, and the recorded wheels' rotation over each interval."""
    rng = np.random.default_rng(seed)
    edges = np.arange(rec.gyro.time[0] + 0.05, rec.gyro.time[-1] - 0.05, every)
    st = rec.motion.state(edges)
    lx, ly, lth = laser
    c, s = np.cos(st["theta"]), np.sin(st["theta"])
    px, py = st["x"] + c * lx - s * ly, st["y"] + s * lx + c * ly
    pth = st["theta"] + lth
    dx, dy = np.diff(px), np.diff(py)
    c0, s0 = np.cos(pth[:-1]), np.sin(pth[:-1])
    motion = np.column_stack([c0 * dx + s0 * dy, -s0 * dx + c0 * dy, np.diff(pth)])
    motion = motion + rng.normal(size=motion.shape) * np.array(noise)
    w = rec.wheels
    phi = [np.diff(np.interp(edges, w.time, w.angles[:, k])) for k in (0, 1)]
    keep = np.ones(edges.size - 1, dtype=bool)
    if moving_only:
        keep = np.maximum(np.abs(phi[0]), np.abs(phi[1])) > 0.02
    return MotionIntervals(
        duration=np.diff(edges)[keep],
        phi_left=phi[0][keep],
        phi_right=phi[1][keep],
        sensor_motion=motion[keep],
        start_time=edges[:-1][keep],
        source="simulated scan matching",
    )


def mixed_program(minutes: float = 10.0, rests: bool = True) -> Motion:
    """Straights, spins both ways and arcs, with rests between them (or none)."""
    cycle: list[Segment] = [
        straight(2.0), spin(math.pi), straight(2.0, speed=0.2), spin(-math.pi),
        arc(1.5, math.pi / 2), spin(2 * math.pi, rate=math.radians(90)),
        arc(1.5, -math.pi / 2), straight(-1.0, speed=0.15), spin(-2 * math.pi),
        straight(1.0, speed=0.4),
    ]  # fmt: skip
    out: list[Segment] = []
    while sum(seg.duration for seg in out) < 60.0 * minutes:
        for seg in cycle:
            out.append(seg)
            if rests:
                out.append(rest(3.0))
    return Motion((rest(4.0), *out))


def program(segments: Sequence[Segment], repeat: int = 1, rests: float = 0.0) -> Motion:
    out: list[Segment] = [rest(4.0)] if rests else []
    for _ in range(repeat):
        for seg in segments:
            out.append(seg)
            if rests:
                out.append(rest(rests))
    return Motion(tuple(out))

"""A robot driven by wheel-rate programs, with a known effective wheelbase per turning share.

Squares (straight legs that weave as a line-following controller does, turns on the spot)
and circles of given turning share, driven by a robot whose true wheel radii and scrub
model ``b_eff(w) = b_arc + (b_spot - b_arc) w`` are chosen here; the true path is
integrated here with exact arcs (numpy, independent of umbmark), with Gaussian wheel slip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from umbmark.model.recording import RunLog

#: Sampling period [s], as OptiOdom's 20 Hz.
DT = 0.05
#: Nominal wheel radius [m] and wheelbase [m] (OptiOdom's robot).
RADIUS = 0.042
WHEELBASE = 0.2
#: Wheel rate on legs and circles [rad/s] (0.2 m/s) and in spot turns [rad/s].
RATE = 0.2 / RADIUS
TURN_RATE = 3.0


@dataclass(frozen=True)
class Robot:
    """True wheel radii [m] and the scrub model's wheelbases [m]."""

    r_left: float = 0.0419
    r_right: float = 0.0421
    b_arc: float = 0.200
    b_spot: float = 0.206


SCRUB = Robot()
NO_SCRUB = Robot(b_arc=0.203, b_spot=0.203)


def _ramp(n: int) -> np.ndarray:
    """Speed profile of ``n`` steps: up and down in 0.5 s."""
    t = np.arange(n) * DT
    return np.clip(np.minimum(t + DT, n * DT - t) / 0.5, 0.0, 1.0)


def square_rates(side: float, sign: int, weave: float, phase: float) -> np.ndarray:
    """Wheel rates (n, 2) [rad/s] of a square: legs whose wheel rates differ by ``weave *
    sin(2 pi t / 4 s + phase)`` [rad/s] (the heading weaves by a few degrees), each
    followed by a 90 degree turn on the spot (``sign`` 1: ccw)."""
    parts = []
    for _ in range(4):
        n = round(side / (RATE * RADIUS) / DT) + 10
        diff = weave * np.sin(2 * math.pi * np.arange(n) * DT / 4.0 + phase)
        parts.append(np.column_stack([RATE - diff, RATE + diff]) * _ramp(n)[:, None])
        m = round(WHEELBASE * math.pi / 4 / (TURN_RATE * RADIUS) / DT) + 10
        parts.append(np.column_stack([-sign * TURN_RATE * _ramp(m), sign * TURN_RATE * _ramp(m)]))
    return np.vstack(parts)


def circle_rates(share: float, sign: int) -> np.ndarray:
    """Wheel rates (n, 2) [rad/s] of one full circle at turning share ``share`` (radius
    ``b / (2 share)``), ccw for ``sign`` 1."""
    slow, fast = RATE * (1 - share), RATE * (1 + share)
    left, right = (slow, fast) if sign > 0 else (fast, slow)
    duration = 2 * math.pi * WHEELBASE / (RADIUS * 2 * RATE * share)
    n = round(duration / DT) + 10
    return np.column_stack([left, right]) * _ramp(n)[:, None]


def drive(rates: np.ndarray, robot: Robot, slip: float, rng: np.random.Generator) -> RunLog:
    """The run of wheel ``rates`` (n, 2): wheel angles from 0 and the true path (exact arcs,
    ``b_eff`` of each step's true turning share), slip ``slip * sqrt(travel)`` per wheel."""
    steps = rates * DT
    d_left = robot.r_left * steps[:, 0]
    d_right = robot.r_right * steps[:, 1]
    d_left = d_left + slip * np.sqrt(np.abs(d_left)) * rng.normal(size=d_left.size)
    d_right = d_right + slip * np.sqrt(np.abs(d_right)) * rng.normal(size=d_right.size)
    moving = np.abs(d_left) + np.abs(d_right)
    share = np.abs(d_right - d_left) / np.where(moving > 0, moving, 1.0)
    b_eff = robot.b_arc + (robot.b_spot - robot.b_arc) * share
    dth = (d_right - d_left) / b_eff
    ds = 0.5 * (d_left + d_right)
    theta = np.cumsum(dth)
    chord = ds * np.sinc(dth / (2 * math.pi))  # sin(dth / 2) / (dth / 2)
    mid = theta - 0.5 * dth
    path = np.column_stack([np.cumsum(chord * np.cos(mid)), np.cumsum(chord * np.sin(mid)), theta])
    truth = np.vstack([np.zeros((1, 3)), path])
    angles = np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    return RunLog(np.arange(angles.shape[0]) * DT, angles, truth)


def squares(robot: Robot, seed: int, runs: int = 6, side: float = 1.5) -> list[RunLog]:
    """Squares, alternately cw and ccw, legs weaving by about 5 degrees, slip 3e-4."""
    rng = np.random.default_rng(seed)
    return [
        drive(square_rates(side, 1 if k % 2 else -1, 0.3, rng.uniform(0, 6.3)), robot, 3e-4, rng)
        for k in range(runs)
    ]


def circles(robot: Robot, seed: int, shares: tuple[float, ...] = (0.15, 0.3, 0.5)) -> list[RunLog]:
    """One circle at each turning share, each way (radii b / (2 share)), slip 3e-4."""
    rng = np.random.default_rng(seed)
    return [
        drive(circle_rates(share, sign), robot, 3e-4, rng) for share in shares for sign in (1, -1)
    ]


def write_session(folder: Path, logs: list[RunLog], rest: float = 2.0) -> Path:
    """Write runs as a run-log folder (wheel angles, one CSV per run, still ``rest`` [s]
    before and after), nominal D 0.084 m, b 0.2 m."""
    from umbmark.sources.runlog.reader import LogMetadata
    from umbmark.sources.runlog.writer import write_log_csv, write_metadata

    write_metadata(
        folder, LogMetadata(wheel_diameter=2 * RADIUS, wheelbase=WHEELBASE, wheel_data="angles")
    )
    still = round(rest / DT)
    for k, log in enumerate(logs):
        angles = np.vstack([np.repeat(log.wheel_angles[:1], still, 0), log.wheel_angles])
        angles = np.vstack([angles, np.repeat(angles[-1:], still, 0)])
        truth = np.vstack([np.repeat(log.truth[:1], still, 0), log.truth])
        truth = np.vstack([truth, np.repeat(truth[-1:], still, 0)])
        time = np.arange(angles.shape[0]) * DT
        write_log_csv(folder / f"run-{k + 1:02d}.csv", time, truth, angles)
    return folder

"""The simulator's model as a plain per-sample Python loop, one run at a time.

Slow on purpose: it is the reference that :func:`umbmark.sim.engine.simulate` is checked
against (``tests/sim/test_engine.py``) and timed against (``benchmarks/bench_simulator.py``,
which puts ``tests/`` on its path). Noise-free robots only.
"""

from __future__ import annotations

import math

from umbmark.core.conventions import Direction
from umbmark.sim.paths import Path
from umbmark.sim.robot import ControlConfig, SimRobot

__all__ = ["simulate_run_loop"]


def _chord(ds: float, dth: float, theta: float, method: str) -> tuple[float, float]:
    if method == "arc":
        half = 0.5 * dth
        return (ds if half == 0.0 else ds * math.sin(half) / half), theta + half
    if method == "midpoint":
        return ds, theta + 0.5 * dth
    return ds, theta + dth


def simulate_run_loop(
    robot: SimRobot,
    path: Path,
    direction: Direction,
    control: ControlConfig | None = None,
) -> tuple[tuple[float, float, float], tuple[float, float, float], int]:
    """One noise-free run of the same closed-loop model, sample by sample.

    Returns
    -------
    true_end, odometry_end : tuple of 3 floats
        ``x, y, theta`` [m, rad].
    samples : int
        Sampling periods simulated.
    """
    if not robot.noise.is_noise_free:
        raise ValueError("the reference loop simulates noise-free robots only")
    c = control or ControlConfig()
    o = robot.odometry
    dt = c.dt
    half_b = 0.5 * o.wheelbase
    cpr = o.gear_ratio * o.encoder_resolution
    meters_per_count = math.pi * o.wheel_diameter / cpr
    omega_max = c.turn_wheel_speed / half_b
    omega_acc = c.acceleration / half_b
    omega_creep = c.creep_speed / half_b
    stop_distance = 2.0 * meters_per_count * max(o.c_left, o.c_right)
    starts, heads = path.references(direction.turn_sign)

    X = Y = TH = x = y = th = 0.0
    phi_l = phi_r = 0.0
    cnt_l = cnt_r = 0
    v = w = 0.0
    steps = 0
    for k, segment in enumerate(path.segments):
        sx, sy = float(starts[k, 0]), float(starts[k, 1])
        h0, h1 = float(heads[k, 0]), float(heads[k, 1])
        cos_h, sin_h = math.cos(h0), math.sin(h0)
        while True:
            if segment.kind == "straight":
                along = (x - sx) * cos_h + (y - sy) * sin_h
                cross = -(x - sx) * sin_h + (y - sy) * cos_h
                remaining = segment.amount - along
                done = remaining <= stop_distance
                rest = max(remaining, 0.0)
                half = 0.5 * c.acceleration * dt
                brake = math.sqrt(half * half + 2 * c.acceleration * rest) - half
                v_goal = min(max(brake, c.creep_speed), c.speed, rest / dt)
                w_goal = c.heading_gain * (h0 - th) - c.cross_track_gain * cross
            else:
                err = h1 - th
                done = abs(err) <= 2.0 * stop_distance / o.wheelbase
                v_goal = 0.0
                half = 0.5 * omega_acc * dt
                brake = math.sqrt(half * half + 2 * omega_acc * abs(err)) - half
                rate = min(max(brake, omega_creep), omega_max, abs(err) / dt)
                w_goal = math.copysign(rate, err) if err != 0 else 0.0
            if done:
                v = w = 0.0
            else:
                a = c.acceleration * dt
                v = v + min(max(v_goal - v, -a), a)
                w = w + min(max(w_goal - w, -omega_acc * dt), omega_acc * dt)
                w = min(max(w, -omega_max), omega_max)
                # The last period may brake harder than the ramp.
                if segment.kind == "straight":
                    v = min(v, max(remaining, 0.0) / dt)
                else:
                    cap = abs(h1 - th) / dt
                    w = min(max(w, -cap), cap)
            dphi_l = (v - w * half_b) * (dt / (0.5 * o.c_left * o.wheel_diameter))
            dphi_r = (v + w * half_b) * (dt / (0.5 * o.c_right * o.wheel_diameter))
            du_l = dphi_l * 0.5 * robot.diameter_left
            du_r = dphi_r * 0.5 * robot.diameter_right
            ds = 0.5 * (du_r + du_l)
            dth = (du_r - du_l) / robot.wheelbase
            chord, heading = _chord(ds, dth, TH, "arc")
            X += chord * math.cos(heading)
            Y += chord * math.sin(heading)
            TH += dth
            phi_l += dphi_l
            phi_r += dphi_r
            new_l = math.floor(phi_l * cpr / (2 * math.pi))
            new_r = math.floor(phi_r * cpr / (2 * math.pi))
            d_l = o.c_left * meters_per_count * (new_l - cnt_l)
            d_r = o.c_right * meters_per_count * (new_r - cnt_r)
            cnt_l, cnt_r = new_l, new_r
            chord, heading = _chord(0.5 * (d_r + d_l), (d_r - d_l) / o.wheelbase, th, c.method)
            x += chord * math.cos(heading)
            y += chord * math.sin(heading)
            th += (d_r - d_l) / o.wheelbase
            steps += 1
            if done:
                break
    return (X, Y, TH), (x, y, th), steps

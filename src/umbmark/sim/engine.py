"""The closed-loop simulator, vectorized over runs (and robots).

Every sampling period, for every run at once:

1. The controller reads the robot's **odometry** pose and commands a body speed ``v`` and
   turn rate ``omega``: on a leg it follows the ideal line from the leg's start corner and
   slows to stop where its odometry says the leg ends; in a turn it rotates on the spot
   until its odometry heading reaches the target, to within two encoder pulses. Speeds
   ramp with an acceleration limit, brake in time, creep at the end and never command a
   step past the target.
2. The commands become wheel rotations through the robot's **own** model (its ``D_n``,
   ``c_L``, ``c_R``, ``b``): as on a real robot, the wheel speed loops track them.
3. The wheels move the robot over the floor by their **true** diameters, less slip and
   bumps; the true pose advances by the exact arc.
4. The encoders quantize the wheel rotations; the odometry integrates the count
   increments (Eqs. 2.1, 2.2, 4.33) with the robot's own parameters.

Runs finish at different times; a finished run stands still.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..conventions import Direction
from ..kinematics import chord_step
from ..runs import EndPose, Run
from .paths import Path
from .robot import ControlConfig, VirtualRobot

__all__ = ["SimResult", "Trace", "simulate"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Trace:
    """Time series of a simulation (recorded on request).

    Attributes
    ----------
    time : array, shape (T,)
        Sample times [s], from 0.
    true_pose : array, shape (R, T, 3)
        True ``x, y, theta`` of every run [m, rad].
    counts : array, shape (R, T, 2)
        Cumulative encoder counts ``left, right``.
    odometry_pose : array, shape (R, T, 3)
        The robot's odometry pose [m, rad].
    """

    time: FloatArray
    true_pose: FloatArray
    counts: IntArray
    odometry_pose: FloatArray


@dataclass(frozen=True)
class SimResult:
    """End poses of simulated runs.

    Attributes
    ----------
    directions : tuple of Direction
    true_end, odometry_end : array, shape (R, 3)
        True and odometry end poses ``x, y, theta`` [m, rad], headings unwrapped.
    duration : array, shape (R,)
        Time each run took [s].
    samples_used : array, shape (R,)
        Sampling periods each run took (its last sample, in a trace, is this index).
    samples : int
        Number of sampling periods simulated (for the longest run).
    trace : Trace or None
    """

    directions: tuple[Direction, ...]
    true_end: FloatArray
    odometry_end: FloatArray
    duration: FloatArray
    samples_used: IntArray
    samples: int
    trace: Trace | None = None

    def runs(self, label: str = "sim") -> list[Run]:
        """The simulated runs as :class:`umbmark.runs.Run` values."""
        return [
            Run(
                direction=d,
                true_end=EndPose(*(float(v) for v in self.true_end[i])),
                odometry_end=EndPose(*(float(v) for v in self.odometry_end[i])),
                label=f"{label} run {i + 1}",
            )
            for i, d in enumerate(self.directions)
        ]


def _robot_arrays(robots: Sequence[VirtualRobot]) -> dict[str, FloatArray]:
    def col(fn: Callable[[VirtualRobot], float]) -> FloatArray:
        return np.array([fn(r) for r in robots], dtype=np.float64)

    return {
        "D_n": col(lambda r: r.odometry.wheel_diameter),
        "b_odo": col(lambda r: r.odometry.wheelbase),
        "c_L": col(lambda r: r.odometry.c_left),
        "c_R": col(lambda r: r.odometry.c_right),
        "cpr": col(lambda r: r.odometry.gear_ratio * r.odometry.encoder_resolution),
        "D_L": col(lambda r: r.diameter_left),
        "D_R": col(lambda r: r.diameter_right),
        "b_true": col(lambda r: r.wheelbase),
        "slip": col(lambda r: r.noise.slip),
        "bump_rate": col(lambda r: r.noise.bump_rate),
        "bump_size": col(lambda r: r.noise.bump_size),
    }


def simulate(
    robots: VirtualRobot | Sequence[VirtualRobot],
    path: Path,
    directions: Sequence[Direction],
    control: ControlConfig | None = None,
    rng: np.random.Generator | None = None,
    *,
    record: bool = False,
    progress: Callable[[float], None] | None = None,
) -> SimResult:
    """Drive ``path`` once per entry of ``directions``, all runs in one vectorized pass.

    Parameters
    ----------
    robots : VirtualRobot or sequence of VirtualRobot
        One robot for every run, or one per run (length R).
    path : Path
        The path, written for ccw travel; cw runs mirror its turns.
    directions : sequence of Direction, length R
    control : ControlConfig, optional
    rng : numpy.random.Generator, optional
        Source of the non-systematic errors (needed only when a robot has noise).
    record : bool
        Keep the time series (memory grows as R x samples).
    progress : callable, optional
        Called now and then with the fraction of runs finished.

    Returns
    -------
    SimResult
    """
    control = control or ControlConfig()
    n_runs = len(directions)
    if n_runs == 0:
        raise ValueError("no runs to simulate")
    fleet = [robots] * n_runs if isinstance(robots, VirtualRobot) else list(robots)
    if len(fleet) != n_runs:
        raise ValueError(f"{len(fleet)} robots for {n_runs} runs")
    p = _robot_arrays(fleet)
    has_slip = bool(np.any(p["slip"] > 0))
    has_bumps = bool(np.any(p["bump_rate"] * p["bump_size"] > 0))
    noisy = has_slip or has_bumps
    if noisy and rng is None:
        raise ValueError("a robot has non-systematic errors: pass a random generator")

    dt = control.dt
    half_b = 0.5 * p["b_odo"]
    meters_per_count = np.pi * p["D_n"] / p["cpr"]  # c_m, Eq. 2.1
    counts_per_rad = p["cpr"] / (2.0 * np.pi)
    omega_max = control.turn_wheel_speed / half_b
    omega_acc = control.acceleration / half_b
    omega_creep = control.creep_speed / half_b
    # The robot stops within two encoder pulses of its target, as its odometry sees it.
    stop_distance = 2.0 * meters_per_count * np.maximum(p["c_L"], p["c_R"])
    stop_angle = 2.0 * stop_distance / p["b_odo"]

    seg_straight = np.array([s.kind == "straight" for s in path.segments])
    seg_amount = np.array([s.amount for s in path.segments])
    n_seg = len(path.segments)
    # One lookup table of every segment's references, ccw rows first, then cw:
    # start x, start y, heading at start and end, cos and sin of the start heading.
    table = np.concatenate(
        [
            np.column_stack([st, hd, np.cos(hd[:, 0]), np.sin(hd[:, 0])])
            for st, hd in (path.references(+1), path.references(-1))
        ]
    )
    row0 = np.array([0 if d is Direction.CCW else n_seg for d in directions])
    wheel_rad_l = dt / (0.5 * p["c_L"] * p["D_n"])  # wheel rotation per (m/s) for dt
    wheel_rad_r = dt / (0.5 * p["c_R"] * p["D_n"])
    odo_l = p["c_L"] * meters_per_count  # Eq. 4.33: metres per count as the robot sees it
    odo_r = p["c_R"] * meters_per_count

    zeros = np.zeros(n_runs)
    X, Y, TH = zeros.copy(), zeros.copy(), zeros.copy()  # true pose
    x, y, th = zeros.copy(), zeros.copy(), zeros.copy()  # odometry pose
    phi_l, phi_r = zeros.copy(), zeros.copy()  # wheel rotation [rad]
    cnt_l = np.zeros(n_runs, dtype=np.int64)
    cnt_r = np.zeros(n_runs, dtype=np.int64)
    v, w = zeros.copy(), zeros.copy()  # commanded body speeds (as the robot believes)
    seg = np.zeros(n_runs, dtype=np.int64)
    finished_at = np.full(n_runs, -1, dtype=np.int64)

    expected = path.length / control.speed + sum(
        abs(s.amount) for s in path.segments if s.kind == "turn"
    ) / float(omega_max.min())
    max_steps = int(4 * expected / dt) + 2000
    trace: dict[str, list[NDArray[np.generic]]] = {"t": [], "true": [], "cnt": [], "odo": []}

    def keep(step: int) -> None:
        trace["t"].append(np.array(step * dt))
        trace["true"].append(np.stack([X, Y, TH], axis=-1))
        trace["cnt"].append(np.stack([cnt_l, cnt_r], axis=-1))
        trace["odo"].append(np.stack([x, y, th], axis=-1))

    if record:
        keep(0)
    step = 0
    while True:
        active = seg < n_seg
        if not active.any():
            break
        if step >= max_steps:
            raise RuntimeError(f"simulation did not finish within {max_steps} samples")
        k = np.minimum(seg, n_seg - 1)
        straight = active & seg_straight[k]
        turning = active & ~seg_straight[k]
        sx, sy, h0, h1, cos_h, sin_h = table[row0 + k].T

        # Controller, in the odometry frame.
        along = (x - sx) * cos_h + (y - sy) * sin_h
        cross = -(x - sx) * sin_h + (y - sy) * cos_h
        remaining = seg_amount[k] - along
        err = h1 - th
        done = (straight & (remaining <= stop_distance)) | (turning & (np.abs(err) <= stop_angle))
        # Speed profiles that brake in time, creep near the target, and never step past
        # it (at most the rest of the way in one period).
        rest = np.maximum(remaining, 0.0)
        v_goal = np.where(
            straight,
            np.minimum(
                _clip(_braking(rest, control.acceleration, dt), control.creep_speed, control.speed),
                rest / dt,
            ),
            0.0,
        )
        w_goal = np.where(
            straight,
            control.heading_gain * (h0 - th) - control.cross_track_gain * cross,
            np.sign(err)
            * np.minimum(
                _clip(_braking(np.abs(err), omega_acc, dt), omega_creep, omega_max),
                np.abs(err) / dt,
            ),
        )
        moving = active & ~done
        v = np.where(
            moving,
            v + _clip(v_goal - v, -control.acceleration * dt, control.acceleration * dt),
            0.0,
        )
        w = np.where(
            moving,
            _clip(w + _clip(w_goal - w, -omega_acc * dt, omega_acc * dt), -omega_max, omega_max),
            0.0,
        )
        # The last period may brake harder than the ramp: never step past the target.
        v = np.where(straight, np.minimum(v, rest / dt), v)
        w_cap = np.abs(err) / dt
        w = np.where(turning, _clip(w, -w_cap, w_cap), w)
        seg = seg + done
        finished_at = np.where(done & (seg == n_seg), step, finished_at)

        # Wheels turn as the robot's own model says they should.
        dphi_l = (v - w * half_b) * wheel_rad_l
        dphi_r = (v + w * half_b) * wheel_rad_r
        # The floor moves by the true diameters, less slip and bumps.
        du_l = dphi_l * 0.5 * p["D_L"]
        du_r = dphi_r * 0.5 * p["D_R"]
        if noisy:
            assert rng is not None
            du_l, du_r = _non_systematic(du_l, du_r, p, rng, has_slip, has_bumps)
        ds = 0.5 * (du_r + du_l)
        dth = (du_r - du_l) / p["b_true"]
        chord, heading = chord_step(ds, dth, TH, "arc")
        X = X + chord * np.cos(heading)
        Y = Y + chord * np.sin(heading)
        TH = TH + dth

        # Encoders and odometry.
        phi_l = phi_l + dphi_l
        phi_r = phi_r + dphi_r
        new_l = np.floor(phi_l * counts_per_rad).astype(np.int64)
        new_r = np.floor(phi_r * counts_per_rad).astype(np.int64)
        d_l = odo_l * (new_l - cnt_l)
        d_r = odo_r * (new_r - cnt_r)
        cnt_l, cnt_r = new_l, new_r
        ods = 0.5 * (d_r + d_l)
        odth = (d_r - d_l) / p["b_odo"]
        chord, heading = chord_step(ods, odth, th, control.method)
        x = x + chord * np.cos(heading)
        y = y + chord * np.sin(heading)
        th = th + odth

        step += 1
        if record:
            keep(step)
        if progress is not None and step % 200 == 0:
            progress(float(np.mean(seg >= n_seg)))
    if progress is not None:
        progress(1.0)

    out_trace = None
    if record:
        out_trace = Trace(
            time=np.array(trace["t"], dtype=np.float64),
            true_pose=np.stack(trace["true"], axis=1).astype(np.float64),
            counts=np.stack(trace["cnt"], axis=1).astype(np.int64),
            odometry_pose=np.stack(trace["odo"], axis=1).astype(np.float64),
        )
    return SimResult(
        directions=tuple(directions),
        true_end=np.stack([X, Y, TH], axis=-1),
        odometry_end=np.stack([x, y, th], axis=-1),
        duration=((finished_at + 1) * dt).astype(np.float64),
        samples_used=(finished_at + 1).astype(np.int64),
        samples=step,
        trace=out_trace,
    )


def _clip(value: FloatArray, low: FloatArray | float, high: FloatArray | float) -> FloatArray:
    """``np.clip`` without its per-call overhead (it matters once per sampling period)."""
    return np.minimum(np.maximum(value, low), high)


def _braking(distance: FloatArray, deceleration: FloatArray | float, dt: float) -> FloatArray:
    """Fastest speed from which a discrete stop (speed falling by ``a dt`` per period)
    ends within ``distance``: ``sqrt((a dt / 2)^2 + 2 a d) - a dt / 2``."""
    half = 0.5 * deceleration * dt
    return np.asarray(np.sqrt(half * half + 2.0 * deceleration * distance) - half)


def _non_systematic(
    du_l: FloatArray,
    du_r: FloatArray,
    p: dict[str, FloatArray],
    rng: np.random.Generator,
    slip: bool,
    bumps: bool,
) -> tuple[FloatArray, FloatArray]:
    """Slip (variance proportional to travel) and bumps (rotation without travel)."""
    out = []
    for du in (du_l, du_r):
        travel = np.abs(du)
        moved = du
        if slip:
            moved = moved + p["slip"] * np.sqrt(travel) * rng.standard_normal(du.shape)
        if bumps:
            bump = rng.random(du.shape) < p["bump_rate"] * travel
            moved = moved - np.where(bump, np.sign(du) * p["bump_size"], 0.0)
        out.append(moved)
    return out[0], out[1]

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

How the pass is organised
-------------------------
Each run's numbers go through the model's floating-point operations in the model's order,
whatever else is in the batch (the arcs as in :func:`umbmark.model.kinematics.chord_step`,
whose sin(h)/h takes its series form when every run's ``|h|`` is below 0.01). What is
arranged for speed is the bookkeeping around them, since a period costs a few dozen numpy
calls whatever the number of runs:

* Every per-run quantity (state, the current segment's references, the robot's constants)
  is a row of one matrix whose columns are the runs: first the runs on a leg, then the
  runs turning, then the finished ones. The leg and the turn laws each work on their
  block of columns; the wheels, the encoders and both poses (the true and the odometry
  pose in one stacked update) on all columns. When a run changes segment its column moves
  to its new block; finished columns are dropped now and then.
* Far from a leg's end the speed goal is the cruise speed, and far from a turn's end the
  turn-rate goal is the largest one: as the odometry moves a bounded amount per period,
  one check tells for how many periods that holds, and the braking profiles are evaluated
  only when they may bind.
* Slip and bumps are drawn for every run in every period, in the caller's order of the
  runs, as the model's period draws them (seeded results repeat).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from umbmark.core.conventions import Direction
from umbmark.model.runs import EndPose, Run
from umbmark.sim.paths import Path
from umbmark.sim.robot import ControlConfig, VirtualRobot

__all__ = ["SimResult", "Trace", "simulate"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


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
        """The simulated runs as :class:`umbmark.model.runs.Run` values."""
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
    batch = _Batch(fleet, path, directions, control)
    if batch.noisy and rng is None:
        raise ValueError("a robot has non-systematic errors: pass a random generator")
    return batch.run(rng, record, progress)


# -- The run matrix: a row per per-run quantity (stacked ones take several), a column per run.

_ROWS: tuple[tuple[str, int], ...] = (
    # State.
    ("pose", 6),  # x (true, odometry), y (true, odometry), theta (true, odometry)
    ("phi", 2),  # wheel rotation [rad], left and right
    ("counts", 4),  # encoder counts (whole numbers), left and right; two buffers
    ("speed", 2),  # commanded v [m/s] and omega [rad/s]
    ("goal", 2),  # the controller's goals for v and omega
    ("limit", 2),  # this period's caps on |v| and |omega|
    ("neg_limit", 2),
    ("segment", 1),  # index of the current segment
    ("refs", 7),  # its start x, y, cos and sin of its start heading, amount, h0, h1
    # The robot's constants.
    ("half_b", 1),  # b / 2 of its own model
    ("wheel_rad", 2),  # wheel rotation per (m/s) commanded, over dt, left and right
    ("travel_per", 4),  # floor travel per wheel radian (D_L / 2, D_R / 2), c_L c_m, c_R c_m
    ("counts_per_rad", 2),  # (the same for both wheels)
    ("wheelbase", 2),  # true, own
    ("ramp", 2),  # largest change of v and omega per period
    ("neg_ramp", 2),
    ("omega_max", 1),
    ("turn_brake", 4),  # a dt / 2, (a dt / 2)^2 and 2 a of turns, their creep rate
    ("stop_distance", 1),
    ("stop_angle", 1),
    ("turn_cruise", 1),  # heading error from which the turn-rate goal is omega_max
    ("noise", 3),  # slip, bump rate, bump size
    ("table_row", 1),  # the run's first column in the segment table (ccw ones, then cw)
    ("run", 1),  # the run's index in the caller's order
)
_ROW: dict[str, slice] = {}
for _name, _count in _ROWS:
    _start = sum(s.stop - s.start for s in _ROW.values())
    _ROW[_name] = slice(_start, _start + _count)
_N_ROWS = sum(count for _, count in _ROWS)
_REFS = _ROW["refs"]
_SEGMENT = _ROW["segment"].start
_RUN = _ROW["run"].start

#: ``chord_step`` takes sin(h)/h in its series form when every ``|h|`` is below this.
_SINC_SERIES_LIMIT = 0.01
#: The series' divisions: h^2/42, h^2/20, and h^2/12 = (h^2/6)/2 so that the series
#: yields half of sin(h)/h (halving is exact in binary).
_SERIES_DIVISORS = np.array([42.0, 20.0, 12.0]).reshape(3, 1, 1)


def _half_sinc_series(
    h: FloatArray,
    h2: FloatArray,
    terms: FloatArray,
    ones: FloatArray,
    halves: FloatArray,
    out: FloatArray,
) -> Callable[[], None]:
    """A function writing ``0.5 * sin(h)/h`` of the current ``h`` into ``out``, by the
    series of :func:`umbmark.model.kinematics.chord_step` and to the same bits.

    ``h2`` (shaped as ``h``) and ``terms`` (3 by that) are work space; ``ones`` and
    ``halves`` (shaped as ``h``) hold 1 and 1/2.
    """
    multiply, subtract, divide = np.multiply, np.subtract, np.divide
    by42, by20, by12 = terms

    def evaluate() -> None:
        multiply(h, h, h2)
        divide(h2, _SERIES_DIVISORS, terms)
        # (1 - h2/6 (1 - h2/20 (1 - h2/42))) / 2
        subtract(ones, by42, by42)
        multiply(by42, by20, by42)
        subtract(ones, by42, by42)
        multiply(by42, by12, by42)
        subtract(halves, by42, out)

    return evaluate


def _floor_noise(
    floor: FloatArray,
    noise: FloatArray,
    order: IntArray,
    rng: np.random.Generator,
    slip: bool,
    bumps: bool,
    work: _Work,
) -> Callable[[], None]:
    """A function taking slip and bumps off the floor travel ``floor`` (left and right
    wheel, a column per run) for one period.

    ``noise`` holds the runs' slip, bump rate and bump size; ``order`` the caller's index
    of each column's run. The generator draws for every run of the call, in the caller's
    order, as the model's period does: slip then bumps of the left wheels, then of the
    right ones.
    """
    absolute, add, subtract, multiply = np.abs, np.add, np.subtract, np.multiply
    slip_rate, bump_rate, bump_size = noise
    normal, uniform = work.normal, work.uniform
    in_order = order.size == normal.shape[1] and bool(np.all(order == np.arange(order.size)))
    normal_here = normal if in_order else work.normal_here
    uniform_here = uniform if in_order else work.uniform_here
    travel, moved, direction = work.noise
    bumped = work.bumped

    def apply() -> None:
        if slip and bumps:
            rng.standard_normal(out=normal[0])
            rng.random(out=uniform[0])
            rng.standard_normal(out=normal[1])
            rng.random(out=uniform[1])
        elif slip:
            rng.standard_normal(out=normal)
        else:
            rng.random(out=uniform)
        absolute(floor, travel)
        if bumps:
            np.sign(floor, direction)
        if slip:  # Gaussian, of variance slip^2 * travel
            if not in_order:
                np.take(normal, order, axis=1, out=normal_here)
            np.sqrt(travel, moved)
            multiply(slip_rate, moved, moved)
            multiply(moved, normal_here, moved)
            add(floor, moved, floor)
        if bumps:  # at a rate per metre travelled, each turning the wheel without travel
            if not in_order:
                np.take(uniform, order, axis=1, out=uniform_here)
            multiply(bump_rate, travel, moved)
            np.less(uniform_here, moved, bumped)
            multiply(direction, bump_size, moved)
            multiply(moved, bumped, moved)
            subtract(floor, moved, floor)

    return apply


def _braking(
    distance: FloatArray, half: FloatArray | float, hh: FloatArray | float, a2: FloatArray | float
) -> FloatArray:
    """Fastest speed from which a discrete stop (speed falling by ``a dt`` per period)
    ends within ``distance``: ``sqrt((a dt / 2)^2 + 2 a d) - a dt / 2``, given
    ``half = a dt / 2``, ``hh = half^2`` and ``a2 = 2 a`` (the operations of the
    controller, in its order)."""
    return np.asarray(np.sqrt(hh + a2 * distance) - half, dtype=np.float64)


def _cruise_threshold(
    top: FloatArray,
    half: FloatArray,
    hh: FloatArray,
    a2: FloatArray,
    dt: float,
    stop: FloatArray,
) -> FloatArray:
    """Distance to go (per run) from which the controller's goal is its top speed ``top``.

    From there on the braking speed is at least ``top`` (it grows with the distance, also
    in floating point: every operation is monotonic), the one-period cap ``distance / dt``
    is at least twice ``top`` (so it binds neither the goal nor the speed, which never
    exceeds ``top``) and the target is beyond the stop tolerance ``stop``.
    """
    r = np.maximum(((top + half) ** 2 - hh) / a2, 0.0)
    r = np.maximum(np.maximum(r, 2.0 * top * dt), 2.0 * stop) * (1.0 + 1e-9)
    while True:
        short = (_braking(r, half, hh, a2) < top) | (r / dt < 2.0 * top)
        if not short.any():
            return r
        r = np.where(short, r * (1.0 + 1e-9), r)


class _Batch:
    """The runs of one :func:`simulate` call, as the columns of one matrix.

    Columns ``[0, n_legs)`` hold runs on a straight leg, ``[n_legs, n_active)`` runs
    turning, the rest finished runs (see the module notes).
    """

    def __init__(
        self,
        fleet: Sequence[VirtualRobot],
        path: Path,
        directions: Sequence[Direction],
        control: ControlConfig,
    ) -> None:
        n_runs = len(directions)
        p = _robot_arrays(fleet)
        self.slip = bool(np.any(p["slip"] > 0))
        self.bumps = bool(np.any(p["bump_rate"] * p["bump_size"] > 0))
        self.noisy = self.slip or self.bumps
        self.control = control
        self.n_runs = n_runs
        self.directions = tuple(directions)
        dt = control.dt

        # The robot's own model and the controller's limits, per run.
        half_b = 0.5 * p["b_odo"]
        meters_per_count = np.pi * p["D_n"] / p["cpr"]  # c_m, Eq. 2.1
        counts_per_rad = p["cpr"] / (2.0 * np.pi)
        omega_max = control.turn_wheel_speed / half_b
        omega_acc = control.acceleration / half_b
        omega_creep = control.creep_speed / half_b
        # The robot stops within two encoder pulses of its target, as its odometry sees it.
        stop_distance = 2.0 * meters_per_count * np.maximum(p["c_L"], p["c_R"])
        stop_angle = 2.0 * stop_distance / p["b_odo"]
        wheel_rad_l = dt / (0.5 * p["c_L"] * p["D_n"])  # wheel rotation per (m/s) for dt
        wheel_rad_r = dt / (0.5 * p["c_R"] * p["D_n"])
        odo_l = p["c_L"] * meters_per_count  # Eq. 4.33: metres per count as the robot sees it
        odo_r = p["c_R"] * meters_per_count
        turn_half = 0.5 * omega_acc * dt
        turn_hh = turn_half * turn_half
        turn_a2 = 2.0 * omega_acc
        # Legs brake with the linear acceleration, the same for every run.
        self.leg_half = 0.5 * control.acceleration * dt
        self.leg_hh = self.leg_half * self.leg_half
        self.leg_a2 = 2.0 * control.acceleration
        top, half, hh, a2, stop = (
            np.array([a])
            for a in (control.speed, self.leg_half, self.leg_hh, self.leg_a2, stop_distance.max())
        )
        self.leg_cruise = float(_cruise_threshold(top, half, hh, a2, dt, stop)[0])
        self.stop_distance_max = float(stop_distance.max())
        self.stop_angle_max = float(stop_angle.max())
        turns = sum(abs(s.amount) for s in path.segments if s.kind == "turn")
        expected = path.length / control.speed + turns / float(omega_max.min())
        self.max_steps = int(4 * expected / dt) + 2000

        # Bounds on one period's motion: |v| <= speed (it never overshoots its goals),
        # |omega| <= omega_max (a cap) and one count of quantization per wheel give the
        # odometry's largest move along a leg and in heading, and the largest heading
        # changes (as h = dtheta/2) of both poses.
        e_l = odo_l * wheel_rad_l * counts_per_rad  # odometry metres per (m/s) commanded
        e_r = odo_r * wheel_rad_r * counts_per_rad
        k_l = wheel_rad_l * (0.5 * p["D_L"])  # floor metres per (m/s) commanded
        k_r = wheel_rad_r * (0.5 * p["D_R"])
        v_top = control.speed * (1.0 + 1e-9)
        w_top = omega_max * half_b
        pulses = (odo_l + odo_r) * (1.0 + 1e-6)
        odo_travel = 0.5 * (v_top * (e_r + e_l) + w_top * np.abs(e_r - e_l) + pulses)
        odo_turn = (v_top * np.abs(e_r - e_l) + w_top * (e_r + e_l) + pulses) / p["b_odo"]
        bumps = np.where(p["bump_rate"] * p["bump_size"] > 0, p["bump_size"], 0.0)
        floor_turn = (v_top * np.abs(k_r - k_l) + w_top * (k_r + k_l) + 2.0 * bumps) / p["b_true"]
        self.leg_step = 1.01 * float(odo_travel.max())
        self.turn_step = 1.01 * float(odo_turn.max())
        # sin(h)/h must be checked for its series form every period unless the bounds
        # keep |h| below the limit (slip has no bound).
        self.arc_odometry = control.method == "arc"
        h_top = 0.5 * max(
            float(floor_turn.max()), float(odo_turn.max()) if self.arc_odometry else 0.0
        )
        self.check_sinc = self.slip or 1.01 * h_top >= _SINC_SERIES_LIMIT

        # One lookup table of every segment's references, ccw columns first, then cw:
        # start x, start y, cos and sin of the start heading, amount, heading at start and
        # end (the rows of "refs").
        segments = path.segments
        self.n_seg = len(segments)
        self.table = np.concatenate(
            [
                np.column_stack(
                    [st, np.cos(hd[:, 0]), np.sin(hd[:, 0]), [s.amount for s in segments], hd]
                )
                for st, hd in (path.references(+1), path.references(-1))
            ]
        ).T.copy()
        straight = np.array([s.kind == "straight" for s in segments])
        self.seg_straight = straight
        # Block of a run by its segment index: 0 leg, 1 turn, 2 finished (index n_seg).
        self.seg_block = np.append(np.where(straight, 0, 1), 2).astype(np.int64)

        M = np.zeros((_N_ROWS, n_runs))
        first = np.array([0 if d is Direction.CCW else self.n_seg for d in directions])

        def put(name: str, *rows: FloatArray | float) -> None:
            M[_ROW[name]] = np.array([np.broadcast_to(r, (n_runs,)) for r in rows])

        put("limit", np.inf, omega_max)
        put("neg_limit", -np.inf, -omega_max)
        put("refs", *self.table[:, first])
        put("half_b", half_b)
        put("wheel_rad", wheel_rad_l, wheel_rad_r)
        put("travel_per", 0.5 * p["D_L"], 0.5 * p["D_R"], odo_l, odo_r)
        put("counts_per_rad", counts_per_rad, counts_per_rad)
        put("wheelbase", p["b_true"], p["b_odo"])
        put("ramp", control.acceleration * dt, omega_acc * dt)
        put("neg_ramp", -control.acceleration * dt, -omega_acc * dt)
        put("omega_max", omega_max)
        put("turn_brake", turn_half, turn_hh, turn_a2, omega_creep)
        put("stop_distance", stop_distance)
        put("stop_angle", stop_angle)
        put(
            "turn_cruise", _cruise_threshold(omega_max, turn_half, turn_hh, turn_a2, dt, stop_angle)
        )
        put("noise", p["slip"], p["bump_rate"], p["bump_size"])
        put("table_row", first.astype(np.float64))
        put("run", np.arange(n_runs, dtype=np.float64))
        self.M = M
        self.counts_flip = 0  # which of the two count buffers holds the counts
        self.n_active = n_runs
        self.n_legs = n_runs if straight[0] else 0
        self.finished_at = np.full(n_runs, -1, dtype=np.int64)
        self.true_end = np.zeros((n_runs, 3))
        self.odometry_end = np.zeros((n_runs, 3))
        self.work: _Work | None = None

    def run(
        self,
        rng: np.random.Generator | None,
        record: bool,
        progress: Callable[[float], None] | None,
    ) -> SimResult:
        """Simulate until every run has finished."""
        trace: list[tuple[FloatArray, FloatArray, FloatArray]] | None = None
        if record:
            trace = [self._snapshot()]
        step = 0
        while self.n_active:
            step = self._drive(step, rng, trace, progress)
        if progress is not None:
            progress(1.0)
        self._park(0)

        dt = self.control.dt
        out_trace = None
        if trace is not None:
            out_trace = Trace(
                time=np.array([k * dt for k in range(len(trace))], dtype=np.float64),
                true_pose=np.stack([t for t, _, _ in trace], axis=1),
                counts=np.stack([c for _, c, _ in trace], axis=1).astype(np.int64),
                odometry_pose=np.stack([o for _, _, o in trace], axis=1),
            )
        return SimResult(
            directions=self.directions,
            true_end=self.true_end,
            odometry_end=self.odometry_end,
            duration=((self.finished_at + 1) * dt).astype(np.float64),
            samples_used=(self.finished_at + 1).astype(np.int64),
            samples=step,
            trace=out_trace,
        )

    def _drive(
        self,
        step: int,
        rng: np.random.Generator | None,
        trace: list[tuple[FloatArray, FloatArray, FloatArray]] | None,
        progress: Callable[[float], None] | None,
    ) -> int:
        """Simulate periods until a run reaches the end of its segment; return the count.

        The numbered comments are the model's steps (module notes). The loop runs once per
        sampling period: every view it uses is made before it (a view costs as much as a
        small numpy operation), and every operation writes into existing arrays.
        """
        add, subtract, multiply, divide = np.add, np.subtract, np.multiply, np.divide
        maximum, minimum, negative = np.maximum, np.minimum, np.negative
        sqrt, sign, absolute, floor, cos, sin = np.sqrt, np.sign, np.abs, np.floor, np.cos, np.sin
        less_equal, lowest, highest = np.less_equal, np.minimum.reduce, np.maximum.reduce
        c = self.control
        dt, cruise_speed, creep_speed = c.dt, c.speed, c.creep_speed
        leg_half, leg_hh, leg_a2 = self.leg_half, self.leg_hh, self.leg_a2
        leg_cruise, leg_step, turn_step = self.leg_cruise, self.leg_step, self.turn_step
        stop_distance_max, stop_angle_max = self.stop_distance_max, self.stop_angle_max
        check_sinc, max_steps = self.check_sinc, self.max_steps

        M = self.M
        width = M.shape[1]
        n_legs, n_active = self.n_legs, self.n_active
        legs, turns = slice(0, n_legs), slice(n_legs, n_active)
        R = _ROW
        pose = M[R["pose"]].reshape(3, 2, width)
        xy, theta = pose[:2], pose[2]  # (x, y) and theta, each of (true, odometry)
        x_odo, y_odo, th_odo = pose[0, 1], pose[1, 1], pose[2, 1]
        phi = M[R["phi"]]
        flip = self.counts_flip
        both_counts = M[R["counts"]].reshape(2, 2, width)
        counts, counts_next = both_counts[flip], both_counts[1 - flip]
        speed, goal = M[R["speed"]], M[R["goal"]]
        v, w = speed
        limit, neg_limit = M[R["limit"]], M[R["neg_limit"]]
        ramp, neg_ramp = M[R["ramp"]], M[R["neg_ramp"]]
        half_b, wheel_rad = M[R["half_b"]][0], M[R["wheel_rad"]]
        travel_per = M[R["travel_per"]].reshape(2, 2, width)
        counts_per_rad, wheelbase = M[R["counts_per_rad"]], M[R["wheelbase"]]
        # The blocks' views (1-D: contiguous).
        start_x, start_y, cos_h, sin_h, amount, h0, _ = (r[legs] for r in M[_REFS])
        x_leg, y_leg, th_leg = x_odo[legs], y_odo[legs], th_odo[legs]
        v_goal, w_goal_leg = goal[0, legs], goal[1, legs]
        v_cap, v_cap_neg = limit[0, legs], neg_limit[0, legs]
        stop_leg = M[R["stop_distance"]][0, legs]
        th_turn, h1_turn = th_odo[turns], M[_REFS][6, turns]
        w_goal_turn, w_cap, w_cap_neg = goal[1, turns], limit[1, turns], neg_limit[1, turns]
        omega_max = M[R["omega_max"]][0, turns]
        turn_half, turn_hh, turn_a2, omega_creep = (r[turns] for r in M[R["turn_brake"]])
        stop_turn = M[R["stop_angle"]][0, turns]
        turn_cruise = M[R["turn_cruise"]][0, turns]

        if self.work is None or self.work.width != width:
            self.work = _Work.make(width, self.n_runs, self.control)
        work = self.work
        heading_share, ones, halves = work.constants
        heading_gain, cross_track_gain = (a[legs] for a in work.gains)
        dx, dy, t1, t2, rem, rest, brake = (a[legs] for a in work.leg)
        err, abs_err, t3, brake_turn = (a[turns] for a in work.turn)
        done_leg, done_turn = work.done[0, legs], work.done[1, turns]
        d_speed, w_arm = work.d_speed, work.w_arm
        wheel, travel = work.wheel, work.travel  # rotations, counts; floor, odometry
        d_phi, d_counts = wheel
        d_phi_l, d_phi_r = d_phi
        (floor_l, floor_r), (odo_l, odo_r) = travel
        ds, d_theta, half, chord, heading = work.sums  # each (true, odometry)
        ds_true, ds_odo = ds
        dth_true, dth_odo = d_theta
        cs = work.cs
        cos_rows, sin_rows = cs
        # Rows of h whose sin(h)/h takes the arc rule (the true pose; the odometry's unless
        # it integrates otherwise, its factor then staying 1/2).
        n_arc = 2 if self.arc_odometry else 1
        h, h_abs, half_sinc = half[:n_arc], chord[:n_arc], work.half_sinc
        series = _half_sinc_series(
            h,
            work.h2[:n_arc],
            work.terms[:, :n_arc],
            ones[:n_arc],
            halves[:n_arc],
            half_sinc[:n_arc],
        )
        noise: Callable[[], None] | None = None
        if self.noisy:
            assert rng is not None
            order = M[_RUN].astype(np.int64)
            noise = _floor_noise(travel[0], M[R["noise"]], order, rng, self.slip, self.bumps, work)

        # For so many more periods the cruise goals hold (on legs, in turns).
        leg_left = turn_left = 0
        leg_cruising = turn_cruising = False
        while True:
            if step >= max_steps:
                raise RuntimeError(f"simulation did not finish within {max_steps} samples")
            event = False

            # 1. Controller, in the odometry frame. On a leg: follow the line from the
            # leg's start corner, stop at its end.
            if n_legs:
                subtract(x_leg, start_x, dx)
                subtract(y_leg, start_y, dy)
                if leg_left:
                    leg_left -= 1
                else:
                    multiply(dx, cos_h, t1)  # along the line
                    multiply(dy, sin_h, t2)
                    add(t1, t2, t1)
                    subtract(amount, t1, rem)  # remaining
                    nearest = float(lowest(rem))
                    if nearest >= leg_cruise:  # cruise speed, no cap, no stop
                        leg_left = max(int((nearest - leg_cruise) / leg_step) - 1, 0)
                        if not leg_cruising:
                            v_goal.fill(cruise_speed)
                            v_cap.fill(np.inf)
                            v_cap_neg.fill(-np.inf)
                            leg_cruising = True
                    else:
                        # Brake in time, creep near the end, never step past it (at most
                        # the rest of the way in one period).
                        leg_cruising = False
                        maximum(rem, 0.0, out=rest)
                        multiply(rest, leg_a2, brake)
                        add(brake, leg_hh, brake)
                        sqrt(brake, brake)
                        subtract(brake, leg_half, brake)
                        maximum(brake, creep_speed, out=brake)
                        minimum(brake, cruise_speed, out=brake)
                        divide(rest, dt, v_cap)
                        minimum(brake, v_cap, out=v_goal)
                        negative(v_cap, v_cap_neg)
                        if nearest <= stop_distance_max:
                            less_equal(rem, stop_leg, done_leg)
                            event = bool(done_leg.any())
                multiply(dx, sin_h, t1)  # cross-track error
                multiply(dy, cos_h, t2)
                subtract(t2, t1, t2)
                subtract(h0, th_leg, t1)  # heading error
                multiply(t1, heading_gain, t1)
                multiply(t2, cross_track_gain, t2)
                subtract(t1, t2, w_goal_leg)
            # In a turn: rotate on the spot until the heading reaches the target.
            if n_active > n_legs:
                if turn_left:
                    turn_left -= 1
                else:
                    subtract(h1_turn, th_turn, err)
                    absolute(err, abs_err)
                    subtract(abs_err, turn_cruise, t3)
                    margin = float(lowest(t3))
                    if margin >= 0.0:  # the largest rate, no cap, no stop
                        turn_left = max(int(margin / turn_step) - 1, 0)
                        if not turn_cruising:
                            sign(err, w_goal_turn)
                            multiply(w_goal_turn, omega_max, w_goal_turn)
                            w_cap[:] = omega_max
                            negative(omega_max, w_cap_neg)
                            turn_cruising = True
                    else:
                        turn_cruising = False
                        multiply(turn_a2, abs_err, brake_turn)
                        add(turn_hh, brake_turn, brake_turn)
                        sqrt(brake_turn, brake_turn)
                        subtract(brake_turn, turn_half, brake_turn)
                        maximum(brake_turn, omega_creep, out=brake_turn)
                        minimum(brake_turn, omega_max, out=brake_turn)
                        divide(abs_err, dt, t3)
                        minimum(brake_turn, t3, out=brake_turn)
                        sign(err, err)
                        multiply(err, brake_turn, w_goal_turn)
                        minimum(omega_max, t3, out=w_cap)  # the caps of both clips
                        negative(w_cap, w_cap_neg)
                        if float(lowest(abs_err)) <= stop_angle_max:
                            less_equal(abs_err, stop_turn, done_turn)
                            event = bool(done_turn.any()) or event
            # Speeds ramp towards the goals and are capped; a run at its target stops.
            subtract(goal, speed, d_speed)
            maximum(d_speed, neg_ramp, out=d_speed)
            minimum(d_speed, ramp, out=d_speed)
            add(speed, d_speed, speed)
            maximum(speed, neg_limit, out=speed)
            minimum(speed, limit, out=speed)
            if event:
                done = np.concatenate(
                    [np.flatnonzero(done_leg), n_legs + np.flatnonzero(done_turn)]
                )
                done_leg.fill(False)
                done_turn.fill(False)
                speed[:, done] = 0.0

            # 2. Wheels turn as the robot's own model says they should.
            multiply(w, half_b, w_arm)
            subtract(v, w_arm, d_phi_l)
            add(v, w_arm, d_phi_r)
            multiply(d_phi, wheel_rad, d_phi)
            add(phi, d_phi, phi)
            # 4. (taken along with 3.) The encoders count whole pulses.
            multiply(phi, counts_per_rad, counts_next)
            floor(counts_next, counts_next)
            subtract(counts_next, counts, d_counts)
            counts, counts_next = counts_next, counts
            flip = 1 - flip
            # 3. and 4. Each wheel moves over the floor by its true diameter, less slip
            # and bumps; the odometry sees the counts by the robot's own parameters.
            multiply(wheel, travel_per, travel)
            if noise is not None:
                noise()
            # Both poses advance along the arcs (kinematics.chord_step): by the chord
            # (ds/2) sin(h)/h, with ds = travel_R + travel_L, towards theta + h.
            add(floor_r, floor_l, ds_true)
            add(odo_r, odo_l, ds_odo)
            subtract(floor_r, floor_l, dth_true)
            subtract(odo_r, odo_l, dth_odo)
            divide(d_theta, wheelbase, d_theta)
            multiply(d_theta, heading_share, half)
            if check_sinc:
                absolute(h, h_abs)
                beyond = np.flatnonzero(highest(h_abs, axis=1) >= _SINC_SERIES_LIMIT)
                series()
                for k in beyond:
                    half_sinc[k] = 0.5 * np.sinc(half[k] / np.pi)
            else:
                series()
            multiply(ds, half_sinc, chord)
            add(theta, half, heading)
            cos(heading, cos_rows)
            sin(heading, sin_rows)
            multiply(cos_rows, chord, cos_rows)
            multiply(sin_rows, chord, sin_rows)
            add(xy, cs, xy)
            add(theta, d_theta, theta)

            step += 1
            if trace is not None:
                self.counts_flip = flip
                trace.append(self._snapshot())
            if event:
                break
            if progress is not None and step % 200 == 0:
                progress((self.n_runs - self.n_active) / self.n_runs)

        self.counts_flip = flip
        self._advance(done, step - 1)
        if trace is None and self.n_active and width - self.n_active >= max(1, width // 8):
            self._park(self.n_active)
        if progress is not None and step % 200 == 0:
            progress((self.n_runs - self.n_active) / self.n_runs)
        return step

    def _advance(self, columns: IntArray, step: int) -> None:
        """The runs in ``columns`` reached the end of their segment in period ``step``."""
        M = self.M
        segment = M[_SEGMENT, columns] + 1.0
        M[_SEGMENT, columns] = segment
        k = segment.astype(np.int64)
        finished = k >= self.n_seg
        if finished.any():
            done = columns[finished]
            self.finished_at[M[_RUN, done].astype(np.int64)] = step
            for name in ("goal", "limit", "neg_limit"):  # a finished run stands still
                M[_ROW[name], done] = 0.0
        going, k = columns[~finished], k[~finished]
        if going.size:
            M[_REFS, going] = self.table[:, M[_ROW["table_row"].start, going].astype(np.int64) + k]
            on_leg = self.seg_straight[k]
            M[_ROW["goal"].start, going[~on_leg]] = 0.0  # no speed while turning
            legs = going[on_leg]
            omega_max = M[_ROW["omega_max"].start, legs]
            M[_ROW["limit"].start + 1, legs] = omega_max
            M[_ROW["neg_limit"].start + 1, legs] = -omega_max
        # Sort the active columns into blocks again (legs, turns, finished), moving only
        # the columns in the wrong block.
        block = self.seg_block[M[_SEGMENT, : self.n_active].astype(np.int64)]
        sizes = np.bincount(block, minlength=3)
        wrong = np.flatnonzero(block != np.repeat(np.arange(3), sizes))
        if wrong.size:
            M[:, wrong] = M[:, wrong[np.argsort(block[wrong], kind="stable")]]
        self.n_legs = int(sizes[0])
        self.n_active = int(sizes[0] + sizes[1])

    def _park(self, keep: int) -> None:
        """Store the end poses of the (finished) runs in columns ``keep`` on; drop them."""
        gone = self.M[:, keep:]
        runs = gone[_RUN].astype(np.int64)
        pose = gone[_ROW["pose"]]
        self.true_end[runs] = pose[0::2].T
        self.odometry_end[runs] = pose[1::2].T
        self.M = self.M[:, :keep].copy()

    def _snapshot(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """True pose, counts and odometry pose of every run, in the caller's order."""
        columns = np.argsort(self.M[_RUN])  # no run is dropped while recording
        pose = self.M[_ROW["pose"]][:, columns]
        first = _ROW["counts"].start + 2 * self.counts_flip
        counts = self.M[first : first + 2, columns]
        return pose[0::2].T.copy(), counts.T.copy(), pose[1::2].T.copy()


@dataclass(frozen=True)
class _Work:
    """Work space of the period loop, for ``width`` columns (rows as commented)."""

    width: int
    constants: FloatArray  # dtheta's share of the heading (true, odometry), 1, 1/2
    gains: FloatArray  # heading and cross-track gains
    leg: FloatArray  # dx, dy, two temporaries, remaining, rest, braking speed
    turn: FloatArray  # error, |error|, a temporary, braking rate
    done: BoolArray  # runs at their target: on legs, in turns
    d_speed: FloatArray
    w_arm: FloatArray  # omega b / 2
    wheel: FloatArray  # wheel rotation (l, r), count increments (l, r)
    travel: FloatArray  # floor travel (l, r), odometry travel (l, r)
    sums: FloatArray  # ds, dtheta, h, chord, heading; each (true, odometry)
    h2: FloatArray
    terms: FloatArray
    half_sinc: FloatArray
    cs: FloatArray  # cos and sin of the heading (true, odometry), then times the chord
    normal: FloatArray  # the generator's draws, in the caller's order (l, r)
    uniform: FloatArray
    normal_here: FloatArray  # ... in the order of the columns
    uniform_here: FloatArray
    noise: FloatArray  # |travel|, a temporary, sign of the travel
    bumped: BoolArray

    @classmethod
    def make(cls, width: int, n_runs: int, control: ControlConfig) -> _Work:
        e = np.empty
        share = [[0.5], [1.0 if control.method == "segment" else 0.5]]
        return cls(
            width=width,
            constants=np.array(
                [np.broadcast_to(share, (2, width)), np.ones((2, width)), np.full((2, width), 0.5)]
            ),
            gains=np.array(
                [np.full(width, control.heading_gain), np.full(width, control.cross_track_gain)]
            ),
            leg=e((7, width)),
            turn=e((4, width)),
            done=np.zeros((2, width), dtype=np.bool_),
            d_speed=e((2, width)),
            w_arm=e(width),
            wheel=e((2, 2, width)),
            travel=e((2, 2, width)),
            sums=e((5, 2, width)),
            h2=e((2, width)),
            terms=e((3, 2, width)),
            half_sinc=np.full((2, width), 0.5),
            cs=e((2, 2, width)),
            normal=e((2, n_runs)),
            uniform=e((2, n_runs)),
            normal_here=e((2, width)),
            uniform_here=e((2, width)),
            noise=e((3, 2, width)),
            bumped=np.zeros((2, width), dtype=np.bool_),
        )

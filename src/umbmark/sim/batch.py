"""The runs of one :func:`umbmark.sim.engine.simulate` call as the columns of one matrix:
the batch's state, set up from the robots and the path, and the period loop that drives
it (the controller on legs and in turns, the wheels, the encoders, both poses)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray, IntArray
from umbmark.core.conventions import Direction
from umbmark.sim.kernels import (
    SINC_SERIES_LIMIT,
    cruise_threshold,
    floor_noise,
    half_sinc_series,
)
from umbmark.sim.layout import N_ROWS, REFS, ROW, RUN, SEGMENT, Work
from umbmark.sim.paths import Path
from umbmark.sim.result import SimResult, Trace
from umbmark.sim.robot import ControlConfig, SimRobot

__all__ = ["Batch"]


def _robot_arrays(robots: Sequence[SimRobot]) -> dict[str, FloatArray]:
    def col(fn: Callable[[SimRobot], float]) -> FloatArray:
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


class Batch:
    """The runs of one :func:`umbmark.sim.engine.simulate` call, as the columns of one matrix.

    Columns ``[0, n_legs)`` hold runs on a straight leg, ``[n_legs, n_active)`` runs
    turning, the rest finished runs (see :mod:`umbmark.sim.engine`).
    """

    def __init__(
        self,
        fleet: Sequence[SimRobot],
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
        self.leg_cruise = float(cruise_threshold(top, half, hh, a2, dt, stop)[0])
        self.stop_distance_max = float(stop_distance.max())
        self.stop_angle_max = float(stop_angle.max())
        turns = sum(abs(s.amount) for s in path.segments if s.kind == "turn")
        expected = path.length / control.speed + turns / float(omega_max.min())
        self.max_steps = int(4 * expected / dt) + 2000

        self._step_bounds(p, odo_l, odo_r, wheel_rad_l, wheel_rad_r, counts_per_rad, omega_max)

        straight = self._segment_table(path)

        M = np.zeros((N_ROWS, n_runs))
        first = np.array([0 if d is Direction.CCW else self.n_seg for d in directions])

        def put(name: str, *rows: FloatArray | float) -> None:
            M[ROW[name]] = np.array([np.broadcast_to(r, (n_runs,)) for r in rows])

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
        put("turn_cruise", cruise_threshold(omega_max, turn_half, turn_hh, turn_a2, dt, stop_angle))
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
        self.work: Work | None = None

    def _step_bounds(
        self,
        p: dict[str, FloatArray],
        odo_l: FloatArray,
        odo_r: FloatArray,
        wheel_rad_l: FloatArray,
        wheel_rad_r: FloatArray,
        counts_per_rad: FloatArray,
        omega_max: FloatArray,
    ) -> None:
        """The largest move of one period, along a leg and in heading, for the cruise
        shortcuts (``leg_step``, ``turn_step``), and whether sin(h)/h needs its check."""
        half_b = 0.5 * p["b_odo"]
        # Bounds on one period's motion: |v| <= speed (it never overshoots its goals),
        # |omega| <= omega_max (a cap) and one count of quantization per wheel give the
        # odometry's largest move along a leg and in heading, and the largest heading
        # changes (as h = dtheta/2) of both poses.
        e_l = odo_l * wheel_rad_l * counts_per_rad  # odometry metres per (m/s) commanded
        e_r = odo_r * wheel_rad_r * counts_per_rad
        k_l = wheel_rad_l * (0.5 * p["D_L"])  # floor metres per (m/s) commanded
        k_r = wheel_rad_r * (0.5 * p["D_R"])
        v_top = self.control.speed * (1.0 + 1e-9)
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
        self.arc_odometry = self.control.method == "arc"
        h_top = 0.5 * max(
            float(floor_turn.max()), float(odo_turn.max()) if self.arc_odometry else 0.0
        )
        self.check_sinc = self.slip or 1.01 * h_top >= SINC_SERIES_LIMIT

    def _segment_table(self, path: Path) -> BoolArray:
        """The segments' references, as one lookup table; which segments are legs."""
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
        return straight

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

        The numbered comments are the model's steps (:mod:`umbmark.sim.engine`). The loop
        runs once per sampling period, two calls: the controller (:meth:`_controller`) and
        the robot moving (:meth:`_mover`). Every view they use is made before the loop (a
        view costs as much as a small numpy operation) and held by the two closures, and
        every operation writes into existing arrays.
        """
        width = self.M.shape[1]
        if self.work is None or self.work.width != width:
            self.work = Work.make(width, self.n_runs, self.control)
        control = self._controller(self.work)
        move, flip = self._mover(self.work, rng)
        max_steps = self.max_steps
        while True:
            if step >= max_steps:
                raise RuntimeError(f"simulation did not finish within {max_steps} samples")
            done = control()
            move()
            step += 1
            if trace is not None:
                self.counts_flip = flip[0]
                trace.append(self._snapshot())
            if done is not None:
                break
            if progress is not None and step % 200 == 0:
                progress((self.n_runs - self.n_active) / self.n_runs)

        self.counts_flip = flip[0]
        self._advance(done, step - 1)
        if trace is None and self.n_active and width - self.n_active >= max(1, width // 8):
            self._park(self.n_active)
        if progress is not None and step % 200 == 0:
            progress((self.n_runs - self.n_active) / self.n_runs)
        return step

    def _controller(self, work: Work) -> Callable[[], IntArray | None]:
        """Step 1 of one period, in the odometry frame: on a leg, follow the line from the
        leg's start corner and stop at its end; in a turn, rotate on the spot until the
        heading reaches the target; the speeds ramp towards the goals and are capped. The
        closure returns the columns of the runs that reached their target (their speeds
        set to zero), or None."""
        add, subtract, multiply, divide = np.add, np.subtract, np.multiply, np.divide
        maximum, minimum, negative = np.maximum, np.minimum, np.negative
        sqrt, less_equal, lowest = np.sqrt, np.less_equal, np.minimum.reduce
        c = self.control
        dt, cruise_speed, creep_speed = c.dt, c.speed, c.creep_speed
        leg_half, leg_hh, leg_a2 = self.leg_half, self.leg_hh, self.leg_a2
        leg_cruise, leg_step = self.leg_cruise, self.leg_step
        stop_distance_max = self.stop_distance_max

        M = self.M
        n_legs, n_active = self.n_legs, self.n_active
        legs, turns = slice(0, n_legs), slice(n_legs, n_active)
        R = ROW
        pose = M[R["pose"]].reshape(3, 2, M.shape[1])
        x_odo, y_odo, th_odo = pose[0, 1], pose[1, 1], pose[2, 1]
        speed, goal = M[R["speed"]], M[R["goal"]]
        limit, neg_limit = M[R["limit"]], M[R["neg_limit"]]
        ramp, neg_ramp = M[R["ramp"]], M[R["neg_ramp"]]
        # The blocks' views (1-D: contiguous).
        start_x, start_y, cos_h, sin_h, amount, h0, _ = (r[legs] for r in M[REFS])
        x_leg, y_leg, th_leg = x_odo[legs], y_odo[legs], th_odo[legs]
        v_goal, w_goal_leg = goal[0, legs], goal[1, legs]
        v_cap, v_cap_neg = limit[0, legs], neg_limit[0, legs]
        stop_leg = M[R["stop_distance"]][0, legs]
        heading_gain, cross_track_gain = (a[legs] for a in work.gains)
        dx, dy, t1, t2, rem, rest, brake = (a[legs] for a in work.leg)
        done_leg, done_turn = work.done[0, legs], work.done[1, turns]
        d_speed = work.d_speed
        turn = self._turn_controller(work)
        # For so many more periods the cruise goals hold on the legs.
        leg_left = 0
        leg_cruising = False

        def control() -> IntArray | None:
            nonlocal leg_left, leg_cruising
            event = False
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
            if n_active > n_legs:
                event = turn() or event
            # Speeds ramp towards the goals and are capped; a run at its target stops.
            subtract(goal, speed, d_speed)
            maximum(d_speed, neg_ramp, out=d_speed)
            minimum(d_speed, ramp, out=d_speed)
            add(speed, d_speed, speed)
            maximum(speed, neg_limit, out=speed)
            minimum(speed, limit, out=speed)
            if not event:
                return None
            done = np.concatenate([np.flatnonzero(done_leg), n_legs + np.flatnonzero(done_turn)])
            done_leg.fill(False)
            done_turn.fill(False)
            speed[:, done] = 0.0
            return done

        return control

    def _turn_controller(self, work: Work) -> Callable[[], bool]:
        """Step 1 in the turns: rotate on the spot until the heading reaches the target,
        braking in time. The closure returns whether a run reached its target."""
        add, subtract, multiply, divide = np.add, np.subtract, np.multiply, np.divide
        maximum, minimum, negative = np.maximum, np.minimum, np.negative
        sqrt, sign, absolute = np.sqrt, np.sign, np.abs
        less_equal, lowest = np.less_equal, np.minimum.reduce
        dt, turn_step, stop_angle_max = self.control.dt, self.turn_step, self.stop_angle_max
        M = self.M
        turns = slice(self.n_legs, self.n_active)
        R = ROW
        th_turn = M[R["pose"]].reshape(3, 2, M.shape[1])[2, 1][turns]
        h1_turn = M[REFS][6, turns]
        goal, limit, neg_limit = M[R["goal"]], M[R["limit"]], M[R["neg_limit"]]
        w_goal_turn, w_cap, w_cap_neg = goal[1, turns], limit[1, turns], neg_limit[1, turns]
        omega_max = M[R["omega_max"]][0, turns]
        turn_half, turn_hh, turn_a2, omega_creep = (r[turns] for r in M[R["turn_brake"]])
        stop_turn = M[R["stop_angle"]][0, turns]
        turn_cruise = M[R["turn_cruise"]][0, turns]
        err, abs_err, t3, brake_turn = (a[turns] for a in work.turn)
        done_turn = work.done[1, turns]
        # For so many more periods the cruise goals hold in the turns.
        turn_left = 0
        turn_cruising = False

        def turn() -> bool:
            nonlocal turn_left, turn_cruising
            event = False
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
                        event = bool(done_turn.any())
            return event

        return turn

    def _mover(
        self, work: Work, rng: np.random.Generator | None
    ) -> tuple[Callable[[], None], list[int]]:
        """Steps 2 to 4 of one period: the wheels turn as the robot's own model says, the
        encoders count whole pulses, each wheel moves over the floor by its true diameter
        (less slip and bumps) while the odometry sees the counts, and both poses advance
        along the arcs. Returns the closure, and which count buffer holds the counts
        (a list it keeps current)."""
        add, subtract, multiply, divide = np.add, np.subtract, np.multiply, np.divide
        absolute, floor, cos, sin = np.abs, np.floor, np.cos, np.sin
        highest = np.maximum.reduce
        check_sinc = self.check_sinc
        M = self.M
        width = M.shape[1]
        R = ROW
        pose = M[R["pose"]].reshape(3, 2, width)
        xy, theta = pose[:2], pose[2]  # (x, y) and theta, each of (true, odometry)
        phi = M[R["phi"]]
        flip = [self.counts_flip]
        both_counts = M[R["counts"]].reshape(2, 2, width)
        counts, counts_next = both_counts[flip[0]], both_counts[1 - flip[0]]
        v, w = M[R["speed"]]
        half_b, wheel_rad = M[R["half_b"]][0], M[R["wheel_rad"]]
        travel_per = M[R["travel_per"]].reshape(2, 2, width)
        counts_per_rad, wheelbase = M[R["counts_per_rad"]], M[R["wheelbase"]]
        heading_share, ones, halves = work.constants
        w_arm = work.w_arm
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
        series = half_sinc_series(
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
            order = M[RUN].astype(np.int64)
            noise = floor_noise(travel[0], M[R["noise"]], order, rng, self.slip, self.bumps, work)

        def move() -> None:
            nonlocal counts, counts_next
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
            flip[0] = 1 - flip[0]
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
                beyond = np.flatnonzero(highest(h_abs, axis=1) >= SINC_SERIES_LIMIT)
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

        return move, flip

    def _advance(self, columns: IntArray, step: int) -> None:
        """The runs in ``columns`` reached the end of their segment in period ``step``."""
        M = self.M
        segment = M[SEGMENT, columns] + 1.0
        M[SEGMENT, columns] = segment
        k = segment.astype(np.int64)
        finished = k >= self.n_seg
        if finished.any():
            done = columns[finished]
            self.finished_at[M[RUN, done].astype(np.int64)] = step
            for name in ("goal", "limit", "neg_limit"):  # a finished run stands still
                M[ROW[name], done] = 0.0
        going, k = columns[~finished], k[~finished]
        if going.size:
            M[REFS, going] = self.table[:, M[ROW["table_row"].start, going].astype(np.int64) + k]
            on_leg = self.seg_straight[k]
            M[ROW["goal"].start, going[~on_leg]] = 0.0  # no speed while turning
            legs = going[on_leg]
            omega_max = M[ROW["omega_max"].start, legs]
            M[ROW["limit"].start + 1, legs] = omega_max
            M[ROW["neg_limit"].start + 1, legs] = -omega_max
        # Sort the active columns into blocks again (legs, turns, finished), moving only
        # the columns in the wrong block.
        block = self.seg_block[M[SEGMENT, : self.n_active].astype(np.int64)]
        sizes = np.bincount(block, minlength=3)
        wrong = np.flatnonzero(block != np.repeat(np.arange(3), sizes))
        if wrong.size:
            M[:, wrong] = M[:, wrong[np.argsort(block[wrong], kind="stable")]]
        self.n_legs = int(sizes[0])
        self.n_active = int(sizes[0] + sizes[1])

    def _park(self, keep: int) -> None:
        """Store the end poses of the (finished) runs in columns ``keep`` on; drop them."""
        gone = self.M[:, keep:]
        runs = gone[RUN].astype(np.int64)
        pose = gone[ROW["pose"]]
        self.true_end[runs] = pose[0::2].T
        self.odometry_end[runs] = pose[1::2].T
        self.M = self.M[:, :keep].copy()

    def _snapshot(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """True pose, counts and odometry pose of every run, in the caller's order."""
        columns = np.argsort(self.M[RUN])  # no run is dropped while recording
        pose = self.M[ROW["pose"]][:, columns]
        first = ROW["counts"].start + 2 * self.counts_flip
        counts = self.M[first : first + 2, columns]
        return pose[0::2].T.copy(), counts.T.copy(), pose[1::2].T.copy()

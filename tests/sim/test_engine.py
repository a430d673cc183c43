"""The virtual robot against closed forms, the paper's model assumptions and its own loop.

Everything here is noise-free unless a test says otherwise; expected values come from
hand-derived closed forms or from the independent turtle walk in ``helpers.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from umbmark.core.conventions import Direction
from umbmark.model.kinematics import WheelParams
from umbmark.sim.engine import simulate
from umbmark.sim.experiments import calibrate_robot, umbmark_trials
from umbmark.sim.paths import spot_turn, square, straight_line
from umbmark.sim.robot import ControlConfig, NoiseModel, SimRobot

from helpers import turtle_square
from reference_sim import simulate_run_loop

# A fine encoder keeps quantization out of the way of the geometry.
FINE = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=4096, gear_ratio=50)
FAST = ControlConfig(dt=0.02, speed=0.4, turn_wheel_speed=0.3, acceleration=1.0)
L = 4.0
CW, CCW = Direction.CW, Direction.CCW


def test_true_diameters_from_errors_by_hand():
    robot = SimRobot.with_errors(FINE, E_d=1.01, E_b=1.02, E_s=0.99)
    d_avg = 0.99 * 0.15
    assert robot.diameter_left == pytest.approx(2 * d_avg / 2.01)
    assert robot.diameter_right == pytest.approx(2 * d_avg * 1.01 / 2.01)
    assert robot.wheelbase == pytest.approx(0.3468)
    assert robot.E_d == pytest.approx(1.01)
    assert robot.E_s == pytest.approx(0.99)


def test_closed_loop_square_matches_the_turtle_walk():
    # Truth: each turn falls short by alpha = (pi/2)(1 - 1/E_b) (the odometry counts 90
    # degrees with the nominal b); each leg, an arc of length L, bends by
    # beta = (2L / b_true)(E_d - 1)/(E_d + 1); the turns pivot about a point
    # (b_true/2)(E_d - 1)/(E_d + 1) to the left (Sec. 2.3).
    E_d, E_b = 1.002, 1.01
    robot = SimRobot.with_errors(FINE, E_d=E_d, E_b=E_b)
    b_true = 0.34 * E_b
    alpha = 90.0 * (1 - 1 / E_b)
    beta = math.degrees(2 * L / b_true * (E_d - 1) / (E_d + 1))
    offset = b_true / 2 * (E_d - 1) / (E_d + 1)
    result = simulate(robot, square(L), [CW, CCW])
    for i, d in enumerate(("cw", "ccw")):
        x, y, heading = turtle_square(90 - alpha, beta, L, d, steps=3000, turn_offset=offset)
        np.testing.assert_allclose(result.true_end[i, :2], [x, y], atol=3e-4)
        # The odometry believes it came home.
        np.testing.assert_allclose(result.odometry_end[i, :2], [0, 0], atol=3e-4)
        # Heading error (Eq. 3.1): the same as the turtle's, whatever the stop tolerance.
        ideal = 2 * math.pi if d == "ccw" else -2 * math.pi
        eps_theta = result.true_end[i, 2] - result.odometry_end[i, 2]
        assert eps_theta == pytest.approx(heading - ideal, abs=1e-5)


def test_vectorized_simulator_equals_the_plain_loop():
    robot = SimRobot.with_errors(FINE, E_d=0.998, E_b=1.03)
    result = simulate(robot, square(2.0), [CW, CCW], FAST)
    for i, d in enumerate((CW, CCW)):
        true_end, odo_end, samples = simulate_run_loop(robot, square(2.0), d, FAST)
        np.testing.assert_allclose(result.true_end[i], true_end, atol=1e-9)
        np.testing.assert_allclose(result.odometry_end[i], odo_end, atol=1e-9)
        assert result.samples_used[i] == samples


def test_a_run_alone_ends_as_in_a_large_batch():
    # Runs in one pass share nothing but the generator: a noise-free run ends where it
    # ends alone, whatever the batch. Robots with different odometry reach their corners
    # in different periods, so the batch reorders and drops runs as it goes.
    draw = np.random.default_rng(2).uniform
    errors = draw([0.99, 0.96, 0.995, 0.995, 0.33], [1.01, 1.04, 1.005, 1.005, 0.35], (48, 5))
    robots = [
        SimRobot.with_errors(FINE, E_d=e_d, E_b=e_b).calibrated(c_l, c_r, b)
        for e_d, e_b, c_l, c_r, b in errors
    ]
    directions = [CW, CCW] * 24
    batch = simulate(robots, square(1.0), directions)
    assert len(set(batch.samples_used.tolist())) > 10  # they do finish apart
    few = simulate(robots[:5], square(1.0), directions[:5])
    singles = [simulate(robots[i], square(1.0), [directions[i]]) for i in (0, 7, 30, 47)]
    for i, alone in [*zip((0, 7, 30, 47), singles, strict=True), (3, few)]:
        k = 3 if alone is few else 0
        np.testing.assert_allclose(batch.true_end[i], alone.true_end[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.odometry_end[i], alone.odometry_end[k], rtol=0, atol=1e-12)
        assert batch.samples_used[i] == alone.samples_used[k]


def test_a_finished_run_stands_still_while_the_others_drive():
    # A wider odometry wheelbase turns slower: the first robot finishes first.
    fleet = [SimRobot.with_errors(FINE), SimRobot.with_errors(FINE).calibrated(1, 1, 0.36)]
    result = simulate(fleet, square(0.5), [CCW, CW], FAST, record=True)
    trace = result.trace
    assert trace is not None
    end = int(result.samples_used[0])
    assert end < result.samples == result.samples_used[1]
    for series in (trace.true_pose, trace.counts, trace.odometry_pose):
        assert (series[0, end:] == series[0, end]).all()
        assert (series[1, end:] != series[1, end]).any()


@pytest.mark.parametrize("noise", [NoiseModel(slip=0.001), NoiseModel(0.001, 1.0, 0.001)])
def test_noise_is_drawn_for_every_run_in_every_period(noise):
    # Seeded results repeat: each period draws for every run, finished or not, in the
    # caller's order: the left wheels' slip (and bumps), then the right wheels'.
    noisy = SimRobot.with_errors(FINE, noise=noise)
    quiet = SimRobot.with_errors(FINE, E_d=1.01).calibrated(1.0, 1.0, 0.35)
    rng = np.random.default_rng(4)
    result = simulate([noisy, quiet, noisy], square(1.0), [CW, CCW, CW], FAST, rng)
    assert len(set(result.samples_used.tolist())) == 2
    replay = np.random.default_rng(4)
    for _ in range(result.samples):
        for _wheel in range(2):
            replay.standard_normal(3)
            if noise.bump_rate:
                replay.random(3)
    assert rng.random() == replay.random()


def test_seeded_noisy_runs_repeat():
    # End poses of a seeded batch with slip and bumps whose runs finish apart, as
    # simulated when the engine was written: every draw goes to the same run and wheel.
    noise = NoiseModel(slip=0.001, bump_rate=1.0, bump_size=0.001)
    robots = [
        SimRobot.with_errors(FINE, E_d=1 + 0.002 * k, E_b=1 - 0.01 * k, noise=noise).calibrated(
            1 - 0.001 * k, 1 + 0.001 * k, 0.34 + 0.002 * k
        )
        for k in range(6)
    ]
    result = simulate(robots, square(1.0), [CW, CCW] * 3, FAST, np.random.default_rng(11))
    assert result.samples_used.tolist() == [820, 820, 824, 824, 824, 824]
    expected = [
        [-1.9511875906997420e-03, 4.1196566465502450e-03, -6.2884698624621445e00],
        [4.2990558837951887e-02, -2.7727679185407375e-02, 6.3709379900929157e00],
        [1.0687082585420134e-01, 7.6686193837985417e-02, -6.4809761211369521e00],
        [1.5287813775048903e-01, -1.1765073604976177e-01, 6.5688315751604591e00],
        [2.2039890253603772e-01, 1.5974983778825955e-01, -6.6874372148434640e00],
        [2.8034100851631355e-01, -1.9022118718337441e-01, 6.7946762021394127e00],
    ]
    np.testing.assert_allclose(result.true_end, expected, rtol=0, atol=1e-12)


def test_the_engines_arc_step_is_chord_step_to_the_bit():
    # The engine computes chord_step's series for sin(h)/h inline, halved.
    from umbmark.model.kinematics import chord_step
    from umbmark.sim.kernels import half_sinc_series

    rng = np.random.default_rng(0)
    ds, theta = rng.uniform(-0.01, 0.01, (2, 2, 64))
    d_theta = rng.uniform(-0.0199, 0.0199, (2, 64))
    h = 0.5 * d_theta
    half_sinc = np.empty_like(h)
    work = np.empty_like(h), np.empty((3, *h.shape)), np.ones_like(h), np.full_like(h, 0.5)
    half_sinc_series(h, *work, half_sinc)()
    chord, heading = chord_step(ds, d_theta, theta, "arc")
    assert np.array_equal((ds + ds) * half_sinc, chord)
    assert np.array_equal(theta + h, heading)


@pytest.mark.parametrize(("E_d", "E_s"), [(1.0, 1.02), (1.03, 1.0), (1.03, 0.97)])
def test_on_the_spot_turn_section_2_3(E_d, E_s):
    # tau = tau_n D_avg / D_n (Eq. 2.13), and the centre circles a point
    # (b/2)(E_d - 1)/(E_d + 1) to its left: it moves by (d sin tau, d (1 - cos tau)).
    tau_n = math.pi / 2
    robot = SimRobot.with_errors(FINE, E_d=E_d, E_s=E_s)
    result = simulate(robot, spot_turn(tau_n), [CCW])
    odometry_turn = result.odometry_end[0, 2]
    assert odometry_turn == pytest.approx(tau_n, abs=1e-3)
    tau = result.true_end[0, 2]
    # The odometry counts whole encoder pulses: one pulse per wheel is 2.3e-6 m here,
    # 1.4e-5 rad of heading.
    assert tau == pytest.approx(odometry_turn * E_s, abs=3e-5)
    d = 0.17 * (E_d - 1) / (E_d + 1)
    np.testing.assert_allclose(
        result.true_end[0, :2], [d * math.sin(tau), d * (1 - math.cos(tau))], atol=1e-7
    )


def test_straight_line_shows_the_scale_error():
    robot = SimRobot.with_errors(FINE, E_s=1.015)
    result = simulate(robot, straight_line(5.0), [CCW])
    assert result.true_end[0, 0] / result.odometry_end[0, 0] == pytest.approx(1.015, rel=1e-6)
    assert result.odometry_end[0, 0] == pytest.approx(5.0, abs=1e-3)


@settings(max_examples=3, deadline=None)
@given(st.lists(st.tuples(st.floats(0.98, 1.02), st.floats(0.95, 1.05)), min_size=6, max_size=6))
@example([(0.98, 0.95), (0.98, 1.05), (1.02, 0.95), (1.02, 1.05), (1.0, 1.0), (1.001, 0.99)])
@pytest.mark.slow
def test_repeated_paper_correction_converges_to_the_truth(errors):
    # Noise-free, each pass of the paper's correction is applied on top of the last one
    # (Sec. 5); the odometry's wheel ratio and wheelbase must converge to the true ones.
    robots = [SimRobot.with_errors(FINE, E_d=e_d, E_b=e_b) for e_d, e_b in errors]
    for _ in range(8):
        trials = umbmark_trials(robots, L, runs_per_direction=2, control=FAST)
        robots = [calibrate_robot(trial, L)[1] for trial in trials]
    for robot, (e_d, e_b) in zip(robots, errors, strict=True):
        odo = robot.odometry
        assert odo.c_right / odo.c_left == pytest.approx(e_d, abs=2e-5)
        assert odo.wheelbase / 0.34 == pytest.approx(e_b, abs=2e-4)


@settings(max_examples=4, deadline=None)
@given(st.floats(0.98, 1.02), st.floats(0.95, 1.05))
def test_cw_and_ccw_are_mirror_images(E_d, E_b):
    # Mirroring the world swaps the wheels: a cw run of a robot with E_d is the mirror
    # image of a ccw run of the robot with 1 / E_d.
    robot = SimRobot.with_errors(FINE, E_d=E_d, E_b=E_b)
    mirror = SimRobot.with_errors(FINE, E_d=1 / E_d, E_b=E_b)
    result = simulate([robot, mirror], square(2.0), [CW, CCW], FAST)
    x, y, th = result.true_end[0]
    np.testing.assert_allclose(result.true_end[1], [x, -y, -th], atol=2e-4)


@settings(max_examples=4, deadline=None)
@given(st.floats(0.95, 1.05))
def test_wheelbase_error_alone_makes_only_type_a_errors(E_b):
    # Heading errors: cw 4 alpha + 4 beta, ccw -4 alpha + 4 beta (exact). Type A only:
    # beta = 0, and alpha = (pi/2)(1 - 1/E_b).
    result = simulate(SimRobot.with_errors(FINE, E_b=E_b), square(2.0), [CW, CCW], FAST)
    eps = result.true_end[:, 2] - result.odometry_end[:, 2]
    assert (eps[0] + eps[1]) / 8 == pytest.approx(0.0, abs=2e-5)
    assert (eps[0] - eps[1]) / 8 == pytest.approx(math.pi / 2 * (1 - 1 / E_b), abs=2e-5)


@settings(max_examples=4, deadline=None)
@given(st.floats(0.98, 1.02))
def test_diameter_ratio_alone_makes_only_type_b_errors(E_d):
    result = simulate(SimRobot.with_errors(FINE, E_d=E_d), square(2.0), [CW, CCW], FAST)
    eps = result.true_end[:, 2] - result.odometry_end[:, 2]
    beta = 2 * 2.0 / 0.34 * (E_d - 1) / (E_d + 1)
    assert (eps[0] - eps[1]) / 8 == pytest.approx(0.0, abs=2e-5)
    assert (eps[0] + eps[1]) / 8 == pytest.approx(beta, abs=2e-5)


def test_slip_variance_grows_with_distance_as_specified():
    # Each wheel's floor travel errs by N(0, slip^2 * travel); the centre's distance is
    # their mean, so its standard deviation over a line of length D is slip sqrt(D / 2).
    slip, length = 0.002, 3.0
    robot = SimRobot.with_errors(FINE, noise=NoiseModel(slip=slip))
    result = simulate(robot, straight_line(length), [CCW] * 400, FAST, np.random.default_rng(7))
    along = result.true_end[:, 0] - result.odometry_end[:, 0]
    expected = slip * math.sqrt(length / 2)
    assert np.std(along, ddof=1) == pytest.approx(expected, rel=0.12)
    assert abs(np.mean(along)) < 4 * expected / math.sqrt(400)


def test_bumps_make_the_wheels_turn_more_than_they_travel():
    # Bumps at rate lam per metre of wheel travel, each costing s of floor travel: over a
    # line of length D the centre falls short by lam D s on average.
    lam, size, length = 2.0, 0.003, 3.0
    robot = SimRobot.with_errors(FINE, noise=NoiseModel(bump_rate=lam, bump_size=size))
    result = simulate(robot, straight_line(length), [CCW] * 300, FAST, np.random.default_rng(3))
    short = result.odometry_end[:, 0] - result.true_end[:, 0]
    # Bumps per wheel are Poisson(lam D): the shortfall's sd is s sqrt(lam D / 2).
    sem = size * math.sqrt(lam * length / 2) / math.sqrt(300)
    assert np.mean(short) == pytest.approx(lam * length * size, abs=4 * sem)


def test_paper_noise_gives_the_papers_spread():
    # Sec. 5: about 25 mm standard deviation per cluster on a 4 x 4 m square.
    from umbmark.sim.reproduce import PAPER_NOISE

    robot = SimRobot.with_errors(FINE, noise=PAPER_NOISE)
    trials = umbmark_trials([robot] * 8, L, control=FAST, rng=np.random.default_rng(5))
    sigmas = [c.sigma for t in trials for c in t.benchmark.clusters]
    assert 0.018 < float(np.sqrt(np.mean(np.square(sigmas)))) < 0.032


def test_noisy_robot_needs_a_generator_and_runs_need_robots():
    robot = SimRobot.with_errors(FINE, noise=NoiseModel(slip=0.001))
    with pytest.raises(ValueError, match="random generator"):
        simulate(robot, square(1.0), [CW])
    with pytest.raises(ValueError, match="2 robots for 1 runs"):
        simulate([robot, robot], square(1.0), [CW])
    with pytest.raises(ValueError, match="positive amount"):
        straight_line(0.0)


def test_trace_records_every_sample():
    result = simulate(SimRobot.with_errors(FINE), straight_line(0.5), [CCW, CCW], FAST, record=True)
    trace = result.trace
    assert trace is not None
    n = result.samples + 1
    assert trace.time.shape == (n,)
    assert trace.true_pose.shape == (2, n, 3)
    assert trace.counts.shape == (2, n, 2)
    assert trace.counts.dtype == np.int64
    # Counts grow as the wheels turn: 0.5 m on a 0.15 m wheel with 4096 x 50 per turn.
    expected = 0.5 / (math.pi * 0.15) * 4096 * 50
    assert trace.counts[0, -1, 0] == pytest.approx(expected, rel=1e-3)

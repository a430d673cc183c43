"""The trajectory fit: whole runs against the ground truth, the time offset, honest
standard errors, and the scrub model (a wheelbase for arcs and one for spot turns).

Expected values are the simulated robots' true parameters, or quantities derived by hand
here (a plain loop integrating the richer model, a jackknife by refitting); never the
code under test.
"""

from __future__ import annotations

import io
import math
import re
import subprocess
import sys

import numpy as np
import pytest
from rich.console import Console

import umbmark
from umbmark.cli.render import render_calibration
from umbmark.core.stats import t_quantile
from umbmark.estimators.trajectory import trajectory_estimate
from umbmark.estimators.trajectory_fit import _cluster_covariance, fit_trajectories
from umbmark.model.kinematics import (
    WheelParams,
    effective_wheelbase,
    integrate_odometry,
    turning_share,
)
from umbmark.model.recording import PoseSeries, Recording, RunLog, WheelSeries
from umbmark.runs.logged import runs_from_recordings
from umbmark.sim.robot import NoiseModel, SimRobot

from helpers import cli_error, simulated_session

ODO = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
ROBOT = SimRobot.with_errors(ODO, E_d=1.002, E_b=1.01)

# --- the scrub model in the odometry -----------------------------------------------------


def test_turning_share_and_effective_wheelbase_by_hand():
    left = np.array([1.0, -1.0, 1.0, 0.0, 0.0, -2.0])
    right = np.array([1.0, 1.0, 3.0, 2.0, 0.0, -2.0])
    # straight, spot turn, arc (|3 - 1| / (3 + 1)), one wheel standing, no motion, backwards
    np.testing.assert_allclose(turning_share(left, right), [0, 1, 0.5, 1, 0, 0])
    b_eff = effective_wheelbase(left, right, wheelbase=0.2, spot_wheelbase=0.22)
    np.testing.assert_allclose(b_eff, [0.2, 0.22, 0.21, 0.22, 0.2, 0.2])
    with pytest.raises(ValueError, match="spot wheelbase must be > 0"):
        effective_wheelbase(left, right, 0.2, -0.1)


def test_integration_takes_a_wheelbase_per_step():
    # Spot turns of +-u per wheel: the heading turns by 2u / b of each step's b.
    u = 0.001
    b = np.array([0.2, 0.25, 0.2, 0.25])
    poses = integrate_odometry(np.full(4, -u), np.full(4, u), b)
    np.testing.assert_allclose(poses[:, 2], np.cumsum(np.r_[0, 2 * u / b]), rtol=1e-12)
    np.testing.assert_allclose(poses[-1, :2], 0.0, atol=1e-15)
    with pytest.raises(ValueError, match="wheelbase must be > 0 in every interval"):
        integrate_odometry(np.ones(2), np.ones(2), np.array([0.2, 0.0]))


def test_wheel_params_carry_a_spot_wheelbase():
    plain = WheelParams(wheelbase=0.2, wheel_diameter=0.084)
    assert plain.spot_wheelbase is None
    assert plain == WheelParams(0.2, 0.084, spot_wheelbase=None)
    scrub = WheelParams(0.2, 0.084, spot_wheelbase=0.21)
    assert scrub != plain
    assert scrub.with_corrections(c_left=1.01).spot_wheelbase == 0.21
    assert scrub.with_corrections(c_left=1.01) == WheelParams(
        0.2, 0.084, c_left=1.01, spot_wheelbase=0.21
    )
    with pytest.raises(ValueError, match="spot wheelbase must be > 0"):
        WheelParams(0.2, 0.084, spot_wheelbase=0.0)


def test_run_log_odometry_uses_the_spot_wheelbase():
    # A spot turn of one wheel turn each way: D/2 * 2 pi of travel per wheel, heading
    # 2 * (pi D) / b_spot, position unchanged; a straight line ignores b_spot.
    steps = np.linspace(0.0, 2 * math.pi, 101)
    turn = RunLog(
        time=np.arange(101.0),
        wheel_angles=np.column_stack([-steps, steps]),
        truth=np.zeros((101, 3)),
    )
    params = WheelParams(0.2, 0.084, spot_wheelbase=0.25)
    odo = turn.odometry(params)
    assert odo[-1, 2] == pytest.approx(2 * math.pi * 0.084 / 0.25, rel=1e-12)
    assert turn.odometry(WheelParams(0.2, 0.084))[-1, 2] == pytest.approx(
        2 * math.pi * 0.084 / 0.2, rel=1e-12
    )
    line = RunLog(np.arange(101.0), np.column_stack([steps, steps]), np.zeros((101, 3)))
    np.testing.assert_allclose(line.odometry(params)[-1], [math.pi * 0.084, 0, 0], atol=1e-15)


# --- the fit on simulated robots ----------------------------------------------------------


@pytest.fixture(scope="module")
def session():
    t, counts, poses, _ = simulated_session(ROBOT, ["cw", "cw", "ccw", "ccw"], side=1.0)
    recording = Recording(
        name="session.csv",
        wheels=WheelSeries(t, counts * ODO.radians_per_pulse),
        truth=PoseSeries(t, poses),
        params=ODO,
    )
    return runs_from_recordings([recording], ODO).runs


def test_importing_the_module_leaves_scipy_alone():
    code = "import sys, umbmark.estimators.trajectory; print('scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize(("start_pose", "rel"), [("fitted", 1e-6), ("truth", 1e-5)])
def test_fit_recovers_the_simulated_robot(session, start_pose, rel):
    fit = fit_trajectories([r.log for r in session], ODO, start_pose=start_pose)
    # The robot has no slip; encoders quantize to 12 micrometres per count. The fit
    # recovers the truth to far below that (the start taken from the first ground-truth
    # sample costs a few parts per million).
    assert fit.r_left == pytest.approx(ROBOT.diameter_left / 2, rel=rel)
    assert fit.r_right == pytest.approx(ROBOT.diameter_right / 2, rel=rel)
    assert fit.wheelbase == pytest.approx(ROBOT.wheelbase, rel=rel)
    assert abs(fit.time_offset) < 1e-4
    assert fit.runs == 4
    assert fit.samples == sum(int(r.log.matched.sum()) for r in session)
    assert fit.rms_position < 1e-4
    assert fit.parameters == ("r_left", "r_right", "wheelbase", "time_offset")
    assert fit.spot_wheelbase is None
    # The fitted parameters replay the runs onto the ground truth.
    params = fit.params(ODO)
    assert params.c_left == pytest.approx(ROBOT.diameter_left / ODO.wheel_diameter, rel=1e-5)
    assert params.spot_wheelbase is None
    for run in session:
        end = run.reintegrated(params)
        assert math.hypot(*end.return_error) < 2e-4


@pytest.mark.slow
def test_errors_relative_to_the_active_parameters():
    sim = umbmark.simulate(E_d=1.002, E_b=1.01, E_s=1.005, runs=2, side_length=1.0,
                           noise_free=True, record=True, seed=1)  # fmt: skip
    active = sim.robot.odometry
    estimate, fit = trajectory_estimate([r.log for r in sim.runs], active, side_length=1.0)
    assert estimate.method == "trajectory"
    assert estimate.E_d == pytest.approx(1.002, abs=1e-6)
    assert estimate.E_b == pytest.approx(1.01, abs=1e-6)
    assert estimate.E_s == pytest.approx(1.005, abs=1e-6)
    # alpha: a turn the odometry counts as 90 degrees turns 90 E_s / E_b (Eq. 2.13);
    # beta: a leg of 1 m curves by (2L / b)(E_d - 1)/(E_d + 1).
    assert estimate.alpha == pytest.approx(math.pi / 2 * (1 - 1.005 / 1.01), abs=1e-6)
    b_true = 1.01 * active.wheelbase
    assert estimate.beta == pytest.approx(2 / b_true * 0.002 / 2.002, rel=1e-4)
    components = {"r_left", "r_right", "wheelbase", "time_offset", "rms_position",
                  "rms_heading", "runs", "samples"}  # fmt: skip
    assert components <= set(estimate.components)
    assert estimate.components["runs"] == 4
    assert {"E_d", "E_b", "E_s", "r_left", "r_right", "wheelbase", "time_offset"} <= set(
        estimate.standard_errors
    )
    assert estimate.components["wheelbase"] == fit.wheelbase


def test_long_recordings_are_compared_at_a_bounded_number_of_samples(session, monkeypatch):
    # Thinning the comparison to 150 samples a run (of several hundred) keeps the fit on
    # the simulated robot's truth: the wheel data are still integrated whole.
    from umbmark.estimators import trajectory_model

    counts = [int(r.log.matched.sum()) for r in session]
    assert min(counts) > 300
    monkeypatch.setattr(trajectory_model, "MAX_COMPARED_PER_RUN", 150)
    fit = fit_trajectories([r.log for r in session], ODO)
    assert fit.samples == 150 * len(session)
    assert fit.r_left == pytest.approx(ROBOT.diameter_left / 2, rel=1e-5)
    assert fit.r_right == pytest.approx(ROBOT.diameter_right / 2, rel=1e-5)
    assert fit.wheelbase == pytest.approx(ROBOT.wheelbase, rel=1e-5)


def _delayed(log: RunLog, delay: float) -> RunLog:
    """The same run with the ground truth's time stamps ``delay`` seconds late."""
    t = log.time
    truth = np.column_stack([np.interp(t - delay, t, log.truth[:, j]) for j in range(3)])
    return RunLog(t, log.wheel_angles, truth, log.source)


@pytest.mark.slow
def test_time_offset_is_found_and_can_be_left_out():
    sim = umbmark.simulate(E_d=1.002, E_b=1.01, runs=2, side_length=1.0, record=True, seed=2)
    odo = sim.robot.odometry
    late = [_delayed(run.log, 0.04) for run in sim.runs]
    fit = fit_trajectories(late, odo)
    # Ground truth 40 ms late: the truth at t + 40 ms matches the wheels at t.
    assert fit.time_offset == pytest.approx(0.04, abs=3 * fit.standard_errors["time_offset"])
    assert 0 < fit.standard_errors["time_offset"] < 0.002
    assert fit.wheelbase == pytest.approx(sim.robot.wheelbase, rel=1e-3)
    fixed = fit_trajectories(late, odo, fit_time_offset=False)
    assert fixed.time_offset == 0.0
    assert fixed.standard_errors["time_offset"] == 0.0
    assert "time_offset" not in fixed.parameters
    assert fixed.rms_heading > 3 * fit.rms_heading  # 40 ms of turning left unexplained


@pytest.mark.slow
def test_standard_errors_are_honest():
    """95 % intervals cover the truth about 95 % of the time over many noisy sessions.

    Sixty sessions of four runs (2 cw + 2 ccw around 1 m squares, the simulator's default
    slip): the residuals of a run are strongly correlated, and the textbook standard
    errors from them are 8 to 45 times too small (measured while writing this test: they
    cover E_d in 3 % of the sessions). The cluster-robust ones must cover each quantity in
    85 % or more of the sessions and all of them together in 88 to 99.5 %, and be of the
    size of the actual spread of the estimates.
    """
    sessions, per_direction = 60, 2
    sim = umbmark.simulate(E_d=0.997, E_b=1.02, E_s=1.01, runs=sessions * per_direction,
                           side_length=1.0, dt=0.05, record=True, seed=100)  # fmt: skip
    robot, odo = sim.robot, sim.robot.odometry
    truth = {
        "E_d": robot.diameter_right / robot.diameter_left,
        "E_b": robot.wheelbase / odo.wheelbase,
        "E_s": (robot.diameter_left + robot.diameter_right) / (2 * odo.wheel_diameter),
        "r_left": robot.diameter_left / 2,
        "wheelbase": robot.wheelbase,
    }
    by_direction = {d: [r.log for r in sim.runs if r.direction.value == d] for d in ("cw", "ccw")}
    values, errors = [], []
    for i in range(sessions):
        part = slice(i * per_direction, (i + 1) * per_direction)
        logs = by_direction["cw"][part] + by_direction["ccw"][part]
        estimate, fit = trajectory_estimate(logs, odo)
        found = {"E_d": estimate.E_d, "E_b": estimate.E_b, "E_s": estimate.E_s,
                 "r_left": fit.r_left, "wheelbase": fit.wheelbase}  # fmt: skip
        values.append([found[k] for k in truth])
        errors.append([estimate.standard_errors[k] for k in truth])
        dof = estimate.dof
    value, se = np.array(values), np.array(errors)
    z = (value - np.array(list(truth.values()))) / se
    # Four runs, three degrees of freedom: the 95 % interval is +- t_3 standard errors.
    assert dof == 3
    covered = np.abs(z) < t_quantile(0.975, 3)
    assert np.all(covered.mean(axis=0) >= 0.85), covered.mean(axis=0)
    assert 0.88 <= covered.mean() <= 0.995
    ratio = np.median(se, axis=0) / value.std(axis=0)
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio


def test_one_run_falls_back_to_its_halves():
    sim = umbmark.simulate(E_d=1.002, E_b=1.01, runs=2, side_length=1.0, dt=0.05,
                           record=True, seed=3)  # fmt: skip
    fit = fit_trajectories([sim.runs[0].log], sim.robot.odometry)
    assert fit.runs == 1
    assert fit.clusters == 2
    for key, true in (("r_left", sim.robot.diameter_left / 2), ("wheelbase", sim.robot.wheelbase)):
        se = fit.standard_errors[key]
        assert 0 < se < 0.01 * true
        # Two halves: one degree of freedom, a 95 % interval of +- 12.7 standard errors.
        assert abs(getattr(fit, key) - true) < t_quantile(0.975, fit.clusters - 1) * se


def test_cluster_covariance_is_the_jackknife_over_runs():
    """For a linear least-squares problem the one-step jackknife is exact: compare with
    refitting without each cluster."""
    rng = np.random.default_rng(5)
    groups = np.repeat(np.arange(5), [7, 9, 6, 8, 10])
    design = rng.normal(size=(groups.size, 3))
    y = design @ [1.0, -2.0, 0.5] + rng.normal(size=groups.size) + rng.normal(size=5)[groups]
    full = np.linalg.lstsq(design, y, rcond=None)[0]
    left_out = np.array(
        [np.linalg.lstsq(design[groups != g], y[groups != g], rcond=None)[0] for g in range(5)]
    )
    dev = left_out - full
    expected = dev.T @ dev * 4 / 5
    # Residuals of the weighted problem are model minus data; the Jacobian is the design.
    got, alone = _cluster_covariance(design, design @ full - y, groups, 5)
    np.testing.assert_allclose(got, expected, rtol=1e-9)
    assert alone == ()  # every parameter is pinned by the clusters left in


def test_too_little_motion_is_refused():
    t = np.arange(4.0)
    short = RunLog(t, np.zeros((4, 2)), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="no run has 5 or more samples"):
        fit_trajectories([short], ODO)
    # Straight lines only: nothing pins the wheelbase down.
    t = np.arange(50.0)
    angles = np.column_stack([t, t])
    line = RunLog(t, angles, np.column_stack([0.075 * t, 0 * t, 0 * t]))
    with pytest.raises(ValueError, match="does not pin down wheelbase"):
        fit_trajectories([line, line], ODO)


# --- the scrub model ----------------------------------------------------------------------

#: Wheel rates [rad/s] (left, right) and durations [s] of one run: straight, spot turn,
#: arc, spot turn the other way, arc the other way, straight.
_LEGS = [(5, 5, 4), (-3, 3, 2.5), (4, 6, 5), (3, -3, 2.5), (6, 4, 5), (5, 5, 3)]
_DT = 0.02


def _wheel_angles(scale: float) -> np.ndarray:
    """Wheel angles (n, 2) [rad] of one run: each leg ramps up and down in 0.5 s."""
    rates = []
    for left, right, duration in _LEGS:
        t = np.arange(0.0, duration, _DT)
        ramp = np.clip(np.minimum(t, duration - t) / 0.5, 0.0, 1.0)
        rates.append(np.column_stack([left * ramp, right * ramp]) * scale)
    steps = np.vstack(rates) * _DT
    return np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])


def _scrub_truth(angles, radius, b_arc, b_spot, slip, rng):
    """The true path, integrated step by step with the scrub model and Gaussian slip of
    standard deviation ``slip * sqrt(travel)`` per wheel and step."""
    pose = np.zeros(3)
    out = [pose.copy()]
    for d_phi_l, d_phi_r in np.diff(angles, axis=0):
        du_l, du_r = radius * d_phi_l, radius * d_phi_r
        du_l += slip * math.sqrt(abs(du_l)) * rng.normal()
        du_r += slip * math.sqrt(abs(du_r)) * rng.normal()
        moving = abs(du_l) + abs(du_r)
        w = abs(du_r - du_l) / moving if moving > 0 else 0.0
        b = b_arc + (b_spot - b_arc) * w
        ds, dth = (du_r + du_l) / 2, (du_r - du_l) / b
        chord = ds * (math.sin(dth / 2) / (dth / 2) if dth else 1.0)
        heading = pose[2] + dth / 2
        pose = pose + np.array([chord * math.cos(heading), chord * math.sin(heading), dth])
        out.append(pose.copy())
    return np.array(out)


def _scrub_session(b_arc, b_spot, seed, runs=6):
    rng = np.random.default_rng(seed)
    logs = []
    for k in range(runs):
        angles = _wheel_angles(1.0 + 0.1 * k)
        truth = _scrub_truth(angles, 0.042, b_arc, b_spot, 1e-4, rng)
        logs.append(RunLog(np.arange(angles.shape[0]) * _DT, angles, truth))
    return logs


NOMINAL = WheelParams(wheelbase=0.2, wheel_diameter=0.084)


@pytest.mark.slow
def test_scrub_fit_recovers_both_wheelbases():
    logs = _scrub_session(b_arc=0.200, b_spot=0.206, seed=1)
    fit = fit_trajectories(logs, NOMINAL, model="scrub")
    se = fit.standard_errors
    assert fit.model == "scrub"
    assert fit.parameters == ("r_left", "r_right", "wheelbase", "spot_wheelbase", "time_offset")
    assert fit.wheelbase == pytest.approx(0.200, abs=3 * se["wheelbase"])
    assert fit.spot_wheelbase == pytest.approx(0.206, abs=3 * se["spot_wheelbase"])
    assert se["wheelbase"] < 2e-4
    assert se["spot_wheelbase"] < 2e-4
    # Replayed with the fitted scrub model, every run ends where the truth does.
    params = fit.params(NOMINAL)
    assert params.spot_wheelbase == fit.spot_wheelbase
    for log in logs:
        end = log.odometry(params)[-1]
        assert math.hypot(*(end[:2] - log.truth[-1, :2])) < 0.005
    # One wheelbase for both lands in between, and misses the runs' ends by far more.
    estimate, scrub = trajectory_estimate(logs, NOMINAL, model="scrub")
    assert estimate.method == "trajectory-scrub"
    assert scrub.spot_wheelbase == fit.spot_wheelbase
    single = estimate.components["wheelbase"]
    assert 0.200 < single < 0.206
    assert estimate.components["arc_wheelbase"] == fit.wheelbase
    assert estimate.components["spot_wheelbase"] == fit.spot_wheelbase
    assert estimate.standard_errors["spot_wheelbase"] == se["spot_wheelbase"]
    assert estimate.E_b == pytest.approx(single / NOMINAL.wheelbase)
    assert estimate.components["rms_position"] > 3 * estimate.components["scrub_rms_position"]


def test_scrub_fit_of_a_robot_without_scrub_finds_one_wheelbase():
    logs = _scrub_session(b_arc=0.203, b_spot=0.203, seed=2)
    fit = fit_trajectories(logs, NOMINAL, model="scrub")
    assert fit.spot_wheelbase is not None
    i, j = fit.parameters.index("wheelbase"), fit.parameters.index("spot_wheelbase")
    contrast = np.zeros(len(fit.parameters))
    contrast[[i, j]] = [-1.0, 1.0]
    se_difference = math.sqrt(contrast @ fit.covariance @ contrast)
    assert abs(fit.spot_wheelbase - fit.wheelbase) < 3 * se_difference
    assert abs(fit.spot_wheelbase - fit.wheelbase) < 5e-4
    assert fit.wheelbase == pytest.approx(0.203, abs=5e-4)


# --- a tracked point off the axle centre --------------------------------------------------

#: Where the simulated marker sits in the robot frame [m]: 250 mm ahead of the axle
#: centre and 80 mm to its right.
MARKER = (0.25, -0.08)


def _marker_poses(poses: np.ndarray, offset: tuple[float, float]) -> np.ndarray:
    """Poses (n, 3) of a point at ``offset`` in the robot frame, from axle poses (n, 3),
    written out by hand: ``x + cos(th) d_x - sin(th) d_y``, ``y + sin(th) d_x + cos(th) d_y``,
    the heading unchanged."""
    x, y, th = poses[:, 0], poses[:, 1], poses[:, 2]
    dx, dy = offset
    return np.column_stack(
        [x + np.cos(th) * dx - np.sin(th) * dy, y + np.sin(th) * dx + np.cos(th) * dy, th]
    )


def _axle_and_marker_runs(robot: SimRobot, seed: int = 0):
    """One simulated session (2 cw + 2 ccw runs around 1 m squares) cut into runs twice:
    with the axle centre's ground truth and with the marker's."""
    t, counts, poses, _ = simulated_session(robot, ["cw", "cw", "ccw", "ccw"], side=1.0, seed=seed)
    out = []
    for truth in (poses, _marker_poses(poses, MARKER)):
        recording = Recording(
            name="session.csv",
            wheels=WheelSeries(t, counts * ODO.radians_per_pulse),
            truth=PoseSeries(t, truth),
            params=ODO,
        )
        out.append(runs_from_recordings([recording], ODO).runs)
    return out


@pytest.fixture(scope="module")
def marker_session():
    return _axle_and_marker_runs(ROBOT)[1]


@pytest.mark.slow
@pytest.mark.parametrize(("start_pose", "rel"), [("fitted", 1e-6), ("truth", 1e-5)])
def test_fit_finds_the_tracked_point(marker_session, start_pose, rel):
    logs = [r.log for r in marker_session]
    fit = fit_trajectories(logs, ODO, start_pose=start_pose, fit_truth_offset=True)
    assert fit.parameters == ("r_left", "r_right", "wheelbase", "time_offset",
                              "truth_offset_x", "truth_offset_y")  # fmt: skip
    assert fit.truth_offset_fitted
    assert fit.truth_offset_x == pytest.approx(MARKER[0], abs=1e-3)
    assert fit.truth_offset_y == pytest.approx(MARKER[1], abs=1e-3)
    assert fit.standard_errors["truth_offset_x"] > 0
    assert fit.standard_errors["truth_offset_y"] > 0
    # The wheels come out as from the axle centre's truth (test_fit_recovers_the_simulated_robot).
    assert fit.r_left == pytest.approx(ROBOT.diameter_left / 2, rel=rel)
    assert fit.r_right == pytest.approx(ROBOT.diameter_right / 2, rel=rel)
    assert fit.wheelbase == pytest.approx(ROBOT.wheelbase, rel=rel)
    estimate, _ = trajectory_estimate(logs, ODO, 1.0, start_pose=start_pose, fit_truth_offset=True)
    assert estimate.E_d == pytest.approx(1.002, abs=10 * rel)
    assert estimate.E_b == pytest.approx(1.01, abs=10 * rel)
    for key, true in zip(("truth_offset_x", "truth_offset_y"), MARKER, strict=True):
        assert estimate.components[key] == pytest.approx(true, abs=1e-3)
        assert estimate.standard_errors[key] == fit.standard_errors[key]


@pytest.mark.slow
def test_truth_offset_at_its_bound_is_refused(marker_session):
    # The marker sits 250 mm ahead: a bound of 100 mm cannot hold it.
    with pytest.raises(
        ValueError, match=r"truth offset \(100, -?\d+\) mm reaches its bound of 0.1 m"
    ):
        fit_trajectories([r.log for r in marker_session], ODO, fit_truth_offset=True,
                         max_truth_offset=0.1)  # fmt: skip


@pytest.mark.slow
def test_offset_left_alone_is_not_fitted(session):
    fit = fit_trajectories([r.log for r in session], ODO)
    assert not fit.truth_offset_fitted
    assert (fit.truth_offset_x, fit.truth_offset_y) == (0.0, 0.0)
    assert fit.standard_errors["truth_offset_x"] == fit.standard_errors["truth_offset_y"] == 0.0
    estimate, _ = trajectory_estimate([r.log for r in session], ODO)
    assert "truth_offset_x" not in estimate.components


@pytest.mark.slow
def test_offset_on_noisy_runs_is_honest():
    """With slip: axle truth gives an offset of zero within its standard error and the
    errors of the plain fit; the marker's truth gives the marker's offset and the same
    errors. Four runs: the 95 % interval is +- t_3 = 3.18 standard errors."""
    noisy = SimRobot.with_errors(ODO, E_d=1.002, E_b=1.01, noise=NoiseModel(slip=0.0004))
    axle, marker = _axle_and_marker_runs(noisy, seed=2)
    limit = t_quantile(0.975, 3)
    plain, _ = trajectory_estimate([r.log for r in axle], ODO, 1.0)
    true = {"E_d": noisy.diameter_right / noisy.diameter_left, "E_b": 1.01}
    for runs, offset in ((axle, (0.0, 0.0)), (marker, MARKER)):
        estimate, fit = trajectory_estimate([r.log for r in runs], ODO, 1.0, fit_truth_offset=True)
        assert estimate.dof == 3
        for key, expected in zip(("truth_offset_x", "truth_offset_y"), offset, strict=True):
            se = fit.standard_errors[key]
            assert 0 < se < 1e-3
            assert abs(estimate.components[key] - expected) < min(limit * se, 1e-3)
        for key in ("E_d", "E_b"):
            se = estimate.standard_errors[key]
            assert abs(getattr(estimate, key) - true[key]) < limit * se
            # Fitting the offset moves the wheel errors little: over 30 seeds the median
            # shift from the plain fit is 0.06 standard errors for E_d, the largest 1.4.
            assert abs(getattr(estimate, key) - getattr(plain, key)) < 0.5 * se


def _arc_run(turn_deg: float, radius: float = 2.0, samples: int = 50) -> RunLog:
    """One run along a circular arc of ``radius`` [m] turning left by ``turn_deg``: wheel
    angles of the nominal wheels (``ODO``) and the axle centre's true poses, by hand."""
    s = np.linspace(0.0, radius * math.radians(turn_deg), samples)  # arc length [m]
    half = ODO.wheelbase / (2 * radius)
    angles = np.column_stack([s * (1 - half), s * (1 + half)]) / (ODO.wheel_diameter / 2)
    truth = np.column_stack([radius * np.sin(s / radius), radius * (1 - np.cos(s / radius)),
                             s / radius])  # fmt: skip
    return RunLog(np.arange(float(samples)), angles, truth)


def test_truth_offset_needs_turns():
    t = np.arange(50.0)
    line = RunLog(t, np.column_stack([t, t]), np.column_stack([0.075 * t, 0 * t, 0 * t]))
    arc = _arc_run(20.0)
    for runs in ([line, line], [arc, arc], [line, arc]):
        with pytest.raises(ValueError, match="does not pin down the truth offset: no run turns"):
            fit_trajectories(runs, ODO, fit_truth_offset=True)
    with pytest.raises(ValueError, match="does not pin down the truth offset"):
        trajectory_estimate([arc, arc], ODO, fit_truth_offset=True)


@pytest.mark.slow
def test_calibrate_fits_the_truth_offset_of_run_logs(tmp_path):
    """The whole path: run logs written by the simulator, their ground truth moved to the
    marker by hand, calibrated and summarized; other methods refuse the flag (exit 2)."""
    logs = tmp_path / "logs"
    sim = umbmark.simulate(E_d=1.002, E_b=1.01, runs=2, side_length=1.0, seed=2, logs=logs)
    robot = sim.robot
    for path in sorted(logs.glob("run-*.csv")):
        lines = path.read_text(encoding="utf-8").splitlines()
        head = [line for line in lines if line.startswith("#") or line.startswith("time")]
        table = np.loadtxt(path, delimiter=",", comments="#", skiprows=len(head))
        assert head[-1] == "time,x,y,theta,left,right"
        table[:, 1:4] = _marker_poses(table[:, 1:4], MARKER)
        rows = [",".join(repr(float(v)) for v in row) for row in table]
        path.write_text("\n".join([*head, *rows]) + "\n", encoding="utf-8")
    report = umbmark.calibrate(logs, method="trajectory", fit_truth_offset=True)
    data = report.to_dict()  # what --json prints
    comp, se = data["components"], data["standard_errors"]
    for key, true in zip(("truth_offset_x", "truth_offset_y"), MARKER, strict=True):
        assert comp[key] == pytest.approx(true, abs=1e-3)
        assert 0 < se[key] < 1e-3
    limit = t_quantile(0.975, 3)
    assert abs(data["E_d"] - robot.diameter_right / robot.diameter_left) < limit * se["E_d"]
    assert abs(data["E_b"] - 1.01) < limit * se["E_b"]
    # The printed summary (what the command prints without --json), in millimetres.
    shown = io.StringIO()
    render_calibration(report, Console(file=shown, width=120))
    for key, label in (("truth_offset_x", "forward"), ("truth_offset_y", "left")):
        found = re.search(rf"tracked point {label} \[mm\] +(-?[\d.]+) ± ([\d.]+)", shown.getvalue())
        assert found, shown.getvalue()
        assert found.group(1) == f"{1000 * comp[key]:.1f}"
        assert found.group(2) == f"{1000 * se[key]:.1f}"
    line = cli_error("calibrate", str(logs), "--method", "exact", "--fit-truth-offset")
    assert "--fit-truth-offset needs --method trajectory or trajectory-scrub" in line

"""The scan-matching calibration (Censi et al. 2013) on simulated intervals of known truth.

The intervals are made here independently of the estimator: each interval's robot motion
is integrated numerically (many small steps of the differential-drive kinematics), and
the sensor's motion is ``inv(L) @ O @ L`` with homogeneous matrices, where the estimator
composes poses in closed form. Expected values are the simulation's truth, or figures
derived by hand from it (``E_d = r_R / r_L`` ...).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.estimators.scan_excitation import excitation
from umbmark.estimators.scan_matching import fit_intervals, scan_matching_estimate
from umbmark.model.kinematics import WheelParams
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.sources.tuples import read_tuples, write_tuples

from helpers import cli_error, cli_json, run_cli

R_L, R_R, B = 0.0412, 0.0415, 0.088  # truth: wheel radii and wheelbase [m]
LASER = (0.05, -0.02, 0.3)  # truth: the laser's mounting [m, m, rad]


def _pose(x: float, y: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def _integrate(w_l, w_r, duration, r_l: float, r_r: float, b: float):
    """``(n, 3)`` the robot's motion over intervals of constant wheel speeds [rad/s]
    (``(n,)`` arrays), by 400 midpoint steps of ``x' = v cos(th), y' = v sin(th),
    th' = w``."""
    v, w = 0.5 * (r_l * w_l + r_r * w_r), (r_r * w_r - r_l * w_l) / b
    x, y, th = np.zeros_like(v), np.zeros_like(v), np.zeros_like(v)
    dt = duration / 400
    for _ in range(400):
        mid = th + 0.5 * w * dt
        x = x + v * np.cos(mid) * dt
        y = y + v * np.sin(mid) * dt
        th = th + w * dt
    return np.column_stack([x, y, th])


def _speeds(kind: str, rng: np.random.Generator) -> tuple[float, float]:
    """Wheel speeds [rad/s] of one interval of ``kind``."""
    a = rng.uniform(3.0, 8.0) * rng.choice([-1.0, 1.0])
    if kind == "spot":
        return -a, a
    if kind == "straight":
        return a, a
    if kind == "left":
        return 0.4 * abs(a), abs(a)
    return abs(a), 0.4 * abs(a)  # right


def simulate(
    kinds: list[str],
    *,
    rng: np.random.Generator,
    noise: tuple[float, float, float] = (0.0, 0.0, 0.0),
    laser: tuple[float, float, float] = LASER,
    truth: tuple[float, float, float] = (R_L, R_R, B),
) -> MotionIntervals:
    """Intervals of the given kinds, the sensor's motion with Gaussian noise added."""
    mount = _pose(*laser)
    speeds = np.array([_speeds(kind, rng) for kind in kinds])
    duration = rng.uniform(0.1, 0.3, size=len(kinds))
    robot = _integrate(speeds[:, 0], speeds[:, 1], duration, *truth)
    rows = []
    for k in range(len(kinds)):
        s = np.linalg.inv(mount) @ _pose(*robot[k]) @ mount
        rows.append((s[0, 2], s[1, 2], math.atan2(s[1, 0], s[0, 0])))
    motion = np.array(rows) + rng.normal(0.0, noise, size=(len(kinds), 3))
    return MotionIntervals(duration, speeds[:, 0] * duration, speeds[:, 1] * duration, motion)


MIX = ["spot", "straight", "left", "right"]


def _mix(n: int) -> list[str]:
    return [MIX[k % 4] for k in range(n)]


def test_noiseless_intervals_give_the_truth_exactly():
    cal = fit_intervals(simulate(_mix(80), rng=np.random.default_rng(1)), rounds=0)
    assert cal.radius_left == pytest.approx(R_L, rel=1e-6)
    assert cal.radius_right == pytest.approx(R_R, rel=1e-6)
    assert cal.wheelbase == pytest.approx(B, rel=1e-6)
    assert cal.laser_pose == pytest.approx(LASER, abs=1e-6)


@pytest.mark.parametrize("yaw", [math.pi - 0.05, -math.pi + 0.2, -2.0, 1.9])
def test_the_mirrored_solution_is_resolved_to_a_positive_wheelbase(yaw):
    # x and -x minimise the same form: -x is a negative wheelbase with the laser turned by
    # 180 degrees; a laser mounted backwards must come out as itself.
    laser = (-0.1, 0.03, yaw)
    cal = fit_intervals(simulate(_mix(60), rng=np.random.default_rng(2), laser=laser))
    assert cal.wheelbase == pytest.approx(B, rel=1e-6)
    assert cal.laser_pose[:2] == pytest.approx(laser[:2], abs=1e-6)
    assert math.remainder(cal.laser_pose[2] - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-6)


NOISE = (0.002, 0.002, math.radians(0.5))


def test_noisy_estimates_lie_within_their_intervals():
    cal = fit_intervals(simulate(_mix(600), rng=np.random.default_rng(3), noise=NOISE))
    se = np.sqrt(np.diag(cal.covariance))
    truth = np.array([R_L, R_R, B, *LASER])
    assert np.all(np.abs(cal.values - truth) < 4.0 * se), (cal.values - truth) / se
    # the noise the covariance assumes is the one simulated (rejection trims its tails)
    assert cal.noise == pytest.approx(NOISE, rel=0.2)


@pytest.mark.slow
@pytest.mark.parametrize(("rounds", "high"), [(0, 1.25), (4, 1.4)])
def test_standard_errors_match_the_monte_carlo_scatter(rounds, high):
    # 200 trials measured: scatter / standard error 0.99-1.08 without rejection (the
    # bound is reached), 1.02-1.16 with the default four rounds (rejection drops good
    # intervals too); 60 trials know a standard deviation within about +/-20 % (2 sigma).
    rng = np.random.default_rng(4)
    values, errors = [], []
    for _ in range(60):
        cal = fit_intervals(simulate(_mix(300), rng=rng, noise=NOISE), rounds=rounds)
        values.append(cal.values)
        errors.append(np.sqrt(np.diag(cal.covariance)))
    scatter = np.std(values, axis=0, ddof=1)
    ratio = scatter / np.mean(errors, axis=0)
    assert np.all((ratio > 0.8) & (ratio < high)), ratio


def test_outliers_are_rejected():
    rng = np.random.default_rng(5)
    intervals = simulate(_mix(400), rng=rng, noise=NOISE)
    bad = rng.choice(400, size=12, replace=False)
    motion = intervals.sensor_motion.copy()
    motion[bad, 0] += 0.15  # a scan matcher's wrong match: 15 cm and 25 degrees off
    motion[bad, 2] += math.radians(25)
    spoiled = MotionIntervals(intervals.duration, intervals.phi_left, intervals.phi_right, motion)
    cal = fit_intervals(spoiled)
    assert not cal.kept[bad].any()
    se = np.sqrt(np.diag(cal.covariance))
    truth = np.array([R_L, R_R, B, *LASER])
    assert np.all(np.abs(cal.values - truth) < 4.0 * se)
    naive = fit_intervals(spoiled, rounds=0)
    assert np.max(np.abs(naive.values - truth) / se) > 5.0  # without rejection: off


@pytest.mark.parametrize(
    ("kinds", "missing"),
    [
        (["straight"] * 50, "turns on the spot"),
        (["spot"] * 50, "straights"),
        (["left"] * 50, "turns on the spot and straights"),
        (["straight"] * 200 + ["spot"], "turns on the spot"),
    ],
)
def test_unexcited_motion_is_refused_naming_what_to_drive(kinds, missing):
    intervals = simulate(kinds, rng=np.random.default_rng(6), noise=NOISE)
    with pytest.raises(InputError, match="does not excite") as caught:
        fit_intervals(intervals)
    assert f"drive more {missing}" in str(caught.value)


def test_turning_one_way_only_is_refused_when_ill_conditioned_and_warned_otherwise():
    rng = np.random.default_rng(7)
    one_way = simulate(["straight"] * 300 + ["left"], rng=rng, noise=NOISE)
    with pytest.raises(InputError, match="turns in both directions"):
        fit_intervals(one_way)
    cal = fit_intervals(simulate(["straight", "left"] * 40, rng=rng, noise=NOISE))
    assert any("every turn is to the left" in w for w in cal.warnings)


def test_excitation_counts_the_kinds_of_motion():
    found = excitation(np.array([1.0, 1.0, -1.0, 0.4, 0.0]), np.array([1.0, -1.0, 1.0, 1.0, 0.0]))
    assert (found.n_straight, found.n_spot, found.n_arc, found.n_still) == (1, 2, 1, 1)
    assert (found.n_left, found.n_right) == (2, 1)


def test_intervals_with_values_that_are_not_numbers_are_refused():
    intervals = simulate(_mix(20), rng=np.random.default_rng(12))
    motion = intervals.sensor_motion.copy()
    motion[4, 1] = np.nan
    spoiled = MotionIntervals(intervals.duration, intervals.phi_left, intervals.phi_right, motion)
    with pytest.raises(InputError, match=r"not finite numbers \(the first: interval 5\)"):
        fit_intervals(spoiled)


def test_runs_methods_and_intervals_do_not_mix():
    from umbmark.calibration.heldout import CANDIDATES
    from umbmark.estimators.dispatch import estimate_runs
    from umbmark.estimators.registry import INTERVALS, RUNS

    assert not set(INTERVALS) & set(CANDIDATES)  # validate and auto compare runs' methods
    assert not set(INTERVALS) & set(RUNS)
    with pytest.raises(InputError, match="needs motion intervals"):
        estimate_runs(
            INTERVALS[0], [], wheelbase=0.3, params=None, side_length=None,
            square_side=lambda: 1.0,
        )  # fmt: skip


def test_too_few_intervals_are_refused():
    with pytest.raises(InputError, match="at least 10"):
        fit_intervals(simulate(_mix(8), rng=np.random.default_rng(8)))


def test_errors_against_the_active_parameters():
    # By hand: the odometry used D_n = 0.082 m with c_L = 1.01, c_R = 0.99 and b = 0.09 m;
    # f = r / (c D_n / 2), E_d = f_R / f_L, E_s = (f_L + f_R) / 2, E_b = b / 0.09.
    intervals = simulate(_mix(80), rng=np.random.default_rng(9))
    active = WheelParams(wheelbase=0.09, wheel_diameter=0.082, c_left=1.01, c_right=0.99)
    estimate, _ = scan_matching_estimate(intervals, active)
    f_l, f_r = R_L / (0.041 * 1.01), R_R / (0.041 * 0.99)
    assert estimate.E_d == pytest.approx(f_r / f_l, rel=1e-6)
    assert estimate.E_b == pytest.approx(B / 0.09, rel=1e-6)
    assert estimate.E_s == pytest.approx(0.5 * (f_l + f_r), rel=1e-6)
    assert estimate.components["wheel_diameter_left"] == pytest.approx(2 * R_L, rel=1e-6)
    assert estimate.components["laser_yaw"] == pytest.approx(LASER[2], abs=1e-6)


# --- tuple files ---------------------------------------------------------------------


def test_tuple_file_round_trip(tmp_path):
    intervals = simulate(_mix(20), rng=np.random.default_rng(10), noise=NOISE)
    path = write_tuples(tmp_path / "a.tuple", intervals)
    back = read_tuples(path)
    for name in ("duration", "phi_left", "phi_right", "sensor_motion"):
        assert np.allclose(getattr(back, name), getattr(intervals, name), rtol=1e-12, atol=0)
    with pytest.raises(InputError, match="exists"):
        write_tuples(path, intervals)


def test_tuple_lines_hold_velocities_and_may_be_written_back_to_back(tmp_path):
    # The reference files' layout: phi are average wheel speeds [rad/s]; where two logs
    # were concatenated, two objects share a line.
    path = tmp_path / "b.tuple"
    path.write_text(
        '{ "T": 0.5, "phi_l": 2.0, "phi_r": -4.0, "sm": [ 0.01, 0.0, -0.1 ] }\n'
        '{ "T": 0.25, "phi_l": 1.0, "phi_r": 1.0, "sm": [ 0.02, 0.0, 0.0 ] }'
        '{ "T": 1.0, "phi_l": 0.0, "phi_r": 0.5, "sm": [ 0.0, 0.0, 0.05 ], "other": 1 }\n'
    )
    got = read_tuples(path)
    assert got.phi_left.tolist() == [1.0, 0.25, 0.0]
    assert got.phi_right.tolist() == [-2.0, 0.25, 0.5]
    assert got.sensor_motion[:, 2].tolist() == [-0.1, 0.0, 0.05]


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ('{ "T": 0.5, "phi_l": NaN, "phi_r": 1.0, "sm": [0, 0, 0] }', "'phi_l' is nan"),
        ('{ "T": 0.5, "phi_l": 1.0, "phi_r": 1.0, "sm": [0, 0, Infinity] }', "'sm[2]' is inf"),
        ('{ "T": 0.5, "phi_l": 1.0, "sm": [0, 0, 0] }', "has no 'phi_r'"),
        ('{ "T": 0.0, "phi_l": 1.0, "phi_r": 1.0, "sm": [0, 0, 0] }', "lasts > 0 s"),
        ('{ "T": 0.5, "phi_l": 1.0, "phi_r": 1.0, "sm": [0, 0] }', "not [x, y, theta]"),
        ('{ "T": 0.5, "phi_l": "1", "phi_r": 1.0, "sm": [0, 0, 0] }', "not a number"),
        ('{ "T": 0.5, "phi_l": 1e9, "phi_r": 1.0, "sm": [0, 0, 0] }', "beyond"),
        ("T=0.5 phi_l=1", "not a JSON object"),
    ],
)
def test_bad_tuple_lines_are_refused_naming_file_and_line(tmp_path, line, problem):
    path = tmp_path / "c.tuple"
    good = '{ "T": 0.5, "phi_l": 1.0, "phi_r": 1.0, "sm": [0, 0, 0] }'
    path.write_text(f"{good}\n# a comment\n{line}\n")
    with pytest.raises(InputError) as caught:
        read_tuples(path)
    assert str(caught.value).startswith(f"{path}, row 3: ")
    assert problem in str(caught.value)


def test_an_empty_tuple_file_is_refused(tmp_path):
    path = tmp_path / "d.tuple"
    path.write_text("\n")
    with pytest.raises(InputError, match="holds no interval"):
        read_tuples(path)


# --- the command ---------------------------------------------------------------------


@pytest.mark.slow
def test_calibrate_reads_a_tuple_file(tmp_path):
    path = write_tuples(
        tmp_path / "sim.tuple", simulate(_mix(200), rng=np.random.default_rng(11), noise=NOISE)
    )
    # the nominal 80 mm wheels and 90 mm wheelbase are 3 % and 2 % off the truth (82.7, 88
    # mm): a correction the verdict applies
    args = ("calibrate", str(path), "--method", "scan-matching", "--wheelbase", "0.09")
    out = cli_json(*args, "--wheel-diameter", "0.080")
    assert out["format"] == "tuples"
    se = out["standard_errors"]
    for key, truth in (
        ("wheel_diameter_left", 2 * R_L),
        ("wheel_diameter_right", 2 * R_R),
        ("wheelbase", B),
    ):
        assert abs(out[key] - truth) < 4 * se[key]
        assert out[f"{key}_standard_error"] == se[key]
    off = np.abs(np.array(out["laser_pose"]) - LASER)
    assert np.all(off < 4 * np.array(out["laser_pose_standard_errors"]))
    assert out["E_d"] == pytest.approx(out["wheel_diameter_right"] / out["wheel_diameter_left"])
    json.dumps(out)
    summary = run_cli(*args, "--wheel-diameter", "0.080").stdout
    assert re.search(r"laser yaw +1[67]\.\d+ ± 0\.\d+ deg", summary), summary
    assert re.search(r"wheelbase +8[78]\.\d+ ± 0\.\d+ mm", summary), summary
    yaml = cli_error(*args, "--yaml", str(tmp_path / "o.yaml"))
    assert "--yaml needs the nominal geometry" in yaml
    assert "calibrated by --method scan-matching, not exact" in cli_error(
        "calibrate", str(path), "--method", "exact", "--wheelbase", "0.09"
    )


def test_a_tuple_file_calibrates_without_nominal_geometry(tmp_path):
    # scan matching measures the radii and the wheelbase absolutely: no --wheelbase or
    # --wheel-diameter is needed; E_d = D_R / D_L, and no E_b, E_s or multipliers (they
    # are against a nominal nobody gave)
    import umbmark

    path = write_tuples(
        tmp_path / "sim.tuple", simulate(_mix(400), rng=np.random.default_rng(12), noise=NOISE)
    )
    report = umbmark.calibrate(path, method="scan-matching")
    out = report.to_dict()
    se = out["standard_errors"]
    for key, truth in (
        ("wheel_diameter_left", 2 * R_L),
        ("wheel_diameter_right", 2 * R_R),
        ("wheelbase", B),
    ):
        assert abs(out[key] - truth) < 4 * se[key], key
    # D_R / D_L = 1.00728: more than 6 standard errors from 1 (equal wheels fail)
    assert abs(out["E_d"] - R_R / R_L) < 4 * se["E_d"]
    assert 6 * se["E_d"] < R_R / R_L - 1
    off = np.abs(np.array(out["laser_pose"]) - LASER)
    assert np.all(off < 4 * np.array(out["laser_pose_standard_errors"]))
    assert out["nominal"] is None
    for key in ("E_b", "E_s", "c_L", "c_R", "new", "active"):
        assert out[key] is None, key
    assert any("no nominal geometry" in note for note in report.notes)
    page = umbmark.calibrate(path, method="scan-matching").html()
    assert "No overlay: no nominal geometry was given" in page
    assert "wheel_separation_multiplier:" not in page  # no overlay
    assert "Correction, composed" not in page
    with pytest.raises(InputError, match="yaml needs the nominal geometry"):
        umbmark.calibrate(path, method="scan-matching", yaml=tmp_path / "o.yaml")
    assert not (tmp_path / "o.yaml").exists()


@pytest.mark.slow
def test_standard_errors_widen_where_some_intervals_scatter_more():
    # A sweep distorted by the robot's own turning: the turns on the spot (a quarter of
    # the intervals, most of what fixes the laser's offset) scatter sideways 6 times more
    # than the rest, whose residuals set the noise the bound takes alike everywhere. 60
    # trials, the scatter over the standard error measured: the bound alone 3.5 for
    # laser_x and 2.3 for laser_y; widened 1.5 and 1.45 (the sandwich's score is the
    # weighted fit's, the estimator the closed-form steps: not all of it), the rest 0.65
    # (laser_yaw) to 0.95.
    rng = np.random.default_rng(5)
    kinds = _mix(300)
    spot = np.array([k == "spot" for k in kinds])
    values, errors = [], []
    for _ in range(60):
        intervals = simulate(kinds, rng=rng, noise=NOISE)
        intervals.sensor_motion[:, 1] += np.where(spot, rng.normal(0.0, 0.012, len(kinds)), 0.0)
        cal = fit_intervals(intervals)
        values.append(cal.values)
        errors.append(np.sqrt(np.diag(cal.covariance)))
    ratio = np.std(values, axis=0, ddof=1) / np.mean(errors, axis=0)
    assert np.all((ratio > 0.5) & (ratio < 1.8)), ratio

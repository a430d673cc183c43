"""The wheels and a gyro calibrated together, on simulated robots of known truth.

The recordings are the tests' own closed-form simulator's (``tests/gyro_sim.py``): a
differential drive whose wheels are 1 % apart and wheelbase 1.5 % off the nominal, a gyro
2 % off in scale with a bias of 0.4 deg/s that wanders (a random walk), white noise and
an IMU tilted by 1 degree the stated transform does not know. Every expected value is the
simulation's truth: ``E_d = r_R / r_L``, ``E_b = b / b_nominal``, ``E_s`` the mean radius
over the nominal, and the gyro's scale as its z reading sees it, ``k_g / cos(tilt)`` (the
stated transform misses the tilt). "The reference alone" is a plain least squares of the
reference's heading changes on the wheels' rotations written here, or the package's
scan-matching estimator (Censi et al.) on the same intervals.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gyro_sim import (
    Motion,
    Truth,
    arc,
    heading_reference,
    mixed_program,
    program,
    record,
    scan_reference,
    spin,
    straight,
)
from umbmark.core.messages import Blocking
from umbmark.estimators.gyro import SCALE_TOLERANCE, fit_gyro, gyro_estimate
from umbmark.estimators.registry import GYRO
from umbmark.estimators.scan_matching import scan_matching_estimate
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import WheelSeries
from umbmark.scans.gyro_intervals import HeadingReference, gyro_intervals, gyro_reference

TRUTH = Truth()
ACTIVE = WheelParams(TRUTH.nominal_wheelbase, TRUTH.nominal_diameter)
#: What wheels and gyro alone identify: E_b k_g / E_s, with the gyro's z scale.
PRODUCT = TRUTH.E_b * TRUTH.k_z / TRUTH.E_s


@pytest.fixture(scope="module")
def mixed():
    """Ten minutes of straights, spins both ways and arcs with rests between."""
    rec = record(mixed_program(10.0), TRUTH, seed=3)
    return rec, gyro_intervals(rec.wheels, rec.gyro)


def _true_mean_bias(rec, iv) -> float:
    t = np.linspace(iv.start.min(), iv.end.max(), 20_001)
    return float(np.mean(rec.bias_at(t)))


def _reference_alone(rec, start, end, yaw):
    """The heading reference against the wheels, without the gyro: ``yaw = W_R U_R - W_L
    U_L`` by ordinary least squares (``U = r phi / b`` with the nominal geometry), ``E_d =
    W_R / W_L`` and ``E_b / E_s = 2 / (W_R + W_L)`` with their standard errors."""
    w = rec.wheels
    phi = [
        np.interp(end, w.time, w.angles[:, k]) - np.interp(start, w.time, w.angles[:, k])
        for k in (0, 1)
    ]
    r, b = 0.5 * TRUTH.nominal_diameter, TRUTH.nominal_wheelbase
    a = np.column_stack([r * phi[1] / b, -r * phi[0] / b])
    coef, *_ = np.linalg.lstsq(a, yaw, rcond=None)
    resid = yaw - a @ coef
    cov = np.linalg.inv(a.T @ a) * (resid @ resid) / (len(yaw) - 2)
    wr, wl = coef
    g_ed = np.array([1 / wl, -wr / wl**2])
    g_eb = np.array([-2 / (wr + wl) ** 2, -2 / (wr + wl) ** 2])
    return {
        "E_d": (wr / wl, math.sqrt(g_ed @ cov @ g_ed)),
        "E_b": (2 / (wr + wl), math.sqrt(g_eb @ cov @ g_eb)),
    }


# --- wheels and gyro alone ----------------------------------------------------------------


def test_without_a_reference_E_d_within_2e4_and_E_b_k_g_within_its_interval(mixed):
    rec, iv = mixed
    cal = fit_gyro(iv, ACTIVE)
    v, se = cal.values, cal.standard_errors
    assert abs(v["E_d"] - TRUTH.E_d) < 2e-4
    assert abs(v["E_d"] - TRUTH.E_d) < 3 * se["E_d"]
    low, high = cal.interval("E_b_k_g")
    assert low <= PRODUCT <= high
    assert high - low < 2e-4  # the product is pinned: the gyro's scale is in it
    assert "k_g" not in v
    assert "E_s" not in v
    assert abs(v["bias"] - _true_mean_bias(rec, iv)) < math.radians(0.01)
    assert cal.undetermined == {}
    assert cal.reference == "no reference"


def test_without_a_reference_E_b_is_relative_to_the_gyro_its_interval_widened(mixed):
    _, iv = mixed
    cal = fit_gyro(iv, ACTIVE)
    v, se = cal.values, cal.standard_errors
    assert cal.relative_to_gyro == ("E_b",)
    assert v["E_b"] == v["E_b_k_g"]
    # the tolerance as a 95 % bound, in quadrature with the driving's own
    widened = math.hypot(se["E_b_k_g"], v["E_b_k_g"] * SCALE_TOLERANCE / 1.959963984540054)
    assert se["E_b"] == pytest.approx(widened, rel=1e-12)
    low, high = cal.interval("E_b")
    assert low <= TRUTH.E_b <= high  # the true E_b: the gyro's 2 % is within +-3 %
    assert any("E_b is relative to the gyro" in w for w in cal.warnings)
    exact = fit_gyro(iv, ACTIVE, scale_tolerance=0.0)  # a gyro calibrated beforehand
    assert exact.standard_errors["E_b"] == exact.standard_errors["E_b_k_g"]
    assert not any("relative to the gyro" in w for w in exact.warnings)


def test_the_estimate_is_the_registrys_and_says_the_gyros_figures(mixed):
    _, iv = mixed
    estimate, cal = gyro_estimate(iv, ACTIVE, 4.0)
    assert estimate.method == GYRO.name
    assert estimate.E_d == cal.values["E_d"]
    assert estimate.E_b == cal.values["E_b"]
    assert estimate.E_s is None
    assert estimate.components["E_b_gyro"] == cal.values["E_b_k_g"]
    assert estimate.components["gyro_bias"] == cal.values["bias"]
    assert "gyro_scale" not in estimate.components
    assert estimate.standard_errors["E_b"] == cal.standard_errors["E_b"]
    # alpha: the turn a 90 degree turn falls short by with this E_b, Eq. 4.27
    assert estimate.alpha == pytest.approx(math.pi / 2 * (1 - 1 / estimate.E_b), rel=1e-9)


def test_the_imus_tilt_is_found_from_its_turns_and_from_gravity(mixed):
    _, iv = mixed
    m = fit_gyro(iv, ACTIVE).mounting
    assert m.tilt == pytest.approx(TRUTH.tilt_angle, abs=math.radians(0.05))
    assert m.roll == pytest.approx(TRUTH.tilt[0], abs=math.radians(0.05))
    assert m.pitch == pytest.approx(TRUTH.tilt[1], abs=math.radians(0.05))
    assert m.gravity_tilt == pytest.approx(TRUTH.tilt_angle, abs=math.radians(0.05))
    assert m.differs
    assert not m.upside_down
    stated = np.eye(3)
    assert fit_gyro(iv, ACTIVE, stated=stated).mounting.stated_in_imu == pytest.approx([0, 0, 1])


# --- with a heading reference -------------------------------------------------------------


def test_with_a_heading_reference_every_figure_is_separated(mixed):
    rec, iv = mixed
    start, end, yaw = heading_reference(rec, noise=math.radians(0.2))
    ref = gyro_reference(rec.gyro, HeadingReference(start, end, yaw))
    cal = fit_gyro(iv, ACTIVE, reference=ref)
    v, se = cal.values, cal.standard_errors
    assert abs(v["k_g"] / TRUTH.k_z - 1) < 1e-3
    assert abs(v["k_g"] - TRUTH.k_z) < 3 * se["k_g"]
    assert abs(v["bias"] - _true_mean_bias(rec, iv)) < math.radians(0.01)
    # the bias followed as it wanders, at every knot
    assert np.abs(cal.bias_values - rec.bias_at(cal.bias_times)).max() < math.radians(0.01)
    assert cal.relative_to_gyro == ()
    alone = _reference_alone(rec, start, end, yaw)
    # E_d: the gyro sees the straights' drift the reference hardly does; E_b: as tight as
    # the reference alone, but for the gyro's own noise, counted in both kinds of rows
    assert se["E_d"] < 0.2 * alone["E_d"][1]
    assert se["E_b"] <= 1.02 * alone["E_b"][1]
    for name, truth in (("E_d", TRUTH.E_d), ("E_b", TRUTH.E_b / TRUTH.E_s)):
        assert abs(v[name] - truth) < 3 * se[name]
    assert abs(v["E_d"] - TRUTH.E_d) < abs(alone["E_d"][0] - TRUTH.E_d) + 3 * se["E_d"]


def test_with_scan_matching_E_s_and_the_laser_too(mixed):
    rec, iv = mixed
    scans = scan_reference(rec, laser=(0.12, -0.03, 0.05))
    cal = fit_gyro(iv, ACTIVE, reference=gyro_reference(rec.gyro, scans))
    v, se = cal.values, cal.standard_errors
    assert cal.reference == "scan matching"
    assert abs(v["k_g"] / TRUTH.k_z - 1) < 1e-3
    assert abs(v["bias"] - _true_mean_bias(rec, iv)) < math.radians(0.01)
    alone, _ = scan_matching_estimate(scans, ACTIVE)
    for name, truth in (("E_d", TRUTH.E_d), ("E_b", TRUTH.E_b), ("E_s", TRUTH.E_s)):
        # the laser's equations weighed as scan matching alone weighs them, the gyro's on
        # top: the joint fit is never looser
        assert se[name] <= alone.standard_errors[name], name
        assert abs(v[name] - truth) < 3 * se[name], name
    assert se["E_d"] < 0.2 * alone.standard_errors["E_d"]  # the gyro sees the straights' drift
    assert cal.extra["laser_x"] == pytest.approx(0.12, abs=3 * se["laser_x"])
    assert cal.extra["laser_yaw"] == pytest.approx(0.05, abs=3 * se["laser_yaw"])
    assert cal.extra["wheelbase"] == pytest.approx(TRUTH.wheelbase, abs=3 * se["wheelbase"])
    assert cal.scan is not None
    assert cal.scan.wheelbase == cal.extra["wheelbase"]


@pytest.mark.slow
def test_a_gyro_that_reads_late_has_its_delay_fitted_and_stays_as_tight_as_the_laser():
    """A gyro whose readings are 10 ms late (half a period at 50 Hz: a reading that is
    the mean over its period), the wheels and the laser on time: the delay is found, and
    the joint fit is as tight as scan matching alone at least and holds the truth."""
    truth = replace(TRUTH, delay=0.010)
    rec = record(mixed_program(5.0), truth, seed=7)
    iv = gyro_intervals(rec.wheels, rec.gyro)
    scans = scan_reference(rec, seed=8)
    cal = fit_gyro(iv, ACTIVE, reference=gyro_reference(rec.gyro, scans))
    v, se = cal.values, cal.standard_errors
    late, late_se = cal.delays["imu"]
    assert abs(late - 0.010) < 3 * late_se + 1e-4
    assert late_se < 2e-4  # the turns' starts and stops pin it to 0.2 ms
    assert abs(v["k_g"] / truth.k_z - 1) < 1e-3
    assert abs(v["bias"] - _true_mean_bias(rec, iv)) < math.radians(0.01)
    alone, _ = scan_matching_estimate(scans, ACTIVE)
    for name, value in (("E_d", truth.E_d), ("E_b", truth.E_b), ("E_s", truth.E_s)):
        assert se[name] <= alone.standard_errors[name], name
        assert abs(v[name] - value) < 3 * se[name], name


# --- motion that does not separate them ---------------------------------------------------


def _odometry_straight(length: float):
    """A leg the odometry drives straight: both wheels turn alike, the robot curves."""
    r_l, r_r, b = TRUTH.radius_left, TRUTH.radius_right, TRUTH.wheelbase
    return arc(length, (r_r - r_l) * 2 * length / ((r_l + r_r) * b))


@pytest.mark.parametrize(
    ("motion", "undetermined", "words"),
    [
        (
            program([straight(2.0), straight(-2.0)], 6, rests=3.0),
            {"E_b", "E_b_k_g"},
            "no turns: drive turns on the spot or arcs",
        ),
        (
            program([spin(2 * math.pi), spin(-2 * math.pi)], 4, rests=3.0),
            {"E_d"},
            "no straights: drive straights",
        ),
        (
            Motion((spin(30 * math.pi),)),
            {"E_d", "E_b", "E_b_k_g", "bias"},
            "every turn is to the left: they cannot be told from the gyro's bias",
        ),
        (
            Motion((straight(40.0),)),
            {"E_d", "E_b", "E_b_k_g", "bias"},
            "no rest, and nothing else fixes the gyro's bias",
        ),
    ],
    ids=["straights only", "spins only", "one way, no rests", "one straight, no rests"],
)
def test_motion_that_does_not_separate_them_says_which_figure(motion, undetermined, words):
    rec = record(motion, TRUTH, seed=4)
    iv = gyro_intervals(rec.wheels, rec.gyro)
    cal = fit_gyro(iv, ACTIVE)
    assert set(cal.undetermined) == undetermined
    assert any(words in why for why in cal.undetermined.values())
    assert not undetermined & set(cal.values)
    estimate, _ = gyro_estimate(iv, ACTIVE)
    for name in {"E_d", "E_b"} & undetermined:
        assert getattr(estimate, name) == 1.0  # no correction
        assert any(w.startswith(f"{name} is not determined") for w in estimate.warnings)
    if {"E_d", "E_b"} <= undetermined:
        assert any(isinstance(w, Blocking) for w in estimate.warnings)


def test_straights_alone_still_give_E_d():
    """Driven truly straight, ``E_d`` is the ratio the straights fix; driven straight by
    the odometry (the robot curves), to first order, the turning gain taken as 1."""
    truly = record(program([straight(2.0), straight(-2.0)], 6, rests=3.0), TRUTH, seed=5)
    cal = fit_gyro(gyro_intervals(truly.wheels, truly.gyro), ACTIVE)
    assert abs(cal.values["E_d"] - TRUTH.E_d) < min(2e-4, 3 * cal.standard_errors["E_d"])
    legs = [_odometry_straight(2.0), _odometry_straight(-2.0)]
    by_odometry = record(program(legs, 6, rests=3.0), TRUTH, seed=5)
    cal = fit_gyro(gyro_intervals(by_odometry.wheels, by_odometry.gyro), ACTIVE)
    # the gyro reads the drift times S = 1 / PRODUCT, taken as 1: 3.5 % of E_d - 1 off,
    # within the fifth of E_d - 1 the standard error allows for it
    assert abs(cal.values["E_d"] - TRUTH.E_d) < cal.standard_errors["E_d"]
    assert cal.standard_errors["E_d"] == pytest.approx(0.2 * abs(TRUTH.E_d - 1), rel=0.1)


def test_an_imu_upside_down_reads_the_turns_backwards_and_is_not_applied():
    upside = replace(TRUTH, tilt=(math.pi, 0.0))
    rec = record(mixed_program(3.0), upside, seed=6)
    iv = gyro_intervals(rec.wheels, rec.gyro)
    estimate, cal = gyro_estimate(iv, ACTIVE)
    assert cal.values["E_b_k_g"] == pytest.approx(-PRODUCT, rel=1e-3)
    assert cal.mounting.upside_down
    blocking = [w for w in estimate.warnings if isinstance(w, Blocking)]
    assert "reads the turns backwards" in blocking[0]
    assert estimate.E_b == 1.0
    assert "E_b" not in estimate.standard_errors
    start, end, yaw = heading_reference(rec)
    cal = fit_gyro(
        iv, ACTIVE, reference=gyro_reference(rec.gyro, HeadingReference(start, end, yaw))
    )
    assert cal.values["k_g"] == pytest.approx(-TRUTH.k_g, rel=2e-3)
    assert cal.values["E_b"] == pytest.approx(TRUTH.E_b / TRUTH.E_s, rel=2e-3)


def test_a_wheel_that_slips_once_is_left_out():
    rec = record(mixed_program(5.0), TRUTH, seed=7)
    angles = rec.wheels.angles.copy()
    during = np.flatnonzero(rec.wheels.time > 100.0)[0]
    angles[during:, 0] += 2.0  # the left wheel spins by 2 rad in place: 2 cm of slip
    iv = gyro_intervals(WheelSeries(rec.wheels.time, angles), rec.gyro)
    cal = fit_gyro(iv, ACTIVE)
    assert cal.n_outliers >= 1
    assert abs(cal.values["E_d"] - TRUTH.E_d) < 2e-4
    low, high = cal.interval("E_b_k_g")
    assert low <= PRODUCT <= high


def test_too_few_intervals_are_refused():
    rec = record(program([straight(0.5)], 1, rests=0.0), TRUTH)
    iv = gyro_intervals(rec.wheels, rec.gyro)
    assert len(iv) < 10
    with pytest.raises(ValueError, match="needs at least 10"):
        fit_gyro(iv, ACTIVE)


@pytest.mark.slow
def test_an_hour_with_a_bias_that_wanders_is_followed_throughout():
    """An hour of driving, the bias wandering five times faster than the others' (0.0025
    deg/s/sqrt(s): 0.15 deg/s over the hour, 0.008 deg/s between two knots), with a
    heading reference: the bias at the knots within 0.005 deg/s rms and each within 4.5 of
    its standard errors, ``k_g`` within 0.1 %."""
    truth = replace(TRUTH, bias_walk=math.radians(0.0025))
    rec = record(mixed_program(60.0), truth, seed=8)
    assert np.ptp(np.degrees(rec.bias)) > 0.05  # it does wander
    iv = gyro_intervals(rec.wheels, rec.gyro)
    start, end, yaw = heading_reference(rec)
    cal = fit_gyro(
        iv, ACTIVE, reference=gyro_reference(rec.gyro, HeadingReference(start, end, yaw))
    )
    off = cal.bias_values - rec.bias_at(cal.bias_times)
    assert math.degrees(float(np.sqrt(np.mean(off**2)))) < 0.005
    assert np.abs(off / cal.bias_errors).max() < 4.5
    assert abs(cal.values["k_g"] / truth.k_z - 1) < 1e-3
    assert cal.bias_walk == pytest.approx(truth.bias_walk, rel=0.5)


@pytest.mark.parametrize(
    ("rates", "words"),
    [
        (lambda r: np.tile(r[:1], (len(r), 1)), "frozen, its yaw not on the base's z axis"),
        (lambda r: r * 180.0 / math.pi, "in degrees per second, read as radians per second"),
    ],
    ids=["frozen", "degrees per second"],
)
def test_a_gyro_that_does_not_read_the_turns_as_a_gyro_can_is_not_applied(mixed, rates, words):
    rec, _ = mixed
    bad = replace(rec.gyro, rate=rates(rec.gyro.rate))
    estimate, _ = gyro_estimate(gyro_intervals(rec.wheels, bad), ACTIVE)
    blocking = [w for w in estimate.warnings if isinstance(w, Blocking)]
    assert any(words in w for w in blocking), estimate.warnings


def test_a_robot_that_never_moves_has_nothing_to_apply():
    rec = record(program([straight(0.0)], 1, rests=60.0), TRUTH)
    estimate, cal = gyro_estimate(gyro_intervals(rec.wheels, rec.gyro), ACTIVE)
    assert cal.values["bias"] == pytest.approx(TRUTH.bias, abs=math.radians(0.01))
    assert {"E_d", "E_b"} <= set(cal.undetermined)
    assert any(isinstance(w, Blocking) and "nothing to apply" in w for w in estimate.warnings)

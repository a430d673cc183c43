"""The wheel radii alone, the wheelbase and the laser's mounting held
(:mod:`umbmark.estimators.scan_radii`), on intervals of known truth.

The intervals are tests/estimators/test_scan_matching.py's: each one integrated
numerically and the sensor's motion composed with homogeneous matrices. Driving that is
all straights is what the full fit refuses (the wheel rotations are proportional). The
expected figures come from the truth and, where the held wheelbase is off, from the closed
form worked out by hand in the test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_scan_matching import LASER, R_L, R_R, B, simulate

from umbmark.core.errors import InputError
from umbmark.estimators.scan_matching import fit_intervals
from umbmark.estimators.scan_radii import fit_radii

NOISE = (0.0005, 0.0005, 0.001)  # the matched motion's noise [m, m, rad]
TRUE_E_D = R_R / R_L
HALF = 0.5 * (R_L + R_R)  # the radius the odometry uses: E_s 1 at the truth's mean


def _held(b: float = B) -> np.ndarray:
    return np.array([HALF, HALF, b, *LASER])


def _straights(n: int, seed: int, noise: tuple[float, float, float] = NOISE):  # type: ignore[no-untyped-def]
    return simulate(["straight"] * n, rng=np.random.default_rng(seed), noise=noise)


def test_straights_the_full_fit_refuses_give_the_radii():
    intervals = _straights(200, 3)
    with pytest.raises(InputError, match="does not excite"):
        fit_intervals(intervals)
    fit = fit_radii(intervals, _held(), np.zeros((4, 4)))
    figures = fit.errors_of(HALF, HALF)
    e_d, se_d = figures["E_d"]
    e_s, se_s = figures["E_s"]
    assert abs(e_d - TRUE_E_D) < 4.0 * se_d
    assert abs(e_s - 1.0) < 4.0 * se_s
    # E_d is pinned far tighter than it is off nominal (7.3e-3): a change of a few 1e-3 shows
    assert se_d < 5e-4


def test_noiseless_straights_give_the_radii_exactly():
    fit = fit_radii(_straights(40, 4, (0.0, 0.0, 0.0)), _held(), np.zeros((4, 4)), rounds=0)
    assert fit.radius_left == pytest.approx(R_L, rel=1e-7)
    assert fit.radius_right == pytest.approx(R_R, rel=1e-7)


def test_a_wheelbase_held_off_moves_e_d_by_the_closed_form_and_is_carried_in_its_error():
    # Straights of equal wheel rotations phi: the heading drifts (r_R - r_L) phi / b and
    # the robot drives (r_L + r_R) phi / 2. A wheelbase held at b' = 1.02 b makes the fit's
    # difference D' = D b' / b while the sum S stays: E_d' = (S + D') / (S - D').
    off = 1.02
    s, d = R_L + R_R, (R_R - R_L) * off
    expected = (s + d) / (s - d)
    held_cov = np.diag([(0.02 * B) ** 2, 0.0, 0.0, 0.0])
    fit = fit_radii(_straights(40, 5, (0.0, 0.0, 0.0)), _held(off * B), held_cov, rounds=0)
    e_d, se_d = fit.errors_of(HALF, HALF)["E_d"]
    assert e_d == pytest.approx(expected, rel=1e-6)
    # the held wheelbase's 2 % is carried: (E_d - 1) times 0.02, the noise-free fit's own 0
    assert se_d == pytest.approx((TRUE_E_D - 1.0) * 0.02, rel=0.02)
    assert abs(e_d - TRUE_E_D) < 1.5 * se_d


def test_a_laser_knocked_since_the_mounting_was_held_moves_neither_e_d_nor_e_s():
    # the laser turned 3 degrees and moved 10 mm since its mounting was held: the length
    # of its translation and its turn are the same whatever its yaw, and its x only adds
    # the turn times 10 mm to a straight's translation (a drift of 3e-3 rad over 0.05 m)
    knocked = (LASER[0] + 0.01, LASER[1], LASER[2] + math.radians(3.0))
    intervals = simulate(["straight"] * 40, rng=np.random.default_rng(8), laser=knocked)
    fit = fit_radii(intervals, _held(), np.zeros((4, 4)), rounds=0)
    figures = fit.errors_of(HALF, HALF)
    assert figures["E_d"][0] == pytest.approx(TRUE_E_D, abs=1e-6)
    assert figures["E_s"][0] == pytest.approx(1.0, abs=1e-5)


def test_its_intervals_cover_at_the_stated_rate():
    # 300 draws: noisy straights and a held wheelbase drawn 1 % about the truth, said so
    rng = np.random.default_rng(11)
    z = []
    sigma_b = 0.01 * B
    for k in range(300):
        b = B + rng.normal(0.0, sigma_b)
        fit = fit_radii(_straights(120, 100 + k), _held(b), np.diag([sigma_b**2, 0, 0, 0]))
        e_d, se_d = fit.errors_of(HALF, HALF)["E_d"]
        z.append((e_d - TRUE_E_D) / se_d)
    rms = math.sqrt(float(np.mean(np.square(z))))
    assert 0.85 < rms < 1.2, rms
    inside = float(np.mean(np.abs(z) < 1.959964))
    assert 0.91 < inside < 0.99, inside


@pytest.mark.parametrize(
    ("held", "cov", "said"),
    [
        (np.array([HALF, HALF, 0.0, *LASER]), np.zeros((4, 4)), "not finite and positive"),
        (np.array([HALF, HALF, math.nan, *LASER]), np.zeros((4, 4)), "not finite and positive"),
        (_held(), np.zeros((3, 3)), "finite 4 x 4"),
    ],
)
def test_bad_held_parameters_are_one_line(held, cov, said):  # type: ignore[no-untyped-def]
    with pytest.raises(InputError, match=said):
        fit_radii(_straights(20, 6), held, cov)


def test_too_few_intervals_are_refused():
    with pytest.raises(InputError, match="at least 10"):
        fit_radii(_straights(5, 7), _held(), np.zeros((4, 4)))

"""The paper's correction (Sec. 4): closed forms, Fig. 11, symmetry, warnings, uncertainty."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.core.conventions import Direction
from umbmark.estimators.base import SquareTest
from umbmark.estimators.dispatch import estimate_errors
from umbmark.estimators.paper import paper_estimate
from umbmark.model.run import EndPose, Run
from umbmark.returns.clusters import umbmark_benchmark

from helpers import linear_cgs, runs_around, turtle_square

L, B = 4.0, 0.34


def _runs(rows) -> list[Run]:
    return [Run(Direction(d), EndPose(xa, ya), EndPose(xo, yo)) for d, xa, ya, xo, yo in rows]


def _estimate(alpha: float, beta: float, spread: float = 0.0, side: float = L, b: float = B):
    runs = _runs(runs_around(linear_cgs(alpha, beta, side), spread))
    return paper_estimate(umbmark_benchmark(runs), SquareTest(side, b))


@pytest.mark.parametrize(
    ("alpha_deg", "beta_deg"), [(1.0, 0.0), (0.0, 0.5), (-1.0254, 0.566), (0.3, -0.8)]
)
def test_inverts_the_first_order_closed_forms_exactly(alpha_deg, beta_deg):
    alpha, beta = math.radians(alpha_deg), math.radians(beta_deg)
    est = _estimate(alpha, beta, spread=0.02)
    assert est.alpha == pytest.approx(alpha, abs=1e-12)
    assert est.beta == pytest.approx(beta, abs=1e-12)
    # Eq. 4.27 as printed, in degrees.
    assert est.E_b == pytest.approx(90.0 / (90.0 - alpha_deg), rel=1e-12)
    # Eqs. 4.21 and 4.22 as printed.
    if beta_deg == 0.0:
        assert est.E_d == 1.0
    else:
        radius = (L / 2) / math.sin(beta / 2)
        assert est.E_d == pytest.approx((radius + B / 2) / (radius - B / 2), rel=1e-12)
    # The x and y estimates agree on first-order data.
    c = est.components
    assert c["alpha_x"] == pytest.approx(c["alpha_y"], abs=1e-12)
    assert c["beta_x"] == pytest.approx(c["beta_y"], abs=1e-12)


def test_beta_zero_gives_E_d_exactly_one():
    est = _estimate(math.radians(1.0), 0.0)
    assert est.E_d == 1.0
    assert est.beta == 0.0


def test_fig_11_figures_are_consistent():
    # Fig. 11: b 340.00 mm -> 336.17 mm, D_R/D_L 1.00000 -> 1.00084. Invert by hand:
    E_b = 336.17 / 340.00
    alpha_deg = 90.0 - 90.0 / E_b  # Eq. 4.27 solved for alpha
    E_d = 1.00084
    radius = (B / 2) * (E_d + 1) / (E_d - 1)  # Eq. 4.22 solved for R
    beta = 2 * math.asin((L / 2) / radius)  # Eq. 4.21 solved for beta
    est = _estimate(math.radians(alpha_deg), beta, spread=0.025)
    assert est.E_b * 340.00 == pytest.approx(336.17, abs=1e-9)
    assert est.E_d == pytest.approx(1.00084, abs=1e-12)
    # ... and with them the first-order centres give E_max,syst near the 317 mm printed.
    bench = umbmark_benchmark(_runs(runs_around(linear_cgs(math.radians(alpha_deg), beta, L))))
    assert bench.e_max_syst == pytest.approx(0.317, rel=0.02)
    # The robot over-turned (alpha < 0, wheelbase shrinks) and its legs curved left.
    assert alpha_deg < 0
    assert beta > 0


def test_mirror_image_flips_beta_and_keeps_alpha():
    # Reflect every run in the x axis and swap cw and ccw: the mirror robot has the same
    # turning error and legs curving the other way.
    alpha, beta = math.radians(-0.8), math.radians(0.4)
    rows = runs_around(linear_cgs(alpha, beta, L), 0.03)
    mirrored = [("ccw" if d == "cw" else "cw", xa, -ya, xo, -yo) for d, xa, ya, xo, yo in rows]
    est = paper_estimate(umbmark_benchmark(_runs(rows)), SquareTest(L, B))
    mir = paper_estimate(umbmark_benchmark(_runs(mirrored)), SquareTest(L, B))
    assert mir.alpha == pytest.approx(est.alpha, abs=1e-12)
    assert mir.beta == pytest.approx(-est.beta, abs=1e-12)
    assert mir.E_b == pytest.approx(est.E_b, rel=1e-12)
    assert mir.E_d == pytest.approx(1 / est.E_d, rel=1e-9)


def test_x_and_y_estimates_average_as_in_footnote_2():
    # Centres that make x and y disagree a little: E_d and E_b are the averages of the
    # x- and y-based values (not values of the averaged angles).
    rows = [
        ("cw", 0.060, 0.070, 0, 0),
        ("cw", 0.062, 0.072, 0, 0),
        ("ccw", 0.220, -0.215, 0, 0),
        ("ccw", 0.224, -0.219, 0, 0),
    ]
    est = paper_estimate(umbmark_benchmark(_runs(rows)), SquareTest(L, B))
    x_cw, y_cw, x_ccw, y_ccw = 0.061, 0.071, 0.222, -0.217
    a_x, a_y = (x_cw + x_ccw) / (-4 * L), (y_cw - y_ccw) / (-4 * L)
    b_x, b_y = (x_cw - x_ccw) / (-4 * L), (y_cw + y_ccw) / (-4 * L)

    def e_d(beta: float) -> float:
        r = (L / 2) / math.sin(beta / 2)
        return (r + B / 2) / (r - B / 2)

    e_b_x, e_b_y = 90 / (90 - math.degrees(a_x)), 90 / (90 - math.degrees(a_y))
    assert est.E_b == pytest.approx((e_b_x + e_b_y) / 2, rel=1e-12)
    assert est.E_d == pytest.approx((e_d(b_x) + e_d(b_y)) / 2, rel=1e-12)
    assert est.alpha == pytest.approx((a_x + a_y) / 2, rel=1e-12)


def test_standard_error_of_alpha_matches_its_linear_formula():
    # alpha = ((x_cw + y_cw) + (x_ccw - y_ccw)) / (-8L): its variance follows from the
    # per-run sums s = x + y (cw) and differences d = x - y (ccw).
    rng = np.random.default_rng(11)
    cgs = linear_cgs(0.01, 0.005, L)
    rows = []
    for d, (cx, cy) in cgs.items():
        for _ in range(6):
            rows.append((d, cx + rng.normal(0, 0.02), cy + rng.normal(0, 0.03), 0.0, 0.0))
    est = paper_estimate(umbmark_benchmark(_runs(rows)), SquareTest(L, B))
    s = np.array([r[1] + r[2] for r in rows if r[0] == "cw"])
    d = np.array([r[1] - r[2] for r in rows if r[0] == "ccw"])
    var = (s.var(ddof=1) / len(s) + d.var(ddof=1) / len(d)) / (8 * L) ** 2
    assert est.standard_errors["alpha"] == pytest.approx(math.sqrt(var), rel=1e-6)


def test_disagreeing_x_and_y_give_a_warning():
    # x says the robot under-turns, y says it over-turns, and the clusters are tight.
    rows = [
        ("cw", -0.08, 0.08, 0, 0),
        ("cw", -0.081, 0.081, 0, 0),
        ("cw", -0.079, 0.080, 0, 0),
        ("ccw", -0.08, -0.08, 0, 0),
        ("ccw", -0.081, -0.079, 0, 0),
        ("ccw", -0.080, -0.081, 0, 0),
    ]
    runs = _runs(rows)
    est = estimate_errors("paper", umbmark_benchmark(runs), runs, SquareTest(L, B))
    (warning,) = est.warnings
    assert "positions do not fit one robot of the model" in warning
    assert "on 2 degrees of freedom" in warning  # four centre coordinates, two unknowns


@pytest.mark.parametrize("seed", range(5))
def test_consistent_noisy_runs_give_no_warning(seed):
    # The robot of Fig. 11 (over-turns 1 deg, legs bend 0.57 deg left), walked exactly,
    # with the paper's scatter of about 25 mm.
    rng = np.random.default_rng(seed)
    rows = []
    for d in ("cw", "ccw"):
        x, y, _ = turtle_square(91.0, 0.57, L, d, steps=500)
        rows += [
            (d, x + rng.normal(0, 0.018), y + rng.normal(0, 0.018), 0.0, 0.0) for _ in range(5)
        ]
    runs = _runs(rows)
    est = estimate_errors("paper", umbmark_benchmark(runs), runs, SquareTest(L, B))
    assert est.warnings == ()


def test_errors_too_large_for_small_angles_give_a_warning_but_a_result():
    # A robot that turns 86 deg per commanded 90 and whose legs bend 2 deg, walked exactly.
    rows = []
    for d in ("cw", "ccw"):
        x, y, _ = turtle_square(86.0, 2.0, L, d, steps=500)
        rows += [(d, x + dx, y + dy, 0.0, 0.0) for dx, dy in ((-0.005, 0), (0.005, 0), (0, 0.005))]
    runs = _runs(rows)
    est = estimate_errors("paper", umbmark_benchmark(runs), runs, SquareTest(L, B))
    assert any("small-angle" in w for w in est.warnings)
    assert not any("do not fit" in w for w in est.warnings)  # explained by the geometry
    assert est.E_b > 1


def test_exact_method_recovers_large_errors_the_paper_misses():
    turn, bend = 86.0, 2.0
    E_b_true = 90.0 / turn
    beta = math.radians(bend)
    E_d_true = (2 * L + beta * B * E_b_true) / (2 * L - beta * B * E_b_true)
    # The sideways shift of each on-the-spot turn with unequal wheels (Sec. 2.3, Fig. 2).
    offset = (B * E_b_true / 2) * (E_d_true - 1) / (E_d_true + 1)
    rows = []
    for d in ("cw", "ccw"):
        x, y, _ = turtle_square(turn, bend, L, d, steps=4000, turn_offset=offset)
        rows += [(d, x + dx, y, 0.0, 0.0) for dx in (-0.005, 0.005)]
    runs = _runs(rows)
    bench = umbmark_benchmark(runs)
    exact = estimate_errors("exact", bench, runs, SquareTest(L, B))
    paper = estimate_errors("paper", bench, runs, SquareTest(L, B))
    assert exact.E_b == pytest.approx(E_b_true, rel=1e-7)
    assert exact.E_d == pytest.approx(E_d_true, rel=1e-7)
    assert abs(paper.E_b - E_b_true) > 100 * abs(exact.E_b - E_b_true)


def test_heading_method_needs_headings():
    runs = _runs(runs_around(linear_cgs(0.01, 0.0, L)))
    with pytest.raises(ValueError, match="theta_abs and theta_odo"):
        estimate_errors("heading", umbmark_benchmark(runs), runs, SquareTest(L, B))


def test_square_test_refuses_non_positive_geometry():
    with pytest.raises(ValueError, match="side length must be > 0"):
        SquareTest(0.0, B)
    with pytest.raises(ValueError, match="wheelbase must be > 0"):
        SquareTest(L, -0.34)


@pytest.mark.parametrize("seed", range(6))
def test_exact_fit_is_the_least_squares_solution_scipy_finds(seed):
    """The exact geometry is inverted by a small Gauss-Newton of ours (scipy.optimize
    stays off the default path); scipy's Levenberg-Marquardt on the same residuals must
    land on the same point, for noise-free and noisy centres, small and large errors."""
    from scipy.optimize import least_squares

    from umbmark.estimators.exact import exact_components, exact_end_positions

    rng = np.random.default_rng(seed)
    test = SquareTest(rng.uniform(0.5, 6.0), rng.uniform(0.1, 0.8))
    alpha, beta = rng.uniform(-0.07, 0.07, size=2)  # up to 4 degrees
    z = exact_end_positions(alpha, beta, test)
    if seed % 2:
        z = z + rng.normal(0.0, 0.03 * test.side_length, size=4)
    ours = exact_components(z, test)

    def residuals(p):
        return (exact_end_positions(p[0], p[1], test) - z) / test.side_length

    start = [ours["alpha"] + 0.01, ours["beta"] - 0.01]
    fit = least_squares(
        residuals, start, jac="3-point", method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    assert ours["alpha"] == pytest.approx(fit.x[0], abs=1e-9)
    assert ours["beta"] == pytest.approx(fit.x[1], abs=1e-9)
    ours_residual = residuals([ours["alpha"], ours["beta"]])
    assert ours_residual @ ours_residual <= (fit.fun @ fit.fun) * (1 + 1e-12) + 1e-28
    if seed % 2 == 0:  # noise-free: the truth itself, to the last bits
        assert ours["alpha"] == pytest.approx(alpha, abs=1e-14)
        assert ours["beta"] == pytest.approx(beta, abs=1e-14)

"""The end-pose estimator and the model checks: exact recovery, intervals that cover,
warnings that fire rarely on honest runs and name the cause on broken ones.

Run ends come from ``turtle_square`` (a slow, obvious walk of the square) or, for Monte
Carlo, from ``square_run_end`` once it has been checked against the turtle here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.core.conventions import Direction
from umbmark.estimators.base import SquareTest
from umbmark.estimators.dispatch import estimate_errors
from umbmark.estimators.endpose import endpose_estimate
from umbmark.model.run import EndPose, Run
from umbmark.model.square import icr_offset, square_run_end
from umbmark.returns.clusters import umbmark_benchmark

from helpers import turtle_square

L, B = 4.0, 0.34
TEST = SquareTest(L, B)


def _turtle_end(E_d: float, E_b: float, E_s: float, direction: str) -> tuple[float, float, float]:
    """End of a square walked by the turtle, for a robot with these errors (by hand)."""
    k_left = 2 * E_s / (E_d + 1)
    k_right = E_d * k_left
    true_b = E_b * B
    leg_turn = math.degrees(L * (k_right - k_left) / true_b)
    turn = 90.0 * E_s / E_b
    offset = 0.5 * true_b * (k_right - k_left) / (k_right + k_left)
    x, y, heading = turtle_square(turn, leg_turn, L * E_s, direction, 400, turn_offset=offset)
    return x, y, heading - (2 * math.pi if direction == "ccw" else -2 * math.pi)


def _runs(ends: dict[str, list[tuple[float, float, float | None]]]) -> list[Run]:
    runs = []
    for direction, points in ends.items():
        for x, y, theta in points:
            runs.append(
                Run(
                    direction=Direction(direction),
                    true_end=EndPose(x, y, theta),
                    odometry_end=EndPose(0.0, 0.0, None if theta is None else 0.0),
                    label=f"row {len(runs) + 2}",
                )
            )
    return runs


def _around(centre, spread: float, n: int = 5, heading_spread: float = 0.001):
    """n points symmetric about ``centre`` (a regular polygon), headings too."""
    x, y, th = centre
    return [
        (
            x + spread * math.cos(2 * math.pi * k / n),
            y + spread * math.sin(2 * math.pi * k / n),
            th + heading_spread * math.cos(2 * math.pi * k / n + 1.0),
        )
        for k in range(n)
    ]


@pytest.mark.parametrize(("E_d", "E_b", "E_s"), [(1.004, 1.02, 1.0), (0.99, 0.97, 1.03)])
def test_exact_geometry_is_the_turtles(E_d, E_b, E_s):
    for d in ("cw", "ccw"):
        got = square_run_end(E_d, E_b, E_s, L, B, Direction(d))
        assert got == pytest.approx(_turtle_end(E_d, E_b, E_s, d), abs=1e-6)
    assert icr_offset(1.0, B) == 0.0


@pytest.mark.parametrize("headings", [True, False])
@pytest.mark.parametrize(("E_d", "E_b"), [(1.00084, 336.17 / 340), (1.03, 1.06), (0.98, 0.95)])
def test_recovers_the_robot_from_exact_ends(E_d, E_b, headings):
    # E_d 1.03 and E_b 1.06 put the runs 5.4 m from the start of a 4 m square: beyond the
    # paper's formulas, within the geometry.
    ends = {d: _around(_turtle_end(E_d, E_b, 1.0, d), 0.02) for d in ("cw", "ccw")}
    if not headings:
        ends = {d: [(x, y, None) for x, y, _ in pts] for d, pts in ends.items()}
    runs = _runs(ends)
    est = estimate_errors("endpose", umbmark_benchmark(runs), runs, TEST)
    assert est.E_d == pytest.approx(E_d, abs=2e-8)
    assert est.E_b == pytest.approx(E_b, abs=2e-8)
    assert est.alpha == pytest.approx(0.5 * math.pi * (1 - 1 / E_b), abs=1e-8)
    assert est.warnings == ()
    exact = estimate_errors("exact", umbmark_benchmark(runs), runs, TEST)
    assert exact.E_d == pytest.approx(E_d, abs=2e-8)


def test_paper_method_refuses_what_only_the_geometry_explains():
    runs = _runs({d: _around(_turtle_end(1.03, 1.06, 1.0, d), 0.02) for d in ("cw", "ccw")})
    with pytest.raises(ValueError, match=r"larger than the square's side .* use --method exact"):
        estimate_errors("paper", umbmark_benchmark(runs), runs, TEST)


def test_a_unit_slip_is_refused_by_every_method():
    runs = _runs({d: _around((300.0, 10.0, 0.0), 5.0) for d in ("cw", "ccw")})
    for method in ("exact", "endpose"):
        with pytest.raises(ValueError, match="farther from the start than the whole 16 m path"):
            estimate_errors(method, umbmark_benchmark(runs), runs, TEST)


def test_heading_method_converts_beta_with_the_actual_wheelbase():
    ends = {d: _around(_turtle_end(1.02, 1.05, 1.0, d), 0.02) for d in ("cw", "ccw")}
    runs = _runs(ends)
    est = estimate_errors("heading", umbmark_benchmark(runs), runs, TEST)
    assert est.E_d == pytest.approx(1.02, abs=1e-7)
    assert est.E_b == pytest.approx(1.05, abs=1e-7)


def test_a_scale_error_measured_apart_is_held_fixed():
    E_d, E_b, E_s = 1.004, 1.03, 1.02
    runs = _runs({d: _around(_turtle_end(E_d, E_b, E_s, d), 0.02) for d in ("cw", "ccw")})
    bench = umbmark_benchmark(runs)
    fixed = estimate_errors("endpose", bench, runs, TEST, E_s=E_s)
    assert fixed.E_b == pytest.approx(E_b, abs=1e-7)
    assert fixed.E_d == pytest.approx(E_d, abs=1e-7)
    assert fixed.E_s == E_s
    # Without it, the turns show E_b / E_s (to first order; the legs' length is second).
    blind = estimate_errors("endpose", bench, runs, TEST)
    assert blind.E_b == pytest.approx(E_b / E_s, abs=2e-4)
    assert blind.E_s is None
    paper = estimate_errors("paper", bench, runs, TEST, E_s=E_s)
    assert paper.E_b == pytest.approx(E_b, abs=2e-3)


def _gaussian_trials(n_trials: int, seed: int, headings: bool, per_direction: int = 5):
    """Runs scattered about exact ends: 18 mm per axis, 0.3 deg of heading."""
    rng = np.random.default_rng(seed)
    E_d, E_b = 1.00084, 336.17 / 340
    centres = {d: square_run_end(E_d, E_b, 1.0, L, B, Direction(d)) for d in ("cw", "ccw")}
    for _ in range(n_trials):
        ends = {}
        for d, (x, y, th) in centres.items():
            noise = rng.normal(0, [0.018, 0.018, math.radians(0.3)], size=(per_direction, 3))
            ends[d] = [(x + nx, y + ny, (th + nt) if headings else None) for nx, ny, nt in noise]
        yield _runs(ends), (E_d, E_b)


@pytest.mark.slow
@pytest.mark.parametrize("headings", [False, True])
def test_the_model_check_rarely_fires_on_gaussian_scatter(headings):
    """The issue's bar: at most 0.5 % of honest runs get a model warning (the check's level
    is 0.1 %)."""
    fired = {"paper": 0, "endpose": 0}
    trials = 600
    for runs, _ in _gaussian_trials(trials, seed=11 + headings, headings=headings):
        bench = umbmark_benchmark(runs)
        for method in fired:
            fired[method] += bool(estimate_errors(method, bench, runs, TEST).warnings)
    for method, count in fired.items():
        assert count / trials <= 0.005, (method, count)


@pytest.mark.slow
def test_95_percent_intervals_cover_the_truth():
    covered = {"E_d": 0, "E_b": 0}
    trials = 400
    for runs, truth in _gaussian_trials(trials, seed=5, headings=True):
        est = endpose_estimate(umbmark_benchmark(runs), runs, TEST)
        for name, true in zip(("E_d", "E_b"), truth, strict=True):
            low, high = est.interval(name)
            covered[name] += low <= true <= high
    for name, count in covered.items():
        # 95 % of 400: 380; two binomial standard deviations are 9 trials.
        assert 0.91 <= count / trials <= 0.99, (name, count)


def test_a_swapped_direction_label_is_named():
    ends = {d: _around(_turtle_end(1.00084, 336.17 / 340, 1.0, d), 0.02) for d in ("cw", "ccw")}
    runs = _runs(ends)
    swapped = runs[2]
    runs[2] = Run(Direction.CCW, swapped.true_end, swapped.odometry_end, swapped.label)
    est = estimate_errors("endpose", umbmark_benchmark(runs), runs, TEST)
    # The swapped run inflates the scatter, so the model check alone would pass it.
    (warning,) = est.warnings
    assert warning.startswith(f"{swapped.label}, labelled ccw, sits in the cw cluster")


def test_headings_in_degrees_read_as_radians_are_named():
    ends = {d: _around(_turtle_end(1.00084, 336.17 / 340, 1.0, d), 0.02) for d in ("cw", "ccw")}
    as_radians = {d: [(x, y, math.degrees(th)) for x, y, th in p] for d, p in ends.items()}
    runs = _runs(as_radians)
    est = estimate_errors("endpose", umbmark_benchmark(runs), runs, TEST)
    assert any("are the headings in degrees? (--angle-unit deg)" in w for w in est.warnings)

"""``umbmark plan``: closed-form standard errors, checked by hand and by Monte Carlo."""

from __future__ import annotations

import math

import numpy as np
import pytest

import umbmark
from umbmark.conventions import Direction
from umbmark.runs import EndPose, Run

from helpers import api_error, cli_error, cli_json, linear_cgs


def test_the_figures_by_hand():
    # se(alpha) = sigma / (4 L sqrt(n)); se(E_b) = (2/pi) se(alpha); se(E_d) = (b/L) se(beta)
    report = umbmark.plan(scatter=0.01, wheelbase=0.34, side_length=4.0, runs=5)
    se = 0.01 / (4 * 4.0 * math.sqrt(5))
    assert report.se_alpha == pytest.approx(2.7951e-4, rel=1e-4)
    assert report.se_alpha == pytest.approx(se, rel=1e-12)
    assert report.se_E_b == pytest.approx(2 / math.pi * se, rel=1e-12)
    assert report.se_E_d == pytest.approx(0.34 / 4.0 * se, rel=1e-12)
    assert report.threshold == pytest.approx(3 * math.sqrt(2) * 0.01 / math.sqrt(5), rel=1e-12)


def test_a_recommendation_fits_the_floor_and_meets_the_target():
    report = umbmark.plan(scatter=0.005, wheelbase=0.2, floor=1.6, target_E_b=2e-4)
    assert report.side_length == pytest.approx(1.0)  # 1.6 m floor less 0.6 m margin
    # (2/pi) * 0.005 / (4 * 1.0 * sqrt(n)) <= 2e-4  ->  n >= 15.83
    assert report.runs == 16
    assert report.se_E_b <= 2e-4
    assert umbmark.plan(scatter=0.005, wheelbase=0.2, floor=1.6, target_E_b=1e-2).runs == 5


@pytest.mark.slow
def test_small_robot_on_a_small_floor_against_monte_carlo():
    """A 0.2 m robot on a 1 m square, 5 + 5 runs, 4 mm scatter per axis: the spread of
    the default estimator's E_d and E_b over 500 simulated tests agrees with the plan
    within 10 %."""
    side, wheelbase, runs, sigma = 1.0, 0.2, 5, 0.004
    cgs = linear_cgs(-0.004, 0.002, side)
    rng = np.random.default_rng(11)
    E_d, E_b = [], []
    for _ in range(500):
        table = [
            Run(Direction(d), EndPose(*(np.array(cgs[d]) + rng.normal(0, sigma, 2))), EndPose(0, 0))
            for d in ("cw", "ccw")
            for _ in range(runs)
        ]
        est = umbmark.calibrate(table, side_length=side, wheelbase=wheelbase).estimate
        E_d.append(est.E_d)
        E_b.append(est.E_b)
    report = umbmark.plan(scatter=sigma, wheelbase=wheelbase, side_length=side, runs=runs)
    assert np.std(E_d, ddof=1) == pytest.approx(report.se_E_d, rel=0.10)
    assert np.std(E_b, ddof=1) == pytest.approx(report.se_E_b, rel=0.10)


def test_the_command_and_its_refusals():
    printed = cli_json("plan", "--scatter", "0.01", "-L", "4", "--runs", "5")
    assert printed == umbmark.plan(scatter=0.01, side_length=4, runs=5).to_dict()
    assert {"se_E_d", "se_E_b"} <= set(printed)
    assert "--floor" in cli_error("plan", "--scatter", "0.01")
    assert "twice its wheelbase" in api_error(umbmark.plan, scatter=0.01, floor=0.8)
    assert "outside" in api_error(umbmark.plan, scatter=math.nan, side_length=4, runs=5)
    assert "runs per direction" in api_error(umbmark.plan, scatter=0.05, floor=1.6, target_E_d=1e-6)

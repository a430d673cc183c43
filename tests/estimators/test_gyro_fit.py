"""The gyro estimator's intervals cover the truth at the rate they state (Monte Carlo).

A hundred simulated robots of the tests' own closed-form simulator (``tests/gyro_sim.py``),
each drawn at random: wheels up to 1 % apart, a wheelbase up to 3 % off, a gyro scale in
0.97-1.03 and a bias up to 0.5 deg/s that wanders, white noise, the IMU tilted by a
degree; five minutes of straights, spins and arcs with rests, calibrated without a
reference, with a heading reference and with scan matching. Each figure's 95 % interval
must hold the truth in 95 % of the robots (within what a hundred draws scatter), and the
standardised errors must scatter as a standard normal does. With scan matching the joint
fit must be as tight as scan matching alone on the same intervals, robot by robot, and
as close to the truth.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from helpers import ROOT

sys.path.insert(0, str(ROOT / "tools"))

from gyro_coverage import Z95, draws


@pytest.fixture(scope="module")
def drawn() -> dict[str, np.ndarray]:
    """Each figure's ``(error, standard error)`` over the robots, ``(100, 2)``."""
    return draws()


@pytest.fixture(scope="module")
def standardised(drawn) -> dict[str, np.ndarray]:
    return {name: pairs[:, 0] / pairs[:, 1] for name, pairs in drawn.items()}


STATISTICAL = (
    "E_d", "E_b k_g", "bias", "k_g (heading)", "E_b (heading)", "bias (heading)",
    "k_g (scan)", "bias (scan)", "E_b (scan)", "E_s (scan)", "E_d (scan)",
)  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("name", STATISTICAL)
def test_the_95_percent_intervals_cover_the_truth_95_times_in_100(standardised, name):
    z = standardised[name]
    covered = float(np.mean(np.abs(z) <= Z95))
    # a hundred draws: the share covered scatters by 2.2 %, the spread by 7 %, the mean by 0.1
    assert abs(covered - 0.95) <= 0.065, (name, covered)
    assert 0.8 <= float(np.std(z)) <= 1.2, (name, float(np.std(z)))
    assert abs(float(np.mean(z))) <= 0.35, (name, float(np.mean(z)))


@pytest.mark.slow
def test_the_wheelbase_relative_to_the_gyro_holds_the_true_one_within_the_tolerance(standardised):
    """Without a reference ``E_b`` is ``E_b k_g``: its widened interval is for a gyro
    within +-3 %, which every drawn gyro is, so it holds the true ``E_b`` more often."""
    covered = float(np.mean(np.abs(standardised["E_b (tolerance)"]) <= Z95))
    assert covered >= 0.95


@pytest.mark.slow
@pytest.mark.parametrize("name", ["E_d", "E_b", "E_s"])
def test_with_the_laser_the_joint_fit_is_as_tight_and_as_close_as_scan_matching_alone(drawn, name):
    """On every robot the joint fit's standard error is at most scan matching alone's on
    the same intervals (the laser's equations weighed alike, the gyro's on top), and its
    errors against the truth are no larger in the root mean square."""
    joint, alone = drawn[f"{name} (scan)"], drawn[f"{name} (scan matching alone)"]
    assert (joint[:, 1] <= alone[:, 1]).all(), float((joint[:, 1] / alone[:, 1]).max())
    rms = [float(np.sqrt(np.mean(pairs[:, 0] ** 2))) for pairs in (joint, alone)]
    assert rms[0] <= rms[1], rms


@pytest.mark.slow
def test_with_the_laser_the_gyros_scale_and_bias_come_within_the_issues_bounds(drawn):
    """``k_g`` within 0.1 % and the bias within 0.01 deg/s: the bias on every robot, the
    scale on nine in ten at least (five minutes of driving pin it to 0.055 % one sigma:
    0.1 % is 1.8 of them; ten minutes hold it on one robot, ``test_gyro_model.py``)."""
    k_g = np.abs(drawn["k_g (scan)"][:, 0])  # of a scale near 1: relative within 3 %
    assert float(np.mean(k_g < 1e-3)) >= 0.9
    assert float(np.degrees(np.abs(drawn["bias (scan)"][:, 0])).max()) < 0.01

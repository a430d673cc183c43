"""The gyro estimator's intervals cover the truth at the rate they state (Monte Carlo).

A hundred simulated robots of the tests' own closed-form simulator (``tests/gyro_sim.py``),
each drawn at random: wheels up to 1 % apart, a wheelbase up to 3 % off, a gyro scale in
0.97-1.03 and a bias up to 0.5 deg/s that wanders, white noise, the IMU tilted by a
degree; five minutes of straights, spins and arcs with rests, calibrated without a
reference, with a heading reference and with scan matching. Each figure's 95 % interval
must hold the truth in 95 % of the robots (within what a hundred draws scatter), and the
standardised errors must scatter as a standard normal does.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gyro_sim import Truth, heading_reference, mixed_program, record, scan_reference
from umbmark.estimators.gyro import fit_gyro
from umbmark.model.kinematics import WheelParams
from umbmark.scans.gyro_intervals import HeadingReference, gyro_intervals, gyro_reference

ROBOTS = 100
Z95 = 1.959963984540054


def _robot(rng: np.random.Generator) -> Truth:
    r = 0.05
    return Truth(
        radius_left=r * (1 + rng.uniform(-0.005, 0.005)),
        radius_right=r * (1 + rng.uniform(-0.005, 0.005)),
        wheelbase=0.34 * (1 + rng.uniform(-0.03, 0.03)),
        k_g=rng.uniform(0.97, 1.03),
        bias=math.radians(rng.uniform(-0.5, 0.5)),
    )


@pytest.fixture(scope="module")
def errors() -> dict[str, np.ndarray]:
    """Each figure's standardised error (estimate less truth, over its standard error)
    over the robots."""
    rng = np.random.default_rng(2026)
    motion = mixed_program(5.0)
    out: dict[str, list[float]] = {}

    def add(name: str, value: float, truth: float, se: float) -> None:
        out.setdefault(name, []).append((value - truth) / se)

    for seed in range(ROBOTS):
        truth = _robot(rng)
        active = WheelParams(truth.nominal_wheelbase, truth.nominal_diameter)
        rec = record(motion, truth, seed=seed)
        iv = gyro_intervals(rec.wheels, rec.gyro)
        t = np.linspace(iv.start.min(), iv.end.max(), 20_001)
        bias = float(np.mean(rec.bias_at(t)))
        cal = fit_gyro(iv, active)
        v, se = cal.values, cal.standard_errors
        add("E_d", v["E_d"], truth.E_d, se["E_d"])
        add("E_b k_g", v["E_b_k_g"], truth.E_b * truth.k_z / truth.E_s, se["E_b_k_g"])
        add("bias", v["bias"], bias, se["bias"])
        add("E_b (tolerance)", v["E_b"], truth.E_b / truth.E_s, se["E_b"])
        start, end, yaw = heading_reference(rec, seed=1000 + seed)
        ref = gyro_reference(rec.gyro, HeadingReference(start, end, yaw))
        cal = fit_gyro(iv, active, reference=ref)
        v, se = cal.values, cal.standard_errors
        add("k_g (heading)", v["k_g"], truth.k_z, se["k_g"])
        add("E_b (heading)", v["E_b"], truth.E_b / truth.E_s, se["E_b"])
        add("bias (heading)", v["bias"], bias, se["bias"])
        cal = fit_gyro(
            iv, active, reference=gyro_reference(rec.gyro, scan_reference(rec, seed=2000 + seed))
        )
        v, se = cal.values, cal.standard_errors
        add("k_g (scan)", v["k_g"], truth.k_z, se["k_g"])
        add("E_b (scan)", v["E_b"], truth.E_b, se["E_b"])
        add("E_s (scan)", v["E_s"], truth.E_s, se["E_s"])
        add("E_d (scan)", v["E_d"], truth.E_d, se["E_d"])
    return {name: np.array(z) for name, z in out.items()}


STATISTICAL = (
    "E_d", "E_b k_g", "bias", "k_g (heading)", "E_b (heading)", "bias (heading)",
    "k_g (scan)", "E_b (scan)", "E_s (scan)", "E_d (scan)",
)  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("name", STATISTICAL)
def test_the_95_percent_intervals_cover_the_truth_95_times_in_100(errors, name):
    z = errors[name]
    covered = float(np.mean(np.abs(z) <= Z95))
    # a hundred draws: the share covered scatters by 2.2 %, the spread by 7 %, the mean by 0.1
    assert abs(covered - 0.95) <= 0.065, (name, covered)
    assert 0.8 <= float(np.std(z)) <= 1.2, (name, float(np.std(z)))
    assert abs(float(np.mean(z))) <= 0.35, (name, float(np.mean(z)))


@pytest.mark.slow
def test_the_wheelbase_relative_to_the_gyro_holds_the_true_one_within_the_tolerance(errors):
    """Without a reference ``E_b`` is ``E_b k_g``: its widened interval is for a gyro
    within +-3 %, which every drawn gyro is, so it holds the true ``E_b`` more often."""
    covered = float(np.mean(np.abs(errors["E_b (tolerance)"]) <= Z95))
    assert covered >= 0.95

"""The gyro estimator's intervals against the truth of many simulated robots (Monte Carlo).

Robots of the tests' closed-form simulator (``tests/gyro_sim.py``), each drawn at random:
wheels up to 1 % apart, a wheelbase up to 3 % off, a gyro scale in 0.97-1.03 and a bias up
to 0.5 deg/s that wanders, white noise, the IMU tilted by a degree; five minutes of
straights, spins and arcs with rests, calibrated without a reference, with a heading
reference (0.2 deg a second) and with scan matching (2 mm, 0.3 deg a second), and by scan
matching alone. For each figure: the share of robots whose 95 % interval holds the truth,
the mean and spread of the standardised errors (estimate less truth, over the standard
error), the root mean square error and the mean standard error.
``tests/estimators/test_gyro_fit.py`` asserts them; this prints them
(``docs/estimators.md``).

    PYTHONPATH=src python tools/gyro_coverage.py [ROBOTS]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from gyro_sim import Truth, heading_reference, mixed_program, record, scan_reference
from umbmark.estimators.gyro import fit_gyro
from umbmark.model.kinematics import WheelParams
from umbmark.scans.gyro_intervals import (
    HeadingReference,
    gyro_intervals,
    gyro_reference,
)

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


def draws(robots: int = ROBOTS) -> dict[str, np.ndarray]:
    """Each figure's error (estimate less truth) and standard error over the robots,
    ``(robots, 2)``; ``scan matching alone`` is the package's scan-matching estimator
    (Censi et al.) on the same intervals, without the gyro."""
    from umbmark.estimators.scan_matching import scan_matching_estimate

    rng = np.random.default_rng(2026)
    motion = mixed_program(5.0)
    out: dict[str, list[tuple[float, float]]] = {}

    def add(name: str, value: float, truth: float, se: float) -> None:
        out.setdefault(name, []).append((value - truth, se))

    for seed in range(robots):
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
        scans = scan_reference(rec, seed=2000 + seed)
        cal = fit_gyro(iv, active, reference=gyro_reference(rec.gyro, scans))
        v, se = cal.values, cal.standard_errors
        add("k_g (scan)", v["k_g"], truth.k_z, se["k_g"])
        add("E_d (scan)", v["E_d"], truth.E_d, se["E_d"])
        add("E_b (scan)", v["E_b"], truth.E_b, se["E_b"])
        add("E_s (scan)", v["E_s"], truth.E_s, se["E_s"])
        alone, _ = scan_matching_estimate(scans, active)
        for name, value in (("E_d", truth.E_d), ("E_b", truth.E_b), ("E_s", truth.E_s)):
            add(f"{name} (scan matching alone)", getattr(alone, name), value,
                alone.standard_errors[name])  # fmt: skip
    return {name: np.array(pairs) for name, pairs in out.items()}


def errors(robots: int = ROBOTS) -> dict[str, np.ndarray]:
    """Each figure's standardised error (estimate less truth, over its standard error)
    over the robots."""
    return {name: pairs[:, 0] / pairs[:, 1] for name, pairs in draws(robots).items()}


def main() -> None:
    robots = int(sys.argv[1]) if len(sys.argv) > 1 else ROBOTS
    print(
        f"| figure ({robots} robots) | 95 % interval holds the truth | mean z | spread of z "
        "| rms error | mean standard error |"
    )
    print("|---|---|---|---|---|---|")
    for name, pairs in draws(robots).items():
        z = pairs[:, 0] / pairs[:, 1]
        covered = float(np.mean(np.abs(z) <= Z95))
        scale, unit = (math.degrees(1.0), " deg/s") if name.startswith("bias") else (1.0, "")
        rms = scale * float(np.sqrt(np.mean(pairs[:, 0] ** 2)))
        se = scale * float(np.mean(pairs[:, 1]))
        print(
            f"| {name} | {100 * covered:.0f} % | {np.mean(z):+.2f} | {np.std(z):.2f} "
            f"| {rms:.2g}{unit} | {se:.2g}{unit} |"
        )


if __name__ == "__main__":
    main()

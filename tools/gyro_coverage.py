"""The gyro estimator's intervals against the truth of many simulated robots (Monte Carlo).

Robots of the tests' closed-form simulator (``tests/gyro_sim.py``), each drawn at random:
wheels up to 1 % apart, a wheelbase up to 3 % off, a gyro scale in 0.97-1.03 and a bias up
to 0.5 deg/s that wanders, white noise, the IMU tilted by a degree; five minutes of
straights, spins and arcs with rests, calibrated without a reference, with a heading
reference (0.2 deg a second) and with scan matching (2 mm, 0.3 deg a second), and by scan
matching alone. For each figure: the share of robots whose 95 % interval holds the truth,
the mean and spread of the standardised errors (estimate less truth, over the standard
error), the root mean square error and the mean standard error; then the joint fit with
scan matching against scan matching alone, robot by robot (:func:`against_scan_matching`).
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
        add("bias (scan)", v["bias"], bias, se["bias"])
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


def _rms(pairs: np.ndarray) -> float:
    return float(np.sqrt(np.mean(pairs[:, 0] ** 2)))


def against_scan_matching(drawn: dict[str, np.ndarray]) -> list[str]:
    """The joint fit (with scan matching) against scan matching alone on the same
    recordings, as Markdown lines: per figure the share of robots whose joint standard
    error is at most the scan-alone one, the largest ratio of the two, and each one's
    root mean square error; then how many robots have ``k_g`` within 0.1 % and the bias
    within 0.01 deg/s."""
    robots = drawn["E_d"].shape[0]
    lines = [
        f"| figure ({robots} robots) | joint standard error <= scan matching alone's "
        "| largest ratio of the two | rms error, joint | rms error, scan matching alone |",
        "|---|---|---|---|---|",
    ]
    for name in ("E_d", "E_b", "E_s"):
        joint, alone = drawn[f"{name} (scan)"], drawn[f"{name} (scan matching alone)"]
        ratio = joint[:, 1] / alone[:, 1]
        lines.append(
            f"| {name} | {100 * float(np.mean(ratio <= 1.0)):.0f} % | {float(ratio.max()):.3f} "
            f"| {_rms(joint):.2g} | {_rms(alone):.2g} |"
        )
    k_g = np.abs(drawn["k_g (scan)"][:, 0])
    bias = np.degrees(np.abs(drawn["bias (scan)"][:, 0]))
    lines += [
        "",
        f"k_g within 0.1 %: {int(np.sum(k_g < 1e-3))} of {robots} robots (the largest error "
        f"{100 * float(k_g.max()):.3f} %); the bias within 0.01 deg/s: "
        f"{int(np.sum(bias < 0.01))} of {robots} (the largest error {float(bias.max()):.4f} deg/s)",
    ]
    return lines


def main() -> None:
    robots = int(sys.argv[1]) if len(sys.argv) > 1 else ROBOTS
    drawn = draws(robots)
    print(
        f"| figure ({robots} robots) | 95 % interval holds the truth | mean z | spread of z "
        "| rms error | mean standard error |"
    )
    print("|---|---|---|---|---|---|")
    for name, pairs in drawn.items():
        z = pairs[:, 0] / pairs[:, 1]
        covered = float(np.mean(np.abs(z) <= Z95))
        scale, unit = (math.degrees(1.0), " deg/s") if name.startswith("bias") else (1.0, "")
        rms = scale * float(np.sqrt(np.mean(pairs[:, 0] ** 2)))
        se = scale * float(np.mean(pairs[:, 1]))
        print(
            f"| {name} | {100 * covered:.0f} % | {np.mean(z):+.2f} | {np.std(z):.2f} "
            f"| {rms:.2g}{unit} | {se:.2g}{unit} |"
        )
    print()
    print("\n".join(against_scan_matching(drawn)))


if __name__ == "__main__":
    main()

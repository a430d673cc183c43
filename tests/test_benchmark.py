"""The benchmark, Eqs. 3.1-3.4, and the 3 x SEM rule of Sec. 5, against hand calculations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.benchmark import Cluster, umbmark_benchmark
from umbmark.conventions import Direction
from umbmark.runs import EndPose, Run


def _run(direction: str, ex: float, ey: float) -> Run:
    # Odometry ends off the origin on purpose: only the difference may count (Eq. 3.1).
    return Run(Direction(direction), EndPose(ex + 0.5, ey - 0.25), EndPose(0.5, -0.25))


def test_centres_r_cg_and_e_max_by_hand():
    runs = [
        _run("cw", 0.02, 0.04),
        _run("cw", 0.04, 0.04),  # cg (0.03, 0.04): r = 0.05
        _run("ccw", -0.10, 0.20),
        _run("ccw", -0.14, 0.28),  # cg (-0.12, 0.24)
    ]
    bench = umbmark_benchmark(runs)
    np.testing.assert_allclose(bench.cw.cg, [0.03, 0.04])
    np.testing.assert_allclose(bench.ccw.cg, [-0.12, 0.24])
    assert bench.cw.r_cg == pytest.approx(0.05)
    assert bench.ccw.r_cg == pytest.approx(math.sqrt(0.12**2 + 0.24**2))
    assert bench.e_max_syst == pytest.approx(math.sqrt(0.12**2 + 0.24**2))
    assert bench.worst.direction is Direction.CCW


def test_spread_by_hand():
    # Errors (0, 0) and (0.02, 0): cg (0.01, 0), radial sigma^2 = (1e-4 + 1e-4) / 1.
    cluster = Cluster.of(Direction.CW, np.array([[0.0, 0.0], [0.02, 0.0]]))
    assert cluster.sigma == pytest.approx(math.sqrt(2e-4))
    assert cluster.sem == pytest.approx(math.sqrt(2e-4) / math.sqrt(2))
    np.testing.assert_allclose(cluster.std_xy, [math.sqrt(2e-4), 0.0])


def _cluster_with_sigma(direction: str, centre: tuple[float, float], sigma: float) -> list[Run]:
    # Four runs at distance sigma around the centre and one on it:
    # sum |d|^2 = 4 sigma^2 over n - 1 = 4, so the radial spread is exactly sigma.
    cx, cy = centre
    offsets = [(0, 0), (sigma, 0), (-sigma, 0), (0, sigma), (0, -sigma)]
    return [_run(direction, cx + dx, cy + dy) for dx, dy in offsets]


def test_papers_sem_rule_experiment_7():
    # Sec. 5: sigma about 25 mm, n = 5, SEM = 11.2 mm; 66 mm > 3 SEM = 33.6 mm: second pass.
    runs = _cluster_with_sigma("cw", (0.066, 0.0), 0.025) + _cluster_with_sigma(
        "ccw", (0.0, 0.010), 0.025
    )
    bench = umbmark_benchmark(runs)
    assert bench.sem == pytest.approx(0.025 / math.sqrt(5))
    assert bench.sem == pytest.approx(0.0112, abs=5e-5)
    assert bench.second_pass_threshold == pytest.approx(0.0335, abs=2e-4)
    assert bench.second_pass_recommended


def test_papers_sem_rule_after_calibration():
    # Fig. 11 after calibration: 21 mm < 3 SEM: no second pass.
    runs = _cluster_with_sigma("cw", (0.0, -0.021), 0.025) + _cluster_with_sigma(
        "ccw", (0.010, 0.0), 0.025
    )
    bench = umbmark_benchmark(runs)
    assert bench.e_max_syst == pytest.approx(0.021)
    assert not bench.second_pass_recommended


@pytest.mark.parametrize(("n_cw", "n_ccw"), [(1, 5), (5, 1), (0, 5), (5, 0)])
def test_fewer_than_two_runs_in_a_direction_is_refused(n_cw, n_ccw):
    runs = [_run("cw", 0.01 * i, 0) for i in range(n_cw)]
    runs += [_run("ccw", 0.01 * i, 0) for i in range(n_ccw)]
    with pytest.raises(ValueError, match="at least 2 runs in each direction"):
        umbmark_benchmark(runs)


def test_unequal_numbers_of_runs_are_fine():
    runs = [_run("cw", 0.01, 0.0), _run("cw", 0.03, 0.0)]
    runs += [_run("ccw", 0.0, 0.01 * i) for i in range(7)]
    bench = umbmark_benchmark(runs)
    assert (bench.cw.n, bench.ccw.n) == (2, 7)
    assert bench.ccw.cg[1] == pytest.approx(0.03)

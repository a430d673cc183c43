"""The t and F quantiles of umbmark.core.stats against scipy.stats (an independent reference)."""

from __future__ import annotations

import math

import pytest
from scipy import stats

from umbmark.core.stats import beta_cdf, f_cdf, f_quantile, t_quantile


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 8, 18, 98, 1000])
@pytest.mark.parametrize("p", [0.6, 0.9, 0.975, 0.995, 0.9995])
def test_t_quantile_is_scipys(p, dof):
    assert t_quantile(p, dof) == pytest.approx(stats.t.ppf(p, dof), rel=1e-9)
    assert t_quantile(1 - p, dof) == pytest.approx(stats.t.ppf(1 - p, dof), rel=1e-9)


def test_normal_limit():
    assert t_quantile(0.975, math.inf) == pytest.approx(stats.norm.ppf(0.975), rel=1e-12)


@pytest.mark.parametrize(("d1", "d2"), [(1, 1), (2, 3), (2, 8), (4, 6), (4, 20), (7, 150)])
@pytest.mark.parametrize("p", [0.5, 0.95, 0.999])
def test_f_quantile_and_cdf_are_scipys(p, d1, d2):
    q = f_quantile(p, d1, d2)
    assert q == pytest.approx(stats.f.ppf(p, d1, d2), rel=1e-9)
    assert f_cdf(q, d1, d2) == pytest.approx(p, abs=1e-12)


@pytest.mark.parametrize(("a", "b"), [(0.5, 0.5), (1, 3), (2.5, 7), (30, 2), (200, 300)])
@pytest.mark.parametrize("x", [1e-6, 0.1, 0.5, 0.9, 0.999999])
def test_incomplete_beta_is_scipys(x, a, b):
    assert beta_cdf(x, a, b) == pytest.approx(stats.beta.cdf(x, a, b), rel=1e-10, abs=1e-15)

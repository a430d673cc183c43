"""The few distributions the estimators need: Student's t and Fisher's F quantiles.

Confidence intervals from a handful of runs need Student's t (five runs per direction
leave eight degrees of freedom: a 95 % interval is 2.31 standard errors wide, not 1.96),
and the model checks compare a statistic with an F quantile. ``scipy.stats`` has both but
costs half a second to import, more than a whole calibration; so they are computed here
from the regularized incomplete beta function (a continued fraction, Numerical Recipes
Sec. 6.4), which ``tests/core/test_stats.py`` checks against ``scipy.stats``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["beta_cdf", "f_cdf", "f_quantile", "t_quantile"]

_EPS = 1e-15
_TINY = 1e-300
_MAX_TERMS = 500


def _nonzero(value: float) -> float:
    return value if abs(value) > _TINY else _TINY


def _continued_fraction(a: float, b: float, x: float) -> float:
    """The continued fraction of the incomplete beta function (modified Lentz)."""
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = 1.0
    d = 1.0 / _nonzero(1.0 - qab * x / qap)
    h = d
    for m in range(1, _MAX_TERMS + 1):
        m2 = 2 * m
        for aa in (
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ):
            d = 1.0 / _nonzero(1.0 + aa * d)
            c = _nonzero(1.0 + aa / c)
            h *= d * c
        if abs(d * c - 1.0) < _EPS:
            break
    return h


def beta_cdf(x: float, a: float, b: float) -> float:
    """The regularized incomplete beta function ``I_x(a, b)`` (``a, b > 0``)."""
    if not (a > 0 and b > 0):
        raise ValueError(f"beta parameters must be > 0, got {a}, {b}")
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    log_front = (
        math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    )
    front = math.exp(log_front)
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _continued_fraction(a, b, x) / a
    return 1.0 - front * _continued_fraction(b, a, 1.0 - x) / b


def f_cdf(value: float, d1: float, d2: float) -> float:
    """Cumulative distribution of Fisher's F with ``d1`` and ``d2`` degrees of freedom."""
    if value <= 0.0:
        return 0.0
    return beta_cdf(d1 * value / (d1 * value + d2), 0.5 * d1, 0.5 * d2)


def _invert(cdf: Callable[[float], float], target: float, low: float, high: float) -> float:
    """Bisection of a monotone ``cdf`` for ``target`` between ``low`` and ``high``."""
    for _ in range(200):
        mid = 0.5 * (low + high)
        if high - low <= 1e-14 * max(1.0, abs(mid)):
            break
        if cdf(mid) < target:
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


def f_quantile(p: float, d1: float, d2: float) -> float:
    """The ``p`` quantile of Fisher's F with ``d1`` and ``d2`` degrees of freedom."""
    if not 0.0 < p < 1.0:
        raise ValueError(f"probability must be in (0, 1), got {p}")
    high = 1.0
    while f_cdf(high, d1, d2) < p:
        high *= 2.0
        if high > 1e12:
            return math.inf
    return _invert(lambda v: f_cdf(v, d1, d2), p, 0.0, high)


def t_quantile(p: float, dof: float) -> float:
    """The ``p`` quantile of Student's t with ``dof`` degrees of freedom (``p > 0.5``
    gives a positive value; ``dof = inf`` the normal quantile)."""
    if not 0.0 < p < 1.0:
        raise ValueError(f"probability must be in (0, 1), got {p}")
    if p < 0.5:
        return -t_quantile(1.0 - p, dof)
    if p == 0.5:
        return 0.0
    if math.isinf(dof):
        return math.sqrt(2.0) * _erfinv(2.0 * p - 1.0)
    # t^2 with dof degrees of freedom is F(1, dof): P(|T| <= t) = 2p - 1.
    return math.sqrt(f_quantile(2.0 * p - 1.0, 1.0, dof))


def _erfinv(y: float) -> float:
    """Inverse error function by bisection on ``math.erf``."""
    low, high = 0.0, 10.0
    for _ in range(200):
        mid = 0.5 * (low + high)
        if math.erf(mid) < y:
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)

"""Whether one of a robot's calibrated figures changed over time, beyond its own intervals:
a step (a wheel changed, a laser knocked: since which recording) or a trend (tyres
wearing: how much per week).

Each figure (``E_d``, ``E_b``, ``E_s``, the laser's x, y, yaw) is a series of
calibrations ``v_i`` with standard errors ``s_i`` at times ``t_i``. Three models are fitted
by weighted least squares (weights ``1 / s_i^2``):

- **steady**: one value, the weighted mean;
- **step**: one value before recording ``k`` and another from it on, ``k`` chosen to fit
  best, with at least :data:`MIN_SIDE` calibrations on each side (one calibration alone
  is an outlier, not a change);
- **trend**: a straight line in time.

A model other than steady is taken when its change is larger than :data:`Z_CHANGE` of its
own standard errors (the step's ``|v_after - v_before|``, the trend's slope), after the
standard errors are scaled by the Birge ratio ``sqrt(chi^2 / dof)`` of the best model
where that exceeds 1 (calibrations that scatter more than their intervals say do not make
a change out of that scatter). Where both pass, the one with the smaller ``chi^2`` wins. The
threshold is high because the step's place is searched: with 100 calibrations about 100
places are tried, and a Gaussian's two-sided tail beyond 5 sigma is 6e-7, so a steady
robot is flagged in well under one of a thousand series (``tests/fleets/test_changes.py``
measures it on simulated series).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError

__all__ = ["MIN_SIDE", "SECONDS_PER_WEEK", "Z_CHANGE", "Change", "change_of"]

#: A change counts beyond this many of its own standard errors.
Z_CHANGE = 5.0
#: Fewest calibrations on each side of a step (with two, one odd calibration and a good
#: one beside it would make a step).
MIN_SIDE = 3
#: Seconds in a week (a trend is said per week).
SECONDS_PER_WEEK = 7 * 86400.0

Kind = Literal["steady", "step", "trend"]


@dataclass(frozen=True)
class Change:
    """What the series did.

    Attributes
    ----------
    kind : {"steady", "step", "trend"}
        No change beyond the intervals; a step; a trend.
    value : float
        The latest value the chosen model gives (its mean for steady, the value after the
        step, the line at the last time).
    se : float
        Its standard error (scaled, see the module).
    since : int or None
        A step: the index of the first calibration after it.
    size : float
        A step: the value after minus before; a trend: the change per week; 0 when steady.
    size_se : float
        The standard error of ``size``.
    birge : float
        The Birge ratio the standard errors were scaled by (1 when they were not).
    """

    kind: Kind
    value: float
    se: float
    since: int | None = None
    size: float = 0.0
    size_se: float = 0.0
    birge: float = 1.0

    @property
    def z(self) -> float:
        """The change in its standard errors (0 when steady)."""
        return abs(self.size) / self.size_se if self.size_se > 0 else 0.0


def _mean(v: FloatArray, w: FloatArray) -> tuple[float, float, float]:
    """Weighted mean, its standard error and the chi^2 about it."""
    total = float(np.sum(w))
    mean = float(np.sum(w * v) / total)
    return mean, 1.0 / math.sqrt(total), float(np.sum(w * (v - mean) ** 2))


def _best_step(v: FloatArray, w: FloatArray) -> tuple[int, float] | None:
    """The split (first index after it) with the least chi^2, and that chi^2."""
    n = len(v)
    if n < 2 * MIN_SIDE:
        return None
    cw, cwv, cwv2 = np.cumsum(w), np.cumsum(w * v), np.cumsum(w * v * v)
    ks = np.arange(MIN_SIDE, n - MIN_SIDE + 1)
    w1, s1, q1 = cw[ks - 1], cwv[ks - 1], cwv2[ks - 1]
    w2, s2, q2 = cw[-1] - w1, cwv[-1] - s1, cwv2[-1] - q1
    chi2 = (q1 - s1 * s1 / w1) + (q2 - s2 * s2 / w2)
    best = int(np.argmin(chi2))
    return int(ks[best]), float(max(chi2[best], 0.0))


def change_of(times: FloatArray, values: FloatArray, errors: FloatArray) -> Change:
    """Whether a figure stayed within its intervals, stepped or trended.

    Parameters
    ----------
    times : array, shape (n,)
        When each calibration's recording was made [s], oldest first.
    values : array, shape (n,)
        The figure of each calibration.
    errors : array, shape (n,)
        Its standard errors (positive, finite).

    Returns
    -------
    Change

    Raises
    ------
    InputError
        For fewer than one calibration, arrays of different lengths, times not in order,
        or standard errors that are not positive and finite.
    """
    t, v, s = (np.asarray(a, dtype=np.float64) for a in (times, values, errors))
    n = len(v)
    if n < 1 or t.shape != (n,) or s.shape != (n,) or v.shape != (n,):
        raise InputError(f"a series needs matching times, values and errors, got {n}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise InputError("a series' times and values must be finite")
    if not np.all(np.isfinite(s) & (s > 0)):
        raise InputError("a series' standard errors must be positive and finite")
    if np.any(np.diff(t) < 0):
        raise InputError("a series' times must be in order, oldest first")
    w = 1.0 / (s * s)
    mean, mean_se, chi2_0 = _mean(v, w)
    steady = Change("steady", mean, mean_se)
    if n < 2 * MIN_SIDE:
        return steady
    candidates: list[tuple[float, Change, int]] = []  # chi^2, change, parameters
    step = _best_step(v, w)
    if step is not None:
        k, chi2_step = step
        m1, se1, _ = _mean(v[:k], w[:k])
        m2, se2, _ = _mean(v[k:], w[k:])
        candidates.append((chi2_step, Change("step", m2, se2, k, m2 - m1, math.hypot(se1, se2)), 2))
    span = t - t[0]
    if span[-1] > 0:
        design = np.column_stack([np.ones(n), span / SECONDS_PER_WEEK])
        normal = design.T @ (design * w[:, None])
        coef = np.linalg.solve(normal, design.T @ (w * v))
        cov = np.linalg.inv(normal)
        chi2_trend = float(np.sum(w * (v - design @ coef) ** 2))
        last = np.array([1.0, span[-1] / SECONDS_PER_WEEK])
        value, value_se = float(last @ coef), float(math.sqrt(last @ cov @ last))
        slope, slope_se = float(coef[1]), float(math.sqrt(cov[1, 1]))
        candidates.append((chi2_trend, Change("trend", value, value_se, None, slope, slope_se), 2))
    fits = [(chi2_0, steady, 1), *candidates]
    chi2_best, _, p_best = min(fits, key=lambda f: f[0])
    dof = n - p_best
    birge = max(1.0, math.sqrt(chi2_best / dof)) if dof > 0 else 1.0
    passed = []
    for chi2, change, _ in candidates:
        scaled = Change(
            change.kind,
            change.value,
            change.se * birge,
            change.since,
            change.size,
            change.size_se * birge,
            birge,
        )
        if scaled.z > Z_CHANGE:
            passed.append((chi2, scaled))
    if not passed:
        return Change("steady", mean, mean_se * birge, birge=birge)
    return min(passed, key=lambda f: f[0])[1]

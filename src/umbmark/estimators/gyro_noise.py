"""The gyro estimator's rows and their noise: what each row is, and its variance.

The rows' variances follow their kind (:func:`row_variances`): a rest's is the gyro's
white noise integrated over it, ``n_g^2 T``; a driving interval's adds the gyro's own
error while it turns, ``g_0`` (what is left of its delay, its bias's model), the wheels'
slip, ``c (U_R^2 + U_L^2)`` (each wheel's rotation in radians of heading), a floor
``e_0`` and the error of the wheels' readings at its two ends (their encoders' counts:
``2 q``), which the next interval shares with the opposite sign: two driving intervals
one after the other have the covariance ``-q`` (fitted as minus the mean product of
their residuals), and the rows are whitened by the Cholesky factor of that banded
covariance (:func:`~umbmark.estimators.gyro_fit.whiten`). A reference's variance adds
the reference's own noise (its given variances times a factor, or one variance for all);
the reference's heading change is also its rows' regressor, and its noise would
attenuate ``s`` (the errors-in-variables bias, about the reference's noise variance over
its mean squared turn: 5e-5 for 0.2 degree a second): the normal matrix's ``s`` term is
corrected for it (:func:`~umbmark.estimators.gyro_fit.attenuation`).

Where the wheels' rotation over a reference's stretch is known (scan matching's
intervals, or heading changes with the wheels' readings), the stretch gives two rows of
the same gyro reading: against the wheels (:data:`PAIRED`) and against the reference
(:data:`REFERENCE`, next to it). The gyro's error is the same in both: their covariance is
the gyro's variance over the stretch (``n_g^2 T + g_0``, ``g_0`` fitted as the mean
product of the pair's residuals), so their difference is the reference against the wheels
with no gyro in it, and the fit holds all the reference's own information on the wheels
(what the reference alone has) and the gyro's on top: never looser than the reference
alone. The gyro's intervals mostly covered by those stretches are left out (their wheels
and gyro are in the pairs already: counted twice, they would be overweighted).

Each variance is fitted to the squared residuals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray, IntArray

__all__ = ["DRIVING", "PAIRED", "REFERENCE", "REST", "Rows", "row_variances"]

#: Row kinds: a rest, a driving interval, a reference's stretch (the gyro against the
#: reference), and the gyro against the wheels over a reference's stretch (the reference's
#: row right after it).
REST, DRIVING, REFERENCE, PAIRED = 0, 1, 2, 3
#: The median of a chi-square variable of one degree of freedom: a squared residual's
#: median over it estimates its variance.
_CHI2_MEDIAN = 0.454936423119572
#: The mean of the squares of Gaussian residuals without their largest 2 %, over their
#: variance.
_TRIMMED = 0.8734649911150025


@dataclass(frozen=True)
class Rows:
    """The rows of the fit.

    Attributes
    ----------
    y : array, shape (n,)
        The gyro's heading changes [rad].
    x : array, shape (n, k)
        The figures' regressors, the last :attr:`delays` of them the delays'.
    start, end : array, shape (n,)
        Each row's interval [s].
    kind : array of int, shape (n,)
        :data:`REST`, :data:`DRIVING`, :data:`REFERENCE` or :data:`PAIRED` (a
        :data:`REFERENCE` row right after a :data:`PAIRED` one is its pair).
    wheel : array, shape (n,)
        ``U_R^2 + U_L^2`` of driving rows (0 elsewhere) [rad^2].
    given : array, shape (n,)
        A reference row's own variance [rad^2] where given, else NaN.
    noisy : int or None
        The column of ``x`` that is the reference's own reading, with its noise (the
        errors in a regressor, which attenuate its coefficient: corrected, the module's
        documentation), or None.
    delays : int
        How many of ``x``'s last columns are the gyro's delays' (minus the gyro's rate
        change across the row: their coefficients are the delays [s]).
    spread : float or None
        The reference's heading noise against the wheels over one stretch [rad], as the
        reference alone measured it (the scan-matching estimator's yaw noise): each
        pair's difference gets it (times ``s``); None: the differences' own median
        absolute deviation.
    """

    y: FloatArray
    x: FloatArray
    start: FloatArray
    end: FloatArray
    kind: IntArray
    wheel: FloatArray
    given: FloatArray
    noisy: int | None = None
    delays: int = 0
    spread: float | None = None

    @property
    def duration(self) -> FloatArray:
        return np.asarray(self.end - self.start)

    def __len__(self) -> int:
        return int(self.y.shape[0])

    @property
    def figures(self) -> int:
        """How many of ``x``'s columns are the figures' (the rest: the delays)."""
        return int(self.x.shape[1]) - self.delays

    @property
    def pairs(self) -> BoolArray:
        """``(n,)`` a reference's row right after its :data:`PAIRED` row."""
        out = np.zeros(len(self), dtype=bool)
        out[1:] = (self.kind[1:] == REFERENCE) & (self.kind[:-1] == PAIRED)
        return out

    @property
    def moving(self) -> BoolArray:
        """``(n,)`` the rows over which the robot moved (or may have): driving rows, the
        paired rows whose wheels turned and their reference's rows, and a reference's
        rows without wheels."""
        turned = (self.kind == PAIRED) & (self.wheel > 0.0)
        out = (self.kind == DRIVING) | turned | (self.kind == REFERENCE)
        pairs = self.pairs
        out[1:] = np.where(pairs[1:], turned[:-1], out[1:])
        return np.asarray(out)

    @property
    def chained(self) -> BoolArray:
        """``(n,)`` a driving row that begins where the row before it, driving too, ended."""
        out = np.zeros(len(self), dtype=bool)
        driving = self.kind == DRIVING
        out[1:] = driving[1:] & driving[:-1] & (np.abs(self.start[1:] - self.end[:-1]) < 1e-9)
        return out


def row_variances(
    rows: Rows, residual: FloatArray, kept: BoolArray, s: float = 1.0
) -> tuple[FloatArray, FloatArray, FloatArray, dict[str, float]]:
    """Each row's variance and covariance with the row before, fitted to the residuals
    of the ``kept`` rows (the module's documentation), the reference's own share of each
    (0 for the others), and the noise figures; ``s``: the reference's coefficient (the
    gyro's heading per radian of the reference's)."""
    r2, t, n = residual**2, rows.duration, len(rows)
    rest, ref = (kept & (rows.kind == k) for k in (REST, REFERENCE))
    moving = rows.moving
    pairs = np.zeros(n, dtype=bool)
    pairs[1:] = rows.chained[1:] & kept[1:] & kept[:-1]
    reading = 0.0
    if pairs.sum() >= 10:
        reading = max(-_trimmed_mean(residual[1:][pairs[1:]] * residual[:-1][pairs[1:]]), 0.0)
    # the gyro's own noise from the rests, else from the pairs, else the driving rows
    gyro = float(np.median(r2[rest] / t[rest])) / _CHI2_MEDIAN if rest.sum() >= 5 else math.nan
    gyro, common = _common(rows, residual, kept, gyro)
    wheels = kept & moving & ((rows.kind == DRIVING) | (rows.kind == PAIRED))
    slip = floor = 0.0
    if wheels.sum() >= 5:
        gyro, slip, floor = _driving_noise(
            r2[wheels] - 2.0 * reading - common, t[wheels], rows.wheel[wheels], gyro
        )
    if not math.isfinite(gyro):
        gyro = float(np.median(r2[kept] / t[kept])) / _CHI2_MEDIAN if kept.any() else 1e-12
    gyro = max(gyro, 1e-16)
    shared = gyro * t + np.where(moving, common, 0.0)  # the gyro's own, a pair's in common
    on_wheels = moving & ((rows.kind == DRIVING) | (rows.kind == PAIRED))
    var = shared + np.where(on_wheels, slip * rows.wheel + floor + 2 * reading, 0.0)
    noise = {
        "angle_random_walk": math.sqrt(gyro), "gyro_turning": math.sqrt(common),
        "slip": math.sqrt(slip), "floor": math.sqrt(floor), "wheel_reading": math.sqrt(reading),
    }  # fmt: skip
    refs = rows.kind == REFERENCE
    own = np.zeros(n)
    if refs.any():
        given = np.isfinite(rows.given) & (rows.given > 0)
        own = np.maximum(r2 - shared, 0.0)
        use = ref if ref.any() else refs
        if given[refs].all():
            factor = float(np.median(own[use] / rows.given[use])) / _CHI2_MEDIAN
            factor = max(factor, 1e-6)
            own = np.where(refs, factor * np.where(given, rows.given, 0.0), 0.0)
            noise["reference"] = factor
        else:
            spread = max(float(np.median(own[use])) / _CHI2_MEDIAN, 1e-14)
            own = np.where(refs, spread, 0.0)
            noise["reference"] = math.sqrt(spread)
        var = np.where(refs, shared + own, var)
    var, own = _as_the_reference_alone(rows, residual, (var, own, shared), s, noise)
    var = np.where(kept, np.maximum(var, 1e-18), 1e30)
    lag = np.zeros(n)
    lag[1:] = np.where(pairs[1:], -reading, 0.0)
    tied = rows.pairs & kept & np.concatenate([[False], kept[:-1]])
    lag = np.where(tied, shared, lag)
    own = np.where(kept, own, 0.0)
    return var, lag, own, noise


#: The median absolute deviation's factor to a Gaussian's standard deviation.
_MAD = 1.482602218505602


def _as_the_reference_alone(
    rows: Rows,
    residual: FloatArray,
    variances: tuple[FloatArray, FloatArray, FloatArray],
    s: float,
    noise: dict[str, float],
) -> tuple[FloatArray, FloatArray]:
    """``(var, own)`` with each pair's difference (the reference against the wheels, the
    gyro cancelling) of the one variance the reference alone gives it: the scan-matching
    estimator's yaw noise (:attr:`Rows.spread`, times ``s``: the difference is in the
    gyro's radians), else the differences' median absolute deviation over every pair
    (outliers included, as that estimator takes it). It is shared between the wheels'
    row and the reference's as the fitted model shares it; the gyro's part, common to
    both, stays as fitted. So the pairs hold the reference alone's equations on the
    wheels unchanged, and the gyro's on top. Fewer than 10 pairs: as they were."""
    var, own, shared = variances
    second = np.flatnonzero(rows.pairs)
    if second.size < 10:
        return var, own
    first = second - 1
    difference = residual[first] - residual[second]
    spread = _MAD * float(np.median(np.abs(difference - np.median(difference))))
    if rows.spread is not None and rows.spread > 0.0:
        spread = abs(s) * rows.spread
    wheels = np.maximum(var[first] - shared[first], 0.0)
    total = wheels + own[second]
    if spread <= 0.0 or not (total > 0.0).all():
        return var, own
    share = spread**2 / total
    var, own = var.copy(), own.copy()
    var[first] = shared[first] + wheels * share
    own[second] = own[second] * share
    var[second] = shared[second] + own[second]
    noise["reference_wheels"] = spread
    return var, own


def _trimmed_mean(products: FloatArray) -> float:
    """The mean of ``products`` without the 1 % largest in size."""
    limit = np.quantile(np.abs(products), 0.99)
    return float(np.mean(products[np.abs(products) <= limit]))


def _common(rows: Rows, residual: FloatArray, kept: BoolArray, gyro: float) -> tuple[float, float]:
    """``(gyro, g_0)``: the gyro's white noise (as given where known) and its own error
    while the robot moves, from the products of the pairs' residuals (the gyro's error is
    the one they share: ``n_g^2 T + g_0``); ``g_0`` is 0 with fewer than 10 pairs."""
    index = np.flatnonzero(rows.pairs & kept & rows.moving)
    index = index[kept[index - 1]]
    if index.size < 10:
        return gyro, 0.0
    products, t = residual[index] * residual[index - 1], rows.duration[index]
    if math.isfinite(gyro):
        return gyro, max(_trimmed_mean(products - gyro * t), 0.0)
    limit = np.quantile(np.abs(products), 0.99)
    keep = np.abs(products) <= limit
    coef = _nonnegative(np.column_stack([t[keep], np.ones(int(keep.sum()))]), products[keep])
    return (float(coef[0]) if coef[0] > 0.0 else math.nan), float(coef[1])


def _nonnegative(a: FloatArray, target: FloatArray) -> FloatArray:
    """The least squares of ``a`` on ``target``, negative terms dropped."""
    active = np.ones(a.shape[1], dtype=bool)
    coef = np.zeros(a.shape[1])
    for _ in range(a.shape[1]):
        sol, *_ = np.linalg.lstsq(a[:, active], target, rcond=None)
        coef[:] = 0.0
        coef[active] = sol
        if (coef[active] >= 0).all():
            break
        active &= coef > 0
        if not active.any():
            coef[:] = 0.0
            break
    return coef


def _driving_noise(
    r2: FloatArray, t: FloatArray, wheel: FloatArray, gyro: float
) -> tuple[float, float, float]:
    """``(gyro, slip, floor)`` variances of the driving rows' model ``gyro T + slip U^2 +
    floor``, least squares on the squared residuals (the largest 2 % trimmed), negative
    terms dropped; ``gyro`` held where known from the rests."""
    keep = r2 <= np.quantile(r2, 0.98)
    known = math.isfinite(gyro)
    target = r2[keep] - (gyro * t[keep] if known else 0.0)
    columns = [wheel[keep], np.ones(int(keep.sum()))]
    if not known:
        columns.insert(0, t[keep])
    coef = _nonnegative(np.column_stack(columns), target)
    # the squared residuals' mean is their variance; the trim took the top 2 %, which
    # holds 1 - 0.8735 of a Gaussian's (P(chi2_3 < q) / 0.98, q chi2_1's 98 % point)
    coef *= 1.0 / _TRIMMED
    if not known:
        gyro = float(coef[0])
        coef = coef[1:]
    return gyro, float(coef[0]), float(coef[1])

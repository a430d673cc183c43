"""The gyro estimator's least squares: a gyro's heading change against a linear model,
with its bias a random walk (:mod:`umbmark.estimators.gyro` says what the rows are).

Each row ``k`` is an interval's gyro heading change ``y_k`` [rad], modelled as
``x_k . a + integral of bias(t) over the interval``: ``a`` the figures' coefficients, the
bias a continuous piecewise-linear function of time with knots every ``spacing`` seconds
(its values at the knots ``beta_j``; row ``k``'s integrals of the knots' hat functions are
:func:`bias_basis`). The bias's steps between knots are those of a random walk,
``beta_(j+1) - beta_j ~ N(0, q spacing)``: a prior that ties each knot to its neighbours
where the data say nothing about it (no singular system from the bias) and lets them
follow a wandering bias where rests or the fit pin them. Its intensity ``q`` is the one
that makes the data likeliest (the restricted likelihood of the linear Gaussian model,
maximised over ``log q`` by golden-section search), between :data:`WALK_RANGE`.

Every row's gyro reading may lag (or lead) what it is compared with: its readings'
delay ``delta`` (a MEMS part's decimation filter, its driver's stamps) makes the gyro's
heading change over ``[t_0, t_1]`` that over ``[t_0 - delta, t_1 - delta]``, which is,
to first order, ``- delta (w_1 - w_0)`` more (``w`` the gyro's rate read at the ends):
one column of each delay (:attr:`Rows.delays`: the gyro's against the wheels', and
against the reference's), fitted with the rest. Unmodelled, 10 ms (half a period at 50
Hz) is an error of 0.2 degree in a second that starts or ends a turn at a rad/s.

The rows' variances follow their kind (:func:`row_variances`): a rest's is the gyro's
white noise integrated over it, ``n_g^2 T``; a driving interval's adds the gyro's own
error while it turns, ``g_0`` (what is left of its delay, its bias's model), the wheels'
slip, ``c (U_R^2 + U_L^2)`` (each wheel's rotation in radians of heading), a floor ``e_0``
and the error of the wheels' readings at its two ends (their encoders' counts: ``2 q``),
which the next interval shares with the opposite sign: two driving intervals one after
the other have the covariance ``-q`` (fitted as minus the mean product of their
residuals), and the rows are whitened by the Cholesky factor of that banded covariance
(:func:`whiten`). A reference's variance adds the reference's own noise (its given
variances times a factor, or one variance for all); the reference's heading change is
also its rows' regressor, and its noise would attenuate ``s`` (the errors-in-variables
bias, about the reference's noise variance over its mean squared turn: 5e-5 for 0.2
degree a second): the normal matrix's ``s`` term is corrected for it (:func:`attenuation`).

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

Each variance is fitted to the squared residuals. Rows beyond :data:`OUTLIER` standard
deviations are dropped (at most 2 % a round) and the fit made again, for :data:`ROUNDS`
rounds.

The covariance of the coefficients and knots is the inverse of the information matrix
(the model's, with the prior), a pseudo-inverse where the rows do not determine some
combinations: :attr:`LinearFit.null` spans those, and :meth:`LinearFit.determined` says
whether a figure's gradient lies clear of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray, IntArray

__all__ = [
    "DRIVING",
    "MAX_KNOTS",
    "OUTLIER",
    "PAIRED",
    "REFERENCE",
    "REST",
    "ROUNDS",
    "WALK_RANGE",
    "LinearFit",
    "Rows",
    "attenuation",
    "bias_basis",
    "fit_rows",
    "knots_for",
    "row_variances",
    "whiten",
]

#: The bias's knots at most.
MAX_KNOTS = 400
#: Row kinds: a rest, a driving interval, a reference's stretch (the gyro against the
#: reference), and the gyro against the wheels over a reference's stretch (the reference's
#: row right after it).
REST, DRIVING, REFERENCE, PAIRED = 0, 1, 2, 3
#: The bias's random-walk intensity searched [rad/s/sqrt(s)]: from a gyro steadier than
#: any MEMS part (6e-6 deg/s/sqrt(s)) to one whose bias wanders by a degree per second
#: within a minute.
WALK_RANGE = (1e-7, 2e-3)
#: A row this many standard deviations off is an outlier ...
OUTLIER = 5.0
#: ... dropped for this many rounds at most.
ROUNDS = 3
#: Eigenvalues of the scaled information below this share of the largest: not determined.
_NULL = 1e-10
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


def knots_for(start: FloatArray, end: FloatArray, spacing: float) -> FloatArray:
    """The knots of the bias [s]: every ``spacing`` from the first start past the last end
    (two at least), further apart where that would make more than :data:`MAX_KNOTS`
    (recordings over an hour at 10 s: the rows' bias basis stays linear in the length)."""
    low, high = float(np.min(start)), float(np.max(end))
    spacing = max(spacing, (high - low) / (MAX_KNOTS - 1))
    count = max(2, math.ceil((high - low) / spacing - 1e-9) + 1)
    return np.asarray(low + spacing * np.arange(count), dtype=np.float64)


def _antiderivative(x: FloatArray, knots: FloatArray) -> FloatArray:
    """``(n, M)`` the integral from the first knot to each ``x`` of each knot's hat."""
    w = float(knots[1] - knots[0])
    m = knots.size
    pos = np.clip((x - knots[0]) / w, 0.0, m - 1.0)
    i = np.minimum(np.floor(pos).astype(np.int64), m - 2)
    u = pos - i
    j = np.arange(m)[None, :]
    below = i[:, None]
    full = 0.5 * w * ((j <= below - 1).astype(np.float64) + ((j >= 1) & (j <= below)))
    rows = np.arange(x.size)
    full[rows, i] += w * (u - 0.5 * u * u)
    full[rows, i + 1] += 0.5 * w * u * u
    return np.asarray(full, dtype=np.float64)


def bias_basis(start: FloatArray, end: FloatArray, knots: FloatArray) -> FloatArray:
    """``(n, M)`` each interval's integral of each knot's hat function [s]: the bias's
    integral over interval ``k`` is ``basis[k] @ beta``."""
    return _antiderivative(end, knots) - _antiderivative(start, knots)


@dataclass(frozen=True)
class LinearFit:
    """The least squares' solution.

    Attributes
    ----------
    coefficients : array, shape (k,)
        The figures' coefficients.
    knots, bias : array, shape (M,)
        The bias's knots [s] and values there [rad/s].
    covariance : array, shape (k + M, k + M)
        Of ``(coefficients, bias)``.
    null : array, shape (k + M, d)
        The combinations the rows do not determine (scaled as :attr:`scale` says).
    scale : array, shape (k + M,)
        The unknowns' scales the null space is expressed in.
    walk : float
        The bias's random-walk intensity found [rad/s/sqrt(s)].
    variances : array, shape (n,)
        Each row's variance [rad^2].
    own : array, shape (n,)
        The reference's own share of each reference row's variance [rad^2].
    lag : array, shape (n,)
        Each row's covariance with the row before it [rad^2].
    kept : array of bool, shape (n,)
        The rows used (the others: outliers).
    residual : array, shape (n,)
        Each row's residual [rad].
    noise : dict of str to float
        The fitted noise: ``angle_random_walk``, the gyro's white noise
        [rad/s/sqrt(Hz)]; ``slip`` [share of a wheel's rotation]; ``floor`` and
        ``wheel_reading`` [rad]; ``reference`` (a factor on the given variances, or a
        standard deviation [rad]).
    """

    coefficients: FloatArray
    knots: FloatArray
    bias: FloatArray
    covariance: FloatArray
    null: FloatArray
    scale: FloatArray
    walk: float
    variances: FloatArray
    own: FloatArray
    lag: FloatArray
    kept: BoolArray
    residual: FloatArray
    noise: dict[str, float]

    def determined(self, gradient: FloatArray) -> bool:
        """Whether the rows determine the figure of ``gradient`` (shape (k + M,))."""
        if self.null.shape[1] == 0:
            return True
        g = gradient / np.where(self.scale > 0, self.scale, 1.0)
        size = float(np.linalg.norm(g))
        return size == 0.0 or float(np.linalg.norm(self.null.T @ g)) <= 1e-6 * size

    def variance(self, gradient: FloatArray) -> float:
        """The variance of the figure of ``gradient``."""
        return max(float(gradient @ self.covariance @ gradient), 0.0)


def whiten(values: FloatArray, variances: FloatArray, lag: FloatArray) -> FloatArray:
    """``values`` (shape (n,) or (n, m)) times the inverse of the lower Cholesky factor
    of the rows' covariance (``variances`` on its diagonal, ``lag`` below it: a row's
    covariance with the one before): rows with independent, unit-variance errors."""
    out = np.array(values, dtype=np.float64, copy=True)
    chain = np.flatnonzero(lag != 0.0)
    diag, below = _factor(variances, lag)
    heads = np.ones(diag.shape, dtype=bool)
    heads[chain] = False
    out[heads] = (out[heads].T / diag[heads]).T
    for k in chain:
        out[k] = (out[k] - below[k] * out[k - 1]) / diag[k]
    return out


def _factor(variances: FloatArray, lag: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(diag, below)`` the lower Cholesky factor of the rows' banded covariance: its
    diagonal and the entries below it (each row's conditional standard deviation given
    the rows before, and its tie to the one before)."""
    diag = np.sqrt(variances)
    below = np.zeros_like(diag)
    for k in np.flatnonzero(lag != 0.0):  # the recurrence, where a row is tied to the one before
        below[k] = lag[k] / diag[k - 1]
        diag[k] = math.sqrt(max(variances[k] - below[k] ** 2, 1e-6 * variances[k]))
    return diag, below


def row_variances(
    rows: Rows, residual: FloatArray, kept: BoolArray
) -> tuple[FloatArray, FloatArray, FloatArray, dict[str, float]]:
    """Each row's variance and covariance with the row before, fitted to the residuals
    of the ``kept`` rows (the module's documentation), the reference's own share of each
    (0 for the others), and the noise figures."""
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
    var = np.where(kept, np.maximum(var, 1e-18), 1e30)
    lag = np.zeros(n)
    lag[1:] = np.where(pairs[1:], -reading, 0.0)
    tied = rows.pairs & kept & np.concatenate([[False], kept[:-1]])
    lag = np.where(tied, shared, lag)
    own = np.where(kept, own, 0.0)
    return var, lag, own, noise


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


def _prior(m: int, spacing: float, walk: float, k: int) -> FloatArray:
    """The random walk's precision on the knots, in the unknowns' order."""
    d = np.diff(np.eye(m), axis=0)
    out = np.zeros((k + m, k + m))
    out[k:, k:] = d.T @ d / (walk * walk * spacing)
    return out


def _restricted(
    normal: FloatArray, rhs: FloatArray, yy: float, m: int, spacing: float, k: int, walk: float
) -> float:
    """``-2`` log restricted likelihood of the walk ``walk`` (constants dropped)."""
    total = normal + _prior(m, spacing, walk, k)
    scale = np.sqrt(np.maximum(np.diag(total), 1e-300))
    scaled = total / scale[:, None] / scale[None, :]
    scaled[np.diag_indices_from(scaled)] += 1e-12
    _, logdet = np.linalg.slogdet(scaled)
    logdet += 2.0 * float(np.sum(np.log(scale)))
    solution = np.linalg.solve(scaled, rhs / scale) / scale
    return float(logdet + (m - 1) * math.log(walk * walk * spacing) + yy - rhs @ solution)


def _best_walk(
    normal: FloatArray, rhs: FloatArray, yy: float, m: int, spacing: float, k: int
) -> float:
    """The walk of the largest restricted likelihood (golden section on its logarithm)."""
    low, high = (math.log(v) for v in WALK_RANGE)
    golden = 0.5 * (math.sqrt(5.0) - 1.0)

    def cost(log_walk: float) -> float:
        return _restricted(normal, rhs, yy, m, spacing, k, math.exp(log_walk))

    a, b = low, high
    c, d = b - golden * (b - a), a + golden * (b - a)
    fc, fd = cost(c), cost(d)
    for _ in range(40):
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - golden * (b - a)
            fc = cost(c)
        else:
            a, c, fc = c, d, fd
            d = a + golden * (b - a)
            fd = cost(d)
        if b - a < 0.02:
            break
    return math.exp(0.5 * (a + b))


def _solve(
    normal: FloatArray, rhs: FloatArray, prior: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """``(solution, covariance, null, scale)`` of the weighted least squares of normal
    matrix ``normal`` with the prior, a pseudo-inverse where it is singular."""
    total = normal + prior
    scale = np.sqrt(np.maximum(np.diag(total), 0.0))
    scale = np.where(scale > 0.0, scale, 1.0)
    scaled = total / scale[:, None] / scale[None, :]
    values, vectors = np.linalg.eigh(0.5 * (scaled + scaled.T))
    top = float(values[-1]) if values.size else 0.0
    good = values > _NULL * max(top, 1e-300)
    inverse = (vectors[:, good] / values[good]) @ vectors[:, good].T
    covariance = inverse / scale[:, None] / scale[None, :]
    solution = covariance @ rhs
    return solution, covariance, vectors[:, ~good], scale


def _weighted(
    design: FloatArray,
    rows: Rows,
    covariance: tuple[FloatArray, FloatArray, FloatArray],
    m: int,
    spacing: float,
    k: int,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
    """The solution, covariance, null space and scale of :func:`_solve` with the walk of
    the largest restricted likelihood, and that walk; ``covariance``: the rows'
    variances, lags and the reference's own variances."""
    variances, lag, own = covariance
    xw = whiten(design, variances, lag)
    yw = whiten(rows.y, variances, lag)
    normal = xw.T @ xw
    if rows.noisy is not None:
        normal[rows.noisy, rows.noisy] -= attenuation(variances, own, lag)
    rhs = xw.T @ yw
    walk = _best_walk(normal, rhs, float(yw @ yw), m, spacing, k)
    return (*_solve(normal, rhs, _prior(m, spacing, walk, k)), walk)


def attenuation(variances: FloatArray, own: FloatArray, lag: FloatArray) -> float:
    """What the reference's noise adds to its column's squares in the normal matrix,
    ``sum own_j / c_j`` over its rows (``c_j`` the row's variance given the row before it,
    its pair's: the whitened row's scale): taken off, the corrected least squares of
    errors in a regressor (Fuller 1987, ch. 2), so that ``k_g`` is not attenuated by the
    reference's noise."""
    diag, _ = _factor(variances, lag)
    return float(np.sum(own / diag**2))


def fit_rows(rows: Rows, spacing: float) -> LinearFit:
    """The least squares of the module's documentation on ``rows``."""
    k = rows.x.shape[1]
    knots = knots_for(rows.start, rows.end, spacing)
    spacing = float(knots[1] - knots[0])
    m = knots.size
    design = np.hstack([rows.x, bias_basis(rows.start, rows.end, knots)])
    kept = np.ones(len(rows), dtype=bool)
    # the first guess: the gyro's noise of a good MEMS part and a per mille of slip
    variances = (1e-4) ** 2 * rows.duration
    variances += np.where(rows.moving & (rows.kind != REFERENCE), 1e-6 * rows.wheel + 1e-8, 0.0)
    variances += np.where(rows.kind == REFERENCE, 1e-6, 0.0)
    lag = np.zeros(len(rows))
    noise: dict[str, float] = {}
    own = np.zeros(len(rows))
    solved = _weighted(design, rows, (variances, lag, own), m, spacing, k)
    for round_ in range(ROUNDS + 1):
        residual = rows.y - design @ solved[0]
        variances, lag, own, noise = row_variances(rows, residual, kept)
        far = np.zeros_like(kept)
        if round_ > 0:  # the first round's variances were a guess
            z = np.abs(residual) / np.sqrt(variances)
            far = kept & (z > OUTLIER)
            cap = max(1, int(0.02 * kept.sum()))
            if far.sum() > cap:
                far &= z >= np.sort(z[far])[-cap]
            if far.any():
                kept &= ~far
                variances, lag, own, noise = row_variances(rows, residual, kept)
        solved = _weighted(design, rows, (variances, lag, own), m, spacing, k)
        if round_ > 0 and not far.any():
            break
    solution, covariance, null, scale, walk = solved
    residual = rows.y - design @ solution
    return LinearFit(
        coefficients=solution[:k],
        knots=knots,
        bias=solution[k:],
        covariance=covariance,
        null=null,
        scale=scale,
        walk=walk,
        variances=variances,
        own=own,
        lag=lag,
        kept=kept,
        residual=residual,
        noise=noise,
    )

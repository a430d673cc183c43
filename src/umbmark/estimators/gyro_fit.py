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

Every row's gyro reading may lag (or lead) what it is compared with: its readings' delay
``delta`` (a MEMS part's decimation filter, its driver's stamps) makes the gyro's
heading change over ``[t_0, t_1]`` that over ``[t_0 - delta, t_1 - delta]``, which is,
to first order, ``- delta (w_1 - w_0)`` more (``w`` the gyro's rate read at the ends):
one column (:attr:`~umbmark.estimators.gyro_noise.Rows.delays`), the gyro's delay
against the wheels and the reference alike (one clock), fitted with the rest.
Unmodelled, 10 ms (half a period at 50 Hz) is an error of 0.2 degree in a second that
starts or ends a turn at a rad/s.

The rows' variances follow their kind, each fitted to the residuals
(:func:`umbmark.estimators.gyro_noise.row_variances`). Rows beyond :data:`OUTLIER`
standard deviations are dropped (at most 2 % a round) and the fit made again, for
:data:`ROUNDS` rounds.

The covariance of the coefficients and knots is the inverse of the information matrix
(the model's, with the prior), a pseudo-inverse where the rows do not determine some
combinations: :attr:`LinearFit.null` spans those, and :meth:`LinearFit.determined` says
whether a figure's gradient lies clear of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.estimators.gyro_noise import (
    DRIVING,
    PAIRED,
    REFERENCE,
    REST,
    Rows,
    row_variances,
)

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
        s = 1.0 if rows.noisy is None else float(solved[0][rows.noisy])
        variances, lag, own, noise = row_variances(rows, residual, kept, s)
        far = np.zeros_like(kept)
        if round_ > 0:  # the first round's variances were a guess
            z = np.abs(residual) / np.sqrt(variances)
            far = kept & (z > OUTLIER)
            cap = max(1, int(0.02 * kept.sum()))
            if far.sum() > cap:
                far &= z >= np.sort(z[far])[-cap]
            if far.any():
                kept &= ~far
                variances, lag, own, noise = row_variances(rows, residual, kept, s)
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

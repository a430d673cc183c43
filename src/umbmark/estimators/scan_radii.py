"""The wheel radii alone from the sensor's motion, the wheelbase and the mounting held.

Driving that turns too little does not determine the wheelbase (the first step of
Censi et al.'s method, :mod:`umbmark.estimators.scan_matching`, is ill-conditioned: the
intervals' wheel rotations are nearly proportional), but the same intervals still hold
each wheel's radius. A straight's heading drift is ``(r_R Phi_R - r_L Phi_L) / b``, and its
length is ``(r_L Phi_L + r_R Phi_R) / 2``. With ``b`` and the sensor's mounting taken from
elsewhere, they give ``r_R - r_L`` (over ``b``) and ``r_L + r_R``, so ``E_d`` and ``E_s``.
That elsewhere is, for example, the monitor's window, which turned both ways. ``E_d``
rests on ``b`` only through ``E_d - 1``: a wheelbase 1 % off moves ``E_d`` by a hundredth
of its error.

The fit is weighted least squares, in the two radii, of what of each interval's sensor
motion its mounting's yaw does not touch: the length of its translation and its turn
(:func:`umbmark.estimators.scan_matching.predicted_motion`, the arcs of the whole model).
A laser knocked since the mounting was held then moves neither ``E_d`` nor ``E_s``: its
x and y enter only through the turn times the lever, its yaw not at all. The radii are
found by Gauss-Newton from the held ones. The noise of each motion component
is the residuals' median absolute deviation, as the full fit takes it
(:func:`umbmark.estimators.scan_matching.residual_noise`), and the same
outlier rounds are used. The covariance is the Cramer-Rao bound, widened to the sandwich
where the intervals scatter unlike (:func:`umbmark.estimators.scan_matching.widened`).
To it is added what the held parameters' own uncertainty does to the radii, to first
order: ``G Sigma_held G^T`` with ``G = (J_r^T W J_r)^-1 J_r^T W J_held``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.errors import InputError
from umbmark.estimators.scan_matching import (
    outliers,
    predicted_motion,
    residual_noise,
    widened,
)
from umbmark.estimators.solve import relative_jacobian
from umbmark.model.motion_intervals import MotionIntervals

__all__ = ["MIN_INTERVALS", "RadiiFit", "fit_radii"]

#: Fewest intervals the radii are fitted from.
MIN_INTERVALS = 10
_STEPS = 4
#: Most solves with the noise estimated again (the weights settle in two or three).
_REWEIGHTS = 8


@dataclass(frozen=True)
class RadiiFit:
    """The wheel radii, the wheelbase and the mounting held.

    Attributes
    ----------
    radius_left, radius_right : float
        ``r_L``, ``r_R`` [m].
    covariance : array, shape (2, 2)
        Of ``(r_L, r_R)`` [m^2]: the fit's own, and the held parameters' carried over.
    kept : array of bool, shape (n,)
        The intervals fitted from (the others: outliers).
    """

    radius_left: float
    radius_right: float
    covariance: FloatArray
    kept: BoolArray

    def errors_of(self, half_left: float, half_right: float) -> dict[str, tuple[float, float]]:
        """``E_d = f_R / f_L`` and ``E_s = (f_L + f_R) / 2`` (``f = r / half``: each radius
        over the one the odometry uses) with their standard errors, to first order."""
        f_l, f_r = self.radius_left / half_left, self.radius_right / half_right
        e_d, e_s = f_r / f_l, 0.5 * (f_l + f_r)
        grads = {
            "E_d": (e_d, np.array([-e_d / self.radius_left, e_d / self.radius_right])),
            "E_s": (e_s, np.array([0.5 / half_left, 0.5 / half_right])),
        }
        return {
            name: (value, math.sqrt(max(float(g @ self.covariance @ g), 0.0)))
            for name, (value, g) in grads.items()
        }


def fit_radii(
    intervals: MotionIntervals,
    held: FloatArray,
    held_covariance: FloatArray,
    *,
    rounds: int = 4,
    fraction: float = 0.01,
) -> RadiiFit:
    """The wheel radii from ``intervals``, the rest of the model held (module notes).

    Parameters
    ----------
    intervals : MotionIntervals
        The wheels' rotations against the sensor's motion.
    held : array, shape (6,)
        The parameters in the order of :data:`umbmark.estimators.scan_matching.PARAMETERS`:
        the radii are where the fit starts, the wheelbase and the mounting are held.
    held_covariance : array, shape (4, 4)
        The covariance of the held wheelbase and mounting ``(b, l_x, l_y, l_theta)``.
    rounds, fraction : int, float
        The outlier rounds, as :func:`umbmark.estimators.scan_matching.fit_intervals`.

    Raises
    ------
    InputError
        Too few intervals, values that are not finite, a held wheelbase that is not
        positive, or intervals that do not determine the radii.
    """
    where = intervals.source or None
    held = np.asarray(held, dtype=np.float64)
    if held.shape != (6,) or not np.isfinite(held).all() or held[2] <= 0.0:
        raise InputError(
            "the held wheelbase and mounting are not finite and positive", source=where
        )
    if np.shape(held_covariance) != (4, 4) or not np.isfinite(held_covariance).all():
        raise InputError("the held parameters' covariance is not a finite 4 x 4", source=where)
    n = len(intervals)
    finite = np.isfinite(intervals.sensor_motion).all(axis=1)
    finite &= np.isfinite(intervals.phi_left) & np.isfinite(intervals.phi_right)
    if n < MIN_INTERVALS or not finite.all():
        raise InputError(
            f"{n} motion interval(s), {int((~finite).sum())} not finite: the radii need at "
            f"least {MIN_INTERVALS} finite ones",
            source=where,
        )
    params, kept = held.copy(), np.ones(n, dtype=bool)
    for round_ in range(rounds + 1):
        params, noise = _reweighted(intervals, params, kept)
        if round_ == rounds:
            break
        residual = _seen(intervals, params, kept) - _measured(intervals, kept)
        drop = outliers(np.column_stack([residual[:, 0], np.zeros(len(residual)), residual[:, 1]]),
                        fraction)  # fmt: skip
        if not drop.any() or kept.sum() - drop.sum() < MIN_INTERVALS:
            break
        kept[np.flatnonzero(kept)[drop]] = False
    return RadiiFit(float(params[0]), float(params[1]),
                    _covariance(intervals, params, kept, noise, held_covariance), kept)  # fmt: skip


def _reweighted(
    intervals: MotionIntervals, params: FloatArray, rows: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """The radii and the noise they leave, solved again until the noise (the weights)
    settles: the held radii's residuals overstate it, most in the translation."""
    noise = _noise(intervals, params)
    for _ in range(_REWEIGHTS):
        params = _solved(intervals, params, rows, noise)
        settled = _noise(intervals, params)
        done = bool(np.all(np.abs(settled - noise) <= 0.01 * noise))
        noise = settled
        if done:
            break
    return params, noise


def _noise(intervals: MotionIntervals, params: FloatArray) -> FloatArray:
    """``(2,)`` the length's and the turn's noise, over all intervals."""
    return residual_noise(_seen(intervals, params) - _measured(intervals))


def _seen(
    intervals: MotionIntervals, params: FloatArray, rows: BoolArray | None = None
) -> FloatArray:
    """``(m, 2)`` the predicted translation's length [m] and turn [rad] of each interval."""
    p = predicted_motion(intervals, params, rows)
    return np.column_stack([np.hypot(p[:, 0], p[:, 1]), p[:, 2]])


def _measured(intervals: MotionIntervals, rows: BoolArray | None = None) -> FloatArray:
    """``(m, 2)`` the matched translation's length [m] and turn [rad] of each interval."""
    s = intervals.sensor_motion if rows is None else intervals.sensor_motion[rows]
    return np.column_stack([np.hypot(s[:, 0], s[:, 1]), s[:, 2]])


def _jacobian(intervals: MotionIntervals, params: FloatArray, rows: BoolArray) -> FloatArray:
    """``(m, 2, 6)`` the length's and turn's derivatives in the six parameters."""
    return relative_jacobian(lambda p: _seen(intervals, p, rows), params)


def _solved(
    intervals: MotionIntervals, params: FloatArray, rows: BoolArray, noise: FloatArray
) -> FloatArray:
    """The radii by Gauss-Newton (the model is all but linear in them)."""
    out: FloatArray = np.array(params, dtype=np.float64)
    for _ in range(_STEPS):
        residual = (_measured(intervals, rows) - _seen(intervals, out, rows)) / noise
        jac = _jacobian(intervals, out, rows)[:, :, :2] / noise[None, :, None]
        a = jac.reshape(-1, 2)
        try:
            step = np.linalg.solve(a.T @ a, a.T @ residual.reshape(-1))
        except np.linalg.LinAlgError:
            raise InputError("the intervals do not determine the wheel radii") from None
        out[:2] += step
        if np.all(np.abs(step) <= 1e-12 * np.abs(out[:2])):
            break
    return out


def _covariance(
    intervals: MotionIntervals, params: FloatArray, rows: BoolArray, noise: FloatArray,
    held_covariance: FloatArray,
) -> FloatArray:  # fmt: skip
    """``(2, 2)`` the radii's covariance: the fit's own, widened, and the held ones'."""
    weighted = _jacobian(intervals, params, rows) / noise[None, :, None]
    free, fixed = weighted[:, :, :2], weighted[:, :, 2:]
    fisher = np.einsum("kij,kil->jl", free, free)
    try:
        bound = np.linalg.inv(fisher)
    except np.linalg.LinAlgError:
        raise InputError("the intervals do not determine the wheel radii") from None
    scaled = (_seen(intervals, params, rows) - _measured(intervals, rows)) / noise
    own = widened(bound, free, scaled)
    carried = bound @ np.einsum("kij,kil->jl", free, fixed)
    out: FloatArray = own + carried @ held_covariance @ carried.T
    return out

"""The gyro estimator with scan matching as its reference: distance too, so ``E_s``.

Scan matching's motion intervals (Censi et al. 2013: the laser's own motion between two
sweeps, :mod:`umbmark.estimators.scan_matching`) give the heading change and the
translation. The heading changes join the gyro's rows as any heading reference's
(:mod:`umbmark.estimators.gyro`), which fixes ``S``, ``D``, ``s = 1 / k_g`` and the bias;
then, as in Censi et al.'s second step, the translations with the wheels' turning gains
``J21 = -(S - D) r_L / (s b)``, ``J22 = (S + D) r_R / (s b)`` (``r``, ``b``: the active
geometry's) fixed give the wheelbase and the laser's mounting in closed form
(:func:`~umbmark.estimators.scan_matching.second_step`). Both are refined together by
Gauss-Newton on every row at once (the gyro's rows with their variances and the bias's
random walk as fitted, the translations' two rows per interval with the matcher's noise
from their residuals' median absolute deviation, as the scan-matching estimator does):
the joint maximum likelihood, whose inverse information is the covariance. Then
``E_b = b_true / b``, ``E_s = S b_true / (s b)`` and the wheels' diameters
``2 (S -/+ D) r b_true / (s b)``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.errors import InputError
from umbmark.estimators.gyro_fit import (
    _NULL,
    OUTLIER,
    REFERENCE,
    LinearFit,
    _prior,
    attenuation,
    bias_basis,
    fit_rows,
    whiten,
)
from umbmark.estimators.gyro_model import calibration_of, gyro_rows
from umbmark.estimators.gyro_result import GyroCalibration
from umbmark.estimators.scan_excitation import excitation
from umbmark.estimators.scan_matching import (
    ScanCalibration,
    fit_intervals,
    predicted_motion,
    second_step,
)
from umbmark.model.kinematics import WheelParams
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.scans.gyro_intervals import GyroIntervals, GyroReference

__all__ = ["fit_gyro_scan"]

#: Gauss-Newton steps at most.
_STEPS = 8
#: The median absolute deviation's factor to a Gaussian's standard deviation.
_MAD = 1.482602218505602


def _geometry(theta: FloatArray, active: WheelParams) -> FloatArray:
    """``(6,)`` ``(r_L, r_R, b, l_x, l_y, l_yaw)`` of the joint unknowns' ``(S, D, s)`` and
    last four."""
    S, D, s = theta[0], theta[1], theta[2]
    b, lx, ly, lyaw = theta[-4:]
    ra_l, ra_r, ba = 0.5 * active.diameter_left, 0.5 * active.diameter_right, active.wheelbase
    return np.array([(S - D) * ra_l * b / (s * ba), (S + D) * ra_r * b / (s * ba), b, lx, ly, lyaw])


def _translation(
    theta: FloatArray, motion: MotionIntervals, active: WheelParams, rows: BoolArray
) -> FloatArray:
    """``(2 m,)`` the translations' residuals (measured less predicted) of ``rows``."""
    predicted = predicted_motion(motion, _geometry(theta, active), rows)[:, :2]
    return np.asarray((motion.sensor_motion[rows, :2] - predicted).ravel())


def _translation_jacobian(
    theta: FloatArray,
    motion: MotionIntervals,
    active: WheelParams,
    rows: BoolArray,
    columns: list[int],
) -> FloatArray:
    """``(2 m, len(columns))`` the predicted translations' derivatives."""
    out = np.empty((2 * int(rows.sum()), len(columns)))
    for c, j in enumerate(columns):
        step = 1e-6 * max(abs(float(theta[j])), 1e-3)
        up, down = theta.copy(), theta.copy()
        up[j] += step
        down[j] -= step
        out[:, c] = (
            _translation(down, motion, active, rows) - _translation(up, motion, active, rows)
        ) / (2 * step)
    return out


def _pseudo_inverse(total: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(inverse, null, scale)`` of a symmetric information matrix."""
    scale = np.sqrt(np.maximum(np.diag(total), 0.0))
    scale = np.where(scale > 0.0, scale, 1.0)
    scaled = total / scale[:, None] / scale[None, :]
    values, vectors = np.linalg.eigh(0.5 * (scaled + scaled.T))
    good = values > _NULL * max(float(values[-1]), 1e-300)
    inverse = (vectors[:, good] / values[good]) @ vectors[:, good].T
    return inverse / scale[:, None] / scale[None, :], vectors[:, ~good], scale


def fit_gyro_scan(
    intervals: GyroIntervals,
    active: WheelParams,
    reference: GyroReference,
    *,
    bias_window: float,
    stated: FloatArray | None = None,
) -> GyroCalibration:
    """The gyro estimator with scan matching's motion intervals (the module's
    documentation): ``k_g``, the bias, ``E_d``, ``E_b``, ``E_s`` and the laser's mounting."""
    motion = reference.motion
    assert motion is not None
    alone = _noise_alone(motion)
    rows = gyro_rows(intervals, active, reference)
    rows = replace(rows, spread=None if alone is None else float(alone[2]))
    linear = fit_rows(rows, bias_window)
    k, m = rows.x.shape[1], linear.knots.size
    design = np.hstack([rows.x, bias_basis(rows.start, rows.end, linear.knots)])
    white = whiten(design, linear.variances, linear.lag)
    prior = _prior(m, float(linear.knots[1] - linear.knots[0]), linear.walk, k)
    S, D, s = (float(v) for v in linear.coefficients[:3])
    ra_l, ra_r, ba = 0.5 * active.diameter_left, 0.5 * active.diameter_right, active.wheelbase
    x = second_step(
        motion.phi_left, motion.phi_right, motion.sensor_motion,
        -(S - D) * ra_l / (s * ba), (S + D) * ra_r / (s * ba),
    )  # fmt: skip
    theta = np.concatenate(
        [linear.coefficients, linear.bias, [x[0], x[1], x[2], math.atan2(x[4], x[3])]]
    )
    n_lin = k + m
    size = n_lin + 4
    columns = [0, 1, 2, size - 4, size - 3, size - 2, size - 1]
    allowed = linear.kept[rows.kind == REFERENCE]  # the reference's rows the linear fit kept
    moving = allowed
    every = np.ones(len(motion), dtype=bool)
    noise = _noise(_translation(theta, motion, active, every)) if alone is None else alone[:2]
    full_prior = np.zeros((size, size))
    full_prior[:n_lin, :n_lin] = prior
    normal_lin = np.zeros((size, size))
    normal_lin[:n_lin, :n_lin] = white.T @ white
    attenuated = attenuation(linear.variances, linear.own, linear.lag)
    normal_lin[2, 2] -= attenuated
    for _ in range(_STEPS):
        w_t = np.tile(1.0 / noise**2, int(moving.sum()))
        r_lin = rows.y - design @ theta[:n_lin]
        r_t = _translation(theta, motion, active, moving)
        jac = _translation_jacobian(theta, motion, active, moving, columns)
        total = normal_lin + full_prior
        total[np.ix_(columns, columns)] += jac.T @ (jac * w_t[:, None])
        grad = np.zeros(size)
        grad[:n_lin] = white.T @ whiten(r_lin, linear.variances, linear.lag)
        grad[2] += attenuated * theta[2]  # the corrected normal equations' fixed point
        grad -= full_prior @ theta
        grad[columns] += jac.T @ (w_t * r_t)
        inverse, _, _ = _pseudo_inverse(total)
        step = inverse @ grad
        theta = theta + step
        if alone is None:
            noise = _noise(_translation(theta, motion, active, every))
        moving = _kept_translations(theta, motion, active, moving, noise, allowed)
        if np.all(np.abs(step[columns]) <= 1e-10 * np.maximum(np.abs(theta[columns]), 1e-3)):
            break
    jac = _translation_jacobian(theta, motion, active, moving, columns)
    total = normal_lin + full_prior
    total[np.ix_(columns, columns)] += jac.T @ (
        jac * np.tile(1.0 / noise**2, int(moving.sum()))[:, None]
    )
    covariance, null, scale = _pseudo_inverse(total)
    fit = LinearFit(
        coefficients=theta[:k], knots=linear.knots, bias=theta[k:n_lin],
        covariance=covariance[:n_lin, :n_lin], null=null[:n_lin], scale=scale[:n_lin],
        walk=linear.walk, variances=linear.variances, own=linear.own, lag=linear.lag,
        kept=linear.kept,
        residual=rows.y - design @ theta[:n_lin],
        noise={**linear.noise, "scan_x": float(noise[0]), "scan_y": float(noise[1])},
    )  # fmt: skip
    geometry = _geometry(theta, active)
    transform = _geometry_jacobian(theta, active, size, columns)
    geo_cov = transform @ covariance @ transform.T
    extra, undetermined = _extras(theta, geometry, transform, geo_cov, null, scale, active)
    scan = ScanCalibration(
        radius_left=float(geometry[0]), radius_right=float(geometry[1]),
        wheelbase=float(geometry[2]),
        laser_pose=(float(geometry[3]), float(geometry[4]), float(geometry[5])),
        covariance=geo_cov, kept=moving,
        noise=(float(noise[0]), float(noise[1]), linear.noise.get("reference", math.nan)),
        excitation=excitation(motion.phi_left, motion.phi_right),
    )  # fmt: skip
    return calibration_of(
        intervals, active, rows, fit, reference, 0.0, stated, extra, scan, undetermined
    )


def _noise_alone(motion: MotionIntervals) -> FloatArray | None:
    """``(3,)`` the laser's noise (x, y [m], yaw [rad]) as the scan-matching estimator
    alone finds it (:func:`~umbmark.estimators.scan_matching.fit_intervals`: its
    residuals' median absolute deviation at its own fit), None where it finds none (the
    motion does not excite it): the joint fit weighs the laser's equations as it does."""
    try:
        found = fit_intervals(motion)
    except InputError:
        return None
    noise = np.asarray(found.noise, dtype=np.float64)
    return noise if bool(np.all(np.isfinite(noise) & (noise > 1e-12))) else None


def _noise(residual: FloatArray) -> FloatArray:
    """``(2,)`` the translations' noise (x, y) [m], by their median absolute deviation."""
    pairs = residual.reshape(-1, 2)
    spread = np.median(np.abs(pairs - np.median(pairs, axis=0)), axis=0) * _MAD
    return np.asarray(np.where(spread > 0.0, spread, 1e-9))


def _kept_translations(
    theta: FloatArray,
    motion: MotionIntervals,
    active: WheelParams,
    moving: BoolArray,
    noise: FloatArray,
    allowed: BoolArray,
) -> BoolArray:
    """The intervals whose translation is within :data:`OUTLIER` standard deviations
    (and whose heading the linear fit kept)."""
    every = np.ones(len(motion), dtype=bool)
    z = np.abs(_translation(theta, motion, active, every).reshape(-1, 2)) / noise
    return np.asarray(allowed & (z.max(axis=1) <= OUTLIER))


def _geometry_jacobian(
    theta: FloatArray, active: WheelParams, size: int, columns: list[int]
) -> FloatArray:
    """``(6, size)`` the derivatives of :func:`_geometry` in the joint unknowns."""
    out = np.zeros((6, size))
    for j in columns:
        step = 1e-7 * max(abs(float(theta[j])), 1e-3)
        up, down = theta.copy(), theta.copy()
        up[j] += step
        down[j] -= step
        out[:, j] = (_geometry(up, active) - _geometry(down, active)) / (2 * step)
    return out


def _extras(
    theta: FloatArray,
    geometry: FloatArray,
    transform: FloatArray,
    geo_cov: FloatArray,
    null: FloatArray,
    scale: FloatArray,
    active: WheelParams,
) -> tuple[dict[str, tuple[float, float]], dict[str, str]]:
    """``E_b``, ``E_s``, the wheels' diameters, the wheelbase and the laser's mounting with
    their standard errors; those the intervals do not determine, and why."""
    r_l, r_r, b = geometry[0], geometry[1], geometry[2]
    ra_l, ra_r = 0.5 * active.diameter_left, 0.5 * active.diameter_right
    # each figure as a linear combination of the geometry's rows
    combos = {
        "E_b": np.array([0, 0, 1.0 / active.wheelbase, 0, 0, 0]),
        "E_s": np.array([0.5 / ra_l, 0.5 / ra_r, 0, 0, 0, 0]),
        "wheel_diameter_left": np.array([2.0, 0, 0, 0, 0, 0]),
        "wheel_diameter_right": np.array([0, 2.0, 0, 0, 0, 0]),
        "wheelbase": np.array([0, 0, 1.0, 0, 0, 0]),
        "laser_x": np.eye(6)[3],
        "laser_y": np.eye(6)[4],
        "laser_yaw": np.eye(6)[5],
    }
    values = {
        "E_b": b / active.wheelbase, "E_s": 0.5 * (r_l / ra_l + r_r / ra_r),
        "wheel_diameter_left": 2 * r_l, "wheel_diameter_right": 2 * r_r, "wheelbase": b,
        "laser_x": geometry[3], "laser_y": geometry[4], "laser_yaw": geometry[5],
    }  # fmt: skip
    out, undetermined = {}, {}
    for name, combo in combos.items():
        gradient = combo @ transform
        g = gradient / scale
        size = float(np.linalg.norm(g))
        open_ = null.shape[1] > 0 and float(np.linalg.norm(null.T @ g)) > 1e-6 * size
        if open_:
            undetermined[name] = (
                "the laser's translations do not fix it: drive straights and turns on the "
                "spot where the laser sees walls"
            )
            continue
        out[name] = (float(values[name]), math.sqrt(max(float(combo @ geo_cov @ combo), 0.0)))
    return out, undetermined

"""Wheels and sensor mounting at once, from the sensor's own motion (Censi et al. 2013).

Censi, Franchi, Marchionni and Oriolo, "Simultaneous calibration of odometry and sensor
parameters for mobile robots", IEEE T-RO 29(2), 2013. Each interval ``k`` of driving
holds the wheels' rotations ``Phi_L``, ``Phi_R`` [rad] and the sensor's displacement
``s_k = (s_x, s_y, s_theta)`` in its own frame (scan matching). A robot of wheel radii
``r_L``, ``r_R`` and wheelbase ``b`` moved by ``o_k``; a sensor mounted at
``l = (l_x, l_y, l_theta)`` on it saw ``s_k = (-l) + o_k + l`` (``+``: pose
composition). Two closed-form steps (the paper's Section IV):

1. The rotations: ``s_theta = J21 Phi_L + J22 Phi_R`` with ``J21 = -r_L / b`` and
   ``J22 = r_R / b``, linear least squares.
2. With ``J21``, ``J22`` fixed the odometry's translation is ``b`` times a known vector,
   and the translation part of ``l + s_k = o_k + l`` is linear in
   ``x = (b, l_x, l_y, cos l_theta, sin l_theta)``: ``L_k x = 0`` (two rows per
   interval). Minimise ``x^T M x`` with ``M = sum L_k^T L_k`` under the constraint
   ``x_4^2 + x_5^2 = 1``. The paper's Lagrange condition ``(M + lambda W) x = 0``
   (``W = diag(0, 0, 0, 1, 1)``) has ``det(M + lambda W) = det(A) det(S + lambda I)``
   with ``A`` the upper-left ``3 x 3`` block of ``M`` and ``S`` the ``2 x 2`` Schur
   complement of ``A``: the multipliers are minus ``S``'s eigenvalues, the minimum is
   the smaller one, ``(cos, sin)`` its unit eigenvector and ``(b, l_x, l_y)`` follows
   from ``A``. Both ``x`` and ``-x`` solve it (the mirrored solution: the same sensor
   turned by 180 degrees on a robot of negative wheelbase); the one with ``b > 0`` is
   kept. Then ``r_L = -J21 b``, ``r_R = J22 b``.

Outliers (the reference implementation's rule): solve, drop every interval whose
rotation residual or translation residual is beyond the ``1 - fraction`` quantile
(default 1 %), solve again; four rounds by default.

Uncertainty: the Cramer-Rao bound at the estimate, the inverse of the Fisher
information ``sum_k J_k^T Sigma^-1 J_k`` of the six parameters ``(r_L, r_R, b, l_x, l_y,
l_theta)`` (``J_k``: the Jacobian of the predicted sensor motion), with the sensor noise
``Sigma`` diagonal and estimated from the residuals (the paper's choice; here robustly,
by their median absolute deviation, so that neither the outliers nor the cut tails of the
kept intervals bias it), widened to the sandwich covariance where the intervals' own
residuals scatter more than that noise says (the intervals across a turn's start or end:
``widened``).
The scan matcher's own covariances are not used: matchers are often optimistic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.errors import InputError
from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.registry import SCAN_MATCHING
from umbmark.estimators.scan_excitation import MAX_CONDITION, Excitation, excitation
from umbmark.estimators.solve import relative_jacobian
from umbmark.model.kinematics import WheelParams
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.systematic import alpha_from_E_b, beta_from_E_d

__all__ = [
    "PARAMETERS",
    "ScanCalibration",
    "fit_intervals",
    "outliers",
    "predicted_motion",
    "residual_noise",
    "scan_matching_estimate",
    "second_step",
    "solve_intervals",
    "widened",
]


#: The six parameters, in the order of :attr:`ScanCalibration.covariance`.
PARAMETERS = ("radius_left", "radius_right", "wheelbase", "laser_x", "laser_y", "laser_yaw")
#: Fewest intervals a calibration is made from (six parameters, three equations each).
MIN_INTERVALS = 10


@dataclass(frozen=True)
class ScanCalibration:
    """The wheels and the sensor's mounting, found from motion intervals.

    Attributes
    ----------
    radius_left, radius_right : float
        Wheel radii ``r_L``, ``r_R`` [m].
    wheelbase : float
        ``b`` [m].
    laser_pose : tuple of float
        The sensor's mounting ``(x, y, yaw)`` on the robot [m, m, rad].
    covariance : array, shape (6, 6)
        Of :data:`PARAMETERS` (Cramer-Rao bound; module documentation).
    kept : array of bool, shape (n,)
        The intervals the estimate is made from (the others: outliers).
    noise : tuple of float
        Standard deviation of the sensor's noise ``(x, y, yaw)`` [m, m, rad], from the
        residuals' median absolute deviation: the noise the covariance assumes.
    excitation : Excitation
        What motion the intervals hold.
    warnings : tuple of str
        The result is valid but shaky, and why.
    """

    radius_left: float
    radius_right: float
    wheelbase: float
    laser_pose: tuple[float, float, float]
    covariance: FloatArray
    kept: BoolArray
    noise: tuple[float, float, float]
    excitation: Excitation
    warnings: tuple[str, ...] = field(default=())

    @property
    def values(self) -> FloatArray:
        """``(6,)`` the parameters in the order of :data:`PARAMETERS`."""
        return np.array([self.radius_left, self.radius_right, self.wheelbase, *self.laser_pose])

    @property
    def standard_errors(self) -> dict[str, float]:
        """One sigma of each of :data:`PARAMETERS` and of the wheel diameters [m, rad]."""
        se = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        out = {name: float(v) for name, v in zip(PARAMETERS, se, strict=True)}
        out["wheel_diameter_left"] = 2.0 * out["radius_left"]
        out["wheel_diameter_right"] = 2.0 * out["radius_right"]
        return out

    @property
    def n_used(self) -> int:
        """How many intervals the estimate is made from."""
        return int(self.kept.sum())


# --- the model ---------------------------------------------------------------------------


def _odometry(
    phi_left: FloatArray, phi_right: FloatArray, r_left: float, r_right: float, b: float
) -> FloatArray:
    """``(n, 3)`` the robot's motion over each interval by its wheels (constant velocities
    over the interval: an arc)."""
    theta = (r_right * phi_right - r_left * phi_left) / b
    travel = 0.5 * (r_left * phi_left + r_right * phi_right)
    t1 = np.sinc(theta / np.pi)  # sin(theta) / theta
    t2 = np.sin(0.5 * theta) * np.sinc(0.5 * theta / np.pi)  # (1 - cos(theta)) / theta
    return np.column_stack([travel * t1, travel * t2, theta])


def predicted_motion(
    intervals: MotionIntervals, params: FloatArray, rows: BoolArray | None = None
) -> FloatArray:
    """``(n, 3)`` the sensor motion the parameters predict, ``(-l) + o_k + l``.

    ``params``: ``(6,)`` in the order of :data:`PARAMETERS`; ``rows``: the intervals to
    predict (all by default).
    """
    r_left, r_right, b, lx, ly, lyaw = (float(v) for v in params)
    pl, pr = intervals.phi_left, intervals.phi_right
    if rows is not None:
        pl, pr = pl[rows], pr[rows]
    o = _odometry(pl, pr, r_left, r_right, b)
    c, s = math.cos(lyaw), math.sin(lyaw)
    co, so = np.cos(o[:, 2]), np.sin(o[:, 2])
    # (o + l) - l, rotated into the sensor frame
    dx = o[:, 0] + co * lx - so * ly - lx
    dy = o[:, 1] + so * lx + co * ly - ly
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, o[:, 2]])


# --- the two steps -----------------------------------------------------------------------


def _first_step(phi_left: FloatArray, phi_right: FloatArray, yaw: FloatArray) -> FloatArray:
    """``(J21, J22)``: the sensor's rotation against the wheels', least squares."""
    a = np.column_stack([phi_left, phi_right])
    solution: FloatArray = np.linalg.solve(a.T @ a, a.T @ yaw)
    return solution


def second_step(
    phi_left: FloatArray, phi_right: FloatArray, motion: FloatArray, j21: float, j22: float
) -> FloatArray:
    """``(5,)`` ``x = (b, l_x, l_y, cos l_theta, sin l_theta)``, ``b > 0``."""
    theta = j21 * phi_left + j22 * phi_right
    travel = 0.5 * (-j21 * phi_left + j22 * phi_right)  # the odometry's travel over b
    t1 = np.sinc(theta / np.pi)
    t2 = np.sin(0.5 * theta) * np.sinc(0.5 * theta / np.pi)
    one_c, sin = 1.0 - np.cos(theta), np.sin(theta)
    sx, sy = motion[:, 0], motion[:, 1]
    row_x = np.column_stack([-travel * t1, one_c, sin, sx, -sy])
    row_y = np.column_stack([-travel * t2, -sin, one_c, sy, sx])
    m = row_x.T @ row_x + row_y.T @ row_y
    a, bm, d = m[:3, :3], m[:3, 3:], m[3:, 3:]
    a_inv_b = np.linalg.solve(a, bm)
    schur = d - bm.T @ a_inv_b
    _, vectors = np.linalg.eigh(0.5 * (schur + schur.T))
    u = vectors[:, 0]  # the smaller eigenvalue: the smaller x^T M x
    x = np.concatenate([-a_inv_b @ u, u])
    return x if x[0] > 0.0 else -x


def solve_intervals(intervals: MotionIntervals, rows: BoolArray | None = None) -> FloatArray:
    """``(6,)`` the parameters (order of :data:`PARAMETERS`) from the intervals ``rows``
    (all by default), both steps once, no outlier rejection.

    Raises
    ------
    ValueError
        When the first step is ill-conditioned (what motion is missing).
    """
    pl, pr, motion = intervals.phi_left, intervals.phi_right, intervals.sensor_motion
    if rows is not None:
        pl, pr, motion = pl[rows], pr[rows], motion[rows]
    found = excitation(pl, pr)
    problem = found.problem()
    if problem is not None:
        raise ValueError(problem)
    j21, j22 = (float(v) for v in _first_step(pl, pr, motion[:, 2]))
    x = second_step(pl, pr, motion, j21, j22)
    b = float(x[0])
    return np.array([-j21 * b, j22 * b, b, x[1], x[2], math.atan2(x[4], x[3])])


# --- outliers and uncertainty ------------------------------------------------------------


def outliers(residual: FloatArray, fraction: float) -> BoolArray:
    """The rows whose rotation or translation residual is beyond the ``1 - fraction``
    quantile (the reference implementation's rule: the value at sorted index
    ``round((1 - fraction) n)``, exceeded strictly)."""
    n = residual.shape[0]
    index = min(max(round((1.0 - fraction) * n), 0), n - 1)
    rot = np.abs(residual[:, 2])
    xy = np.hypot(residual[:, 0], residual[:, 1])
    drop: BoolArray = (rot > np.sort(rot)[index]) | (xy > np.sort(xy)[index])
    return drop


def residual_noise(residual: FloatArray) -> FloatArray:
    """``(c,)`` the noise of each of the ``(m, c)`` residuals' components: 1.4826 times
    their median absolute deviation (a Gaussian's standard deviation, which neither
    outliers nor cut tails bias), ``1e-12`` at least."""
    spread = np.median(np.abs(residual - np.median(residual, axis=0)), axis=0)
    noise: FloatArray = np.maximum(1.482602218505602 * spread, 1e-12)
    return noise


def _covariance(
    intervals: MotionIntervals, params: FloatArray, rows: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """The parameters' covariance, and the sensor noise's ``(3,)`` deviations.

    The noise is the residuals' median absolute deviation over every interval (outliers
    included) times 1.4826: the standard deviation of Gaussian noise, which the residuals
    of the kept intervals alone would understate (their tails were cut). The covariance
    is the Cramer-Rao bound of that noise, widened where the kept intervals' own residuals
    say the noise is not alike in every interval (:func:`widened`).
    """
    residual = predicted_motion(intervals, params) - intervals.sensor_motion
    noise = residual_noise(residual)
    jac = relative_jacobian(lambda p: predicted_motion(intervals, p, rows), params)
    weighted = jac / noise[None, :, None]
    fisher = np.einsum("kij,kil->jl", weighted, weighted)
    bound = np.linalg.inv(fisher)
    return widened(bound, weighted, residual[rows] / noise[None, :]), noise


def widened(bound: FloatArray, weighted: FloatArray, scaled: FloatArray) -> FloatArray:
    """``(k, k)`` the Cramer-Rao ``bound`` of ``k`` parameters (six here), widened to the
    sandwich covariance where that is wider: every figure's variance the larger of the two.

    The bound takes the noise alike in every interval. It is not: a sweep taken while the
    robot starts or stops a turn is distorted by its own motion, and the intervals across
    a turn's start or end scatter sideways several times more than the straights and
    whole turns whose residuals set the noise, while they hold most of what fixes the
    laser's offset along the robot and ``E_d``. The sandwich ``F^-1 (sum_k g_k g_k^T)
    F^-1`` (``g_k`` interval ``k``'s score: its weighted Jacobian times its residual,
    ``weighted`` ``(m, 3, k)`` and ``scaled`` ``(m, 3)`` in units of the noise; times
    ``m / (m - k)``) holds each interval's own scatter (Huber 1967, White 1980). In the
    bound's whitened coordinates the sandwich's eigenvalues below 1 are raised to 1:
    never tighter than the bound (the sandwich of a few intervals scatters itself)."""
    m, k = scaled.shape[0], bound.shape[0]
    if m <= k:
        return bound
    score = np.einsum("kij,ki->kj", weighted, scaled)
    sandwich = bound @ (score.T @ score) @ bound * (m / (m - float(k)))
    values, vectors = np.linalg.eigh(0.5 * (bound + bound.T))
    if not bool(np.all(values > 0.0)):
        return bound
    root = (vectors * np.sqrt(values)) @ vectors.T
    inverse_root = (vectors / np.sqrt(values)) @ vectors.T
    inner = inverse_root @ sandwich @ inverse_root
    lam, basis = np.linalg.eigh(0.5 * (inner + inner.T))
    inner = (basis * np.maximum(lam, 1.0)) @ basis.T
    out: FloatArray = root @ inner @ root
    return out


def fit_intervals(
    intervals: MotionIntervals, *, rounds: int = 4, fraction: float = 0.01
) -> ScanCalibration:
    """The wheels and the sensor's mounting from motion intervals (module documentation).

    Parameters
    ----------
    intervals : MotionIntervals
        The wheels' rotations against the sensor's motion.
    rounds : int
        Rounds of outlier rejection (each drops about ``fraction`` of the intervals for
        their rotation residual and as many for their translation residual).
    fraction : float
        Share of the intervals dropped by each residual per round, in ``[0, 0.5)``.

    Raises
    ------
    InputError
        Too few intervals, or motion that does not excite the parameters (what to drive).
    """
    where = intervals.source or None
    if not 0 <= rounds <= 20 or not 0.0 <= fraction < 0.5:
        raise InputError(
            f"outlier rejection: rounds {rounds} in 0-20, fraction {fraction} in [0, 0.5)",
            source=where,
        )
    n = len(intervals)
    values = (intervals.duration, intervals.phi_left, intervals.phi_right)
    finite = np.all([np.isfinite(v) for v in values], axis=0)
    finite &= np.isfinite(intervals.sensor_motion).all(axis=1)
    if not finite.all():
        raise InputError(
            f"{int((~finite).sum())} motion interval(s) hold values that are not finite "
            f"numbers (the first: interval {int(np.flatnonzero(~finite)[0]) + 1})",
            source=where,
        )
    if (intervals.duration <= 0.0).any():
        raise InputError("a motion interval lasts 0 s or less", source=where)
    if n < MIN_INTERVALS:
        raise InputError(
            f"{n} motion interval(s): the scan-matching calibration needs at least {MIN_INTERVALS}",
            source=where,
        )
    found = excitation(intervals.phi_left, intervals.phi_right)
    kept = np.ones(n, dtype=bool)
    try:
        params = solve_intervals(intervals, kept)
        for _ in range(rounds):
            residual = predicted_motion(intervals, params, kept) - intervals.sensor_motion[kept]
            drop = outliers(residual, fraction)
            if not drop.any():
                break
            kept[np.flatnonzero(kept)[drop]] = False
            if kept.sum() < MIN_INTERVALS:
                raise ValueError(f"outlier rejection left fewer than {MIN_INTERVALS} intervals")
            params = solve_intervals(intervals, kept)
        covariance, noise = _covariance(intervals, params, kept)
    except np.linalg.LinAlgError as exc:
        raise InputError(
            f"scan-matching calibration: a singular system ({exc}); "
            f"{found.problem() or 'drive turns on the spot and straights'}",
            source=where,
        ) from None
    except ValueError as exc:
        raise InputError(f"scan-matching calibration: {exc}", source=where) from None
    warnings = list(found.warnings())
    se = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    if not np.all(np.isfinite(se)) or se[2] > 0.05 * params[2]:
        warnings.append(
            f"the wheelbase is uncertain ({se[2] * 1e3:.3g} mm one sigma on "
            f"{params[2] * 1e3:.4g} mm): drive more straights and turns on the spot"
        )
    if found.condition > 0.5 * MAX_CONDITION:
        warnings.append(
            f"the wheel-rotation fit is barely conditioned (condition number "
            f"{found.condition:.3g}, refused above {MAX_CONDITION:g}): drive more "
            f"{' and '.join(found.missing()) or 'turns on the spot and straights'}"
        )
    return ScanCalibration(
        radius_left=float(params[0]),
        radius_right=float(params[1]),
        wheelbase=float(params[2]),
        laser_pose=(float(params[3]), float(params[4]), float(params[5])),
        covariance=covariance,
        kept=kept,
        noise=(float(noise[0]), float(noise[1]), float(noise[2])),
        excitation=found,
        warnings=tuple(warnings),
    )


# --- against the active parameters -------------------------------------------------------


def scan_matching_estimate(
    intervals: MotionIntervals,
    active: WheelParams,
    side_length: float | None = None,
    *,
    rounds: int = 4,
    fraction: float = 0.01,
) -> tuple[ErrorEstimate, ScanCalibration]:
    """The ``scan-matching`` estimator: the calibration, as errors of ``active``.

    ``E_d = f_R / f_L``, ``E_b = b / b_active`` and ``E_s = (f_L + f_R) / 2`` with
    ``f = r / (D_active / 2)`` (each wheel's radius over what the odometry used), their
    standard errors propagated to first order from the covariance. ``alpha``, ``beta``
    are what these errors make of a square of side ``side_length`` (1 m by default). The
    components hold the absolute figures: ``wheel_diameter_left``,
    ``wheel_diameter_right``, ``wheelbase``, ``laser_x``, ``laser_y``, ``laser_yaw``.
    """
    cal = fit_intervals(intervals, rounds=rounds, fraction=fraction)
    half_l, half_r = 0.5 * active.diameter_left, 0.5 * active.diameter_right
    f_l, f_r = cal.radius_left / half_l, cal.radius_right / half_r
    E_d, E_b, E_s = f_r / f_l, cal.wheelbase / active.wheelbase, 0.5 * (f_l + f_r)
    grads = {
        "E_d": np.array([-E_d / cal.radius_left, E_d / cal.radius_right, 0, 0, 0, 0]),
        "E_b": np.array([0, 0, 1.0 / active.wheelbase, 0, 0, 0]),
        "E_s": np.array([0.5 / half_l, 0.5 / half_r, 0, 0, 0, 0]),
    }
    errors = {k: math.sqrt(max(float(g @ cal.covariance @ g), 0.0)) for k, g in grads.items()}
    absolute = cal.standard_errors
    for name in ("wheel_diameter_left", "wheel_diameter_right", "wheelbase"):
        errors[name] = absolute[name]
    for name in ("laser_x", "laser_y", "laser_yaw"):
        errors[name] = absolute[name]
    side = side_length or 1.0
    components = {
        "wheel_diameter_left": 2.0 * cal.radius_left,
        "wheel_diameter_right": 2.0 * cal.radius_right,
        "wheelbase": cal.wheelbase,
        "laser_x": cal.laser_pose[0],
        "laser_y": cal.laser_pose[1],
        "laser_yaw": cal.laser_pose[2],
        "n_intervals": float(len(intervals)),
        "n_used": float(cal.n_used),
    }
    estimate = ErrorEstimate(
        method=SCAN_MATCHING.name,
        alpha=float(alpha_from_E_b(E_b, E_s)),
        beta=float(beta_from_E_d(E_d, side, cal.wheelbase)),
        E_d=E_d,
        E_b=E_b,
        E_s=E_s,
        components=components,
        standard_errors=errors,
        warnings=cal.warnings,
    )
    return estimate, cal

"""Least squares on where recorded runs of any shape end.

What a user of a calibration sees is how far the odometry is off when a run ends. This
estimator fits the wheel radii ``r_L``, ``r_R`` and the wheelbase ``b`` to exactly that:
every recorded run (squares, circles, straights with spot turns) is integrated again with
the candidate parameters from its start, and the odometry's end pose is compared with the
ground truth's, in the run's start frame. The residuals are each run's end position [m]
and end heading, the heading scaled to metres by the ratio of the runs' position and
heading misfits after a first pass (so each counts as much as a coordinate). Where
:mod:`umbmark.estimators.trajectory` fits every sample of the runs, this fits their ends
only: it trades some precision for exactly the figure a replay measures.

Runs are independent, so the covariance is the sandwich over runs (each run's three
residuals together), with a small-sample factor ``n / (n - k)``; its degrees of freedom
are ``n - k`` for ``n`` runs and ``k`` parameters.

Closed paths (a square comes back to its start) hardly see the scale: a robot whose wheels
and wheelbase are all 1 % larger ends where the true one does. Where the scale's standard
error exceeds :data:`LOOSE_SCALE`, the fit holds the mean wheel radius at the active one
(``E_s = 1``, as the paper assumes) and fits the radii's ratio and the wheelbase only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import ProblemError, option
from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.registry import ENDPOINTS
from umbmark.estimators.solve import gauss_newton
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog
from umbmark.model.systematic import alpha_from_E_b, beta_from_E_d

__all__ = ["DIVERGED", "EndPointFit", "endpoints_estimate", "fit_end_points"]

#: Fewest runs the fit needs: three parameters, and degrees of freedom for the errors.
MIN_RUNS = 4
#: Relative standard error of the scale beyond which it is held at the active one.
LOOSE_SCALE = 0.005


@dataclass(frozen=True)
class EndPointFit:
    """Wheel radii and wheelbase [m] fitted to the runs' end poses.

    Attributes
    ----------
    r_left, r_right, wheelbase : float
        The fitted effective values [m].
    covariance : array, shape (3, 3)
        Of ``(r_left, r_right, wheelbase)`` [m^2].
    runs : int
    scale_fitted : bool
        Whether the mean wheel radius was fitted (else held at the active one).
    rms_position : float
        Root-mean-square end-position misfit [m].
    rms_heading : float
        Root-mean-square end-heading misfit [rad].
    """

    r_left: float
    r_right: float
    wheelbase: float
    covariance: FloatArray
    runs: int
    scale_fitted: bool
    rms_position: float
    rms_heading: float

    @property
    def standard_errors(self) -> dict[str, float]:
        """One-sigma uncertainty of ``r_left``, ``r_right``, ``wheelbase`` [m]."""
        se = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        return dict(zip(("r_left", "r_right", "wheelbase"), (float(v) for v in se), strict=True))


def _ends(logs: Sequence[RunLog]) -> tuple[list[RunLog], FloatArray, list[int]]:
    """The runs with ground truth at an end, their true end poses (n, 3), and the index of
    each run's last sample with ground truth."""
    kept, ends, last = [], [], []
    for log in logs:
        matched = np.flatnonzero(log.matched)
        if matched.size < 2:
            continue
        kept.append(log)
        ends.append(log.truth[matched[-1]])
        last.append(int(matched[-1]))
    return kept, np.array(ends).reshape(-1, 3), last


#: Why a fit of the end points fails, and what to try.
DIVERGED = (
    "the runs' end points do not determine the wheels: the fit diverged towards a wheel or "
    "a wheelbase less than half the nominal one, which no robot has. Check that the ground "
    "truth follows the robot (not a robot on a stand, not a tracker that lost it), the "
    "units and the nominal wheel diameter and wheelbase; or try "
    f"{option('method', 'trajectory')} (whole "
    "trajectories), or more runs that turn both ways"
)


def fit_end_points(logs: Sequence[RunLog], start: WheelParams) -> EndPointFit:
    """Fit ``r_L``, ``r_R``, ``b`` to the runs' end poses (see the module's documentation).

    Raises
    ------
    ValueError
        With fewer than :data:`MIN_RUNS` runs that end with ground truth, or a fit that
        diverges (:data:`DIVERGED`).
    """
    runs, truth, last = _ends(logs)
    if len(runs) < MIN_RUNS:
        raise ValueError(
            f"{len(runs)} run(s) end with ground truth: fitting their end points needs at "
            f"least {MIN_RUNS}"
        )
    fit = _fit(runs, truth, last, start, scale=True)
    if fit.scale_fitted:
        se = fit.standard_errors
        scale_se = math.hypot(se["r_left"] / fit.r_left, se["r_right"] / fit.r_right) / 2.0
        if scale_se > LOOSE_SCALE:
            fit = _fit(runs, truth, last, start, scale=False)
    return fit


def _fit(
    runs: Sequence[RunLog],
    truth: FloatArray,
    last: Sequence[int],
    start: WheelParams,
    *,
    scale: bool,
) -> EndPointFit:
    """The fit with the scale free (``p = (f_L, f_R, g)``) or held (``p = (ratio, g)``):
    ``f`` the radii over the active ones, ``g`` the wheelbase over the active one."""
    r0 = np.array([0.5 * start.diameter_left, 0.5 * start.diameter_right])
    b0 = start.wheelbase

    def physical(p: FloatArray) -> FloatArray:
        """``(r_left, r_right, wheelbase)`` [m] of the parameters."""
        if scale:
            return np.array([p[0] * r0[0], p[1] * r0[1], p[2] * b0])
        # Hold (f_L + f_R) / 2 = 1: f_L = 2 / (1 + ratio), f_R = ratio f_L.
        f_left = 2.0 / (1.0 + p[0])
        return np.array([f_left * r0[0], p[0] * f_left * r0[1], p[1] * b0])

    def params(p: FloatArray) -> WheelParams:
        r_left, r_right, b = physical(p)
        return start.with_corrections(
            c_left=2.0 * r_left / start.wheel_diameter,
            c_right=2.0 * r_right / start.wheel_diameter,
            wheelbase=float(b),
        )

    def misfit(p: FloatArray) -> FloatArray:
        """Odometry end minus true end of every run, shape (n, 3)."""
        trial = params(p)
        ends = np.array([log.odometry(trial)[k] for log, k in zip(runs, last, strict=True)])
        return np.asarray(ends - truth)

    first = np.ones(3) if scale else np.ones(2)
    try:  # a step to a wheel or wheelbase no robot has is refused by WheelParams
        p, _, _ = gauss_newton(lambda q: misfit(q).ravel(), first)  # headings: 1 m per radian
    except ValueError:
        raise ProblemError(DIVERGED) from None
    err = misfit(p)
    rms_position = float(np.sqrt(np.mean(np.sum(err[:, :2] ** 2, axis=1) / 2.0)))
    rms_heading = float(np.sqrt(np.mean(err[:, 2] ** 2)))
    per_radian = rms_position / rms_heading if rms_heading > 0 and rms_position > 0 else 1.0
    weight = np.array([1.0, 1.0, per_radian])

    def residuals(q: FloatArray) -> FloatArray:
        return np.asarray((misfit(q) * weight).ravel())

    try:
        p, r, jac = gauss_newton(residuals, p)
    except ValueError:
        raise ProblemError(DIVERGED) from None
    values = physical(p)
    if not (np.all(np.isfinite(values)) and np.all(values > 0.5 * np.append(r0, b0))):
        raise ProblemError(DIVERGED)
    # Sandwich over runs: each run's three residuals are one independent block.
    n, k = len(runs), p.size
    inverse = np.linalg.pinv(jac.T @ jac)
    meat = np.zeros((k, k))
    for run in range(n):
        block = slice(3 * run, 3 * run + 3)
        score = jac[block].T @ r[block]
        meat += np.outer(score, score)
    cov_p = inverse @ meat @ inverse * n / max(n - k, 1)
    slopes = np.column_stack(
        [(physical(p + dp) - physical(p - dp)) / 2e-7 for dp in np.eye(k) * 1e-7]
    )
    err = misfit(p)
    return EndPointFit(
        r_left=float(values[0]),
        r_right=float(values[1]),
        wheelbase=float(values[2]),
        covariance=slopes @ cov_p @ slopes.T,
        runs=n,
        scale_fitted=scale,
        rms_position=float(np.sqrt(np.mean(np.sum(err[:, :2] ** 2, axis=1)))),
        rms_heading=float(np.sqrt(np.mean(err[:, 2] ** 2))),
    )


def endpoints_estimate(
    logs: Sequence[RunLog], active: WheelParams, side_length: float | None = None
) -> tuple[ErrorEstimate, EndPointFit]:
    """The end-point fit as errors relative to the ``active`` odometry parameters.

    As for :func:`umbmark.estimators.trajectory.trajectory_estimate`: ``E_d``, ``E_s``
    compare the fitted radii with the active ones, ``E_b`` the wheelbases; ``alpha`` and
    ``beta`` are what they make of a square of side ``side_length`` (1 m when unknown).
    """
    fit = fit_end_points(logs, active)
    values = np.array([fit.r_left, fit.r_right, fit.wheelbase])

    def errors(v: FloatArray) -> FloatArray:
        f_left = v[0] / (0.5 * active.diameter_left)
        f_right = v[1] / (0.5 * active.diameter_right)
        return np.array([f_right / f_left, v[2] / active.wheelbase, 0.5 * (f_left + f_right)])

    E_d, E_b, E_s = (float(v) for v in errors(values))
    grad = np.column_stack(
        [(errors(values + dv) - errors(values - dv)) / (2e-9) for dv in np.eye(3) * 1e-9]
    )
    spread = np.sqrt(np.clip(np.diag(grad @ fit.covariance @ grad.T), 0.0, None))
    se = fit.standard_errors
    side = side_length or 1.0
    dof = float(fit.runs - (3 if fit.scale_fitted else 2))
    estimate = ErrorEstimate(
        method=ENDPOINTS.name,
        alpha=float(alpha_from_E_b(E_b, E_s)),
        beta=float(beta_from_E_d(E_d, side, fit.wheelbase)),
        E_d=E_d,
        E_b=E_b,
        E_s=E_s if fit.scale_fitted else None,
        components={
            "r_left": fit.r_left,
            "r_right": fit.r_right,
            "wheelbase": fit.wheelbase,
            "rms_position": fit.rms_position,
            "rms_heading": fit.rms_heading,
            "runs": float(fit.runs),
            "scale_fitted": float(fit.scale_fitted),
        },
        standard_errors={
            "E_d": float(spread[0]),
            "E_b": float(spread[1]),
            **({"E_s": float(spread[2])} if fit.scale_fitted else {}),
            **se,
        },
        dof=dof,
    )
    return estimate, fit

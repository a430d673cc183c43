"""Least squares on whole ground-truth trajectories (in the spirit of Antonelli et al. 2005).

Runs of any shape (squares, circles, anything driven) with a recorded ground truth
calibrate the wheel radii ``r_L``, ``r_R`` and the wheelbase ``b`` absolutely, and with
them the scale error ``E_s`` that UMBmark cannot see.

The trajectories are cut into windows of ``window`` seconds. Over a window, with wheel
rotations ``dphi_L``, ``dphi_R`` per sample:

1. **Heading, linear.** ``dtheta = (r_R/b) sum dphi_R - (r_L/b) sum dphi_L`` is linear in
   ``(r_L/b, r_R/b)``: ordinary least squares against the ground truth's heading changes.
2. **Position, linear in b.** With those ratios the heading along the window is known;
   each sample moves the robot by ``b`` times a known vector
   ``((r_R/b) dphi_R + (r_L/b) dphi_L)/2 * sinc(dtheta/2) * (cos, sin)(theta_mid)``, so the
   window's displacement (in the frame of the window's first ground-truth pose) is
   linear in ``b``: least squares again.
3. **Nonlinear refinement.** ``(r_L, r_R, b)`` minimize the weighted residuals of every
   window's displacement and heading change together (``scipy.optimize.least_squares``),
   each kind weighted by its residual spread; the standard errors come from the Jacobian
   at the solution and the residual variance.

Windows are relative motions, so errors do not accumulate along a run and the start
pose is not needed.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from ..kinematics import WheelParams
from ..model import alpha_from_E_b, beta_from_E_d
from ..recording import RunLog
from .base import ErrorEstimate

__all__ = ["DEFAULT_WINDOW", "TrajectoryFit", "fit_trajectories", "trajectory_estimate"]

FloatArray = NDArray[np.float64]
#: Window length [s].
DEFAULT_WINDOW = 1.0


@dataclass(frozen=True)
class TrajectoryFit:
    """Absolute wheel radii and wheelbase from ground-truth trajectories.

    Attributes
    ----------
    r_left, r_right, wheelbase : float
        Effective wheel radii and wheelbase [m].
    standard_errors : dict
        One-sigma uncertainty of ``r_left``, ``r_right``, ``wheelbase`` [m].
    windows : int
        Windows used.
    rms_position, rms_heading : float
        Residual spread per window after the fit [m], [rad].
    linear : tuple of float
        ``(r_left, r_right, wheelbase)`` after the two linear steps, before refinement.
    """

    r_left: float
    r_right: float
    wheelbase: float
    standard_errors: dict[str, float]
    windows: int
    rms_position: float
    rms_heading: float
    linear: tuple[float, float, float]


@dataclass(frozen=True)
class _Windows:
    """All windows' samples, flattened; ``start[w]`` indexes window w's first sample."""

    dphi: FloatArray  # (k, 2) wheel rotation per sample, left and right
    start: NDArray[np.intp]  # (w,) first sample of each window in dphi
    displacement: FloatArray  # (w, 2) ground-truth displacement in the window's frame
    turn: FloatArray  # (w,) ground-truth heading change


def _windows(logs: Sequence[RunLog], window: float) -> _Windows:
    dphi_parts: list[FloatArray] = []
    starts: list[int] = []
    disp: list[FloatArray] = []
    turns: list[float] = []
    offset = 0
    for log in logs:
        matched = np.flatnonzero(log.matched)
        if matched.size < 2:
            continue
        t = log.time[matched]
        # Window boundaries: the first matched sample at or after each multiple of window.
        marks = np.unique(np.searchsorted(t, np.arange(t[0], t[-1] + window, window)))
        marks = marks[marks < matched.size]
        bounds = matched[marks]
        for i, j in itertools.pairwise(bounds):
            if j - i < 1:
                continue
            step = np.diff(log.wheel_angles[i : j + 1], axis=0)
            p0, p1 = log.truth[i], log.truth[j]
            c, s = math.cos(p0[2]), math.sin(p0[2])
            dx, dy = p1[0] - p0[0], p1[1] - p0[1]
            dphi_parts.append(step)
            starts.append(offset)
            offset += step.shape[0]
            disp.append(np.array([c * dx + s * dy, -s * dx + c * dy]))
            turns.append(float(p1[2] - p0[2]))
    if len(starts) < 3:
        raise ValueError(
            f"only {len(starts)} window(s) of {window:g} s with ground truth at both ends: "
            "the trajectory fit needs more recorded motion"
        )
    return _Windows(
        dphi=np.concatenate(dphi_parts),
        start=np.array(starts, dtype=np.intp),
        displacement=np.array(disp),
        turn=np.array(turns),
    )


def _predict(params: FloatArray, w: _Windows) -> tuple[FloatArray, FloatArray]:
    """Model displacement (w, 2) and heading change (w,) of every window."""
    r_left, r_right, b = (float(v) for v in params)
    travel_l = r_left * w.dphi[:, 0]
    travel_r = r_right * w.dphi[:, 1]
    ds = 0.5 * (travel_l + travel_r)
    dth = (travel_r - travel_l) / b
    # Heading since the window's start, before each sample: a cumulative sum restarted at
    # every window.
    total = np.cumsum(dth)
    before = total - dth
    base = before[w.start]
    counts = np.diff(np.append(w.start, dth.size))
    before = before - np.repeat(base, counts)
    half = 0.5 * dth
    with np.errstate(invalid="ignore", divide="ignore"):
        sinc = np.where(np.abs(half) > 1e-12, np.sin(half) / half, 1.0)
    chord = ds * sinc
    heading = before + half
    dx = np.add.reduceat(chord * np.cos(heading), w.start)
    dy = np.add.reduceat(chord * np.sin(heading), w.start)
    turn = np.add.reduceat(dth, w.start)
    return np.column_stack([dx, dy]), turn


def fit_trajectories(logs: Sequence[RunLog], window: float = DEFAULT_WINDOW) -> TrajectoryFit:
    """Fit ``r_L``, ``r_R``, ``b`` to recorded runs (see the module's documentation).

    Raises
    ------
    ValueError
        If there is too little recorded motion to fit.
    """
    w = _windows(logs, window)
    # 1. Heading: turn = c_R sum dphi_R - c_L sum dphi_L, c = r / b.
    sums = np.add.reduceat(w.dphi, w.start, axis=0)
    design = np.column_stack([-sums[:, 0], sums[:, 1]])
    (c_left, c_right), *_ = np.linalg.lstsq(design, w.turn, rcond=None)
    if not (c_left > 0 and c_right > 0):
        raise ValueError(
            "the heading fit gave a non-positive wheel radius: do the runs turn both ways, "
            "and are the wheels' signs right?"
        )
    # 2. Position: displacement = b * unit, with unit the model at b = 1.
    unit, _ = _predict(np.array([c_left, c_right, 1.0]), w)
    b = float(np.sum(unit * w.displacement) / np.sum(unit * unit))
    linear = np.array([c_left * b, c_right * b, b])
    # 3. Refinement, residuals weighted by their spread after the linear steps.
    disp, turn = _predict(linear, w)
    sigma_p = max(float(np.sqrt(np.mean((disp - w.displacement) ** 2))), 1e-6)
    sigma_t = max(float(np.sqrt(np.mean((turn - w.turn) ** 2))), 1e-7)

    def residuals(p: FloatArray) -> FloatArray:
        d, t = _predict(p, w)
        return np.concatenate([((d - w.displacement) / sigma_p).ravel(), (t - w.turn) / sigma_t])

    fit = least_squares(residuals, linear, x_scale=linear, method="lm")
    d, t = _predict(fit.x, w)
    dof = max(fit.fun.size - 3, 1)
    variance = float(np.sum(fit.fun**2)) / dof
    try:
        cov = np.linalg.inv(fit.jac.T @ fit.jac) * variance
        se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        se = np.full(3, np.nan)
    return TrajectoryFit(
        r_left=float(fit.x[0]),
        r_right=float(fit.x[1]),
        wheelbase=float(fit.x[2]),
        standard_errors={
            "r_left": float(se[0]),
            "r_right": float(se[1]),
            "wheelbase": float(se[2]),
        },
        windows=int(w.start.size),
        rms_position=float(np.sqrt(np.mean((d - w.displacement) ** 2))),
        rms_heading=float(np.sqrt(np.mean((t - w.turn) ** 2))),
        linear=(float(linear[0]), float(linear[1]), float(linear[2])),
    )


def trajectory_estimate(
    logs: Sequence[RunLog],
    active: WheelParams,
    side_length: float | None = None,
    window: float = DEFAULT_WINDOW,
) -> tuple[ErrorEstimate, TrajectoryFit]:
    """The trajectory fit as errors relative to the ``active`` odometry parameters.

    ``E_d`` and ``E_s`` compare the fitted radii with the active effective ones
    (``c D_n / 2``), ``E_b`` the fitted wheelbase with the active one, so that the usual
    composition (:class:`umbmark.calibration.Calibration`) yields the fitted values.
    ``alpha`` and ``beta`` are what these errors would make of a square of side
    ``side_length`` (1 m when unknown).
    """
    fit = fit_trajectories(logs, window)
    f_left = fit.r_left / (0.5 * active.diameter_left)
    f_right = fit.r_right / (0.5 * active.diameter_right)
    E_d = f_right / f_left
    E_s = 0.5 * (f_left + f_right)
    E_b = fit.wheelbase / active.wheelbase
    # Relative uncertainties of the radii carry over to E_d; of b to E_b.
    rl = fit.standard_errors["r_left"] / fit.r_left
    rr = fit.standard_errors["r_right"] / fit.r_right
    side = side_length or 1.0
    estimate = ErrorEstimate(
        method="trajectory",
        alpha=float(alpha_from_E_b(E_b, E_s)),
        beta=float(beta_from_E_d(E_d, side, fit.wheelbase)),
        E_d=E_d,
        E_b=E_b,
        E_s=E_s,
        components={
            "r_left": fit.r_left,
            "r_right": fit.r_right,
            "wheelbase": fit.wheelbase,
            "windows": float(fit.windows),
            "rms_position": fit.rms_position,
            "rms_heading": fit.rms_heading,
        },
        standard_errors={
            "E_d": E_d * math.hypot(rl, rr),
            "E_b": fit.standard_errors["wheelbase"] / active.wheelbase,
            "E_s": 0.5 * math.hypot(f_left * rl, f_right * rr),
            "r_left": fit.standard_errors["r_left"],
            "r_right": fit.standard_errors["r_right"],
            "wheelbase": fit.standard_errors["wheelbase"],
        },
    )
    return estimate, fit

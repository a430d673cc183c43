"""Least squares on whole ground-truth trajectories (in the spirit of Antonelli et al. 2005).

Runs of any shape (squares, circles, anything driven) with a recorded ground truth
calibrate the wheel radii ``r_L``, ``r_R`` and the wheelbase ``b`` absolutely, and with
them the scale error ``E_s`` that UMBmark cannot see.

The fit
-------
Each run's wheel rotation is integrated from the run's start into odometry poses (exact
arcs, :mod:`umbmark.model.kinematics`) with the parameters being fitted, and compared with the
ground truth at **every** matched sample of the whole run: the sideways drift that a
wheel-diameter error accumulates along a run (which pins ``E_d``), the heading that a
wheelbase error accumulates over the turns (which pins ``b``) and the distance travelled
(which pins the scale) are all seen. Per sample ``k`` the residual is the true pose minus
the odometry pose placed in the run's start frame: two position components [m] and the
heading [rad] (unwrapped). ``scipy.optimize.least_squares`` (Levenberg-Marquardt)
minimizes ``sum_k |dp_k|^2 / sigma_p^2 + dtheta_k^2 / sigma_theta^2`` over all samples of
all runs.

**Where the odometry starts** (``start_pose``). The odometry starts at the origin of
the run's start frame, but where the robot really was, and which way it faced, when the
wheel data begin is known only as well as the ground truth's first samples say, and
recordings may begin while the robot already moves. ``"fitted"`` (the default): every
run's start pose ``(x_0, y_0, theta_0)`` is fitted as well (a nuisance: for given wheel
parameters the best start pose of each run is found by a weighted 2-D alignment, a few
Newton steps, so the solver sees only the wheel parameters). ``"truth"``: the odometry
starts exactly at the ground truth's first matched sample, and both are compared in that
sample's frame.

**Weights.** Positions and headings are put on one scale by their own residual spread:
a first fit weighs a heading error like a position error of ``dtheta * b`` (``b`` the
starting wheelbase); ``sigma_p`` (RMS per coordinate) and ``sigma_theta`` are the RMS
residuals of that fit, and the final fit uses them, so that each sample's heading counts
as much as each of its two coordinates. The weights are reported
(:attr:`TrajectoryFit.position_scale`, :attr:`TrajectoryFit.heading_scale`).

**Models.** ``"diff"``: one wheelbase for all motion (the paper's model; parameters
``r_L, r_R, b``). ``"scrub"``: the effective wheelbase of each sampling interval depends on
its turning share ``w = |dU_R - dU_L| / (|dU_R| + |dU_L|)``, ``b_eff = b_arc + (b_spot -
b_arc) w`` (:mod:`umbmark.model.kinematics`; parameters ``r_L, r_R, b_arc, b_spot``), so that
on-the-spot turns and arcs need not share one wheelbase. Its turn-rate term is identified
(:mod:`umbmark.estimators.motions`) only by runs that hold both arcs and turns on the spot
(squares alone leave ``b_arc`` to the weaving of the legs, with a small standard error
that does not see the extrapolation to arcs) and a fit whose standard error of the term
``b_spot - b_arc`` is small; elsewhere the fit refuses it.

**Time offset** (``fit_time_offset``). One time offset ``delta`` [s] between wheel data
and ground truth, shared by all runs, is fitted as a nuisance: the odometry at wheel time
``t`` is compared with the ground truth at ``t + delta``, interpolated by a cubic Hermite
spline through the run's matched ground-truth samples and continued beyond the first and
last along the tangent there (held still when the robot rests), so the cost is smooth in
``delta`` and the same samples are compared whatever ``delta``. ``delta > 0``: the ground
truth's time stamps are late (the motion capture lags the wheels). ``|delta| <
max_time_offset`` (``delta = max_time_offset * tanh(u)``). A path of constant curvature
at constant speed cannot tell a time shift from a rotation, so ``delta`` is pinned by
starts, stops and changes of curvature; its standard error says how well.

**Tracked point** (``fit_truth_offset``). The ground truth may track a point (a
motion-capture marker) at ``d = (d_x, d_y)`` [m] in the robot frame (forward, left) rather
than the axle centre (``docs/conventions.md``, "Tracked point"). ``d``, shared by all runs,
is then fitted as well: every odometry pose ``(x, y, theta)`` is moved to the point it
predicts, ``(x, y) + R(theta) d`` with the heading unchanged, before it is compared.
``|d_x|, |d_y| < max_truth_offset`` (``d = max_truth_offset * tanh(v)``). A run that does
not turn moves ``R(theta) d`` by nothing its start pose cannot absorb, so ``d`` is pinned
only by turning within runs: the fit refuses runs none of which turns by
:data:`~umbmark.estimators.trajectory_fit.MIN_OFFSET_TURN` or more.

**Standard errors.** Errors accumulate along a run, so the residuals of one run are
strongly autocorrelated and the textbook ``sigma^2 (J^T J)^-1`` is far too small (tens of
times, see ``tests/estimators/test_trajectory.py``). Runs are independent of each other, so the
covariance is cluster-robust with the runs as clusters, in its jackknife form (CR3):
leaving run ``g`` out moves the solution by ``d_g = (A - A_g)^-1 s_g`` (``A = J^T J``,
``A_g = J_g^T J_g``, ``s_g = J_g^T r_g`` the run's score) and ``cov = (G - 1)/G sum_g d_g
d_g^T``. It holds whatever the correlation within a run, and unlike the plain sandwich
it does not shrink when a few runs dominate. A direction that the runs left in do not pin
(one run alone pins the wheelbase: the others do not turn) gets no step, decided with a
margin over the numerical Jacobian's own error (so on any machine and last bits alike),
and the estimate warns that those standard errors are too small
(:func:`~umbmark.estimators.trajectory_fit.pinned_alone_warning`). Such an estimate from
``G`` runs has about ``G - 1`` degrees of freedom, which the estimate carries
(``ErrorEstimate.dof``): its 95 % intervals are Student-t intervals (with 3 runs 2.2 times
wider than the normal ones, with 6 runs 1.3 times). A single run is cut into its two
halves, taken as the clusters (wide but, in simulations, still honest intervals).

Assumptions: the effective radii and wheelbase(s) are constant over the runs (wear,
load and floor do not change them; random slip is allowed and is what the standard
errors see); the ground truth measures the position of the point midway between the
wheels' contact points, or of a point fixed on the robot with ``fit_truth_offset``, and a
heading along the robot's forward axis (a marker off that point, not fitted, biases
``b``; a constant yaw between marker body and robot is absorbed by the fitted start
pose, not by ``start_pose="truth"``); the ground truth's noise is small
against the odometry's accumulated error; one time offset serves all runs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.motions import (
    SCRUB_ADVICE,
    SCRUB_FALLBACK,
    SCRUB_MORE,
    motion_coverage,
)
from umbmark.estimators.registry import TRAJECTORY, TRAJECTORY_SCRUB
from umbmark.estimators.trajectory_fit import (
    TrajectoryFit,
    fit_trajectories,
    pinned_alone_warning,
    scrub_term_problem,
)
from umbmark.estimators.trajectory_model import MODELS, StartPose, TrajectoryModel
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog
from umbmark.model.systematic import alpha_from_E_b, beta_from_E_d

__all__ = ["disagreement_warnings", "source_disagreement", "trajectory_estimate"]


# --- errors relative to the active parameters -------------------------------------------


def _relative_errors(radii_and_b: FloatArray, active: WheelParams, side: float) -> FloatArray:
    """``(E_d, E_b, E_s, alpha, beta)`` of ``(r_left, r_right, wheelbase)`` against the
    active parameters, for a square of side ``side`` [m]."""
    r_left, r_right, b = (float(v) for v in radii_and_b)
    f_left = r_left / (0.5 * active.diameter_left)
    f_right = r_right / (0.5 * active.diameter_right)
    E_d = f_right / f_left
    E_b = b / active.wheelbase
    E_s = 0.5 * (f_left + f_right)
    alpha = float(alpha_from_E_b(E_b, E_s))
    beta = float(beta_from_E_d(E_d, side, b))
    return np.array([E_d, E_b, E_s, alpha, beta])


def trajectory_estimate(
    logs: Sequence[RunLog],
    active: WheelParams,
    side_length: float | None = None,
    *,
    model: TrajectoryModel = "diff",
    fit_time_offset: bool = True,
    start_pose: StartPose = "fitted",
    fit_truth_offset: bool = False,
) -> tuple[ErrorEstimate, TrajectoryFit]:
    """The trajectory fit as errors relative to the ``active`` odometry parameters.

    ``E_d = f_R / f_L`` and ``E_s = (f_L + f_R) / 2`` with ``f = r_fit / (c D_n / 2)``
    compare the fitted radii with the active effective ones, ``E_b = b_fit / b_active``
    the fitted wheelbase with the active one, so that the usual composition
    (:class:`umbmark.calibration.compose.Calibration`) yields the fitted values. ``alpha`` and
    ``beta`` are what these errors make of a square of side ``side_length`` (1 m when
    unknown).

    Parameters
    ----------
    logs : sequence of RunLog
        The runs' time series.
    active : WheelParams
        The parameters active during the runs.
    side_length : float, optional
        Side of the square [m] for ``alpha`` and ``beta``.
    model : {"diff", "scrub"}
        ``"diff"``: method ``"trajectory"``, one wheelbase. ``"scrub"``: method
        ``"trajectory-scrub"``; the errors are still those of the best single set
        ``(D_L, D_R, b)`` (the ``"diff"`` fit: a controller such as ros2_control's has one
        wheelbase), and the components add the scrub fit's ``arc_wheelbase`` and
        ``spot_wheelbase`` with their standard errors: what the richer model finds for
        arcs and for turns on the spot. Runs that do not identify its turn-rate term
        (:mod:`umbmark.estimators.motions`: no arcs or no turns on the spot, or a fit
        that does not pin the term) give the single set alone, with a warning.
    fit_time_offset : bool
        Fit a time offset between wheels and ground truth.
    start_pose : {"fitted", "truth"}
        See :func:`fit_trajectories`.
    fit_truth_offset : bool
        Fit where the ground truth's tracked point sits in the robot frame (both fits of
        ``"scrub"``); see :func:`fit_trajectories`.

    Returns
    -------
    estimate : ErrorEstimate
        Components: ``r_left``, ``r_right``, ``wheelbase`` [m] (the single set),
        ``time_offset`` [s], ``rms_position`` [m], ``rms_heading`` [rad], ``runs``,
        ``samples``; with ``fit_truth_offset`` also ``truth_offset_x``,
        ``truth_offset_y`` [m] (of the single set's fit); for ``"scrub"`` also
        ``arc_wheelbase``, ``spot_wheelbase`` [m], ``scrub_r_left``, ``scrub_r_right``
        [m], ``scrub_rms_position`` [m] and ``scrub_rms_heading`` [rad]. Standard errors
        of ``E_d``, ``E_b``, ``E_s``, ``alpha``, ``beta``, ``r_left``, ``r_right``,
        ``wheelbase``, ``time_offset`` (and ``truth_offset_x``, ``truth_offset_y``,
        ``arc_wheelbase``, ``spot_wheelbase``).
    fit : TrajectoryFit
        The fit of ``model``: :meth:`TrajectoryFit.params` replays it.

    Raises
    ------
    ValueError
        See :func:`fit_trajectories`.
    """
    if model not in MODELS:
        raise ValueError(f"unknown trajectory model {model!r}; use diff or scrub")
    options: dict[str, Any] = {
        "fit_time_offset": fit_time_offset,
        "start_pose": start_pose,
        "fit_truth_offset": fit_truth_offset,
    }
    single = fit_trajectories(logs, active, model="diff", **options)
    values, components, standard_errors = _single_set(single, active, side_length or 1.0)
    if fit_truth_offset:
        components.update(
            truth_offset_x=single.truth_offset_x, truth_offset_y=single.truth_offset_y
        )
        for key in ("truth_offset_x", "truth_offset_y"):
            standard_errors[key] = single.standard_errors[key]
    method = (TRAJECTORY_SCRUB if model == "scrub" else TRAJECTORY).name
    fit, problem = _scrub(logs, active, options, single) if model == "scrub" else (single, None)
    if fit.spot_wheelbase is not None:
        components.update(
            arc_wheelbase=fit.wheelbase,
            spot_wheelbase=fit.spot_wheelbase,
            scrub_r_left=fit.r_left,
            scrub_r_right=fit.r_right,
            scrub_rms_position=fit.rms_position,
            scrub_rms_heading=fit.rms_heading,
        )
        standard_errors.update(
            arc_wheelbase=fit.standard_errors["wheelbase"],
            spot_wheelbase=fit.standard_errors["spot_wheelbase"],
        )
    estimate = ErrorEstimate(
        method=method,
        alpha=float(values[3]),
        beta=float(values[4]),
        E_d=float(values[0]),
        E_b=float(values[1]),
        E_s=float(values[2]),
        components=components,
        standard_errors=standard_errors,
        dof=float(single.clusters - 1),
        warnings=tuple(
            dict.fromkeys(
                w for w in (pinned_alone_warning(single), pinned_alone_warning(fit), problem) if w
            )
        ),
    )
    return estimate, fit


def _scrub(
    logs: Sequence[RunLog], active: WheelParams, options: dict[str, Any], single: TrajectoryFit
) -> tuple[TrajectoryFit, str | None]:
    """The scrub model's fit, or ``single`` with the warning why its turn-rate term is
    not identified."""
    problem = motion_coverage(logs, active).scrub_problem()
    if problem is not None:
        return single, f"{problem}; {SCRUB_FALLBACK}; {SCRUB_ADVICE}"
    try:
        scrub = fit_trajectories(logs, active, model="scrub", check_coverage=False, **options)
    except ValueError as exc:  # a wheelbase not pinned at all: no turn-rate term either
        problem = f"the scrub model's turn-rate term is not identified: {exc}"
    else:
        problem = scrub_term_problem(scrub)
        if problem is None:
            return scrub, None
    return single, f"{problem}; {SCRUB_FALLBACK}; {SCRUB_MORE}"


def _single_set(
    single: TrajectoryFit, active: WheelParams, side: float
) -> tuple[FloatArray, dict[str, float], dict[str, float]]:
    """The single set's errors relative to ``active`` (``E_d, E_b, E_s, alpha, beta``), its
    components, and their standard errors (first-order propagation through central
    differences)."""
    v0 = np.array([single.r_left, single.r_right, single.wheelbase])
    values = _relative_errors(v0, active, side)
    grad = np.empty((values.size, 3))
    for j in range(3):
        step = np.zeros(3)
        step[j] = 1e-6 * v0[j]
        plus = _relative_errors(v0 + step, active, side)
        minus = _relative_errors(v0 - step, active, side)
        grad[:, j] = (plus - minus) / (2.0 * step[j])
    variance = np.einsum("ij,jk,ik->i", grad, single.covariance[:3, :3], grad)
    spread = np.sqrt(np.clip(variance, 0.0, None))
    se = dict(zip(("E_d", "E_b", "E_s", "alpha", "beta"), spread, strict=True))
    components: dict[str, float] = {
        "r_left": single.r_left,
        "r_right": single.r_right,
        "wheelbase": single.wheelbase,
        "time_offset": single.time_offset,
        "rms_position": single.rms_position,
        "rms_heading": single.rms_heading,
        "runs": float(single.runs),
        "samples": float(single.samples),
    }
    standard_errors: dict[str, float] = {k: float(v) for k, v in se.items()}
    for key in ("r_left", "r_right", "wheelbase", "time_offset"):
        standard_errors[key] = single.standard_errors[key]
    return values, components, standard_errors


def disagreement_warnings(
    fits: Sequence[tuple[str, TrajectoryFit]], level: float = 0.001
) -> list[str]:
    """Sources whose separate fits differ by more than their standard errors explain.

    One robot driven in several sessions (squares, circles, another day) should give one
    set of radii and one wheelbase. Each pair of sessions' fits is compared, for each of
    ``r_left``, ``r_right`` and ``wheelbase``, with Student's t of the smaller degrees of
    freedom at ``level`` (two-sided, shared among the comparisons): with honest standard
    errors this fires on about ``level`` of sessions that do agree.
    """
    from umbmark.core.stats import t_quantile

    out = []
    pairs = [(a, b) for i, a in enumerate(fits) for b in fits[i + 1 :]]
    names = ("r_left", "r_right", "wheelbase")
    tests = max(len(pairs) * len(names), 1)
    for (name_a, fit_a), (name_b, fit_b) in pairs:
        for key in names:
            a, b = float(getattr(fit_a, key)), float(getattr(fit_b, key))
            se_a, se_b = fit_a.standard_errors[key], fit_b.standard_errors[key]
            se = math.hypot(se_a, se_b)
            dof = max(min(fit_a.clusters, fit_b.clusters) - 1, 1)
            limit = t_quantile(1.0 - 0.5 * level / tests, dof)
            if se > 0.0 and abs(a - b) > limit * se:
                what = key.replace("_", " ")
                out.append(
                    f"{name_a} and {name_b} want different {what}s: {1000 * a:.2f} ± "
                    f"{1000 * se_a:.2f} mm and {1000 * b:.2f} ± {1000 * se_b:.2f} mm, more "
                    "than their scatter explains: different days, loads or floors, or a "
                    "wheelbase that depends on how the robot turns (compare "
                    "trajectory-scrub with umbmark validate)"
                )
    return out


def source_disagreement(
    sources: Sequence[tuple[str, Sequence[RunLog], WheelParams | None]],
    *,
    fit_truth_offset: bool = False,
) -> list[str]:
    """Warnings where pooled sources, fitted one by one, want different wheels
    (:func:`disagreement_warnings`).

    Parameters
    ----------
    sources : sequence of (str, sequence of RunLog, WheelParams or None)
        Each source's name, its recorded runs and the parameters they were integrated
        with (None: a runs table, left out).
    fit_truth_offset : bool
        As for :func:`fit_trajectories`.
    """
    fits = []
    for name, logs, params in sources:
        if params is None or not logs:
            continue
        try:
            fits.append((name, fit_trajectories(logs, params, fit_truth_offset=fit_truth_offset)))
        except ValueError:
            continue  # a source too small to fit alone says nothing against the others
    return disagreement_warnings(fits)

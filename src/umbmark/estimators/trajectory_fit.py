"""The trajectory fit: wheel radii and wheelbase(s) by least squares on whole recordings.

:func:`fit_trajectories` solves the problem of :mod:`umbmark.estimators.trajectory_model`
in two weighted passes (Levenberg-Marquardt), refuses what the recorded motion does not
pin down, and gives the cluster-robust covariance of the fitted parameters. The method,
its weights, its time offset and tracked point, and its assumptions:
:mod:`umbmark.estimators.trajectory`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import ProblemError, option
from umbmark.estimators.motions import (
    SCRUB_ADVICE,
    SCRUB_MORE,
    motion_coverage,
    term_problem,
)
from umbmark.estimators.trajectory_model import (
    DEFAULT_MAX_TRUTH_OFFSET,
    MODELS,
    START_POSES,
    IndexArray,
    Problem,
    RunsData,
    StartPose,
    TrajectoryModel,
    prepare,
)
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog

__all__ = [
    "DEFAULT_MAX_TIME_OFFSET",
    "MIN_OFFSET_TURN",
    "TrajectoryFit",
    "fit_trajectories",
    "pinned_alone_warning",
    "scrub_term_problem",
]

#: Bound of the fitted time offset between wheels and ground truth [s].
DEFAULT_MAX_TIME_OFFSET = 0.5
#: Least heading change [rad] within some run (the ground truth's range of headings) that
#: a fitted tracked-point offset needs: 30 degrees.
MIN_OFFSET_TURN = math.radians(30.0)
#: A single run is cut into this many pieces to stand in for independent runs.
_ONE_RUN_PIECES = 2
#: Largest condition number of the scaled normal matrix: beyond, a parameter is not pinned.
_MAX_CONDITION = 1e12
#: Smallest singular value of the Jacobian of the runs left in by the jackknife (its
#: columns scaled by the whole Jacobian's lengths, to 1) that pins a direction: the same
#: bound as :data:`_MAX_CONDITION`. A direction those runs do not see at all shows at
#: 1e-8 to 4e-8, the error of the numerical Jacobian itself, which moves with the last
#: bits of the input and the machine (``tests/estimators/test_trajectory_fit.py``): the
#: bound stays 25 times above it.
_MIN_LEFT_IN = _MAX_CONDITION**-0.5


@dataclass(frozen=True)
class TrajectoryFit:
    """Wheel radii and wheelbase(s) fitted to ground-truth trajectories.

    Attributes
    ----------
    model : {"diff", "scrub"}
        One wheelbase for all motion, or the scrub model's two.
    r_left, r_right : float
        Effective wheel radii [m].
    wheelbase : float
        ``b`` [m]; with the scrub model ``b_arc``, the wheelbase of straight motion and
        arcs.
    spot_wheelbase : float or None
        ``b_spot`` [m] of the scrub model, the wheelbase of on-the-spot turns; None for
        ``"diff"``.
    time_offset : float
        ``delta`` [s]: the ground truth at ``t + delta`` matches the wheels at ``t``
        (> 0: the ground truth lags); 0 when not fitted.
    standard_errors : mapping of str to float
        One-sigma uncertainty, scaled to Student's t (module documentation), of
        ``r_left``, ``r_right``, ``wheelbase`` [m], ``spot_wheelbase`` [m] (scrub model),
        ``time_offset`` [s] and ``truth_offset_x``, ``truth_offset_y`` [m] (0 when not
        fitted).
    parameters : tuple of str
        The fitted parameters, in the order of ``covariance``: ``r_left``, ``r_right``,
        ``wheelbase``, then ``spot_wheelbase``, ``time_offset`` and ``truth_offset_x``,
        ``truth_offset_y`` when fitted.
    covariance : array, shape (k, k)
        Their covariance [m^2, m s, s^2], scaled like the standard errors.
    start_pose : {"fitted", "truth"}
        Where each run's odometry started.
    time_offset_fitted : bool
        Whether ``time_offset`` was fitted.
    runs : int
        Runs used.
    samples : int
        Ground-truth samples compared (each a position and a heading).
    rms_position : float
        Root mean square distance between odometry and true positions [m].
    rms_heading : float
        Root mean square heading difference [rad].
    position_scale, heading_scale : float
        ``sigma_p`` [m] and ``sigma_theta`` [rad], the weights of the final fit.
    clusters : int
        Independent groups behind the standard errors: the runs, or the two halves of a
        single run.
    truth_offset_x, truth_offset_y : float
        ``d_x``, ``d_y`` [m]: where the tracked point sits in the robot frame, forward of
        and to the left of the axle centre; 0 when not fitted.
    truth_offset_fitted : bool
        Whether the tracked-point offset was fitted.
    pinned_alone : tuple of str
        The parameters (names as in ``parameters``) that one cluster alone pins: the
        jackknife that leaves it out sees nothing of them, so their standard errors do not
        see that run's own scatter (:func:`pinned_alone_warning`).
    """

    model: TrajectoryModel
    r_left: float
    r_right: float
    wheelbase: float
    spot_wheelbase: float | None
    time_offset: float
    standard_errors: Mapping[str, float]
    parameters: tuple[str, ...]
    covariance: FloatArray = field(compare=False, repr=False)
    start_pose: StartPose = "fitted"
    time_offset_fitted: bool = True
    runs: int = 0
    samples: int = 0
    rms_position: float = 0.0
    rms_heading: float = 0.0
    position_scale: float = 0.0
    heading_scale: float = 0.0
    clusters: int = 0
    truth_offset_x: float = 0.0
    truth_offset_y: float = 0.0
    truth_offset_fitted: bool = False
    pinned_alone: tuple[str, ...] = ()

    def params(self, base: WheelParams) -> WheelParams:
        """The fitted model as odometry parameters, for replays.

        Parameters
        ----------
        base : WheelParams
            Supplies the nominal diameter ``D_n`` (and the encoder figures).

        Returns
        -------
        WheelParams
            ``base`` with ``c_left = 2 r_L / D_n``, ``c_right = 2 r_R / D_n``,
            ``wheelbase`` and, for the scrub model, ``spot_wheelbase`` (else None).
        """
        return replace(
            base,
            c_left=2.0 * self.r_left / base.wheel_diameter,
            c_right=2.0 * self.r_right / base.wheel_diameter,
            wheelbase=self.wheelbase,
            spot_wheelbase=self.spot_wheelbase,
        )


def pinned_alone_warning(fit: TrajectoryFit) -> str | None:
    """The warning for a fit some of whose parameters one run alone pins (None if none):
    their standard errors come from the other runs' pull only, not from the spread
    between runs that each see them, and are too small."""
    if not fit.pinned_alone:
        return None
    shown = [name.replace("_", " ") for name in fit.pinned_alone]
    what = shown[0] if len(shown) == 1 else ", ".join(shown[:-1]) + " and " + shown[-1]
    one = "one half of the run" if fit.runs == 1 else f"one of the {fit.runs} runs"
    if len(shown) == 1:
        said = f"the {what} is pinned by {one} alone (leaving it out leaves it free): its "
        said += "standard error cannot see that run's own scatter and is too small"
    else:
        said = f"the {what} are pinned by {one} alone (leaving it out leaves them free): "
        said += "their standard errors cannot see that run's own scatter and are too small"
    return f"{said}; record more runs that drive and turn"


def scrub_term_problem(fit: TrajectoryFit) -> str | None:
    """Why a scrub fit does not pin its turn-rate term ``b_spot - b_arc`` (None when it
    does, or for a single wheelbase): the second condition of
    :mod:`umbmark.estimators.motions`, from the fit's covariance."""
    if fit.spot_wheelbase is None:
        return None
    arc, spot = fit.parameters.index("wheelbase"), fit.parameters.index("spot_wheelbase")
    cov = fit.covariance
    variance = float(cov[arc, arc] + cov[spot, spot] - 2.0 * cov[arc, spot])
    se = math.sqrt(variance) if variance >= 0.0 else math.nan
    return term_problem(fit.wheelbase, fit.spot_wheelbase, se)


@dataclass(frozen=True)
class _Solution:
    x: FloatArray  # (k,)
    residuals: FloatArray  # (3 s,) weighted
    jac: FloatArray  # (3 s, k) of the weighted residuals


def _solve(problem: Problem, x0: FloatArray, sigma: tuple[float, float]) -> _Solution:
    """Weighted least squares from ``x0`` (Levenberg-Marquardt, numerical Jacobian)."""
    from scipy.optimize import least_squares

    weight = np.array([1.0 / sigma[0], 1.0 / sigma[0], 1.0 / sigma[1]])

    def residuals(x: FloatArray) -> FloatArray:
        return np.asarray((problem.errors(x, sigma) * weight).ravel())

    fit = least_squares(residuals, x0, method="lm", x_scale="jac", ftol=1e-10, xtol=1e-10)
    x = np.asarray(fit.x, dtype=np.float64)
    if not np.all(np.isfinite(x)):
        raise ProblemError(
            "the trajectory fit did not converge (its wheel parameters went to numbers that "
            "are not finite): check that the ground truth follows the robot, the wheel "
            "data's units (encoder resolution, gear ratio) and the time offset between wheels "
            f"and ground truth; or try {option('method', 'endpoints')}, or more runs that drive "
            "and turn"
        )
    return _Solution(
        x=x,
        residuals=np.asarray(fit.fun, dtype=np.float64),
        jac=np.asarray(fit.jac, dtype=np.float64),
    )


def _clusters(data: RunsData) -> tuple[IndexArray, int]:
    """The cluster of every compared sample, shape (s,), and the number of clusters: the
    runs, or the two halves of a single run."""
    if data.runs >= 2:
        return data.sample_run, data.runs
    n = data.sample_run.size
    return np.asarray(np.arange(n) * _ONE_RUN_PIECES // n, dtype=np.intp), _ONE_RUN_PIECES


def _cluster_covariance(
    jac: FloatArray, res: FloatArray, cluster: IndexArray, clusters: int
) -> tuple[FloatArray, tuple[int, ...]]:
    """Cluster-robust covariance (CR3, one-step jackknife) of the solver's ``x``.

    Each step is solved on the Jacobian with its columns scaled to unit length, from the
    singular values of the rows left in (not by subtracting ``A_g`` from ``A``, which
    loses the digits of a direction the rest barely sees). A direction the runs left in
    do not pin (a singular value below :data:`_MIN_LEFT_IN`) gets no step: leaving the
    only run that pins it out says nothing of where it would go.

    Parameters
    ----------
    jac : array, shape (N, k)
        Jacobian of the weighted residuals at the solution, no column zero.
    res : array, shape (N,)
        Weighted residuals at the solution.
    cluster : array of int, shape (N,)
        Cluster of every residual, 0 .. clusters - 1.
    clusters : int
        ``G`` >= 2.

    Returns
    -------
    cov : array, shape (k, k)
        ``(G - 1)/G sum_g d_g d_g^T`` with ``d_g = (A - A_g)^-1 J_g^T r_g`` (module
        documentation).
    alone : tuple of int
        The parameters (column indices) that one cluster alone pins: those of the
        directions that leaving it out leaves free, each direction by its components of
        at least half the largest's square.
    """
    norms = np.linalg.norm(jac, axis=0)
    scaled = jac / norms
    steps = []
    alone: set[int] = set()
    for g in range(clusters):
        rows = cluster == g
        _, sv, vt = np.linalg.svd(scaled[~rows], full_matrices=False)
        pinned = sv >= _MIN_LEFT_IN
        free = vt[~pinned]  # (m, k): the directions the rest leaves free
        for v in free**2:  # each named by its large components
            alone.update(int(i) for i in np.flatnonzero(v >= 0.5 * v.max()))
        score = scaled[rows].T @ res[rows]
        basis = vt[pinned]
        steps.append(basis.T @ ((basis @ score) / sv[pinned] ** 2) / norms)
    step = np.array(steps)
    return np.asarray(step.T @ step * ((clusters - 1) / clusters)), tuple(sorted(alone))


def _check_pinned(jac: FloatArray, names: Sequence[str]) -> None:
    """Refuse a fit whose data leave a parameter undetermined (a singular normal matrix)."""
    norms = np.linalg.norm(jac, axis=0)
    if np.any(norms == 0.0) or np.linalg.cond(jac / norms) ** 2 > _MAX_CONDITION:
        loose = names[int(np.argmin(norms))] if np.any(norms == 0.0) else "the parameters"
        raise ValueError(
            f"the recorded motion does not pin down {loose.replace('_', ' ')}: the runs "
            "must drive and turn (a wheelbase needs turns; the scrub model needs both "
            "turns on the spot and arcs)"
        )


#: Largest relative standard error of a length the fit may report: beyond, the recorded
#: motion does not pin it down.
_LOOSE = 0.05


def _check_physical(values: dict[str, float | None], errors: dict[str, float]) -> None:
    """Refuse lengths that are not positive, or so loose that the data do not see them."""
    for name, value in values.items():
        if value is None:
            continue
        se = errors.get(name, 0.0)
        if not (value > 0.0 and se <= _LOOSE * value):
            shown = name.replace("_", " ")
            raise ValueError(
                f"the recorded motion does not pin down the {shown} ({1000 * value:.1f} ± "
                f"{1000 * se:.1f} mm): the scrub model needs both turns on the spot and arcs"
                if name in ("spot_wheelbase", "wheelbase") and values.get("spot_wheelbase")
                else f"the recorded motion does not pin down the {shown} ({1000 * value:.1f} "
                f"± {1000 * se:.1f} mm): check that the ground truth follows the robot (not a "
                "robot on a stand) and the wheel data's units, or record runs that drive and "
                "turn"
            )


def _check_turning(data: RunsData) -> None:
    """Refuse, before fitting, a tracked-point offset that no run turns enough to pin.

    Parameters
    ----------
    data : RunsData
        The runs' matched ground truth, headings [rad] unwrapped.

    Raises
    ------
    ValueError
        If no run's ground-truth headings span :data:`MIN_OFFSET_TURN` or more.
    """
    swing = max(float(np.ptp(data.truth[first : last + 1, 2])) for first, last in data.truth_ends)
    if not swing >= MIN_OFFSET_TURN:
        raise ProblemError(
            "the recorded motion does not pin down the truth offset: no run turns by "
            f"{math.degrees(MIN_OFFSET_TURN):.0f} deg or more (the most is "
            f"{math.degrees(swing):.1f} deg), and a tracked point off the axle shows only "
            f"as the robot turns; give the offset ({option('truth_offset', 'X Y')}) or record "
            "turns"
        )


def _check_truth_offset_inside(d: tuple[float, float], bound: float) -> None:
    """Refuse a fitted tracked-point offset ``d`` [m] stuck at its bound [m]."""
    if max(abs(d[0]), abs(d[1])) > 0.99 * bound:
        raise ValueError(
            f"the fitted truth offset ({1000 * d[0]:.0f}, {1000 * d[1]:.0f}) mm reaches its "
            f"bound of {bound:g} m: the ground truth does not follow a point fixed on the "
            "robot, or the runs do not match the wheel data"
        )


def fit_trajectories(
    logs: Sequence[RunLog],
    start: WheelParams,
    *,
    model: TrajectoryModel = "diff",
    fit_time_offset: bool = True,
    start_pose: StartPose = "fitted",
    max_time_offset: float = DEFAULT_MAX_TIME_OFFSET,
    fit_truth_offset: bool = False,
    max_truth_offset: float = DEFAULT_MAX_TRUTH_OFFSET,
    check_coverage: bool = True,
) -> TrajectoryFit:
    """Fit the wheel radii and wheelbase(s) to recorded runs (module documentation).

    Parameters
    ----------
    logs : sequence of RunLog
        The runs' time series: wheel angles (n, 2) [rad] and ground truth (n, 3) in the
        run's start frame [m, m, rad] (NaN rows where none matched). Runs with fewer
        than :data:`MIN_SAMPLES` matched samples are left out.
    start : WheelParams
        Starting values: the radii ``c D_n / 2``, ``wheelbase`` and ``spot_wheelbase``
        (else ``wheelbase``); usually the parameters active during the runs.
    model : {"diff", "scrub"}
        One wheelbase, or the scrub model's ``b_arc`` (``wheelbase``) and ``b_spot``.
    fit_time_offset : bool
        Fit a time offset between wheels and ground truth.
    start_pose : {"fitted", "truth"}
        Fit every run's start pose, or start the odometry at the ground truth's first
        matched sample.
    max_time_offset : float
        Bound of ``|time_offset|`` [s].
    fit_truth_offset : bool
        Fit where the tracked point of the ground truth sits in the robot frame,
        ``(truth_offset_x, truth_offset_y)`` [m] (module documentation); False: the ground
        truth is the axle centre's.
    max_truth_offset : float
        Bound of ``|truth_offset_x|`` and ``|truth_offset_y|`` [m].
    check_coverage : bool
        ``"scrub"``: refuse runs that do not identify the turn-rate term
        (:mod:`umbmark.estimators.motions`): runs without both arcs and turns on the
        spot, before fitting, and a fit that does not pin the term
        (:func:`scrub_term_problem`); False fits it anyway (to study it).

    Returns
    -------
    TrajectoryFit

    Raises
    ------
    ValueError
        If the runs have too little recorded motion to pin the parameters down (for the
        truth offset: no run turns by :data:`MIN_OFFSET_TURN`; for the scrub model: no
        arcs or no turns on the spot, or a turn-rate term the fit does not pin), or the
        fitted truth offset reaches its bound.
    """
    _check_settings(model, start_pose, max_time_offset, max_truth_offset)
    if model == "scrub" and check_coverage:
        unidentified = motion_coverage(logs, start).scrub_problem()
        if unidentified is not None:
            raise ValueError(f"{unidentified}: {SCRUB_ADVICE}")
    data = prepare(logs)
    if fit_truth_offset:
        _check_turning(data)
    b0 = start.wheelbase
    names, scale, x0 = _unknowns(start, model, fit_time_offset, fit_truth_offset)
    problem = Problem(
        data,
        model,
        start_pose,
        fit_time_offset,
        np.array(scale),
        max_time_offset,
        tuple(names),
        fit_truth_offset,
        max_truth_offset,
    )
    fit, sigma = _two_passes(problem, np.array(x0), b0)
    truth_offset = problem.truth_offset(fit.x)
    if fit_truth_offset:  # before the check of the Jacobian, which a bound flattens
        _check_truth_offset_inside(truth_offset, max_truth_offset)
    _check_pinned(fit.jac, names)
    cov, standard_errors, clusters, alone = _uncertainty(problem, fit, data, names)
    r_left, r_right, b, b_spot, delta = problem.unpack(fit.x)
    _check_physical(
        {"r_left": r_left, "r_right": r_right, "wheelbase": b, "spot_wheelbase": b_spot},
        standard_errors,
    )
    err = problem.errors(fit.x, sigma)
    result = TrajectoryFit(
        model=model,
        r_left=r_left,
        r_right=r_right,
        wheelbase=b,
        spot_wheelbase=b_spot,
        time_offset=delta,
        standard_errors=standard_errors,
        parameters=tuple(names),
        covariance=cov,
        start_pose=start_pose,
        time_offset_fitted=fit_time_offset,
        runs=data.runs,
        samples=int(data.sample.size),
        rms_position=float(np.sqrt(np.mean(np.sum(err[:, :2] ** 2, axis=1)))),
        rms_heading=float(np.sqrt(np.mean(err[:, 2] ** 2))),
        position_scale=sigma[0],
        heading_scale=sigma[1],
        clusters=clusters,
        truth_offset_x=truth_offset[0],
        truth_offset_y=truth_offset[1],
        truth_offset_fitted=fit_truth_offset,
        pinned_alone=alone,
    )
    loose = scrub_term_problem(result) if check_coverage else None
    if loose is not None:
        raise ValueError(f"{loose}: {SCRUB_MORE}")
    return result


def _check_settings(
    model: str, start_pose: str, max_time_offset: float, max_truth_offset: float
) -> None:
    if model not in MODELS:
        raise ValueError(f"unknown trajectory model {model!r}; use diff or scrub")
    if start_pose not in START_POSES:
        raise ValueError(f"unknown start pose {start_pose!r}; use fitted or truth")
    if not (0.0 < max_time_offset < math.inf):
        raise ValueError(f"max time offset must be > 0 s, got {max_time_offset!r}")
    if not (0.0 < max_truth_offset < math.inf):
        raise ValueError(f"max truth offset must be > 0 m, got {max_truth_offset!r}")


def _unknowns(
    start: WheelParams, model: str, fit_time_offset: bool, fit_truth_offset: bool
) -> tuple[list[str], list[float], list[float]]:
    """The fit's unknowns: their names, the scales of the physical ones, the start."""
    r0 = 0.5 * start.wheel_diameter
    b0 = start.wheelbase
    names = ["r_left", "r_right", "wheelbase"]
    scale = [r0, r0, b0]
    x0 = [start.c_left, start.c_right, 1.0]
    if model == "scrub":
        names.append("spot_wheelbase")
        scale.append(b0)
        x0.append((start.spot_wheelbase or b0) / b0)
    if fit_time_offset:
        names.append("time_offset")
        x0.append(0.0)
    if fit_truth_offset:
        names += ["truth_offset_x", "truth_offset_y"]
        x0 += [0.0, 0.0]
    return names, scale, x0


def _uncertainty(
    problem: Problem, fit: _Solution, data: RunsData, names: Sequence[str]
) -> tuple[FloatArray, dict[str, float], int, tuple[str, ...]]:
    """The covariance of the physical unknowns (clustered by run), their standard errors
    (zero for offsets not fitted), the number of clusters, and the unknowns one cluster
    alone pins."""
    cluster, clusters = _clusters(data)
    cov_x, alone = _cluster_covariance(fit.jac, fit.residuals, np.repeat(cluster, 3), clusters)
    _, slopes = problem.physical(fit.x)
    cov = cov_x * np.outer(slopes, slopes)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    standard_errors = {name: float(v) for name, v in zip(names, se, strict=True)}
    for name in ("time_offset", "truth_offset_x", "truth_offset_y"):
        standard_errors.setdefault(name, 0.0)
    return cov, standard_errors, clusters, tuple(names[i] for i in alone)


def _two_passes(
    problem: Problem, x0: FloatArray, b0: float
) -> tuple[_Solution, tuple[float, float]]:
    """The fit, weighted by the scatter of a first pass's position and heading errors (in
    which a heading error weighs like a position error of ``dtheta * b``), and those
    scales."""
    rough = (1.0, 1.0 / b0)
    first = _solve(problem, x0, rough)
    err = problem.errors(first.x, rough)
    sigma = (
        max(float(np.sqrt(np.mean(err[:, :2] ** 2))), 1e-12),
        max(float(np.sqrt(np.mean(err[:, 2] ** 2))), 1e-12),
    )
    return _solve(problem, first.x, sigma), sigma

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
on-the-spot turns and arcs need not share one wheelbase. Its turn-rate term is pinned
only by turns at turning shares far apart (:mod:`umbmark.estimators.motions`): squares
alone (straight legs, spot turns) leave ``b_arc`` to the weaving of the legs, with a
small standard error that does not see the extrapolation to arcs; the fit refuses them.

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
:data:`MIN_OFFSET_TURN` or more.

**Standard errors.** Errors accumulate along a run, so the residuals of one run are
strongly autocorrelated and the textbook ``sigma^2 (J^T J)^-1`` is far too small (tens of
times, see ``tests/test_trajectory.py``). Runs are independent of each other, so the
covariance is cluster-robust with the runs as clusters, in its jackknife form (CR3):
leaving run ``g`` out moves the solution by ``d_g = (A - A_g)^-1 s_g`` (``A = J^T J``,
``A_g = J_g^T J_g``, ``s_g = J_g^T r_g`` the run's score) and ``cov = (G - 1)/G sum_g d_g
d_g^T``. It holds whatever the correlation within a run, and unlike the plain sandwich
it does not shrink when a few runs dominate. Such an estimate from ``G`` runs has about
``G - 1`` degrees of freedom, which the estimate carries (``ErrorEstimate.dof``): its 95 %
intervals are Student-t intervals (with 3 runs 2.2 times wider than the normal ones, with
6 runs 1.3 times). A single run is cut into its two halves, taken as the clusters (wide
but, in simulations, still honest intervals).

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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.motions import SCRUB_ADVICE, SCRUB_FALLBACK, motion_coverage
from umbmark.model.kinematics import WheelParams, chord_step, turning_share
from umbmark.model.recording import RunLog
from umbmark.model.systematic import alpha_from_E_b, beta_from_E_d

__all__ = [
    "DEFAULT_MAX_TIME_OFFSET",
    "DEFAULT_MAX_TRUTH_OFFSET",
    "MIN_OFFSET_TURN",
    "MODELS",
    "START_POSES",
    "StartPose",
    "TrajectoryFit",
    "TrajectoryModel",
    "disagreement_warnings",
    "fit_trajectories",
    "trajectory_estimate",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

TrajectoryModel = Literal["diff", "scrub"]
MODELS: tuple[TrajectoryModel, ...] = ("diff", "scrub")
StartPose = Literal["fitted", "truth"]
START_POSES: tuple[StartPose, ...] = ("fitted", "truth")
#: Bound of the fitted time offset between wheels and ground truth [s].
DEFAULT_MAX_TIME_OFFSET = 0.5
#: Bound of each component of the fitted tracked-point offset [m].
DEFAULT_MAX_TRUTH_OFFSET = 2.0
#: Least heading change [rad] within some run (the ground truth's range of headings) that
#: a fitted tracked-point offset needs: 30 degrees.
MIN_OFFSET_TURN = math.radians(30.0)
#: Fewest matched ground-truth samples a run needs to take part.
MIN_SAMPLES = 5
#: Most samples of one run the fit compares (evenly spread over the run, its first and
#: last always among them). The wheel data are integrated whole and the ground truth is
#: interpolated through all its samples; only the comparison is thinned, so that the
#: work and the memory of the fit (its Jacobian) stay bounded on very long recordings.
MAX_COMPARED_PER_RUN = 20_000
#: A single run is cut into this many pieces to stand in for independent runs.
_ONE_RUN_PIECES = 2
#: Newton steps of the start-pose alignment (quadratic convergence from a close start).
_ALIGN_STEPS = 6
#: Largest condition number of the scaled normal matrix: beyond, a parameter is not pinned.
_MAX_CONDITION = 1e12


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


# --- the runs, laid end to end ----------------------------------------------------------


@dataclass(frozen=True)
class _Data:
    """Every run's wheel steps and compared samples, concatenated.

    Run ``g`` owns poses ``run_start[g] .. run_start[g] + run_length[g] - 1``. Times are
    on a global clock on which the runs lie far apart.
    """

    dphi: FloatArray  # (m, 2) wheel rotation into each pose [rad]; 0 at a run's first
    run_start: IntArray  # (G,) first pose of each run
    run_length: IntArray  # (G,) poses of each run
    sample: IntArray  # (s,) compared poses
    sample_run: IntArray  # (s,) run of each, 0 .. G-1
    sample_time: FloatArray  # (s,) [s]
    anchor: IntArray  # (G,) each run's first compared pose
    anchor_time: FloatArray  # (G,) [s]
    truth_time: FloatArray  # (q,) matched ground-truth samples [s]
    truth: FloatArray  # (q, 3) [m, m, rad]
    truth_slope: FloatArray  # (q, 3) their time derivatives (Hermite tangents)
    truth_ends: IntArray  # (G, 2) index of each run's first and last in truth_time

    @property
    def runs(self) -> int:
        return int(self.run_start.size)


def _tangents(t: FloatArray, v: FloatArray) -> FloatArray:
    """Central-difference slopes of ``v`` (n, 3) over ``t`` (n,), one-sided at the ends."""
    slope = np.empty_like(v)
    slope[1:-1] = (v[2:] - v[:-2]) / (t[2:] - t[:-2])[:, None]
    slope[0] = (v[1] - v[0]) / (t[1] - t[0])
    slope[-1] = (v[-1] - v[-2]) / (t[-1] - t[-2])
    return slope


def _thinned(count: int) -> IntArray:
    """Indices of at most :data:`MAX_COMPARED_PER_RUN` of ``count`` samples, evenly
    spread, the first and the last among them (all of them when there are few)."""
    if count <= MAX_COMPARED_PER_RUN:
        return np.arange(count, dtype=np.intp)
    picks = np.rint(np.linspace(0.0, count - 1.0, MAX_COMPARED_PER_RUN)).astype(np.intp)
    return np.unique(picks)


def _prepare(logs: Sequence[RunLog]) -> _Data:
    """Collect the runs that have at least :data:`MIN_SAMPLES` matched samples."""
    span = max((float(log.time[-1] - log.time[0]) for log in logs if log.time.size), default=0.0)
    gap = span + 10.0  # runs this far apart on the global clock never mix
    parts: dict[str, list[Any]] = {
        k: []
        for k in ("dphi", "sample", "sample_run", "sample_time", "truth", "slope", "truth_time")
    }
    starts: list[int] = []
    lengths: list[int] = []
    anchors: list[int] = []
    anchor_times: list[float] = []
    ends: list[tuple[int, int]] = []
    base = 0
    n_truth = 0
    for log in logs:
        k = np.flatnonzero(log.matched)
        if k.size < MIN_SAMPLES:
            continue
        g = len(starts)
        t = np.asarray(log.time, dtype=np.float64)[k] + g * gap
        truth = np.asarray(log.truth, dtype=np.float64)[k]
        steps = np.diff(np.asarray(log.wheel_angles, dtype=np.float64), axis=0)
        parts["dphi"].append(np.vstack([np.zeros((1, 2)), steps]))
        kept = _thinned(k.size)
        parts["sample"].append(base + k[kept])
        parts["sample_run"].append(np.full(kept.size, g, dtype=np.intp))
        parts["sample_time"].append(t[kept])
        parts["truth_time"].append(t)
        parts["truth"].append(truth)
        parts["slope"].append(_tangents(t, truth))
        starts.append(base)
        lengths.append(log.time.size)
        anchors.append(base + int(k[0]))
        anchor_times.append(float(t[0]))
        ends.append((n_truth, n_truth + k.size - 1))
        base += log.time.size
        n_truth += k.size
    if not starts:
        raise ValueError(
            f"no run has {MIN_SAMPLES} or more samples with ground truth: the trajectory "
            "fit needs recorded motion with ground truth"
        )
    return _Data(
        dphi=np.concatenate(parts["dphi"]),
        run_start=np.array(starts, dtype=np.intp),
        run_length=np.array(lengths, dtype=np.intp),
        sample=np.concatenate(parts["sample"]),
        sample_run=np.concatenate(parts["sample_run"]),
        sample_time=np.concatenate(parts["sample_time"]),
        anchor=np.array(anchors, dtype=np.intp),
        anchor_time=np.array(anchor_times),
        truth_time=np.concatenate(parts["truth_time"]),
        truth=np.concatenate(parts["truth"]),
        truth_slope=np.concatenate(parts["slope"]),
        truth_ends=np.array(ends, dtype=np.intp),
    )


def _truth_at(data: _Data, times: FloatArray, run: IntArray) -> FloatArray:
    """Ground truth of runs ``run`` (s,) at ``times`` (s,), shape (s, 3).

    A cubic Hermite spline through the run's matched samples, continued beyond its first
    and last sample along the tangent there.
    """
    tt = data.truth_time
    ends = data.truth_ends[run]
    inside = np.clip(times, tt[ends[:, 0]], tt[ends[:, 1]])
    i = np.clip(np.searchsorted(tt, inside, side="right") - 1, 0, tt.size - 2)
    h = tt[i + 1] - tt[i]
    u = ((inside - tt[i]) / h)[:, None]
    u2 = u * u
    u3 = u2 * u
    beyond = times - inside
    end = np.where(beyond < 0.0, ends[:, 0], ends[:, 1])
    return np.asarray(
        (2 * u3 - 3 * u2 + 1) * data.truth[i]
        + (u3 - 2 * u2 + u) * h[:, None] * data.truth_slope[i]
        + (3 * u2 - 2 * u3) * data.truth[i + 1]
        + (u3 - u2) * h[:, None] * data.truth_slope[i + 1]
        + beyond[:, None] * data.truth_slope[end]
    )


# --- odometry and frames ----------------------------------------------------------------


def _restart(values: FloatArray, data: _Data) -> FloatArray:
    """Cumulative sums restarted at every run's first pose (whose own value is 0)."""
    total = np.cumsum(values)
    return np.asarray(total - np.repeat(total[data.run_start], data.run_length))


def _odometry(
    r_left: float, r_right: float, b: float, b_spot: float | None, data: _Data
) -> FloatArray:
    """Odometry poses of all runs, shape (m, 3), each run from its own origin (exact arcs,
    the scrub model's ``b_eff`` when ``b_spot`` is given)."""
    d_left = r_left * data.dphi[:, 0]
    d_right = r_right * data.dphi[:, 1]
    b_eff: float | FloatArray = b
    if b_spot is not None:
        b_eff = b + (b_spot - b) * turning_share(d_left, d_right)
    ds = 0.5 * (d_left + d_right)
    dth = (d_right - d_left) / b_eff
    theta = _restart(dth, data)
    chord, heading = chord_step(ds, dth, theta - dth, "arc")
    poses = np.empty((ds.size, 3))
    poses[:, 0] = _restart(chord * np.cos(heading), data)
    poses[:, 1] = _restart(chord * np.sin(heading), data)
    poses[:, 2] = theta
    return poses


def _relative(poses: FloatArray, frames: FloatArray) -> FloatArray:
    """``poses`` (s, 3) seen from ``frames`` (s, 3)."""
    c, s = np.cos(frames[:, 2]), np.sin(frames[:, 2])
    dx = poses[:, 0] - frames[:, 0]
    dy = poses[:, 1] - frames[:, 1]
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, poses[:, 2] - frames[:, 2]])


def _compose(frames: FloatArray, local: FloatArray) -> FloatArray:
    """Poses ``local`` (s, 3) given in ``frames`` (s, 3), in the frames' parent frame."""
    c, s = np.cos(frames[:, 2]), np.sin(frames[:, 2])
    return np.column_stack(
        [
            frames[:, 0] + c * local[:, 0] - s * local[:, 1],
            frames[:, 1] + s * local[:, 0] + c * local[:, 1],
            frames[:, 2] + local[:, 2],
        ]
    )


def _align(
    truth: FloatArray, odo: FloatArray, run: IntArray, runs: int, sigma: tuple[float, float]
) -> FloatArray:
    """Each run's start pose, shape (G, 3), that lays ``odo`` (s, 3) best onto ``truth``.

    Minimizes ``sum |t_k - p - R(theta) o_k|^2 / sigma_p^2 + (t_theta,k - theta -
    o_theta,k)^2 / sigma_theta^2`` per run: ``p`` follows from ``theta`` in closed form
    (the centroids), and ``theta`` solves ``-2 w_p (A cos + B sin)(theta) + w_theta
    sum (e_k - theta)^2 = min`` by Newton steps from the mean heading difference.
    """
    count = np.bincount(run, minlength=runs).astype(np.float64)

    def total(v: FloatArray) -> FloatArray:
        return np.asarray(np.bincount(run, weights=v, minlength=runs), dtype=np.float64)

    t_mean = np.column_stack([total(truth[:, 0]), total(truth[:, 1])]) / count[:, None]
    o_mean = np.column_stack([total(odo[:, 0]), total(odo[:, 1])]) / count[:, None]
    a = truth[:, :2] - t_mean[run]
    c = odo[:, :2] - o_mean[run]
    A = total(a[:, 0] * c[:, 0] + a[:, 1] * c[:, 1])
    B = total(a[:, 1] * c[:, 0] - a[:, 0] * c[:, 1])
    e_mean = total(truth[:, 2] - odo[:, 2]) / count
    w_p, w_t = sigma[0] ** -2, sigma[1] ** -2
    theta = e_mean.copy()
    for _ in range(_ALIGN_STEPS):
        grad = w_p * (A * np.sin(theta) - B * np.cos(theta)) + w_t * count * (theta - e_mean)
        curv = w_p * (A * np.cos(theta) + B * np.sin(theta)) + w_t * count
        theta = theta - grad / np.maximum(curv, w_t * count)
    cos, sin = np.cos(theta), np.sin(theta)
    return np.column_stack(
        [
            t_mean[:, 0] - (cos * o_mean[:, 0] - sin * o_mean[:, 1]),
            t_mean[:, 1] - (sin * o_mean[:, 0] + cos * o_mean[:, 1]),
            theta,
        ]
    )


# --- the least-squares problem ----------------------------------------------------------


@dataclass(frozen=True)
class _Problem:
    """The solver's parameter vector ``x`` and what it means.

    ``x = (r_L / r0, r_R / r0, b / b0[, b_spot / b0][, u][, v_x, v_y])``, each near 1
    (``u``, ``v`` near 0): ``r0 = D_n / 2`` and ``b0`` scale the starting values, the time
    offset is ``delta = max_offset * tanh(u)`` and the tracked point's offset ``d =
    max_truth_offset * tanh(v)`` (smooth and bounded).
    """

    data: _Data
    model: TrajectoryModel
    start_pose: StartPose
    fit_offset: bool
    scale: FloatArray  # (3,) or (4,): physical radius / wheelbase = x * scale
    max_offset: float
    names: tuple[str, ...]
    fit_truth_offset: bool = False
    max_truth_offset: float = DEFAULT_MAX_TRUTH_OFFSET

    def physical(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The named parameters [m, m, m(, m)(, s)(, m, m)] and their derivatives by ``x``."""
        k = self.scale.size
        values = list(x[:k] * self.scale)
        slopes = list(self.scale)
        bounded = [self.max_offset] if self.fit_offset else []
        bounded += [self.max_truth_offset] * (2 if self.fit_truth_offset else 0)
        for j, bound in enumerate(bounded):
            t = math.tanh(float(x[k + j]))
            values.append(bound * t)
            slopes.append(bound * (1.0 - t * t))
        return np.array(values), np.array(slopes)

    def unpack(self, x: FloatArray) -> tuple[float, float, float, float | None, float]:
        """``(r_left, r_right, wheelbase, spot_wheelbase or None, time_offset)``."""
        p, _ = self.physical(x)
        b_spot = float(p[3]) if self.model == "scrub" else None
        delta = float(p[self.scale.size]) if self.fit_offset else 0.0
        return float(p[0]), float(p[1]), float(p[2]), b_spot, delta

    def truth_offset(self, x: FloatArray) -> tuple[float, float]:
        """``(d_x, d_y)`` [m], the tracked point in the robot frame; (0, 0) if not fitted."""
        if not self.fit_truth_offset:
            return 0.0, 0.0
        p, _ = self.physical(x)
        return float(p[-2]), float(p[-1])

    def errors(self, x: FloatArray, sigma: tuple[float, float]) -> FloatArray:
        """Residuals, true minus odometry, shape (s, 3) [m, m, rad].

        ``sigma`` (``sigma_p``, ``sigma_theta``) weighs the start-pose alignment.
        """
        r_left, r_right, b, b_spot, delta = self.unpack(x)
        d = self.data
        poses = _odometry(r_left, r_right, b, b_spot, d)
        if self.fit_truth_offset:
            # The tracked point the odometry predicts: the pose composed with (d, 0).
            dx, dy = self.truth_offset(x)
            c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
            poses[:, 0] += c * dx - s * dy
            poses[:, 1] += s * dx + c * dy
        truth = _truth_at(d, d.sample_time + delta, d.sample_run)
        if self.start_pose == "truth":
            at_anchor = _truth_at(d, d.anchor_time + delta, np.arange(d.runs))
            run = d.sample_run
            odo = _relative(poses[d.sample], poses[d.anchor][run])
            return np.asarray(_relative(truth, at_anchor[run]) - odo)
        odo = poses[d.sample]
        start = _align(truth, odo, d.sample_run, d.runs, sigma)
        return np.asarray(truth - _compose(start[d.sample_run], odo))


@dataclass(frozen=True)
class _Solution:
    x: FloatArray  # (k,)
    residuals: FloatArray  # (3 s,) weighted
    jac: FloatArray  # (3 s, k) of the weighted residuals


def _solve(problem: _Problem, x0: FloatArray, sigma: tuple[float, float]) -> _Solution:
    """Weighted least squares from ``x0`` (Levenberg-Marquardt, numerical Jacobian)."""
    from scipy.optimize import least_squares

    weight = np.array([1.0 / sigma[0], 1.0 / sigma[0], 1.0 / sigma[1]])

    def residuals(x: FloatArray) -> FloatArray:
        return np.asarray((problem.errors(x, sigma) * weight).ravel())

    fit = least_squares(residuals, x0, method="lm", x_scale="jac", ftol=1e-10, xtol=1e-10)
    x = np.asarray(fit.x, dtype=np.float64)
    if not np.all(np.isfinite(x)):
        raise ValueError(
            "the trajectory fit did not converge (its wheel parameters went to numbers that "
            "are not finite): check that the ground truth follows the robot, the wheel "
            "data's units (encoder resolution, gear ratio) and the time offset between wheels "
            "and ground truth; or try --method endpoints, or more runs that drive and turn"
        )
    return _Solution(
        x=x,
        residuals=np.asarray(fit.fun, dtype=np.float64),
        jac=np.asarray(fit.jac, dtype=np.float64),
    )


def _clusters(data: _Data) -> tuple[IntArray, int]:
    """The cluster of every compared sample, shape (s,), and the number of clusters: the
    runs, or the two halves of a single run."""
    if data.runs >= 2:
        return data.sample_run, data.runs
    n = data.sample_run.size
    return np.asarray(np.arange(n) * _ONE_RUN_PIECES // n, dtype=np.intp), _ONE_RUN_PIECES


def _cluster_covariance(
    jac: FloatArray, res: FloatArray, cluster: IntArray, clusters: int
) -> FloatArray:
    """Cluster-robust covariance (CR3, one-step jackknife) of the solver's ``x``.

    Parameters
    ----------
    jac : array, shape (N, k)
        Jacobian of the weighted residuals at the solution.
    res : array, shape (N,)
        Weighted residuals at the solution.
    cluster : array of int, shape (N,)
        Cluster of every residual, 0 .. clusters - 1.
    clusters : int
        ``G`` >= 2.

    Returns
    -------
    array, shape (k, k)
        ``(G - 1)/G sum_g d_g d_g^T`` with ``d_g = (A - A_g)^-1 J_g^T r_g`` (module
        documentation).
    """
    info = jac.T @ jac
    steps = []
    for g in range(clusters):
        rows = cluster == g
        j_g = jac[rows]
        steps.append(np.linalg.pinv(info - j_g.T @ j_g) @ (j_g.T @ res[rows]))
    step = np.array(steps)
    return np.asarray(step.T @ step * ((clusters - 1) / clusters))


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


def _check_turning(data: _Data) -> None:
    """Refuse, before fitting, a tracked-point offset that no run turns enough to pin.

    Parameters
    ----------
    data : _Data
        The runs' matched ground truth, headings [rad] unwrapped.

    Raises
    ------
    ValueError
        If no run's ground-truth headings span :data:`MIN_OFFSET_TURN` or more.
    """
    swing = max(float(np.ptp(data.truth[first : last + 1, 2])) for first, last in data.truth_ends)
    if not swing >= MIN_OFFSET_TURN:
        raise ValueError(
            "the recorded motion does not pin down the truth offset: no run turns by "
            f"{math.degrees(MIN_OFFSET_TURN):.0f} deg or more (the most is "
            f"{math.degrees(swing):.1f} deg), and a tracked point off the axle shows only "
            "as the robot turns; give the offset (--truth-offset X Y) or record turns"
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
        ``"scrub"``: refuse runs whose motion does not identify the turn-rate term
        (:mod:`umbmark.estimators.motions`); False fits it anyway (to study it).

    Returns
    -------
    TrajectoryFit

    Raises
    ------
    ValueError
        If the runs have too little recorded motion to pin the parameters down (for the
        truth offset: no run turns by :data:`MIN_OFFSET_TURN`; for the scrub model: turns
        at too narrow a range of turning shares), or the fitted truth offset reaches its
        bound.
    """
    if model not in MODELS:
        raise ValueError(f"unknown trajectory model {model!r}; use diff or scrub")
    if start_pose not in START_POSES:
        raise ValueError(f"unknown start pose {start_pose!r}; use fitted or truth")
    if not (0.0 < max_time_offset < math.inf):
        raise ValueError(f"max time offset must be > 0 s, got {max_time_offset!r}")
    if not (0.0 < max_truth_offset < math.inf):
        raise ValueError(f"max truth offset must be > 0 m, got {max_truth_offset!r}")
    if model == "scrub" and check_coverage:
        unidentified = motion_coverage(logs, start).scrub_problem()
        if unidentified is not None:
            raise ValueError(f"{unidentified}: {SCRUB_ADVICE}")
    data = _prepare(logs)
    if fit_truth_offset:
        _check_turning(data)
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
    problem = _Problem(
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
    # First pass: a heading error weighs like a position error of dtheta * b.
    rough = (1.0, 1.0 / b0)
    first = _solve(problem, np.array(x0), rough)
    err = problem.errors(first.x, rough)
    sigma = (
        max(float(np.sqrt(np.mean(err[:, :2] ** 2))), 1e-12),
        max(float(np.sqrt(np.mean(err[:, 2] ** 2))), 1e-12),
    )
    fit = _solve(problem, first.x, sigma)
    truth_offset = problem.truth_offset(fit.x)
    if fit_truth_offset:  # before the check of the Jacobian, which a bound flattens
        _check_truth_offset_inside(truth_offset, max_truth_offset)
    _check_pinned(fit.jac, names)
    cluster, clusters = _clusters(data)
    cov_x = _cluster_covariance(fit.jac, fit.residuals, np.repeat(cluster, 3), clusters)
    _, slopes = problem.physical(fit.x)
    cov = cov_x * np.outer(slopes, slopes)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    standard_errors = {name: float(v) for name, v in zip(names, se, strict=True)}
    for name in ("time_offset", "truth_offset_x", "truth_offset_y"):
        standard_errors.setdefault(name, 0.0)
    r_left, r_right, b, b_spot, delta = problem.unpack(fit.x)
    _check_physical(
        {"r_left": r_left, "r_right": r_right, "wheelbase": b, "spot_wheelbase": b_spot},
        standard_errors,
    )
    err = problem.errors(fit.x, sigma)
    return TrajectoryFit(
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
    )


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
        (:mod:`umbmark.estimators.motions`) give the single set alone, with a warning.
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
    side = side_length or 1.0
    v0 = np.array([single.r_left, single.r_right, single.wheelbase])
    values = _relative_errors(v0, active, side)
    # First-order propagation through central differences.
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
    if fit_truth_offset:
        components.update(
            truth_offset_x=single.truth_offset_x, truth_offset_y=single.truth_offset_y
        )
        for key in ("truth_offset_x", "truth_offset_y"):
            standard_errors[key] = single.standard_errors[key]
    fit = single
    method = "trajectory-scrub" if model == "scrub" else "trajectory"
    problem = motion_coverage(logs, active).scrub_problem() if model == "scrub" else None
    if model == "scrub" and problem is None:
        fit = fit_trajectories(logs, active, model="scrub", check_coverage=False, **options)
        assert fit.spot_wheelbase is not None
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
        warnings=() if problem is None else (f"{problem}; {SCRUB_FALLBACK}",),
    )
    return estimate, fit


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

"""The trajectory fit's model: the runs laid end to end, their odometry, and the residuals.

What :func:`umbmark.estimators.trajectory_fit.fit_trajectories` minimizes (the method:
:mod:`umbmark.estimators.trajectory`): every run's wheel steps integrated into odometry
poses (exact arcs; the scrub model's turn-dependent wheelbase), moved to the tracked
point where it is fitted, placed in the run's start frame (fitted, or the ground truth's
first sample), and compared with the ground truth shifted by the time offset (a cubic
Hermite spline through the matched samples, continued along the tangent).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.model.kinematics import chord_step, turning_share
from umbmark.model.recording import RunLog

__all__ = [
    "DEFAULT_MAX_TRUTH_OFFSET",
    "MAX_COMPARED_PER_RUN",
    "MIN_SAMPLES",
    "MODELS",
    "START_POSES",
    "Problem",
    "RunsData",
    "StartPose",
    "TrajectoryModel",
    "prepare",
]

IndexArray = NDArray[np.intp]  # indices

TrajectoryModel = Literal["diff", "scrub"]
MODELS: tuple[TrajectoryModel, ...] = ("diff", "scrub")
StartPose = Literal["fitted", "truth"]
START_POSES: tuple[StartPose, ...] = ("fitted", "truth")
#: Bound of each component of the fitted tracked-point offset [m].
DEFAULT_MAX_TRUTH_OFFSET = 2.0
#: Fewest matched ground-truth samples a run needs to take part.
MIN_SAMPLES = 5
#: Most samples of one run the fit compares (evenly spread over the run, its first and
#: last always among them). The wheel data are integrated whole and the ground truth is
#: interpolated through all its samples; only the comparison is thinned, so that the
#: work and the memory of the fit (its Jacobian) stay bounded on very long recordings.
MAX_COMPARED_PER_RUN = 20_000
#: Newton steps of the start-pose alignment (quadratic convergence from a close start).
_ALIGN_STEPS = 6


# --- the runs, laid end to end ----------------------------------------------------------


@dataclass(frozen=True)
class RunsData:
    """Every run's wheel steps and compared samples, concatenated.

    Run ``g`` owns poses ``run_start[g] .. run_start[g] + run_length[g] - 1``. Times are
    on a global clock on which the runs lie far apart.
    """

    dphi: FloatArray  # (m, 2) wheel rotation into each pose [rad]; 0 at a run's first
    run_start: IndexArray  # (G,) first pose of each run
    run_length: IndexArray  # (G,) poses of each run
    sample: IndexArray  # (s,) compared poses
    sample_run: IndexArray  # (s,) run of each, 0 .. G-1
    sample_time: FloatArray  # (s,) [s]
    anchor: IndexArray  # (G,) each run's first compared pose
    anchor_time: FloatArray  # (G,) [s]
    truth_time: FloatArray  # (q,) matched ground-truth samples [s]
    truth: FloatArray  # (q, 3) [m, m, rad]
    truth_slope: FloatArray  # (q, 3) their time derivatives (Hermite tangents)
    truth_ends: IndexArray  # (G, 2) index of each run's first and last in truth_time

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


def _thinned(count: int) -> IndexArray:
    """Indices of at most :data:`MAX_COMPARED_PER_RUN` of ``count`` samples, evenly
    spread, the first and the last among them (all of them when there are few)."""
    if count <= MAX_COMPARED_PER_RUN:
        return np.arange(count, dtype=np.intp)
    picks = np.rint(np.linspace(0.0, count - 1.0, MAX_COMPARED_PER_RUN)).astype(np.intp)
    return np.unique(picks)


def prepare(logs: Sequence[RunLog]) -> RunsData:
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
    return RunsData(
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


def _truth_at(data: RunsData, times: FloatArray, run: IndexArray) -> FloatArray:
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


def _restart(values: FloatArray, data: RunsData) -> FloatArray:
    """Cumulative sums restarted at every run's first pose (whose own value is 0)."""
    total = np.cumsum(values)
    return np.asarray(total - np.repeat(total[data.run_start], data.run_length))


def _odometry(
    r_left: float, r_right: float, b: float, b_spot: float | None, data: RunsData
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
    truth: FloatArray, odo: FloatArray, run: IndexArray, runs: int, sigma: tuple[float, float]
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
class Problem:
    """The solver's parameter vector ``x`` and what it means.

    ``x = (r_L / r0, r_R / r0, b / b0[, b_spot / b0][, u][, v_x, v_y])``, each near 1
    (``u``, ``v`` near 0): ``r0 = D_n / 2`` and ``b0`` scale the starting values, the time
    offset is ``delta = max_offset * tanh(u)`` and the tracked point's offset ``d =
    max_truth_offset * tanh(v)`` (smooth and bounded).
    """

    data: RunsData
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

"""Point-to-line ICP of two planar scans (the idea of Censi's PLICP, ICRA 2008), in numpy.

:func:`match` finds the pose ``(x, y, yaw)`` of the current sweep's frame in the
reference sweep's frame (the scanner's displacement from the reference to the current
sweep), starting from a guess (the wheels' odometry):

1. every current point, moved by the pose so far, is paired with the nearest reference
   point that lies on a line (:func:`umbmark.scans.points.prepare`; scipy's ``cKDTree``),
   no farther than the correspondence distance;
2. the residual of a pair is the point's distance to that line; the pairs beyond
   ``trim`` of the residuals' spread (``3 x 1.4826 x`` their median absolute value, at
   least ``min_distance``) are dropped and the rest weighted by Cauchy's function of that
   scale (robust to clutter that moved and to what only one sweep sees);
3. one Gauss-Newton step of the weighted point-to-line cost moves the pose; the
   correspondence distance shrinks to a few times the residuals' spread;
4. it stops when a step moves less than ``tolerance`` (metres and radians), or after
   ``max_iterations`` (not converged).

Each match carries its covariance ``s^2 H^-1``: ``H`` is the Gauss-Newton Hessian
(the information matrix) of the final pairs, ``s^2`` their weighted residual variance.
This counts the range noise only, not wrong pairings, so it is optimistic for poor
scenes; it is what the calibration weighs the intervals with.

A match is *degenerate* and refused when the scene does not fix the pose:

- **corridor**: the information in one direction is too small: the smallest eigenvalue
  of ``H / n`` (the rotation scaled by the median range, so that all three are in m^2
  per pair) under ``min_constraint`` (the share of pairs whose normal points that way,
  roughly). Two parallel walls fix only the motion across them;
- **open space**: fewer than ``min_points`` returns on lines in either sweep, or fewer
  than ``min_overlap`` of the current sweep's returns paired at the end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.scans.points import PreparedScan

__all__ = ["Match", "MatchSettings", "Status", "match"]


Status = Literal["ok", "corridor", "open space", "not converged"]


@dataclass(frozen=True)
class MatchSettings:
    """How :func:`match` pairs, weighs and stops (the module's docstring).

    Attributes
    ----------
    max_distance : float
        Correspondence distance [m] of the first iteration (the guess's error at most).
    min_distance : float
        Smallest correspondence distance [m] (a few times the range noise).
    trim : float
        Pairs beyond this many robust spreads of the residuals are dropped.
    max_iterations : int
    tolerance : float
        A step smaller than this [m, rad] ends the iterations.
    min_points : int
        Fewest returns on lines a sweep needs (fewer: open space).
    min_overlap : float
        Smallest share of the current sweep's returns paired at the end (less: open space).
    min_constraint : float
        Smallest eigenvalue of the information per pair [m^2 / m^2] (less: corridor).
    """

    max_distance: float = 0.5
    min_distance: float = 0.05
    trim: float = 3.0
    max_iterations: int = 40
    tolerance: float = 1e-4
    min_points: int = 40
    min_overlap: float = 0.3
    min_constraint: float = 0.02


DEFAULT_SETTINGS = MatchSettings()


@dataclass(frozen=True)
class Match:
    """The result of :func:`match`.

    Attributes
    ----------
    pose : array, shape (3,)
        The current sweep's frame in the reference sweep's frame: ``x, y`` [m], yaw [rad].
    covariance : array, shape (3, 3)
        Covariance of ``pose`` [m^2, m rad, rad^2] (NaN when there are too few pairs).
    status : {"ok", "corridor", "open space", "not converged"}
        Only ``"ok"`` matches are fit to use.
    iterations : int
    pairs : int
        Pairs used in the last step.
    rms : float
        Root mean square of the used pairs' point-to-line residuals [m].
    constraint : float
        Smallest eigenvalue of the information per pair (see ``min_constraint``).
    """

    pose: FloatArray
    covariance: FloatArray
    status: Status
    iterations: int
    pairs: int
    rms: float
    constraint: float

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def _failed(guess: FloatArray, status: Status, iterations: int = 0, pairs: int = 0) -> Match:
    nan = np.full((3, 3), np.nan)
    return Match(guess.copy(), nan, status, iterations, pairs, math.nan, 0.0)


@dataclass
class _State:
    """The iterations so far: pose, correspondence distance, the last step's figures."""

    pose: FloatArray
    distance: float
    iterations: int = 0
    pairs: int = 0
    hessian: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))
    sigma2: float = math.nan
    rms: float = math.nan
    failed: Status | None = None


def _iterate(
    reference: PreparedScan,
    src: FloatArray,
    state: _State,
    settings: MatchSettings,
    tolerance: float,
    budget: int,
    min_pairs: int,
) -> bool:
    """Gauss-Newton steps of ``src`` against ``reference`` from ``state`` (updated in
    place) until a step is under ``tolerance`` (True) or ``budget`` steps are done."""
    tree = reference.tree
    assert tree is not None
    ref_pts, ref_nrm = reference.line_points, reference.normals
    pose = state.pose
    visited: list[FloatArray] = []
    for _ in range(budget):
        state.iterations += 1
        c, s = math.cos(pose[2]), math.sin(pose[2])
        rx = c * src[:, 0] - s * src[:, 1]  # rotated, before the translation
        ry = s * src[:, 0] + c * src[:, 1]
        moved = np.column_stack([rx + pose[0], ry + pose[1]])
        dist, j = tree.query(moved, k=1, distance_upper_bound=state.distance, workers=1)
        near = np.flatnonzero(np.isfinite(dist))
        if near.size < min_pairs:
            state.failed, state.pairs = "open space", int(near.size)
            return False
        j = j[near]
        n = ref_nrm[j]
        d = moved[near] - ref_pts[j]
        res = n[:, 0] * d[:, 0] + n[:, 1] * d[:, 1]
        scale = max(1.4826 * float(np.median(np.abs(res))), 1e-4)
        keep = np.flatnonzero(np.abs(res) <= max(settings.trim * scale, settings.min_distance / 2))
        if keep.size < min_pairs:
            state.failed, state.pairs = "open space", int(keep.size)
            return False
        res, n, at = res[keep], n[keep], near[keep]
        u = res / (settings.trim * scale)
        w = 1.0 / (1.0 + u * u)  # Cauchy
        jac = np.column_stack([n[:, 0], n[:, 1], n[:, 1] * rx[at] - n[:, 0] * ry[at]])
        jw = jac * w[:, None]
        h = jw.T @ jac
        try:
            step = -np.linalg.solve(h, jw.T @ res)
        except np.linalg.LinAlgError:
            state.failed = "corridor"
            return False
        pose += step
        state.pairs, state.hessian = int(res.size), h
        state.sigma2 = float(np.sum(w * res * res) / np.sum(w)) * res.size / max(res.size - 3, 1)
        state.rms = math.sqrt(float(np.mean(res * res)))
        state.distance = min(state.distance, max(settings.min_distance, 4 * settings.trim * scale))
        if float(np.max(np.abs(step))) < tolerance:
            return True
        # pairings that alternate make the pose cycle: back where it was, it has converged
        for back in range(2, min(len(visited), 4) + 1):
            if float(np.max(np.abs(pose - visited[-back]))) < tolerance:
                pose[:] = np.mean([*visited[-back + 1 :], pose], axis=0)
                return True
        visited.append(pose.copy())
    return False


def match(
    reference: PreparedScan,
    current: PreparedScan,
    guess: FloatArray | None = None,
    settings: MatchSettings = DEFAULT_SETTINGS,
) -> Match:
    """Match ``current`` against ``reference`` (the module's docstring).

    The first steps pair every few points of ``current`` only (about 180 of them), the
    last ones all of them: the same result as all points throughout, in about half the
    time.

    Parameters
    ----------
    reference, current : PreparedScan
        The two sweeps (:func:`umbmark.scans.points.prepare`).
    guess : array, shape (3,), optional
        The first pose of ``current`` in ``reference`` [m, m, rad] (default: no motion).
    settings : MatchSettings
    """
    pose = np.zeros(3) if guess is None else np.asarray(guess, dtype=np.float64).copy()
    src = current.points
    few = settings.min_points
    if reference.tree is None or reference.line_points.shape[0] < few:
        return _failed(pose, "open space")
    if current.line_points.shape[0] < few:
        return _failed(pose, "open space")
    state = _State(pose, settings.max_distance)
    stride = max(1, src.shape[0] // 180)
    budget = settings.max_iterations
    if stride > 1:
        coarse = src[::stride]
        _iterate(reference, coarse, state, settings, 10 * settings.tolerance, budget, few // stride)
        budget -= state.iterations
    converged = state.failed is None and _iterate(
        reference, src, state, settings, settings.tolerance, max(budget, 2), few
    )
    if state.failed is not None:
        return _failed(pose, state.failed, state.iterations, state.pairs)
    pose[2] = math.remainder(pose[2], math.tau)
    h, pairs = state.hessian, state.pairs
    length = float(np.median(np.hypot(src[:, 0], src[:, 1])))
    scaled = np.diag([1.0, 1.0, 1.0 / max(length, 1e-3)])
    info = scaled @ h @ scaled / max(pairs, 1)
    constraint = float(np.linalg.eigvalsh(0.5 * (info + info.T))[0])
    try:
        covariance = np.asarray(state.sigma2 * np.linalg.inv(h), dtype=np.float64)
    except np.linalg.LinAlgError:
        covariance = np.full((3, 3), np.nan)
    status: Status = "ok"
    if constraint < settings.min_constraint:
        status = "corridor"
    elif pairs < settings.min_overlap * src.shape[0]:
        status = "open space"
    elif not converged:
        status = "not converged"
    return Match(pose, covariance, status, state.iterations, pairs, state.rms, constraint)

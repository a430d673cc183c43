"""A sweep as points, and the points prepared as the reference of a match.

:func:`scan_points` keeps the beams that returned (finite, inside ``range_min ..
range_max``) and turns them into points of the scanner's frame, right side up (a scanner
mounted upside down has its y mirrored). :func:`prepare` adds what the point-to-line
matcher needs of a reference: each point's normal, fitted to its neighbours in beam
order (a line through up to ``2 * half_window + 1`` points, none farther than
``max_gap`` from the next), kept only where the neighbourhood is a line (the smaller
eigenvalue of its scatter under ``line_ratio`` of the larger), and a KD-tree of the
points with a normal (scipy's ``cKDTree``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.model.scans import ScanSeries

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

__all__ = ["PreparedScan", "prepare", "scan_points", "series_points"]


def scan_points(
    ranges: FloatArray,
    angles: FloatArray,
    range_min: float,
    range_max: float,
    *,
    upside_down: bool = False,
) -> FloatArray:
    """The returns of one sweep as points ``(m, 2)`` [m] in beam order.

    Parameters
    ----------
    ranges, angles : array, shape (beams,)
        Ranges [m] and beam angles [rad] in the scanner's frame as mounted.
    range_min, range_max : float
        The valid range [m]: NaN, inf, and ranges outside ``[range_min, range_max]`` are
        no return and left out.
    upside_down : bool
        Mirror y: the points of a scanner mounted upside down, right side up.
    """
    r = np.asarray(ranges, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(r) & (r >= range_min) & (r <= range_max)
    r, a = r[valid], angles[valid]
    y = r * np.sin(a)
    return np.column_stack([r * np.cos(a), -y if upside_down else y])


def series_points(
    scans: ScanSeries,
    index: int,
    motion: Callable[[FloatArray], FloatArray] | None = None,
) -> FloatArray:
    """The points ``(m, 2)`` of sweep ``index`` of ``scans`` (:func:`scan_points`), in the
    scanner's frame at the sweep's stamp.

    With ``motion`` and a ``time_increment``, the scanner's motion during the sweep is
    undone: beam ``k`` is measured ``tau = k * time_increment`` after the stamp, from the
    pose ``motion(tau)`` (shape ``(m, 3)`` for ``tau`` shape ``(m,)``: ``x, y`` [m], yaw
    [rad] in the scanner's frame at the stamp, right side up), and is moved by that pose
    into the frame at the stamp.
    """
    points = scan_points(
        scans.ranges[index],
        scans.angles(),
        scans.range_min,
        scans.range_max,
        upside_down=scans.upside_down,
    )
    if motion is None or scans.time_increment <= 0.0:
        return points
    r = scans.ranges[index]
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(r) & (r >= scans.range_min) & (r <= scans.range_max)
    pose = motion(np.flatnonzero(valid).astype(np.float64) * scans.time_increment)
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    x = c * points[:, 0] - s * points[:, 1] + pose[:, 0]
    y = s * points[:, 0] + c * points[:, 1] + pose[:, 1]
    return np.column_stack([x, y])


@dataclass(frozen=True)
class PreparedScan:
    """One sweep ready to be matched.

    Attributes
    ----------
    points : array, shape (m, 2)
        Every return [m], right side up, in beam order.
    line_points, normals : array, shape (k, 2)
        The returns that lie on a line, and the unit normal of that line.
    tree : cKDTree or None
        KD-tree of ``line_points`` (None: fewer than 3 of them).
    """

    points: FloatArray
    line_points: FloatArray
    normals: FloatArray
    tree: cKDTree | None


def prepare(
    points: FloatArray,
    *,
    half_window: int = 3,
    max_gap: float = 0.25,
    line_ratio: float = 0.1,
) -> PreparedScan:
    """``points`` ``(m, 2)`` with normals and a KD-tree (the module's docstring).

    Parameters
    ----------
    points : array, shape (m, 2)
        One sweep's returns in beam order (:func:`scan_points`).
    half_window : int
        Neighbours on each side a normal is fitted to.
    max_gap : float
        Neighbours farther than this [m] from the next one in beam order break the line.
    line_ratio : float
        Largest ratio of the scatter's eigenvalues (across over along) of a line.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    m = pts.shape[0]
    if m < 3:
        return PreparedScan(pts, np.zeros((0, 2)), np.zeros((0, 2)), None)
    # segments: runs of points each no farther than max_gap from the next
    step = np.hypot(*np.diff(pts, axis=0).T)
    segment = np.concatenate([[0], np.cumsum(step > max_gap)])
    offsets = np.arange(-half_window, half_window + 1)
    idx = np.arange(m)[:, None] + offsets[None, :]
    inside = (idx >= 0) & (idx < m)
    idx = np.clip(idx, 0, m - 1)
    w = (inside & (segment[idx] == segment[:, None])).astype(np.float64)  # (m, 2w+1)
    x, y = pts[idx, 0], pts[idx, 1]
    count = w.sum(axis=1)
    mx, my = (w * x).sum(axis=1) / count, (w * y).sum(axis=1) / count
    dx, dy = (x - mx[:, None]) * w, (y - my[:, None]) * w
    cxx = (dx * dx).sum(axis=1) / count
    cxy = (dx * dy).sum(axis=1) / count
    cyy = (dy * dy).sum(axis=1) / count
    half_trace = 0.5 * (cxx + cyy)
    root = np.sqrt(np.maximum(0.25 * (cxx - cyy) ** 2 + cxy**2, 0.0))
    big, small = half_trace + root, half_trace - root
    # the direction of the line (largest eigenvalue) is at angle 0.5 * atan2(2 cxy, cxx - cyy)
    along = 0.5 * np.arctan2(2.0 * cxy, cxx - cyy)
    normals = np.column_stack([-np.sin(along), np.cos(along)])
    with np.errstate(invalid="ignore", divide="ignore"):
        good = (count >= 3) & (big > 0) & (small <= line_ratio * big)
    line_points, normals = pts[good], normals[good]
    from scipy.spatial import cKDTree  # imported by the matching alone: a second at start

    tree = cKDTree(line_points) if line_points.shape[0] >= 3 else None
    return PreparedScan(pts, line_points, normals, tree)

"""A laser scan cut into straight pieces (split-and-merge), the walls among which the
corner is looked for (:mod:`umbmark.routines.corner_lidar`).

1. The returns become beams and points in the robot's base frame through the laser's
   mounting.
2. Returns next to each other in the scan form clusters; a jump between neighbours of
   more than ``jump`` (or four beam spacings at their range) breaks them. A full-circle
   scan's last cluster continues into its first.
3. Each cluster is split, recursively, where its points leave a straight line by more
   than ``split_distance`` (at the point farthest from the chord).
4. Neighbouring pieces on one line are merged again, and so are any two pieces of one
   line (an obstacle in front of a wall cuts it apart) up to ``max_gap`` apart.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.robot.base import ScanSweep
from umbmark.routines.corner import line_direction
from umbmark.routines.corner_beams import Beams

__all__ = ["Piece", "pieces", "scan_beams", "scan_points"]

IndexArray = NDArray[np.intp]


@dataclass(frozen=True)
class Piece:
    """A straight piece of a scan.

    Attributes
    ----------
    index : array of int, shape (n,)
        Its returns, as indices into the scan's valid returns (:func:`scan_beams`).
    core : array of int
        Its returns without those at the ends of the pieces it was split into that leave
        their line by more than 2.5 robust standard deviations: where a wall meets another
        object, a return there may belong to either.
    points : array, shape (n, 2)
        Their points in the base frame [m].
    centre, direction : array, shape (2,)
        The centroid [m] and the unit direction of its total-least-squares line.
    length : float
        Its extent along the line [m].
    """

    index: IndexArray
    core: IndexArray
    points: FloatArray
    centre: FloatArray
    direction: FloatArray
    length: float


def scan_beams(scan: ScanSweep) -> Beams:
    """The scan's valid returns as beams in the robot's base frame, in beam order
    (through the laser's mounting ``scan.mount``)."""
    r = np.asarray(scan.ranges, dtype=np.float64)
    ok = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
    m = scan.mount
    angles = scan.angles()[ok] + m.theta
    directions = np.column_stack([np.cos(angles), np.sin(angles)])
    origins = np.broadcast_to(np.array([m.x, m.y]), directions.shape)
    return Beams(origins, directions, r[ok])


def scan_points(scan: ScanSweep) -> FloatArray:
    """The scan's valid returns as points in the robot's base frame, shape (n, 2), in
    beam order."""
    return scan_beams(scan).points


def _piece(index: IndexArray, points: FloatArray, core: IndexArray | None = None) -> Piece:
    p = points[index]
    centre = p.mean(axis=0)
    u = line_direction(p)
    along = (p - centre) @ u
    if core is None:
        core = _trim(index, np.abs((p - centre) @ np.array([-u[1], u[0]])))
    return Piece(index, core, p, centre, u, float(along.max() - along.min()))


def _trim(index: IndexArray, across: FloatArray) -> IndexArray:
    """``index`` without up to three returns at each end farther from the line than 2.5
    robust standard deviations (of five returns or more)."""
    if len(index) < 5:
        return index
    limit = 2.5 * 1.4826 * float(np.median(across))
    first, last = 0, len(index)
    for _ in range(3):
        if across[first] > limit:
            first += 1
        if across[last - 1] > limit:
            last -= 1
    return index[first:last]


def _join(p: Piece, q: Piece, points: FloatArray) -> Piece:
    return _piece(np.union1d(p.index, q.index), points, np.union1d(p.core, q.core))


def _clusters(points: FloatArray, scan: ScanSweep, jump: float) -> list[IndexArray]:
    """Runs of neighbouring returns, as indices."""
    n = len(points)
    if n < 2:
        return [np.arange(n)] if n else []
    step = np.hypot(*np.diff(points, axis=0).T)
    r = np.hypot(*(points - [scan.mount.x, scan.mount.y]).T)
    limit = np.maximum(jump, 4.0 * r[1:] * abs(scan.angle_increment))
    edges = [0, *(np.flatnonzero(step > limit) + 1).tolist(), n]
    runs = [np.arange(a, b) for a, b in itertools.pairwise(edges)]
    full_circle = abs(scan.angle_increment) * scan.ranges.size >= 2 * math.pi - 1e-6
    if full_circle and len(runs) > 1:
        seam = float(np.hypot(*(points[-1] - points[0])))
        if seam <= max(jump, 4.0 * float(r[0]) * abs(scan.angle_increment)):
            runs[0] = np.concatenate([runs.pop(), runs[0]])  # across the scan's seam
    return runs


def _split(run: IndexArray, points: FloatArray, limit: float) -> list[Piece]:
    """Split-and-merge's split: recursively where the points leave a line."""
    out: list[Piece] = []
    stack = [run]
    while stack:
        index = stack.pop()
        if len(index) < 3:
            if len(index) >= 2:
                out.append(_piece(index, points))
            continue
        p = points[index]
        u = line_direction(p)
        across = (p - p.mean(axis=0)) @ np.array([-u[1], u[0]])
        if float(np.abs(across).max()) <= limit:
            out.append(_piece(index, points))
            continue
        chord = p[-1] - p[0]
        norm = math.hypot(*chord)
        dev = (
            np.abs((p - p[0]) @ np.array([-chord[1], chord[0]]) / norm)
            if norm > 0.0
            else np.abs(across)
        )
        k = int(np.argmax(dev[1:-1])) + 1
        stack += [index[k:], index[: k + 1]]
    return out


def _mergeable(p: Piece, q: Piece, split_distance: float, max_gap: float) -> bool:
    """One line through both pieces, with a gap of at most ``max_gap``."""
    if len(p.index) > 4 and len(q.index) > 4 and abs(float(p.direction @ q.direction)) < 0.995:
        return False
    both = np.vstack([p.points, q.points])
    u = line_direction(both)
    centre = both.mean(axis=0)
    across = (both - centre) @ np.array([-u[1], u[0]])
    if float(np.abs(across).max()) > split_distance:
        return False
    sp, sq = (p.points - centre) @ u, (q.points - centre) @ u
    return max(float(sq.min() - sp.max()), float(sp.min() - sq.max())) <= max_gap


def pieces(
    scan: ScanSweep, split_distance: float, jump: float, max_gap: float
) -> tuple[Beams, list[Piece]]:
    """The scan's valid returns and its straight pieces of at least five returns."""
    beams = scan_beams(scan)
    points = beams.points
    found: list[Piece] = []
    for run in _clusters(points, scan, jump):
        split = _split(run, points, split_distance)
        # the stack pops the first half last: back in scan order
        found += sorted(split, key=lambda piece: int(np.searchsorted(run, piece.index[0])))
    merged: list[Piece] = []
    for piece in found:
        if merged and _mergeable(merged[-1], piece, split_distance, max_gap):
            merged.append(_join(merged.pop(), piece, points))
        else:
            merged.append(piece)
    out = [p for p in merged if len(p.index) >= 5]
    joined = True
    while joined:
        joined = False
        for i in range(len(out)):
            for j in range(i + 1, len(out)):
                if _mergeable(out[i], out[j], split_distance, max_gap):
                    out[i] = _join(out[i], out.pop(j), points)
                    joined = True
                    break
            if joined:
                break
    return beams, out

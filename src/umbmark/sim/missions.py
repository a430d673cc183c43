"""Ordinary missions of a warehouse robot, as its odometry knows them: corridors driven
straight, quarter turns at shelves and crossings, now and then a half or whole turn on the
spot. Not squares: what a fleet drives anyway, and what the fleet calibrates from
(``umbmark simulate --fleet``).

A mission is a :class:`~umbmark.sim.paths.Path` from the robot's start (its odometry's
origin), drawn at random on the aisles of a :class:`Warehouse`: from a crossing the robot
turns (left, right, back) to an aisle and drives to the next crossing, sometimes stopping
halfway to face a shelf and turn back. It stays on the aisles by its plan; the truth drifts
off them by the robot's errors, as an uncalibrated robot's does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.sim.paths import Path, Segment

__all__ = ["Warehouse", "mission"]


@dataclass(frozen=True)
class Warehouse:
    """The aisles of a warehouse, a grid of crossings [m] in its world frame.

    Attributes
    ----------
    aisles_x : tuple of float
        The x of the aisles that run along y.
    aisles_y : tuple of float
        The y of the aisles that run along x.
    """

    aisles_x: tuple[float, ...] = (0.0, 6.0, 12.0)
    aisles_y: tuple[float, ...] = (0.0, 3.5, 7.0)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(x0, y0, x1, y1)`` of the crossings [m]."""
        return (
            min(self.aisles_x),
            min(self.aisles_y),
            max(self.aisles_x),
            max(self.aisles_y),
        )

    def start(self, k: int) -> tuple[float, float, float]:
        """The ``k``-th robot's start: a crossing, heading along its aisle (x, y, heading)."""
        i, j = k % len(self.aisles_x), (k // len(self.aisles_x)) % len(self.aisles_y)
        heading = 0.0 if i < len(self.aisles_x) - 1 else math.pi
        return self.aisles_x[i], self.aisles_y[j], heading


_DIRECTIONS = ((1, 0), (0, 1), (-1, 0), (0, -1))


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def mission(
    warehouse: Warehouse,
    start: tuple[float, float, float],
    rng: np.random.Generator,
    seconds: float,
    speed: float,
    turn_seconds: float = 4.0,
) -> Path:
    """A random mission of about ``seconds`` of driving from the crossing ``start``.

    Parameters
    ----------
    warehouse : Warehouse
    start : (float, float, float)
        A crossing and a heading along one of its aisles [m, m, rad].
    rng : numpy.random.Generator
    seconds : float
        How long to drive [s] (straights at ``speed``, each turn about ``turn_seconds``).
    speed : float
        Cruise speed [m/s].

    Returns
    -------
    Path
        Written for ccw travel (drive it as one ccw run), from the odometry's origin.
    """
    xs, ys = list(warehouse.aisles_x), list(warehouse.aisles_y)
    i, j = xs.index(start[0]), ys.index(start[1])
    heading = start[2]
    segments: list[Segment] = []
    spent = 0.0
    while spent < seconds:
        moves = [
            (di, dj) for di, dj in _DIRECTIONS if 0 <= i + di < len(xs) and 0 <= j + dj < len(ys)
        ]
        forward = (round(math.cos(heading)), round(math.sin(heading)))
        ahead = [m for m in moves if m != (-forward[0], -forward[1])]
        di, dj = ahead[rng.integers(len(ahead))] if ahead else moves[0]
        turn = _wrap(math.atan2(dj, di) - heading)
        if abs(turn) > 1e-9:
            segments.append(Segment("turn", turn))
            spent += turn_seconds * abs(turn) / (0.5 * math.pi)
        heading = math.atan2(dj, di)
        length = abs(xs[i + di] - xs[i]) + abs(ys[j + dj] - ys[j])
        if rng.random() < 0.3:  # stop at a shelf halfway: face it and turn back
            side = 1.0 if rng.random() < 0.5 else -1.0
            half = 0.5 * length
            segments += [
                Segment("straight", half),
                Segment("turn", side * 0.5 * math.pi),
                Segment("turn", -side * 0.5 * math.pi),
                Segment("straight", half),
            ]
            spent += 2 * turn_seconds
        else:
            segments.append(Segment("straight", length))
        spent += length / speed
        if rng.random() < 0.1:  # now and then a whole turn on the spot
            whole = 2.0 * math.pi * (1.0 if rng.random() < 0.5 else -1.0)
            segments.append(Segment("turn", whole))
            spent += 4 * turn_seconds
        i, j = i + di, j + dj
    return Path(f"mission of {spent:.0f} s", tuple(segments))

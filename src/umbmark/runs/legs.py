"""The legs of squares as the reference measured them: a wrong side length is refused.

A run of the square path drives four legs with a quarter turn between each two. Where the
ground truth follows the whole run, its corners are where the heading (the reference's,
or for a position-only reference the odometry's) changes faster than :data:`CURVATURE`
per metre moved, by at least :data:`CORNER` in all; a run with three or four corners,
each a quarter turn (within :data:`CORNER`) the same way, is a square, and its legs run
from one corner's end to the next one's start (the first from the run's start). Measured
between the turns, a reference off the axle (a marker that swings round a turn on the
spot) measures the leg, not the swing.

The side length a calibration is given (an option, a file's field) must agree with the
median leg within :data:`LEG_TOLERANCE`: a robot driven by its odometry makes legs longer
or shorter by its scale error (a few per cent; E_d and the wheel diameter by as much) and
a reference tracks it to within centimetres, while a wrong side (5 m for a 4 m square) is
off by a quarter. The real OptiOdom squares measure 0.736 m (L = 0.75 m) and 1.663 m
(L = 1.7 m), 2 % short; simulated squares of 4 m with E_d = 1.03, E_b = 1.1 (or 0.97,
0.92) 3.98 m.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.errors import InputError, given, option
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run

__all__ = ["CORNER", "CURVATURE", "LEG_TOLERANCE", "Legs", "check_side", "measure_legs"]

#: A side length that differs from the median leg by more than this share of it is
#: refused.
LEG_TOLERANCE = 0.1
#: The robot turns (at a corner) where its heading changes by more than this [rad] per
#: metre it moves: a turn of radius under half a metre, or a tracked point up to half a
#: metre off the axle swinging round a turn on the spot; legs bent by a wheel diameter
#: error curve by a tenth of that.
CURVATURE = 2.0
#: A corner turns by at least this [rad] ...
CORNER = 0.25 * math.pi
#: Fewest legs (one square) that can refuse a side length.
MIN_LEGS = 4


@dataclass(frozen=True)
class Legs:
    """The legs of the square runs of a source.

    Attributes
    ----------
    lengths : array, shape (k,)
        Each leg's length [m], as the reference measured it.
    runs : int
        How many runs had four legs.
    """

    lengths: FloatArray
    runs: int

    @property
    def median(self) -> float:
        """The median leg [m]."""
        return float(np.median(self.lengths))


def measure_legs(runs: Sequence[Run], params: WheelParams | None = None) -> Legs:
    """The legs of those of ``runs`` that drove four legs with a quarter turn between each
    two (see the module docstring); runs without a time series, without the reference's
    headings and without ``params`` to read the odometry's, or of another shape, are
    skipped."""
    lengths: list[float] = []
    counted = 0
    for run in runs:
        legs = _run_legs(run, params)
        if legs is not None:
            lengths += legs
            counted += 1
    return Legs(lengths=np.asarray(lengths, dtype=float), runs=counted)


def _run_legs(run: Run, params: WheelParams | None) -> list[float] | None:
    """The four legs [m] of one run, or None (see the module docstring)."""
    log = run.log
    if log is None:
        return None
    truth = log.truth
    if log.headings:
        heading = truth[:, 2]
    elif params is not None:
        heading = log.odometry(params)[:, 2]
    else:
        return None
    ok = np.flatnonzero(np.all(np.isfinite(truth[:, :2]), axis=1) & np.isfinite(heading))
    if ok.size < 8:
        return None
    xy, theta = truth[ok, :2], np.unwrap(heading[ok])
    step = np.hypot(*np.diff(xy, axis=0).T)
    turn = np.diff(theta)
    turning = np.abs(turn) > CURVATURE * step
    driving = ~turning & (step > 0)
    corners = _corners(turning, driving, turn)
    if len(corners) not in (3, 4):
        return None
    turns = [float(np.sum(turn[a:b])) for a, b in corners]
    if not all(CORNER <= t * np.sign(turns[0]) <= 3 * CORNER for t in turns):
        return None  # not quarter turns all one way: no square
    ends = [0, *(c for c, _ in corners), ok.size - 1]
    starts = [0, *(d for _, d in corners)]
    legs = [math.hypot(*(xy[b] - xy[a])) for a, b in zip(starts, ends[1:], strict=False)]
    return legs[:4]


def _corners(turning: BoolArray, driving: BoolArray, turn: FloatArray) -> list[tuple[int, int]]:
    """The corners of a run as sample ranges ``(first, last)``: stretches of intervals
    that turn (``turning``, shape (n - 1,)) or stand, between intervals that drive
    (``driving``), turning by at least :data:`CORNER` in all (``turn`` [rad])."""
    out = []
    start: int | None = None
    for k in range(turning.size + 1):
        if k < turning.size and turning[k]:
            start = k if start is None else start
            continue
        if start is not None and (k == turning.size or driving[k]):
            stop = int(np.flatnonzero(turning[start:k])[-1]) + start + 1
            if abs(float(np.sum(turn[start:stop]))) >= CORNER:
                out.append((start, stop))
            start = None
    return out


def check_side(
    runs: Sequence[Run],
    side: float,
    named: str,
    params: WheelParams | None = None,
    source: str | None = None,
) -> None:
    """Refuse a side length ``side`` [m] (given as ``named``: an option or a file's field)
    that the legs of ``runs`` (:func:`measure_legs`) disagree with by more than
    :data:`LEG_TOLERANCE`; nothing is checked with fewer than :data:`MIN_LEGS` legs.

    Raises
    ------
    InputError
        Naming the measured length, for ``source``.
    """
    legs = measure_legs(runs, params)
    if legs.lengths.size < MIN_LEGS:
        return
    median = legs.median
    if abs(side - median) <= LEG_TOLERANCE * median:
        return
    raise InputError(
        f"{given(named, side, 'm')}, but the reference's legs measure {median:.2f} m (median "
        f"of {legs.lengths.size} legs in {legs.runs} runs): give "
        f"{option('side_length', float(f'{median:.3g}'), 'm')}",
        source=source,
    )

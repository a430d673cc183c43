"""Finding the runs in a recording: rests near the start between runs, or given windows.

A recording of several UMBmark runs looks like this: the robot stands near the start,
drives a loop (stopping briefly at the corners), stands still again near the start while
the experimenter notes the result, drives the next loop, and so on. A run therefore ends
at a rest that is

- at least ``min_rest`` long (corner stops are shorter, or at least not all of these),
- near where the run started (within ``return_radius``), and
- after the robot has turned through most of a full loop (``|total heading change| >=
  min_turn``, 1.75 pi by default), which tells the rest at the start corner before the
  fourth turn from the rest after it.

Rests are read from the wheels (both wheel speeds under ``rest_speed``, a little creep and
short twitches included: :mod:`umbmark.runs.rests`); positions and headings from the
ground truth where there is some, else from the odometry.

As people drive them, runs also end

- at a *reset*: the ground truth jumps while the wheels stand still (the robot was
  carried back to the start, a simulation put it back). A run that made its loop
  (``min_turn - LOOSE_TURN``) ends there, however far from its start; motion that did
  not is left out, named;
- at the last rest of the recording after such a loop, however far from its start.

A run that closes its loop more than once (:meth:`_Finder.closings`: back near its start
with another ``min_turn`` turned since it last left it) is split at the stops near its
start (of any length), or left out, named.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.core.messages import info
from umbmark.model.recording import Recording
from umbmark.runs.rests import TWITCH_ANGLE, Reset, find_resets, stops

__all__ = [
    "LOOSE_TURN",
    "LeftOut",
    "Segmentation",
    "SplitOptions",
    "cut_at_resets",
    "find_runs",
    "split_by_rests",
    "split_by_windows",
    "trim_to_motion",
]


#: A run ended by a reset of the ground truth, or by the last rest of the recording, needs
#: to turn this much [rad] less than ``min_turn``: nothing else ends a run there, and a
#: robot whose four turns fall 67.5 degrees short in all still drove its square (one that
#: stopped after three turns did not).
LOOSE_TURN = math.pi / 8


@dataclass(frozen=True)
class SplitOptions:
    """Parameters of :func:`split_by_rests`.

    Attributes
    ----------
    min_rest : float
        Shortest rest that can separate runs [s].
    rest_speed : float
        Wheel speed below which a wheel is at rest [rad/s].
    return_radius : float or None
        How close to its start a run must end [m]; by default a quarter of the largest
        distance the recording strays from its first pose, at least 0.1 m.
    min_turn : float
        Least total heading change of a run [rad].
    """

    min_rest: float = 1.0
    rest_speed: float = 0.05
    return_radius: float | None = None
    min_turn: float = 1.75 * math.pi


@dataclass(frozen=True)
class LeftOut:
    """Motion that looked like a run and was left out.

    Attributes
    ----------
    first, last : int
        Its samples.
    why : str
        What was seen, for people.
    """

    first: int
    last: int
    why: str


@dataclass(frozen=True)
class Segmentation:
    """The runs of a recording, and what was seen on the way.

    Attributes
    ----------
    runs : list of (int, int)
        Each run's first and last sample.
    resets : list of Reset
        Resets of the ground truth (:mod:`umbmark.runs.rests`); runs end there.
    left_out : list of LeftOut
        Motion left out: ended by a reset before it closed its square, or closing the
        square more than once with no stop between.
    whole : bool
        No run could be told apart: ``runs`` is the recording's motion as one run (a
        path of any shape, for the estimators of whole trajectories).
    """

    runs: list[tuple[int, int]]
    resets: list[Reset] = field(default_factory=list)
    left_out: list[LeftOut] = field(default_factory=list)
    whole: bool = False


def split_by_rests(
    time: FloatArray,
    angles: FloatArray,
    poses: FloatArray,
    options: SplitOptions | None = None,
) -> list[tuple[int, int]]:
    """Runs of a recording, as sample index ranges ``(first, last)`` (both included).

    The runs of :func:`find_runs`.
    """
    return find_runs(time, angles, poses, options).runs


def find_runs(
    time: FloatArray,
    angles: FloatArray,
    poses: FloatArray,
    options: SplitOptions | None = None,
    wheel_radius: float | None = None,
) -> Segmentation:
    """Runs of a recording, split at rests near the start and at resets of the truth.

    Parameters
    ----------
    time : array, shape (n,)
    angles : array, shape (n, 2)
        Wheel rotation [rad].
    poses : array, shape (n, 3)
        Ground truth (or odometry) ``x, y, theta`` at the same samples, NaN where unknown;
        theta unwrapped.
    wheel_radius : float, optional
        [m]: the ground truth's jumps are resets too (:func:`umbmark.runs.rests.find_resets`).

    Returns
    -------
    Segmentation
        Each run from the last sample of the rest before it to the first sample of the
        rest after it. A run ends at a rest near its start after a full loop, at a reset
        of the ground truth after a full loop (wherever it is), or at the last rest of
        the recording after a full loop. A run that closes its square more than once is
        split at the stops near its start, or left out. A recording in which no run can
        be told apart is one run (its still start and end trimmed).
    """
    options = options or SplitOptions()
    known = np.all(np.isfinite(poses), axis=1)
    all_stops = stops(time, angles, options.rest_speed)
    resets = find_resets(time, angles, poses, options.rest_speed, wheel_radius)
    if not known.any():
        return Segmentation(runs=trim_to_motion(time, angles, options.rest_speed), whole=True)
    radius = options.return_radius
    if radius is None:
        first = poses[np.argmax(known)]
        spread = np.hypot(*(poses[known, :2] - first[:2]).T)
        radius = max(0.25 * float(spread.max()), 0.1)
    finder = _Finder(time, angles, poses, known, radius, options, resets)
    reset_at = {r.first for r in resets}
    rests = [(i, j) for i, j in all_stops if time[j] - time[i] >= options.min_rest or i in reset_at]
    # a jump while the wheels turned ends a run as a reset at a stop does
    rests = sorted({*rests, *((r.first, r.last) for r in resets)})
    runs, left_out = finder.loops(rests, 0, time.size - 1, open_end=True)
    kept: list[tuple[int, int]] = []
    for a, b in runs:
        closings = finder.closings(a, b)
        if closings <= 1:
            kept.append((a, b))
            continue
        inner = [(i, j) for i, j in all_stops if a < i and j < b]
        pieces, dangling = finder.loops(inner, a, b, open_end=True)
        whole = finder.closes_often(a, b, closings)
        if len(pieces) < 2:
            left_out.append(LeftOut(a, b, whole))
            continue
        left_out += dangling
        for c, d in pieces:
            if finder.closings(c, d) > 1:
                left_out.append(LeftOut(c, d, finder.closes_often(c, d, finder.closings(c, d))))
            else:
                kept.append((c, d))
    if not kept and not left_out:
        motion = trim_to_motion(time, angles, options.rest_speed)
        return Segmentation(runs=motion, resets=resets, whole=True)
    return Segmentation(runs=sorted(kept), resets=resets, left_out=left_out)


class _Finder:
    """The loop test of :func:`find_runs` on one recording."""

    def __init__(
        self,
        time: FloatArray,
        angles: FloatArray,
        poses: FloatArray,
        known: NDArray[np.bool_],
        radius: float,
        options: SplitOptions,
        resets: list[Reset],
    ) -> None:
        self.time, self.angles, self.poses, self.known = time, angles, poses, known
        self.radius, self.options = radius, options
        self.resets = {r.first: r for r in resets}
        self.candidates = np.flatnonzero(known)

    def pose(self, index: int) -> FloatArray | None:
        """The pose at sample ``index``, or at the nearest sample that has one."""
        c = self.candidates
        if c.size == 0:
            return None
        k = int(np.searchsorted(c, index))
        nearest = [int(c[j]) for j in (k - 1, k) if 0 <= j < c.size]
        return np.asarray(self.poses[min(nearest, key=lambda j: (abs(j - index), j))])

    def _moves(self, a: int, b: int) -> bool:
        """Whether a wheel turns more than a twitch from sample ``a`` to ``b``."""
        swing = np.abs(self.angles[a : b + 1] - self.angles[a])
        return b > a and float(np.max(swing)) > TWITCH_ANGLE

    def loops(
        self, rests: list[tuple[int, int]], lo: int, hi: int, *, open_end: bool
    ) -> tuple[list[tuple[int, int]], list[LeftOut]]:
        """Runs from sample ``lo`` to ``hi`` between ``rests``; ``open_end``: a full loop
        ending at ``hi`` or at the last rest with motion needs not end near its start."""
        pieces: list[tuple[int, int, tuple[int, int] | None]] = []
        previous = lo
        for i, j in rests:
            pieces.append((previous, i, (i, j)))
            previous = j
        pieces.append((previous, hi, None))
        pieces = [p for p in pieces if p[1] > p[0]]
        moving = [k for k, (a, b, _) in enumerate(pieces) if self._moves(a, b)]
        last_moving = moving[-1] if moving else -1
        runs: list[tuple[int, int]] = []
        left_out: list[LeftOut] = []
        start: int | None = None
        for k, (a, b, after) in enumerate(pieces):
            start = a if start is None else start
            begin, end = (
                self.pose(start),
                self.pose(b),
            )
            if begin is None or end is None:
                continue
            turned = abs(float(end[2] - begin[2]))
            home = math.hypot(float(end[0] - begin[0]), float(end[1] - begin[1])) <= self.radius
            reset = self.resets.get(after[0]) if after is not None else None
            final = open_end and k >= last_moving
            closed = turned >= self.options.min_turn and home
            # Put back, or done: a loop whose turns fell short by up to 22.5 degrees more.
            ended = turned >= self.options.min_turn - LOOSE_TURN and (reset is not None or final)
            if closed or ended:
                runs.append((start, b))
                start = None
            elif reset is not None:
                if self._moves(start, b):
                    why = (
                        f"{reset.describe(self.time)} before it closed its square (it turned "
                        f"{turned:.2f} rad)"
                    )
                    left_out.append(LeftOut(start, b, why))
                start = None
        return runs, left_out

    def closings(self, a: int, b: int) -> int:
        """How often the run from sample ``a`` to ``b`` closes its loop: comes back near
        its start having turned ``min_turn`` since it last left it after a loop."""
        index = np.flatnonzero(self.known[a : b + 1]) + a
        if index.size < 2:
            return 0
        p = self.poses[index]
        near = np.hypot(p[:, 0] - p[0, 0], p[:, 1] - p[0, 1]) <= self.radius
        count, reference = 0, float(p[0, 2])
        padded = np.concatenate([[False], near, [False]]).astype(np.int8)
        edges = np.flatnonzero(np.diff(padded))
        for first, stop in zip(edges[::2], edges[1::2], strict=True):
            heading = p[first:stop, 2]
            if np.any(np.abs(heading - reference) >= self.options.min_turn):
                count += 1
                reference = float(heading[-1])
        return count

    def closes_often(self, a: int, b: int, closings: int) -> str:
        """Why the run from ``a`` to ``b`` is left out: it closes its square ``closings``
        times."""
        begin, end = self.pose(a), self.pose(b)
        turned = abs(float(end[2] - begin[2])) if begin is not None and end is not None else 0.0
        return (
            f"it closes its square {closings} times (it turns {turned / math.pi:.2f} pi rad) "
            "with no stop near its start between: give each square a rest of at least "
            f"{self.options.min_rest:g} s (--min-rest), or cut them with --windows"
        )


def trim_to_motion(
    time: FloatArray, angles: FloatArray, rest_speed: float
) -> list[tuple[int, int]]:
    """The whole recording (``time`` (n,), wheel ``angles`` (n, 2)) as one run ``(first,
    last)``, without its still start and end (wheel speeds under ``rest_speed``); empty
    if the wheels never turn."""
    dt = np.diff(time)
    speed = np.abs(np.diff(angles, axis=0)) / dt[:, None]
    moving = np.flatnonzero(np.any(speed >= rest_speed, axis=1))
    if moving.size == 0:
        return []
    return [(int(moving[0]), int(moving[-1]) + 1)]


def split_by_windows(
    time: FloatArray, windows: Sequence[tuple[float, float]], source: str = ""
) -> list[tuple[int, int]]:
    """Runs given as time windows ``(start, end)`` [s from the recording's first sample].

    Raises
    ------
    InputError
        For an empty or reversed window, or one with fewer than two samples.
    """
    t = time - time[0]
    out = []
    for start, end in windows:
        if not end > start:
            raise InputError(f"time window {start:g}:{end:g} s is empty", source=source or None)
        inside = np.flatnonzero((t >= start) & (t <= end))
        if inside.size < 2:
            raise InputError(
                f"time window {start:g}:{end:g} s holds {inside.size} wheel sample(s); "
                f"the recording lasts {t[-1]:.2f} s",
                source=source or None,
            )
        out.append((int(inside[0]), int(inside[-1])))
    return out


def cut_at_resets(
    recording: Recording, resets: Sequence[Reset], rest_speed: float, notes: list[str]
) -> list[tuple[int, int]]:
    """A recording taken as one run (``--split none``) cut where its ground truth was
    reset (the robot put back: no run goes on across it), each piece trimmed to its
    motion; a line for each cut to ``notes``."""
    time, angles = recording.wheels.time, recording.wheels.angles
    if not resets:
        return [(0, time.size - 1)]
    starts = [0, *(r.last for r in resets)]
    ends = [*(r.first for r in resets), time.size - 1]
    out: list[tuple[int, int]] = []
    for a, b in zip(starts, ends, strict=True):
        if b > a:
            out += [
                (a + c, a + d)
                for c, d in trim_to_motion(time[a : b + 1], angles[a : b + 1], rest_speed)
            ]
    notes.extend(
        info(f"{recording.name}: {reset.describe(time)}: a run ends there") for reset in resets
    )
    return out

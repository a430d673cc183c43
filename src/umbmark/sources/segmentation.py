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

Rests are read from the wheels (both wheel speeds under ``rest_speed``); positions and
headings from the ground truth where there is some, else from the odometry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError

__all__ = ["SplitOptions", "split_by_rests", "split_by_windows"]

FloatArray = NDArray[np.float64]


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


def _rest_intervals(
    time: FloatArray, angles: FloatArray, options: SplitOptions
) -> list[tuple[int, int]]:
    """Index ranges ``[i, j]`` (samples) where both wheels stand still long enough."""
    dt = np.diff(time)
    speed = np.abs(np.diff(angles, axis=0)) / dt[:, None]
    still = np.all(speed < options.rest_speed, axis=1)  # per interval
    out = []
    i = 0
    n = still.size
    while i < n:
        if not still[i]:
            i += 1
            continue
        j = i
        while j < n and still[j]:
            j += 1
        # Intervals i..j-1 are still: samples i..j.
        if time[j] - time[i] >= options.min_rest:
            out.append((i, j))
        i = j
    return out


def split_by_rests(
    time: FloatArray,
    angles: FloatArray,
    poses: FloatArray,
    options: SplitOptions | None = None,
) -> list[tuple[int, int]]:
    """Runs of a recording, as sample index ranges ``(first, last)`` (both included).

    Parameters
    ----------
    time : array, shape (n,)
    angles : array, shape (n, 2)
        Wheel rotation [rad].
    poses : array, shape (n, 3)
        Ground truth (or odometry) ``x, y, theta`` at the same samples, NaN where unknown;
        theta unwrapped.

    Returns
    -------
    list of (int, int)
        Each run from the last sample of the rest before it to the first sample of the
        rest after it. A recording in which no run can be told apart is one run (its
        still start and end trimmed).
    """
    options = options or SplitOptions()
    known = np.all(np.isfinite(poses), axis=1)
    rests = _rest_intervals(time, angles, options)
    if not rests or not known.any():
        return _trim_to_motion(time, angles, options)
    radius = options.return_radius
    if radius is None:
        first = poses[np.argmax(known)]
        spread = np.hypot(*(poses[known, :2] - first[:2]).T)
        radius = max(0.25 * float(spread.max()), 0.1)

    # Stretches of motion between rests: (last sample of a rest, first sample of the next).
    edges = [0, *[k for rest in rests for k in rest], time.size - 1]
    stretches = [(edges[k], edges[k + 1]) for k in range(0, len(edges), 2)]
    stretches = [(a, b) for a, b in stretches if b > a]
    runs: list[tuple[int, int]] = []
    start: int | None = None
    for a, b in stretches:
        start = a if start is None else start
        begin, end = _known_pose(poses, known, start), _known_pose(poses, known, b)
        if begin is None or end is None:
            continue
        turned = abs(float(end[2] - begin[2]))
        home = math.hypot(float(end[0] - begin[0]), float(end[1] - begin[1])) <= radius
        if turned >= options.min_turn and home:
            runs.append((start, b))
            start = None
    return runs or _trim_to_motion(time, angles, options)


def _known_pose(poses: FloatArray, known: NDArray[np.bool_], index: int) -> FloatArray | None:
    """The pose at ``index``, or at the nearest sample that has one."""
    candidates = np.flatnonzero(known)
    if candidates.size == 0:
        return None
    nearest = candidates[np.argmin(np.abs(candidates - index))]
    return np.asarray(poses[nearest])


def _trim_to_motion(
    time: FloatArray, angles: FloatArray, options: SplitOptions
) -> list[tuple[int, int]]:
    """The whole recording as one run, without its still start and end."""
    dt = np.diff(time)
    speed = np.abs(np.diff(angles, axis=0)) / dt[:, None]
    moving = np.flatnonzero(np.any(speed >= options.rest_speed, axis=1))
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

"""Where a recording's robot stands still, and where its ground truth was reset meanwhile.

A robot told to stop does not always read as still: simulated wheels creep and jitter in
place, a real one twitches when a person touches it or a brake lets go. A *stop* is
therefore a stretch of samples where

- both wheel speeds are under the rest speed from sample to sample, or averaged over
  :data:`CREEP_WINDOW` (a slow creep, or jitter around a standstill);
- two stops, each at least :data:`BESIDE_TWITCH` long, separated by a short burst of
  motion (at most :data:`TWITCH_TIME` long, widened by the window) in which neither
  wheel turns more than :data:`TWITCH_ANGLE` from where it was, are one stop (a
  twitch); and
- a gap in the samples (:func:`umbmark.model.recording.gap_mask`: the recording paused)
  long enough to hold a twitch between two stops (``2 BESIDE_TWITCH + TWITCH_TIME``,
  0.7 s) across which neither wheel turned more than :data:`TWITCH_ANGLE` is still,
  however long: the wheels did not move meanwhile (a simulator paused while its world
  was reset); a shorter one is a recorder's hiccup, motion or not as the wheels say;
- a stop begins and ends at samples still from sample to sample, where there are any
  within half a window of its ends, so that the window does not move where the runs
  around it end and begin.

A *reset* is a stop across which the ground truth moved by more than
:data:`RESET_DISTANCE` or turned by more than :data:`RESET_TURN`: the wheels stood still,
so the robot was carried, or a simulation put back, to another place. A run cannot go on
across it.

Given the wheel radius, a reset is also a *jump*: a step of the ground truth between two
samples larger than the wheels allow in that time (:data:`JUMP_ALLOWANCE` times the two
wheels' travel, enough for a tracked point two wheelbases off the axle) by more than
:data:`JUMP_FACTOR` times the reference's own scatter (the 99th percentile of that excess
over the recording) and at least :data:`MIN_JUMP`: a simulator's world reset that puts
the robot back at its start between squares, however little it strayed from there, and
whether or not the wheels stood still meanwhile. A localization that corrects itself by
centimetres (AMCL) scatters by as much, and stays below; a jump that the next one undoes
(:data:`GLITCH_RETURN`) is a tracker that lost the robot for a while, no reset.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.model.recording import gap_mask

__all__ = [
    "CREEP_WINDOW",
    "GLITCH_RETURN",
    "JUMP_ALLOWANCE",
    "JUMP_FACTOR",
    "MIN_JUMP",
    "RESET_DISTANCE",
    "RESET_TURN",
    "TWITCH_ANGLE",
    "TWITCH_TIME",
    "Reset",
    "find_resets",
    "still_intervals",
    "stops",
]


#: Wheel speeds are also averaged over this long a window [s] to tell creep from motion.
CREEP_WINDOW = 0.5
#: A burst of motion between two stops at most this long [s] ...
TWITCH_TIME = 0.3
#: ... in which neither wheel turns more than this [rad] is a twitch inside one stop ...
TWITCH_ANGLE = 0.5
#: ... if the stops on either side last at least this long [s].
BESIDE_TWITCH = 0.2
#: The ground truth moving this far [m] ...
RESET_DISTANCE = 0.1
#: ... or turning this far [rad] while the wheels stand still is a reset (a localization
#: that corrects itself by a few centimetres at a stop is not).
RESET_TURN = 0.2
#: A step of the ground truth is within what the wheels allow up to this many times the
#: two wheels' travel in that time ...
JUMP_ALLOWANCE = 2.0
#: ... beyond which it is a jump when it exceeds this many times the reference's scatter
#: (the 99th percentile of the excess over the recording) ...
JUMP_FACTOR = 10.0
#: ... and this [m].
MIN_JUMP = 0.01
#: A jump the next one undoes to within this share of the larger is no reset but a
#: tracker that lost the robot and found it again (left to the checks of the ground
#: truth's steps and to the fit).
GLITCH_RETURN = 0.25


def still_intervals(time: FloatArray, angles: FloatArray, rest_speed: float) -> BoolArray:
    """Which intervals of the recording belong to a stop, shape (n - 1,).

    Parameters
    ----------
    time : array, shape (n,)
        Wheel sample times [s], increasing.
    angles : array, shape (n, 2)
        Wheel angles [rad].
    rest_speed : float
        Wheel speed under which a wheel stands still [rad/s].
    """
    dt = np.diff(time)
    speed = np.abs(np.diff(angles, axis=0)) / dt[:, None]
    still: BoolArray = np.all(speed < rest_speed, axis=1)
    if still.size == 0:
        return still
    # A gap in the samples long enough to hold a twitch between two stops, across which
    # the wheels turned at most a twitch: a rest.
    rest_gap = gap_mask(time) & (dt >= 2 * BESIDE_TWITCH + TWITCH_TIME)
    still |= rest_gap & np.all(np.abs(np.diff(angles, axis=0)) <= TWITCH_ANGLE, axis=1)
    # Creep: the speed over a window around each interval (at least the interval itself).
    middle = 0.5 * (time[:-1] + time[1:])
    low = np.minimum(np.maximum(middle - 0.5 * CREEP_WINDOW, time[0]), time[:-1])
    high = np.maximum(np.minimum(middle + 0.5 * CREEP_WINDOW, time[-1]), time[1:])
    moved = np.column_stack(
        [np.interp(high, time, angles[:, w]) - np.interp(low, time, angles[:, w]) for w in (0, 1)]
    )
    creeping = np.all(np.abs(moved) / (high - low)[:, None] < rest_speed, axis=1)
    merged = _merge_twitches(time, angles, still | creeping)
    # A stop begins and ends where the wheels stand still from sample to sample, if they
    # do within half a window of its ends: the window must not move the runs' ends.
    out: BoolArray = merged.copy()
    for begin, end in _true_runs(merged):
        inside = np.flatnonzero(still[begin:end]) + begin
        if inside.size == 0:
            continue
        first, last = int(inside[0]), int(inside[-1]) + 1
        if time[first] - time[begin] <= 0.5 * CREEP_WINDOW:
            out[begin:first] = False
        if time[end] - time[last] <= 0.5 * CREEP_WINDOW:
            out[last:end] = False
    return out


def _true_runs(mask: BoolArray) -> list[tuple[int, int]]:
    """Maximal runs of True in ``mask`` as ``(first, stop)`` slices."""
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _merge_twitches(time: FloatArray, angles: FloatArray, still: BoolArray) -> BoolArray:
    """``still`` with short, small bursts of motion between two stops that last made still
    (shorter stops inside a burst do not split it)."""
    out: BoolArray = still.copy()
    lasting = [(a, b) for a, b in _true_runs(still) if time[b] - time[a] >= BESIDE_TWITCH]
    for (_, end), (begin, _) in itertools.pairwise(lasting):
        # Motion from sample ``end`` to sample ``begin``; the creep window widens a
        # twitch by up to a window.
        if time[begin] - time[end] > TWITCH_TIME + CREEP_WINDOW:
            continue
        swing = np.abs(angles[end : begin + 1] - angles[end])
        if float(np.max(swing)) <= TWITCH_ANGLE:
            out[end:begin] = True
    return out


def stops(time: FloatArray, angles: FloatArray, rest_speed: float) -> list[tuple[int, int]]:
    """The stops of a recording, as sample ranges ``(first, last)`` (see the module)."""
    return [(a, b) for a, b in _true_runs(still_intervals(time, angles, rest_speed))]


@dataclass(frozen=True)
class Reset:
    """A reset of the ground truth during a stop.

    Attributes
    ----------
    first, last : int
        The stop: from sample ``first`` to sample ``last``.
    at : int
        The sample after the largest step of the ground truth in it: where it jumped.
    moved : float
        How far the ground truth moved across it [m].
    turned : float
        How far it turned [rad].
    allowed : float or None
        A jump (see the module): how far the wheels allow the ground truth to move
        meanwhile [m]; None for a reset found at a stop.
    """

    first: int
    last: int
    at: int
    moved: float
    turned: float
    allowed: float | None = None

    def describe(self, time: FloatArray, origin: float | None = None) -> str:
        """``the ground truth was reset at 35.20 s (it moved 0.50 m and turned 0.10 rad
        while the wheels stood still)``; ``time`` holds the sample times the indices
        count, ``origin`` the time [s] times are given from (default ``time[0]``)."""
        at = float(time[self.at] - (time[0] if origin is None else origin))
        if self.allowed is not None:
            return (
                f"the ground truth was reset at {at:.2f} s (it jumped {self.moved:.3f} m in "
                f"{float(time[self.last] - time[self.first]):.2f} s, where the wheels allow "
                f"{self.allowed:.3f} m)"
            )
        return (
            f"the ground truth was reset at {at:.2f} s (it moved {self.moved:.2f} m and "
            f"turned {self.turned:.2f} rad while the wheels stood still)"
        )


def find_resets(
    time: FloatArray,
    angles: FloatArray,
    poses: FloatArray,
    rest_speed: float,
    wheel_radius: float | None = None,
) -> list[Reset]:
    """The stops across which the ground truth ``poses`` (shape (n, 3), NaN rows where
    unknown, theta unwrapped) moved and, given ``wheel_radius`` [m], its jumps (see the
    module docstring), in time order."""
    found = _stop_resets(time, angles, poses, rest_speed)
    if wheel_radius is None:
        return found
    all_stops = stops(time, angles, rest_speed)
    for jump in _jumps(time, angles, poses, wheel_radius):
        if any(r.first <= jump.first and jump.last <= r.last for r in found):
            continue  # a reset at a stop already
        inside = [(a, b) for a, b in all_stops if a <= jump.first and jump.last <= b]
        if inside:  # at a stop: a run ends at the stop, as at any reset there
            a, b = inside[0]
            found.append(Reset(a, b, jump.at, jump.moved, jump.turned, jump.allowed))
        else:
            found.append(jump)
    return sorted(found, key=lambda r: r.first)


def _jumps(
    time: FloatArray, angles: FloatArray, poses: FloatArray, wheel_radius: float
) -> list[Reset]:
    """The steps of the ground truth the wheels cannot explain (see the module), from
    each sample with a position to the next one (a reference that missed samples, as
    around a pause of the recording, steps across them)."""
    rows = np.flatnonzero(np.all(np.isfinite(poses[:, :2]), axis=1))
    if rows.size < 3:
        return []
    known = poses[rows]
    step = np.hypot(*np.diff(known[:, :2], axis=0).T)
    wheels = np.concatenate([[0.0], np.cumsum(np.sum(np.abs(np.diff(angles, axis=0)), axis=1))])
    allowed = JUMP_ALLOWANCE * wheel_radius * np.diff(wheels[rows])
    excess = step - allowed
    scatter = float(np.percentile(np.maximum(excess, 0.0), 99))
    limit = max(MIN_JUMP, JUMP_FACTOR * scatter)
    # A reference slower than the wheels spreads one jump over several wheel intervals.
    found = _true_runs(excess > limit)
    shifts = [known[stop, :2] - known[first, :2] for first, stop in found]
    glitch = set()
    for k in range(len(found) - 1):  # out and back again: a tracker that lost the robot
        back = float(np.hypot(*(shifts[k] + shifts[k + 1])))
        if back < GLITCH_RETURN * max(float(np.hypot(*shifts[k])), float(np.hypot(*shifts[k + 1]))):
            glitch |= {k, k + 1}
    out = []
    for k, (first, stop) in enumerate(found):
        if k in glitch:
            continue
        a, b = known[first], known[stop]
        moved = math.hypot(float(b[0] - a[0]), float(b[1] - a[1]))
        turn = abs(float(b[2] - a[2])) if np.isfinite(a[2]) and np.isfinite(b[2]) else 0.0
        largest = first + int(np.argmax(step[first:stop]))
        out.append(
            Reset(
                int(rows[first]),
                int(rows[stop]),
                int(rows[largest + 1]),
                moved,
                turn,
                float(np.sum(allowed[first:stop])),
            )
        )
    return out


def _stop_resets(
    time: FloatArray, angles: FloatArray, poses: FloatArray, rest_speed: float
) -> list[Reset]:
    """The resets at stops (see the module docstring)."""
    known = np.all(np.isfinite(poses), axis=1)
    out = []
    for first, last in stops(time, angles, rest_speed):
        inside = np.flatnonzero(known[first : last + 1]) + first
        if inside.size < 2:
            continue
        a, b = poses[inside[0]], poses[inside[-1]]
        moved = math.hypot(float(b[0] - a[0]), float(b[1] - a[1]))
        turned = abs(float(b[2] - a[2]))
        if moved > RESET_DISTANCE or turned > RESET_TURN:
            steps = np.diff(poses[inside], axis=0)
            size = np.hypot(steps[:, 0], steps[:, 1]) + np.abs(steps[:, 2])
            at = int(inside[int(np.argmax(size)) + 1])
            out.append(Reset(first=first, last=last, at=at, moved=moved, turned=turned))
    return out

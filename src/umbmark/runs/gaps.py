"""Gaps in the wheel samples: a while without a message is a gap, not a jump.

Wheel samples come at a typical period, the median interval of the recording. An interval
much longer than that (:func:`umbmark.model.recording.gap_mask`: more than
:data:`~umbmark.model.recording.GAP_FACTOR` periods and more than
:data:`~umbmark.model.recording.MIN_GAP`) is a gap: the messages stopped for a while (a
recorder that could not keep up, a dropped connection, a simulation that paused). The
wheels went on turning meanwhile, so the step of a wheel angle across a gap is large; it
is not a corrupt sample, and the checks for jumps leave gaps out. What happened inside a
gap is known only at its two ends, so odometry can cross it as one arc only when the
motion was steady:

- a gap is **bridged** (its interval integrated like any other) when the wheels did not
  turn across it (their speed across it under a rest speed, or, across one longer than
  :data:`MAX_BRIDGE`, their turn at most a twitch,
  :data:`~umbmark.runs.rests.TWITCH_ANGLE`, and one arc across it within
  :data:`MAX_ARC_ERROR` of any path: a rest, as :mod:`umbmark.runs.rests` takes it, where
  a reset of the ground truth ends a run), or when it is at most :data:`MAX_BRIDGE` long
  and either each wheel turned across it at the speed it had in the :data:`SPEED_WINDOW`
  before it and after it (within :data:`BRIDGE_TOLERANCE` of the larger speed, plus a
  rest speed), or the robot barely turned across it (one arc ends at most
  :data:`MAX_ARC_ERROR` from any path of the same length and turn, whatever the speeds
  did: a recorder's hiccup while the robot speeds up);
- otherwise the path across it is unknown: the run holding it is left out, or, where
  the recording holds no loop to tell runs apart (its motion is one run of any shape),
  the recording is split there and the motion on either side is a run of its own (see
  :func:`umbmark.runs.logged.runs_from_recordings`).

Times in messages are seconds from the recording's first wheel sample, as ``--windows``
takes them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import gap_mask
from umbmark.runs.rests import TWITCH_ANGLE

__all__ = [
    "BRIDGE_TOLERANCE",
    "MAX_ARC_ERROR",
    "MAX_BRIDGE",
    "SPEED_WINDOW",
    "Gap",
    "describe_gaps",
    "find_gaps",
]


#: Longest gap bridged when the wheels turned across it [s].
MAX_BRIDGE = 2.0
#: A gap is bridged when one arc across it ends at most this far [m] from any path of
#: the same length and turn (half the length times the turn): it barely turned.
MAX_ARC_ERROR = 0.002
#: How far before and after a gap the wheel speeds are measured [s].
SPEED_WINDOW = 0.5
#: Wheel speeds across a gap and around it agree when they differ by at most this share
#: of the largest of them, plus the rest speed.
BRIDGE_TOLERANCE = 0.1
#: Wheel speed under which a wheel is taken to stand still [rad/s].
REST_SPEED = 0.05
#: More bridged gaps than this in a recording are summed up in one line.
LISTED_GAPS = 3


@dataclass(frozen=True)
class Gap:
    """One gap in the wheel samples.

    Attributes
    ----------
    index : int
        The interval: between samples ``index`` and ``index + 1``.
    start : float
        When it began [s from the recording's first wheel sample].
    duration : float
        Its length [s].
    turned : tuple of float
        How far each wheel (left, right) turned across it [rad].
    travel : float or None
        How far the wheels moved across it, the mean of both wheels' travel [m]; None
        without wheel parameters.
    bridged : bool
        Whether odometry crosses it as one arc.
    why : str
        Why it was bridged or not, for people.
    """

    index: int
    start: float
    duration: float
    turned: tuple[float, float]
    travel: float | None
    bridged: bool
    why: str

    def describe(self, sample: str = "wheel sample") -> str:
        """``no /odom message for 1.76 s from 41.20 s (the wheels moved 0.66 m
        meanwhile)``; ``sample`` names one wheel sample (``/odom message``)."""
        if self.travel is not None:
            moved = f"{self.travel:.2f} m"
        else:
            moved = f"{max(abs(v) for v in self.turned):.3g} rad"
        return (
            f"no {sample} for {self.duration:.2f} s from {self.start:.2f} s (the wheels "
            f"moved {moved} meanwhile)"
        )


def find_gaps(
    time: FloatArray,
    angles: FloatArray,
    params: WheelParams | None = None,
    origin: float | None = None,
) -> list[Gap]:
    """The gaps of a recording and whether each is bridged (see the module docstring).

    Parameters
    ----------
    time : array, shape (n,)
        Wheel sample times [s], increasing.
    angles : array, shape (n, 2)
        Wheel angles [rad], left and right.
    params : WheelParams, optional
        For the travel in metres.
    origin : float, optional
        The recording's first sample time [s] (default ``time[0]``).
    """
    origin = float(time[0]) if origin is None else origin
    out = []
    for k in np.flatnonzero(gap_mask(time)):
        index = int(k)
        dt = float(time[index + 1] - time[index])
        step = angles[index + 1] - angles[index]
        travel = error = None
        if params is not None:
            radius = 0.5 * params.wheel_diameter
            d_left, d_right = params.c_left * radius * step[0], params.c_right * radius * step[1]
            travel = 0.5 * (abs(d_left) + abs(d_right))
            turn = (d_right - d_left) / params.wheelbase
            error = 0.5 * abs(0.5 * (d_left + d_right) * turn)
        bridged, why = _bridge(time, angles, index, error)
        out.append(
            Gap(
                index=index,
                start=float(time[index]) - origin,
                duration=dt,
                turned=(float(step[0]), float(step[1])),
                travel=travel,
                bridged=bridged,
                why=why,
            )
        )
    return out


def _speed(time: FloatArray, angles: FloatArray, first: int, last: int) -> FloatArray | None:
    """Mean wheel speeds, shape (2,), from sample ``first`` to ``last``; None if equal."""
    if last <= first:
        return None
    return np.asarray((angles[last] - angles[first]) / (time[last] - time[first]))


def _bridge(time: FloatArray, angles: FloatArray, k: int, error: float | None) -> tuple[bool, str]:
    """Whether the gap after sample ``k`` is bridged, and why (see the module docstring);
    ``error`` bounds how far one arc across it may end from the path driven [m]."""
    dt = float(time[k + 1] - time[k])
    across = (angles[k + 1] - angles[k]) / dt
    if np.all(np.abs(across) < REST_SPEED):
        return True, "the wheels did not turn across it"
    if dt > MAX_BRIDGE:
        turned = float(np.max(np.abs(angles[k + 1] - angles[k])))
        if turned <= TWITCH_ANGLE and (error is None or error <= MAX_ARC_ERROR):
            return True, (
                f"the wheels did not move across it (they turned {turned:.2f} rad at most, "
                "a twitch): a rest"
            )
        return False, f"longer than {MAX_BRIDGE:g} s while the wheels turned"
    before, after = _speeds_around(time, angles, k)
    if before is not None and after is not None:
        largest = np.max(np.abs(np.vstack([before, across, after])), axis=0)
        tolerance = BRIDGE_TOLERANCE * largest + REST_SPEED
        if np.all(np.abs(across - before) <= tolerance) and np.all(
            np.abs(across - after) <= tolerance
        ):
            return True, "the wheels turned across it at the speeds they had before and after it"
    if error is not None and error <= MAX_ARC_ERROR:
        return True, (
            f"one arc across it ends at most {1000.0 * error:.1f} mm from any path of its "
            "length and turn"
        )
    if before is None or after is None:
        return False, "no wheel samples on both sides to compare its speed with"
    shown = ", ".join(
        f"{side} {b:.2f}, {a:.2f}, {c:.2f}"
        for side, b, a, c in zip(("left", "right"), before, across, after, strict=True)
    )
    return False, (
        f"the wheels changed speed (before, across, after it: {shown} rad/s): the path "
        "across it is unknown"
    )


def _speeds_around(
    time: FloatArray, angles: FloatArray, k: int
) -> tuple[FloatArray | None, FloatArray | None]:
    """Mean wheel speeds, each shape (2,) or None, in the :data:`SPEED_WINDOW` before the
    gap after sample ``k`` and after it, up to the next gap on either side."""
    gaps = gap_mask(time)
    first = int(np.searchsorted(time, time[k] - SPEED_WINDOW, side="left"))
    last = int(np.searchsorted(time, time[k + 1] + SPEED_WINDOW, side="right")) - 1
    before_gaps = np.flatnonzero(gaps[first:k])
    if before_gaps.size:
        first = first + int(before_gaps[-1]) + 1
    after_gaps = np.flatnonzero(gaps[k + 1 : last])
    if after_gaps.size:
        last = k + 1 + int(after_gaps[0])
    return _speed(time, angles, first, k), _speed(time, angles, k + 1, last)


def describe_gaps(gaps: list[Gap], sample: str = "wheel sample") -> list[str]:
    """Lines for people about bridged gaps: one each, or one for many."""
    bridged = [g for g in gaps if g.bridged]
    if len(bridged) <= LISTED_GAPS:
        return [f"{g.describe(sample)}: bridged, {g.why}" for g in bridged]
    longest = max(bridged, key=lambda g: g.duration)
    return [
        f"{len(bridged)} gaps without a {sample} ({min(g.duration for g in bridged):.2f} to "
        f"{longest.duration:.2f} s) bridged, the wheels turning steadily or not at all; the "
        f"longest: {longest.describe(sample)}"
    ]

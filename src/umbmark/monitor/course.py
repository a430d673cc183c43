"""The robot's course on the monitor: each stretch of driving one calibration of it, each
figure followed by the fleet's change model (:func:`umbmark.calibration.changes.change_of`,
the same module ``umbmark fleet`` and ``umbmark history`` judge with).

A stretch is :attr:`~umbmark.monitor.setup.MonitorSetup.stretch_metres` of wheel travel,
calibrated on its own (:mod:`umbmark.monitor.estimate`); stretches do not overlap. The
course is kept for the last :data:`MAX_STRETCHES` stretches of each figure, on the
odometer's axis (metres driven: it goes on when the clock goes back). A change in the
latest stretch alone is found, to be confirmed (``latest``); confirmed once the next
stretch agrees (``step``): a change is flagged within the stretch it began in and the two
after it. A confirmed change's size is the stretches' after the one it fell in, where it
has any (:meth:`Course.found`): that one holds both states, and pooled with the rest it
would pull the size towards the value before by a share its interval does not hold. A
trend (tyres wearing over weeks) is not flagged here, nor the gyro's bias
(:data:`umbmark.calibration.changes.FOLLOWED`: it wanders; its present value is the
latest stretch's).

Whether a change is beyond what the robot's navigation tolerates (:func:`beyond`): the
odometry's error per metre driven or radian turned it makes, against the tolerance.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from umbmark.calibration.changes import FOLLOWED, Change, change_of, followed_of
from umbmark.monitor.status import ChangeFound

__all__ = ["MAX_STRETCHES", "Z95", "Course", "StretchPoint", "beyond"]

#: The stretches kept per figure (bounded memory; a day of driving at 20 m a stretch).
MAX_STRETCHES = 500
#: z of a 95 % interval.
Z95 = 1.959964


def beyond(name: str, size: float, tolerance: float, wheelbase: float) -> bool:
    """Whether a change of ``size`` in figure ``name`` is more than the navigation
    tolerates: ``E_d``'s heading drift per metre driven straight (its change over the
    wheelbase [rad/m]); the others' change itself (``E_s``, ``E_b``, ``k_g`` per metre or
    radian, the laser's x, y [m] and yaw [rad]). The gyro's bias is followed, not judged."""
    if name == "gyro_bias":
        return False
    effect = abs(size) / wheelbase if name == "E_d" else abs(size)
    return effect > tolerance


@dataclass(frozen=True)
class StretchPoint:
    """One stretch's figure: value and standard error, when it began (the robot's clock
    [s], the odometer [m]) and the wall clock [s since 1970]."""

    value: float
    se: float
    time: float
    odometer: float
    wall: float


def _after_the_mixed(series: deque[StretchPoint], change: Change) -> tuple[float, float]:
    """A step's size and its standard error from the stretches after the first of its
    present state (the stretch the change fell in, part before it and part after), the
    change model's scatter scaling kept; the model's own where the change model left the
    stretch before that first one out as unsettled (then the first is after the change
    whole) or no other stretch is in the present state."""
    since = change.since
    assert since is not None
    left_out = {*change.one_offs, *change.unsettled}
    later = [p for k, p in enumerate(series) if k > since and k not in left_out]
    if since - 1 in change.unsettled or not later:
        return change.size, change.size_se
    before = change.value - change.size  # the mean before the step
    before_var = max(change.size_se**2 - change.se**2, 0.0)
    weights = np.array([1.0 / p.se**2 for p in later])
    value = float(np.sum(weights * np.array([p.value for p in later])) / np.sum(weights))
    se = change.birge / math.sqrt(float(np.sum(weights)))
    return value - before, math.sqrt(se**2 + before_var)


class Course:
    """Every figure's stretches, and what the change model makes of them."""

    def __init__(self) -> None:
        self.points: dict[str, deque[StretchPoint]] = {}
        self._changes: dict[str, Change] = {}  # the change model's, until the next stretch

    def add(self, name: str, point: StretchPoint) -> None:
        """One stretch's figure (in order of the odometer)."""
        series = self.points.setdefault(name, deque(maxlen=MAX_STRETCHES))
        if series and point.odometer <= series[-1].odometer:
            point = StretchPoint(point.value, point.se, point.time,
                                 series[-1].odometer + 1e-6, point.wall)  # fmt: skip
        series.append(point)
        self._changes.pop(name, None)

    def change(self, name: str) -> Change | None:
        """The figure's course by the change model; None without stretches."""
        series = self.points.get(name)
        if not series:
            return None
        if name in self._changes:
            return self._changes[name]
        odo = np.array([p.odometer for p in series])
        values = np.array([p.value for p in series])
        errors = np.array([p.se for p in series])
        judge = followed_of if name in FOLLOWED else change_of
        self._changes[name] = judge(odo, values, errors)
        return self._changes[name]

    def found(
        self, name: str, tolerance: float, wheelbase: float
    ) -> tuple[Change | None, ChangeFound | None]:
        """The figure's course and the change it shows now (a latest or a step), if any."""
        change = self.change(name)
        if name in FOLLOWED or change is None or change.kind not in ("latest", "step"):
            return change, None
        if change.since is None:
            return change, None
        first = self.points[name][change.since]
        size, size_se = change.size, change.size_se
        if change.kind == "step":
            size, size_se = _after_the_mixed(self.points[name], change)
        return change, ChangeFound(
            figure=name,
            size=size,
            size_half_width=Z95 * size_se,
            since=first.time,
            since_metres=first.odometer,
            confirmed=change.kind == "step",
            beyond_tolerance=beyond(name, change.size, tolerance, wheelbase),
        )

    def present(self, name: str) -> tuple[float, float] | None:
        """The figure's present value and standard error by the course (since its last
        change); None without stretches."""
        change = self.change(name)
        if change is None or not math.isfinite(change.se):
            return None
        return change.value, change.se

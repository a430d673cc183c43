"""Whether one of a robot's calibrated figures changed over time, beyond its own intervals:
the robot's course, told as the recordings arrived.

Each figure (``E_d``, ``E_b``, ``E_s``, the laser's x, y, yaw; a gyro's scale) is a
series of calibrations ``v_i`` with standard errors ``s_i`` at times ``t_i``, oldest
first. The course is one of four (:attr:`Change.kind`):

- **steady**: one value, the weighted mean of every calibration (weights ``1 / s_i^2``);
- **latest**: the newest calibration disagrees with the course before it: a change in the
  latest recording, still to be confirmed. The robot's present state is that calibration
  alone, never a value pooled across the change;
- **step**: one value before a calibration and another from it on (a wheel changed, a
  laser knocked), confirmed by the calibrations after it (the one that showed it and one
  that agreed with it); a robot may step more than once (:attr:`Change.steps`), and its
  present state is the value since its last step;
- **trend**: a straight line in time since the last step (tyres wearing), over at least
  :data:`MIN_TREND` calibrations.

A **one-off** is a calibration that disagreed with the course while the next one returned
to it (a bad recording): it is left out of the figures and named (:attr:`Change.
one_offs`). A calibration that disagreed with the course, and with which the next one
disagreed too (neither back nor confirming it), is **unsettled** (:attr:`Change.
unsettled`): left out, the next one judged against the course before both.

The series is read as the recordings arrived (:func:`change_of` replays it, oldest
first), so the story one morning is the story of the day before and one more recording:
each calibration is judged against the prediction of the present state before it (its
mean, or its trend line at the calibration's time), and a disagreement counts beyond
:data:`Z_CHANGE` of its standard errors. Every judgement counts over-dispersion: the
standard errors are scaled by the Birge ratio ``B = sqrt(chi^2 / dof)`` of the course so
far (every state since the first, each about its own mean or line, where it exceeds 1),
so that calibrations that scatter more than their intervals say do not make a change out
of that scatter, and every pooled value carries the scatter in its interval. Once the
whole series is read, the course is settled with the scatter of all of it: a step, a
one-off or a latest change that the whole course's Birge ratio no longer supports is
undone (it was within the robot's scatter after all), and the present state is searched
for a step no single calibration showed (at least :data:`MIN_SIDE` calibrations on each
side, the split with the least chi^2) and for a trend.

The threshold is high because so many comparisons are made: a Gaussian's two-sided tail
beyond 5 sigma is 6e-7, so a steady robot is flagged in well under one of a thousand
series of 30 (``tests/calibration/test_changes.py`` measures it on simulated series, with
errors as stated and three times as large). With two or three calibrations the scatter
cannot be told from the series: they are compared on their stated intervals, and
:attr:`Change.compared` says how many were compared.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError

__all__ = [
    "FOLLOWED",
    "MIN_SIDE",
    "MIN_TREND",
    "SECONDS_PER_WEEK",
    "Z_CHANGE",
    "Change",
    "change_of",
    "followed_of",
]

#: A change counts beyond this many of its own standard errors.
Z_CHANGE = 5.0
#: Fewest calibrations on each side of a step that no single calibration showed.
MIN_SIDE = 3
#: Fewest calibrations a trend is fitted to.
MIN_TREND = 4
#: Seconds in a week (a trend is said per week).
SECONDS_PER_WEEK = 7 * 86400.0
#: Figures followed on their course but never judged (:func:`followed_of`): a MEMS gyro's
#: bias wanders (its random walk, about 7 deg/h of instability at 2e-4 deg/s/sqrt(s),
#: moves it by several of a calibration's standard errors within the hour; its turn-on
#: bias and its temperature move it from one power-up to the next) and is no change of
#: the robot's odometry: each calibration fits its own, and drivers remove it at rest.
FOLLOWED = frozenset({"gyro_bias"})

Kind = Literal["steady", "latest", "step", "trend"]


@dataclass(frozen=True)
class Change:
    """What the series did: the robot's course and its present state.

    Attributes
    ----------
    kind : {"steady", "latest", "step", "trend"}
        No change beyond the intervals; a change in the latest calibration, to be
        confirmed; a step, confirmed; a trend since the last step.
    value : float
        The robot's present value: the mean of a steady series, the latest calibration
        alone, the mean since the last step, the trend's line at the last time.
    se : float
        Its standard error (scaled by ``birge``).
    since : int or None
        The first calibration of the present state after a change (the latest for
        ``latest``, the first after the last step for ``step``); None otherwise.
    size : float
        The present value minus the value before the change (``latest``: against the
        prediction of the course before it; ``step``: against the mean before the step);
        a trend's change per week; 0 when steady.
    size_se : float
        The standard error of ``size`` (scaled).
    birge : float
        The Birge ratio the standard errors were scaled by (1 when they were not).
    steps : tuple of int
        Every step, oldest first: the first calibration after each (the last is
        ``since`` for ``step``; a ``latest`` change is not among them).
    one_offs : tuple of int
        Calibrations left out as one-offs (the next returned to the course).
    unsettled : tuple of int
        Calibrations left out that disagreed with the course and with the next one.
    compared : int
        The calibrations the judgement compared: for ``latest``, those of the present
        state it disagrees with; for ``step``, those before the last step; else those of
        the present state.
    confirmed_by : int
        The calibrations of the present state (1 for ``latest``).
    """

    kind: Kind
    value: float
    se: float
    since: int | None = None
    size: float = 0.0
    size_se: float = 0.0
    birge: float = 1.0
    steps: tuple[int, ...] = ()
    one_offs: tuple[int, ...] = ()
    unsettled: tuple[int, ...] = ()
    compared: int = 0
    confirmed_by: int = 0

    @property
    def z(self) -> float:
        """The change in its standard errors (0 when steady)."""
        return abs(self.size) / self.size_se if self.size_se > 0 else 0.0

    @property
    def changed(self) -> bool:
        """A change beyond the intervals: latest, step or trend."""
        return self.kind != "steady"


@dataclass
class _State:
    """One state of the robot: its calibrations and their weighted sums (values centred,
    times in weeks from the series' start)."""

    members: list[int] = field(default_factory=list)
    w: float = 0.0
    wv: float = 0.0
    wvv: float = 0.0
    wt: float = 0.0
    wtt: float = 0.0
    wtv: float = 0.0

    @classmethod
    def of(cls, members: Sequence[int], t: FloatArray, v: FloatArray, s: FloatArray) -> _State:
        state = cls()
        for i in sorted(members):
            state.add(i, t, v, s)
        return state

    def add(self, i: int, t: FloatArray, v: FloatArray, s: FloatArray) -> None:
        w, x, y = 1.0 / float(s[i]) ** 2, float(t[i]), float(v[i])
        self.members.append(i)
        self.w += w
        self.wv += w * y
        self.wvv += w * y * y
        self.wt += w * x
        self.wtt += w * x * x
        self.wtv += w * x * y

    @property
    def n(self) -> int:
        return len(self.members)

    def mean(self) -> tuple[float, float, float]:
        """The weighted mean, its standard error (unscaled) and the chi^2 about it."""
        mean = self.wv / self.w
        return mean, 1.0 / math.sqrt(self.w), max(self.wvv - self.wv * mean, 0.0)

    def line(self) -> tuple[float, float, FloatArray, float] | None:
        """The weighted straight line ``a + b t``: ``a``, ``b`` (per week), their
        covariance (unscaled) and the chi^2 about it; None with fewer than
        :data:`MIN_TREND` calibrations or no spread in time."""
        det = self.w * self.wtt - self.wt * self.wt
        if self.n < MIN_TREND or det <= 1e-12 * self.w * self.wtt:
            return None
        b = (self.w * self.wtv - self.wt * self.wv) / det
        a = (self.wv - b * self.wt) / self.w
        cov = np.array([[self.wtt, -self.wt], [-self.wt, self.w]]) / det
        chi2 = self.wvv - 2 * a * self.wv - 2 * b * self.wtv
        chi2 += a * a * self.w + 2 * a * b * self.wt + b * b * self.wtt
        return a, b, cov, max(chi2, 0.0)


@dataclass
class _Course:
    """The course so far: the settled states (oldest first; the last is the present),
    the one-offs, the unsettled calibrations, and the calibration off the course still
    waiting for the next."""

    states: list[_State]
    one_offs: set[int] = field(default_factory=set)
    unsettled: set[int] = field(default_factory=set)
    pending: int | None = None

    def trend(self) -> tuple[float, float, FloatArray, float] | None:
        """The present state's line where its slope exceeds :data:`Z_CHANGE` of its
        standard error (scaled by the line's own Birge ratio), else None."""
        line = self.states[-1].line()
        return line if line is not None and self._slope_passes(line, self.states[-1]) else None

    def birge(self) -> float:
        """The Birge ratio of the course: every state about its own mean (the present
        one about its line where that is its model), floored at 1."""
        chi2, dof = 0.0, 0
        for k, state in enumerate(self.states):
            line = state.line() if k == len(self.states) - 1 else None
            if line is not None and self._slope_passes(line, state):
                chi2, dof = chi2 + line[3], dof + state.n - 2
            else:
                chi2, dof = chi2 + state.mean()[2], dof + state.n - 1
        return max(1.0, math.sqrt(chi2 / dof)) if dof > 0 else 1.0

    @staticmethod
    def _slope_passes(line: tuple[float, float, FloatArray, float], state: _State) -> bool:
        """Whether a line's slope passes the threshold on its own scatter."""
        _, b, cov, chi2 = line
        dof = state.n - 2
        own = max(1.0, math.sqrt(chi2 / dof)) if dof > 0 else 1.0
        return abs(b) > Z_CHANGE * own * math.sqrt(cov[1, 1])

    def predict(self, at: float) -> tuple[float, float]:
        """The present state's value at time ``at`` [weeks] and its standard error
        (unscaled)."""
        line = self.trend()
        if line is not None:
            a, b, cov, _ = line
            x = np.array([1.0, at])
            return a + b * at, math.sqrt(float(x @ cov @ x))
        mean, se, _ = self.states[-1].mean()
        return mean, se


def _off(course: _Course, i: int, t: FloatArray, v: FloatArray, s: FloatArray) -> float:
    """Calibration ``i`` against the present state's prediction, in its standard errors
    scaled by the course's Birge ratio."""
    birge = course.birge()
    value, se = course.predict(float(t[i]))
    return abs(float(v[i]) - value) / (birge * math.hypot(float(s[i]), se))


def _replay(t: FloatArray, v: FloatArray, s: FloatArray) -> _Course:
    """The course as the calibrations arrived (see the module)."""
    course = _Course([_State.of([0], t, v, s)])
    for i in range(1, len(v)):
        if _off(course, i, t, v, s) <= Z_CHANGE:  # on the course
            if course.pending is not None:
                course.one_offs.add(course.pending)
                course.pending = None
            course.states[-1].add(i, t, v, s)
            continue
        x = course.pending
        if x is None:
            course.pending = i
            continue
        birge = course.birge()
        if abs(v[i] - v[x]) <= Z_CHANGE * birge * math.hypot(s[i], s[x]):  # confirmed
            course.states.append(_State.of([x, i], t, v, s))
            course.pending = None
        else:
            course.unsettled.add(x)
            course.pending = i
    return course


def _merge(course: _Course, t: FloatArray, v: FloatArray, s: FloatArray) -> bool:
    """Undo the weakest step the whole course's Birge ratio no longer supports (merging
    its two states); whether one was undone."""
    birge = course.birge()
    weakest: tuple[float, int] | None = None
    for k in range(1, len(course.states)):
        (m0, se0, _), (m1, se1, _) = course.states[k - 1].mean(), course.states[k].mean()
        z = abs(m1 - m0) / (birge * math.hypot(se0, se1))
        if z <= Z_CHANGE and (weakest is None or z < weakest[0]):
            weakest = (z, k)
    if weakest is None:
        return False
    k = weakest[1]
    joined = course.states[k - 1].members + course.states[k].members
    course.states[k - 1 : k + 1] = [_State.of(joined, t, v, s)]
    return True


def _state_of(course: _Course, i: int) -> int:
    """The state a left-out calibration lies in by time (the last that started before)."""
    starts = [min(state.members) for state in course.states]
    return max(k for k, start in enumerate(starts) if start < i) if i > starts[0] else 0


def _reinstate(course: _Course, t: FloatArray, v: FloatArray, s: FloatArray) -> bool:
    """Take back one left-out calibration (a one-off or unsettled one) that lies within
    the whole course's scatter of its state; whether one was taken back."""
    birge = course.birge()
    for i in sorted(course.one_offs | course.unsettled):
        k = _state_of(course, i)
        mean, se, _ = course.states[k].mean()
        if abs(v[i] - mean) <= Z_CHANGE * birge * math.hypot(s[i], se):
            course.one_offs.discard(i)
            course.unsettled.discard(i)
            course.states[k] = _State.of([*course.states[k].members, i], t, v, s)
            return True
    return False


def _hidden_step(course: _Course, t: FloatArray, v: FloatArray, s: FloatArray) -> bool:
    """Split the present state where a step no single calibration showed lies beyond the
    threshold (at least :data:`MIN_SIDE` calibrations on each side, the split with the
    least chi^2, scaled by the Birge ratio of the course with it); whether it was split."""
    present = sorted(course.states[-1].members)
    n = len(present)
    if n < 2 * MIN_SIDE:
        return False
    idx = np.array(present)
    w, y = 1.0 / s[idx] ** 2, v[idx] - np.sum(v[idx] / s[idx] ** 2) / np.sum(1.0 / s[idx] ** 2)
    cw, cwv, cwv2 = np.cumsum(w), np.cumsum(w * y), np.cumsum(w * y * y)
    ks = np.arange(MIN_SIDE, n - MIN_SIDE + 1)
    w1, s1, q1 = cw[ks - 1], cwv[ks - 1], cwv2[ks - 1]
    w2, s2, q2 = cw[-1] - w1, cwv[-1] - s1, cwv2[-1] - q1
    chi2 = (q1 - s1 * s1 / w1) + (q2 - s2 * s2 / w2)
    k = int(ks[int(np.argmin(chi2))])
    split = _Course([*course.states[:-1], _State.of(present[:k], t, v, s),
                     _State.of(present[k:], t, v, s)])  # fmt: skip
    (m0, se0, _), (m1, se1, _) = split.states[-2].mean(), split.states[-1].mean()
    if abs(m1 - m0) <= Z_CHANGE * split.birge() * math.hypot(se0, se1):
        return False
    if course.trend() is not None:  # a trend explains it: the better fit wins
        line = course.states[-1].line()
        if line is not None and line[3] <= split.states[-2].mean()[2] + split.states[-1].mean()[2]:
            return False
    course.states[-1:] = split.states[-2:]
    return True


def _settle(course: _Course, t: FloatArray, v: FloatArray, s: FloatArray) -> _Course:
    """The course with the scatter of the whole series (see the module)."""
    for _ in range(4 * len(v)):  # each pass undoes or takes back one: bounded
        if not (_merge(course, t, v, s) or _reinstate(course, t, v, s)):
            break
    if course.pending is not None and _off(course, course.pending, t, v, s) <= Z_CHANGE:
        course.states[-1].add(course.pending, t, v, s)
        course.pending = None
    if course.pending is None:
        _hidden_step(course, t, v, s)
    return course


def _said(course: _Course, t: FloatArray, v: FloatArray, s: FloatArray, unit: float) -> Change:
    """The :class:`Change` a settled course says (``unit``: the values' centre added back)."""
    birge = course.birge()
    present = course.states[-1]
    steps = tuple(min(state.members) for state in course.states[1:])
    left = (tuple(sorted(course.one_offs)), tuple(sorted(course.unsettled)))
    if course.pending is not None:
        i = course.pending
        value, se = course.predict(float(t[i]))
        return Change(
            "latest", float(v[i]) + unit, float(s[i]) * birge, i, float(v[i]) - value,
            birge * math.hypot(float(s[i]), se), birge, steps, *left, present.n, 1,
        )  # fmt: skip
    line = course.trend()
    if line is not None:
        a, b, cov, _ = line
        x = np.array([1.0, float(t[max(present.members)])])
        value, se = a + b * float(x[1]), math.sqrt(float(x @ cov @ x))
        return Change("trend", value + unit, se * birge, None, b,
                      math.sqrt(cov[1, 1]) * birge, birge, steps, *left, present.n,
                      present.n)  # fmt: skip
    mean, se, _ = present.mean()
    if not steps:
        return Change("steady", mean + unit, se * birge, None, 0.0, 0.0, birge, (), *left,
                      present.n, present.n)  # fmt: skip
    m0, se0, _ = course.states[-2].mean()
    return Change("step", mean + unit, se * birge, steps[-1], mean - m0,
                  birge * math.hypot(se, se0), birge, steps, *left, course.states[-2].n,
                  present.n)  # fmt: skip


def _checked(
    times: FloatArray, values: FloatArray, errors: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    t, v, s = (np.asarray(a, dtype=np.float64) for a in (times, values, errors))
    n = len(v)
    if n < 1 or t.shape != (n,) or s.shape != (n,) or v.shape != (n,):
        raise InputError(f"a series needs matching times, values and errors, got {n}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise InputError("a series' times and values must be finite")
    if not np.all(np.isfinite(s) & (s > 0)):
        raise InputError("a series' standard errors must be positive and finite")
    if np.any(np.diff(t) < 0):
        raise InputError("a series' times must be in order, oldest first")
    return t, v, s


def followed_of(times: FloatArray, values: FloatArray, errors: FloatArray) -> Change:
    """The course of a figure followed, not judged (:data:`FOLLOWED`): ``steady``, its
    present value the latest calibration alone (what the figure is now, never a mean over
    its wandering). Parameters and errors as :func:`change_of`."""
    _, v, s = _checked(times, values, errors)
    return Change("steady", float(v[-1]), float(s[-1]), compared=1, confirmed_by=1)


def change_of(times: FloatArray, values: FloatArray, errors: FloatArray) -> Change:
    """The course of a figure over its calibrations (see the module).

    Parameters
    ----------
    times : array, shape (n,)
        When each calibration's recording was made [s], oldest first.
    values : array, shape (n,)
        The figure of each calibration.
    errors : array, shape (n,)
        Its standard errors (positive, finite).

    Returns
    -------
    Change

    Raises
    ------
    InputError
        For fewer than one calibration, arrays of different lengths, times not in order,
        or standard errors that are not positive and finite.
    """
    t, v, s = _checked(times, values, errors)
    centre = float(np.sum(v / s**2) / np.sum(1.0 / s**2))  # the sums lose no digits
    weeks = (t - t[0]) / SECONDS_PER_WEEK
    course = _settle(_replay(weeks, v - centre, s), weeks, v - centre, s)
    return _said(course, weeks, v - centre, s, centre)

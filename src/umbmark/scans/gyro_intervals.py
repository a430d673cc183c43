"""Motion intervals of the wheels against a gyro: what the gyro estimator compares.

A recording's wheels (:class:`~umbmark.model.recording.WheelSeries`) and its gyro
(:class:`~umbmark.model.gyro_series.GyroSeries`, rates in the base frame) are cut into short
intervals, each with the wheels' rotation over it and the gyro's integrated rates:

- **rests**: the wheels stand still (:func:`umbmark.runs.rests.still_intervals`, the
  stops the runs are split at), trimmed by ``rest_margin`` at both ends (the robot
  settles; a brake lets go), kept where at least ``min_rest`` remains, and cut into
  pieces of at most ``rest_piece``: over them the gyro reads its bias alone, piece by
  piece, so a bias that wanders is followed;
- **driving**: everything between two rests kept, their margins included (a motion's
  first and last moments, below a tick of the encoders or the rest speed, are then in a
  driving interval for the wheels and the gyro alike: trimmed away, the wheels would
  count them and the gyro not), cut into equal pieces of at most ``interval`` (pieces
  shorter than ``min_interval`` are left out): over each the wheels' rotations against
  the gyro's heading change.

Every interval begins and ends at a wheel sample (its ends moved to the nearest): the
wheels' rotations are their readings, the gyro's rates are integrated to those times.

Both within the time both cover. An interval is left out, and counted by its reason, when
the gyro has a gap in it (:func:`umbmark.model.recording.gap_mask`), when the wheels have
one in a driving interval, when the gyro saturates in it (an axis held at its extreme:
:func:`umbmark.model.gyro_series.saturated_stretches`, the one rule the bag's reader names them
by too): a turn faster than its range reads short), or when it crosses a stretch the
gyro's reader found it could not have read (``excluded``: a frozen IMU, by
:func:`umbmark.model.gyro_series.frozen_stretches`).

The gyro's integrals are exact for its samples joined by straight lines (the trapezoid
rule, as :meth:`GyroSeries.yaw_change`); its yaw rate at an interval's two ends, the
same way, gives the rate's change across it (``rate_change``): what a delay of the gyro's
readings against the wheels' makes of the interval's heading change, to first order (a
reading that is the mean over its period, a MEMS part's decimation filter, lags by half
of it: 10 ms at 50 Hz). Units: seconds, radians, m/s^2.
"""

from __future__ import annotations

import itertools
import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.errors import InputError
from umbmark.model.gyro_series import GyroSeries, saturated_stretches
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.recording import WheelSeries, gap_mask
from umbmark.runs.rests import still_intervals

__all__ = [
    "DEFAULT_GYRO_OPTIONS",
    "SATURATED",
    "GyroIntervalOptions",
    "GyroIntervals",
    "GyroReference",
    "HeadingReference",
    "gyro_intervals",
    "gyro_reference",
]

#: The reason intervals across a saturated stretch are left out by.
SATURATED = "gyro saturated"


@dataclass(frozen=True)
class GyroIntervalOptions:
    """How a recording is cut (the module's documentation).

    Attributes
    ----------
    interval : float
        Longest driving interval [s].
    min_interval : float
        Shortest driving interval kept [s].
    rest_speed : float
        Wheel speed under which a wheel stands still [rad/s].
    rest_margin : float
        Trimmed from both ends of a stop [s].
    min_rest : float
        Shortest rest kept after trimming [s].
    rest_piece : float
        Longest piece a rest is cut into [s].
    """

    interval: float = 1.0
    min_interval: float = 0.2
    rest_speed: float = 0.05
    rest_margin: float = 0.2
    min_rest: float = 0.4
    rest_piece: float = 2.0

    def __post_init__(self) -> None:
        values = (self.interval, self.min_interval, self.rest_speed, self.min_rest)
        if not all(math.isfinite(v) and v > 0.0 for v in (*values, self.rest_piece)):
            raise ValueError("GyroIntervalOptions needs positive, finite durations and speed")
        if self.min_interval > self.interval or not 0.0 <= self.rest_margin <= 10.0:
            raise ValueError("GyroIntervalOptions needs min_interval <= interval, margin 0-10 s")


DEFAULT_GYRO_OPTIONS = GyroIntervalOptions()


@dataclass(frozen=True)
class GyroIntervals:
    """``n`` intervals of the wheels against the gyro, in time order.

    Attributes
    ----------
    start, end : array, shape (n,)
        Each interval's ends [s] on the recording's clock.
    phi_left, phi_right : array, shape (n,)
        The wheels' rotation over it [rad] (forward positive).
    yaw : array, shape (n,)
        The gyro's yaw rate integrated over it [rad], as read (bias and scale in it).
    rotation : array, shape (n, 3)
        All three rates integrated over it [rad] (base frame x, y, z).
    rest : array of bool, shape (n,)
        The wheels stood still throughout.
    accel : array, shape (n, 3), or None
        The mean acceleration over it [m/s^2] where the IMU gives it.
    left_out : dict of str to int
        Intervals left out, by reason.
    source : str
        The gyro's source, for messages.
    frame : str
        The IMU's own frame.
    rate_change : array, shape (n,), or None
        The gyro's yaw rate at the interval's end less at its start [rad/s], as read
        (None: not known, taken as 0).
    """

    start: FloatArray
    end: FloatArray
    phi_left: FloatArray
    phi_right: FloatArray
    yaw: FloatArray
    rotation: FloatArray
    rest: BoolArray
    accel: FloatArray | None = None
    left_out: dict[str, int] = field(default_factory=dict)
    source: str = ""
    frame: str = "imu_link"
    rate_change: FloatArray | None = None

    def __post_init__(self) -> None:
        n = self.start.shape[0]
        for name in ("end", "phi_left", "phi_right", "yaw", "rest"):
            if getattr(self, name).shape != (n,):
                raise ValueError(f"GyroIntervals.{name} must have shape ({n},)")
        if self.rate_change is not None and self.rate_change.shape != (n,):
            raise ValueError(f"GyroIntervals.rate_change must have shape ({n},)")
        if self.rotation.shape != (n, 3) or (self.accel is not None and self.accel.shape != (n, 3)):
            raise ValueError(f"GyroIntervals.rotation and accel must have shape ({n}, 3)")

    def __len__(self) -> int:
        return int(self.start.shape[0])

    @property
    def duration(self) -> FloatArray:
        """``(n,)`` how long each interval lasts [s]."""
        return np.asarray(self.end - self.start)

    def select(self, rows: BoolArray) -> GyroIntervals:
        """The intervals ``rows`` (a mask of shape (n,))."""
        return GyroIntervals(
            self.start[rows], self.end[rows], self.phi_left[rows], self.phi_right[rows],
            self.yaw[rows], self.rotation[rows], self.rest[rows],
            None if self.accel is None else self.accel[rows], dict(self.left_out),
            self.source, self.frame,
            None if self.rate_change is None else self.rate_change[rows],
        )  # fmt: skip

    @property
    def rate_changes(self) -> FloatArray:
        """``(n,)`` :attr:`rate_change`, zeros where not known."""
        if self.rate_change is None:
            return np.zeros(len(self))
        return self.rate_change


def _true_runs(mask: BoolArray) -> list[tuple[int, int]]:
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _pieces(begin: float, end: float, longest: float) -> list[tuple[float, float]]:
    """``[begin, end]`` in equal pieces of at most ``longest``."""
    count = max(1, math.ceil((end - begin) / longest - 1e-9))
    edges = np.linspace(begin, end, count + 1)
    return [(float(a), float(b)) for a, b in itertools.pairwise(edges)]


def _cut(
    wheels: WheelSeries, span: tuple[float, float], options: GyroIntervalOptions
) -> tuple[list[tuple[float, float, bool]], Counter[str]]:
    """The intervals ``(start, end, rest)`` within ``span``, and those left out by reason.

    The rests are the stops trimmed by the margin; driving is everything between two
    rests kept, margins included: a motion's first and last moments (below a tick of the
    encoders, or the rest speed) are then inside a driving interval for the wheels and the
    gyro alike, not lost to the gyro while the wheels count them."""
    time, low, high = wheels.time, span[0], span[1]
    still = still_intervals(time, wheels.angles, options.rest_speed)
    rests: list[tuple[float, float]] = []
    left: Counter[str] = Counter()
    for a, b in _true_runs(still):
        # no margin where the stop begins or ends the recording: nothing moves there
        begin, end = max(float(time[a]), low), min(float(time[b]), high)
        begin += options.rest_margin if begin > low else 0.0
        end -= options.rest_margin if end < high else 0.0
        if end - begin >= options.min_rest:
            rests.append((begin, end))
        elif end > begin:
            left["rest too short"] += 1
    out = [(s, e, True) for begin, end in rests for s, e in _pieces(begin, end, options.rest_piece)]
    edges = [low, *(t for rest in rests for t in rest), high]
    for begin, end in zip(edges[::2], edges[1::2], strict=True):
        if end - begin >= options.min_interval:
            out += [(s, e, False) for s, e in _pieces(begin, end, options.interval)]
        elif end > begin:
            left["too short"] += 1
    out.sort()
    return _snapped(out, time), left


def _snapped(
    cut: list[tuple[float, float, bool]], time: FloatArray
) -> list[tuple[float, float, bool]]:
    """``cut`` with every end moved to the nearest wheel sample: the wheels' angles are
    then their readings, not interpolated (an interpolation's error at a cut during an
    acceleration correlates with the turn's change across it, which biases the fit)."""
    if not cut:
        return cut
    ends = np.array([[c[0], c[1]] for c in cut])
    i = np.clip(np.searchsorted(time, ends), 1, time.size - 1)
    nearer = np.where(ends - time[i - 1] <= time[i] - ends, i - 1, i)
    snapped = time[nearer]
    return [(float(a), float(b), c[2]) for (a, b), c in zip(snapped, cut, strict=True) if b > a]


def _gap_spans(time: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The gaps of ``time`` as ``(begin, end)`` arrays."""
    gaps = gap_mask(time)
    return time[:-1][gaps], time[1:][gaps]


def _crosses(spans: tuple[FloatArray, FloatArray], start: FloatArray, end: FloatArray) -> BoolArray:
    """Which intervals overlap one of ``spans`` (sorted, disjoint)."""
    begin, finish = spans
    if begin.size == 0:
        return np.zeros(start.shape, dtype=bool)
    # the first span ending after each start: it overlaps when it begins before the end
    k = np.searchsorted(finish, start, side="right")
    inside = k < begin.size
    hit = np.zeros(start.shape, dtype=bool)
    hit[inside] = begin[k[inside]] < end[inside]
    return hit


def _spans(stretches: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Stretches ``(k, 2)`` as sorted, disjoint ``(begin, end)`` arrays."""
    if stretches.size == 0:
        return np.zeros(0), np.zeros(0)
    order = np.argsort(stretches[:, 0])
    merged: list[list[float]] = []
    for a, b in stretches[order].tolist():
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    both = np.array(merged, dtype=np.float64)
    return both[:, 0], both[:, 1]


def _held(gyro: GyroSeries, stretches: FloatArray) -> FloatArray:
    """Saturated stretches widened to the readings on either side (the rate between them
    and the first or last clipped reading is clipped too), shape (k, 2)."""
    t = gyro.time
    if stretches.size == 0:
        return np.zeros((0, 2))
    i = np.searchsorted(t, stretches[:, 0])
    j = np.searchsorted(t, stretches[:, 1])
    return np.column_stack([t[np.maximum(i - 1, 0)], t[np.minimum(j + 1, t.size - 1)]])


def _integrals(
    time: FloatArray, values: FloatArray, start: FloatArray, end: FloatArray
) -> FloatArray:
    """``(k, m)`` the integrals of ``values`` (``(n, m)``, joined by straight lines)
    from each ``start`` to each ``end``."""
    dt = np.diff(time)
    cumulative = np.vstack(
        [
            np.zeros((1, values.shape[1])),
            np.cumsum(0.5 * (values[1:] + values[:-1]) * dt[:, None], 0),
        ]
    )

    def at(x: FloatArray) -> FloatArray:
        i = np.clip(np.searchsorted(time, x, side="right") - 1, 0, time.size - 2)
        step = (x - time[i])[:, None]
        slope = (values[i + 1] - values[i]) / dt[i][:, None]
        return np.asarray(cumulative[i] + values[i] * step + 0.5 * slope * step * step)

    return at(end) - at(start)


def gyro_intervals(
    wheels: WheelSeries,
    gyro: GyroSeries,
    options: GyroIntervalOptions = DEFAULT_GYRO_OPTIONS,
    *,
    excluded: Mapping[str, FloatArray] | None = None,
) -> GyroIntervals:
    """A recording's wheels and gyro cut into intervals (the module's documentation).

    ``excluded`` maps a reason to stretches ``(k, 2)`` [s] the gyro did not read (the
    reader's frozen and saturated ones: :attr:`umbmark.sources.bag.imu.ImuRead.frozen`);
    an interval across one is left out by that reason. Without :data:`SATURATED` among
    them, the saturated stretches are found here
    (:func:`umbmark.model.gyro_series.saturated_stretches`).

    Raises
    ------
    InputError
        The gyro and the wheels do not overlap in time, or no interval is left (naming
        the gyro's source).
    """
    where = gyro.source or None
    if len(gyro) < 2 or wheels.time.size < 2:
        raise InputError("the gyro and the wheels need two readings each at least", source=where)
    low = max(float(wheels.time[0]), float(gyro.time[0]))
    high = min(float(wheels.time[-1]), float(gyro.time[-1]))
    if high <= low:
        raise InputError(
            f"the gyro's readings ({gyro.time[0]:.2f} to {gyro.time[-1]:.2f} s) and the "
            f"wheels' ({wheels.time[0]:.2f} to {wheels.time[-1]:.2f} s) do not overlap in time",
            source=where,
        )
    cut, left = _cut(wheels, (low, high), options)
    if cut:
        start, end = (np.array([c[i] for c in cut], dtype=np.float64) for i in (0, 1))
        rest = np.array([c[2] for c in cut], dtype=bool)
    else:
        start = end = np.zeros(0)
        rest = np.zeros(0, dtype=bool)
    keep = np.ones(start.shape, dtype=bool)
    stretches = dict(excluded or {})
    if SATURATED not in stretches:
        stretches[SATURATED] = saturated_stretches(gyro.time, gyro.rate)
    stretches[SATURATED] = _held(gyro, np.asarray(stretches[SATURATED]).reshape(-1, 2))
    for reason, hit in (
        ("gap in the gyro", _crosses(_gap_spans(gyro.time), start, end)),
        ("gap in the wheels", _crosses(_gap_spans(wheels.time), start, end) & ~rest),
        *(
            (why, _crosses(_spans(np.asarray(spans).reshape(-1, 2)), start, end))
            for why, spans in stretches.items()
        ),
    ):
        dropped = hit & keep
        if dropped.any():
            left[reason] += int(dropped.sum())
        keep &= ~dropped
    start, end, rest = start[keep], end[keep], rest[keep]
    if start.size == 0:
        raise InputError(
            "no interval of driving or rest within the time the gyro and the wheels both "
            "cover" + (f" (left out: {_said(left)})" if left else ""),
            source=where,
        )
    angles = [
        np.interp(end, wheels.time, wheels.angles[:, w])
        - np.interp(start, wheels.time, wheels.angles[:, w])
        for w in (0, 1)
    ]
    rotation = _integrals(gyro.time, gyro.rate, start, end)
    accel = None
    if gyro.accel is not None:
        accel = _integrals(gyro.time, gyro.accel, start, end) / (end - start)[:, None]
    return GyroIntervals(
        start=start,
        end=end,
        phi_left=np.asarray(angles[0]),
        phi_right=np.asarray(angles[1]),
        yaw=gyro.yaw_change(start, end),
        rotation=rotation,
        rest=rest,
        accel=accel,
        left_out=dict(left),
        source=gyro.source,
        frame=gyro.frame,
        rate_change=_rate_change(gyro, start, end),
    )


def _rate_change(gyro: GyroSeries, start: FloatArray, end: FloatArray) -> FloatArray:
    """``(k,)`` the gyro's yaw rate at each ``end`` less at each ``start`` [rad/s] (its
    samples joined by straight lines)."""
    w = gyro.rate[:, 2]
    return np.asarray(np.interp(end, gyro.time, w) - np.interp(start, gyro.time, w))


def _said(left: Counter[str]) -> str:
    return ", ".join(f"{n} {why}" for why, n in sorted(left.items()))


# --- a heading reference over the same recording ----------------------------------------


@dataclass(frozen=True)
class HeadingReference:
    """An absolute heading reference's heading changes: motion capture, corner fixes, a
    localization that does not use the gyro.

    Attributes
    ----------
    start, end : array, shape (n,)
        Each stretch's ends [s] on the recording's clock.
    yaw : array, shape (n,)
        The robot's heading change over it [rad] (counter-clockwise positive, not wrapped).
    variance : array, shape (n,), or None
        Each heading change's variance [rad^2] where the reference gives one (used as
        relative weights: their scale is fitted to the residuals).
    source : str
        Where it came from, for messages.
    """

    start: FloatArray
    end: FloatArray
    yaw: FloatArray
    variance: FloatArray | None = None
    source: str = ""

    def __post_init__(self) -> None:
        n = self.start.shape[0]
        for name in ("end", "yaw"):
            if getattr(self, name).shape != (n,):
                raise ValueError(f"HeadingReference.{name} must have shape ({n},)")
        if self.variance is not None and self.variance.shape != (n,):
            raise ValueError(f"HeadingReference.variance must have shape ({n},)")


@dataclass(frozen=True)
class GyroReference:
    """A reference's heading changes with the gyro's over the same stretches.

    Attributes
    ----------
    start, end, yaw, variance : array, shape (n,)
        As :class:`HeadingReference` (``variance`` NaN where none is given).
    gyro_yaw : array, shape (n,)
        The gyro's yaw rate integrated over each stretch [rad].
    motion : MotionIntervals or None
        The same stretches as scan matching's motion intervals (the reference gives the
        distance too: its translation), else None.
    left_out : dict of str to int
        Stretches left out (outside the gyro's readings, across a gap in them).
    source : str
    phi_left, phi_right : array, shape (n,), or None
        The wheels' rotation over each stretch [rad] (scan matching's own, or the wheels'
        readings where they were given), NaN where the wheels do not cover it; None: not
        known. Where known, the gyro estimator sets the wheels, the gyro and the reference
        side by side over the same stretch (:mod:`umbmark.estimators.gyro_fit`).
    rate_change : array, shape (n,), or None
        The gyro's yaw rate at each stretch's end less at its start [rad/s].
    """

    start: FloatArray
    end: FloatArray
    yaw: FloatArray
    variance: FloatArray
    gyro_yaw: FloatArray
    motion: MotionIntervals | None = None
    left_out: dict[str, int] = field(default_factory=dict)
    source: str = ""
    phi_left: FloatArray | None = None
    phi_right: FloatArray | None = None
    rate_change: FloatArray | None = None

    def __len__(self) -> int:
        return int(self.start.shape[0])

    @property
    def paired(self) -> BoolArray:
        """``(n,)`` the stretches whose wheels' rotation is known."""
        if self.phi_left is None or self.phi_right is None:
            return np.zeros(len(self), dtype=bool)
        return np.asarray(np.isfinite(self.phi_left) & np.isfinite(self.phi_right))

    @property
    def rate_changes(self) -> FloatArray:
        """``(n,)`` :attr:`rate_change`, zeros where not known."""
        if self.rate_change is None:
            return np.zeros(len(self))
        return self.rate_change


def gyro_reference(
    gyro: GyroSeries,
    reference: HeadingReference | MotionIntervals,
    wheels: WheelSeries | None = None,
) -> GyroReference:
    """The reference's stretches within the gyro's readings, with the gyro's heading
    change over each, and the wheels' rotation: scan matching's own, or, for heading
    changes, the ``wheels``' readings (interpolated at the stretch's ends; NaN outside
    them and across a gap in them).

    Raises
    ------
    InputError
        Motion intervals without times (a tuple file: they cannot be set beside the
        gyro), values that are not finite, or no stretch within the gyro's readings.
    """
    where = reference.source or None
    motion = reference if isinstance(reference, MotionIntervals) else None
    if isinstance(reference, MotionIntervals):
        if reference.start_time is None:
            raise InputError(
                "the motion intervals carry no times (a tuple file): they cannot be set "
                "beside the gyro's readings; match the scans of the same recording",
                source=where,
            )
        start = reference.start_time
        end = start + reference.duration
        yaw = reference.sensor_motion[:, 2]
        cov = reference.sensor_covariance
        variance = np.full(start.shape, np.nan) if cov is None else cov[:, 2, 2]
    else:
        start, end, yaw = reference.start, reference.end, reference.yaw
        variance = (
            reference.variance if reference.variance is not None else np.full(start.shape, np.nan)
        )
    if not (np.isfinite(start).all() and np.isfinite(end).all() and np.isfinite(yaw).all()):
        raise InputError(
            "the heading reference holds values that are not finite numbers", source=where
        )
    if (end <= start).any():
        raise InputError("a stretch of the heading reference ends before it starts", source=where)
    left: Counter[str] = Counter()
    inside = (start >= gyro.time[0]) & (end <= gyro.time[-1])
    if (~inside).any():
        left["outside the gyro's readings"] += int((~inside).sum())
    gap = _crosses(_gap_spans(gyro.time), start, end) & inside
    if gap.any():
        left["gap in the gyro"] += int(gap.sum())
    keep = inside & ~gap
    if not keep.any():
        raise InputError(
            "no stretch of the heading reference lies within the gyro's readings", source=where
        )
    start, end = start[keep], end[keep]
    phi: tuple[FloatArray, FloatArray] | None = None
    if motion is not None:
        motion = motion.rows(keep)
        phi = (motion.phi_left, motion.phi_right)
    elif wheels is not None:
        phi = _wheel_rotation(wheels, start, end)
    return GyroReference(
        start=start,
        end=end,
        yaw=yaw[keep],
        variance=np.asarray(variance[keep], dtype=np.float64),
        gyro_yaw=gyro.yaw_change(start, end),
        motion=motion,
        left_out=dict(left),
        source=reference.source,
        phi_left=None if phi is None else phi[0],
        phi_right=None if phi is None else phi[1],
        rate_change=_rate_change(gyro, start, end),
    )


def _wheel_rotation(
    wheels: WheelSeries, start: FloatArray, end: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``(phi_left, phi_right)`` over each stretch [rad], NaN where the wheels' readings
    do not cover it or have a gap in it."""
    t = wheels.time
    covered = (start >= t[0]) & (end <= t[-1]) & ~_crosses(_gap_spans(t), start, end)
    out = []
    for w in (0, 1):
        turned = np.interp(end, t, wheels.angles[:, w]) - np.interp(start, t, wheels.angles[:, w])
        out.append(np.where(covered, turned, np.nan))
    return out[0], out[1]

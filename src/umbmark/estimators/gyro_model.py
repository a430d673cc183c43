"""The gyro estimator's model and figures (:mod:`umbmark.estimators.gyro` says what
they are): the rows of its least squares, each figure's value and gradient, which of them
the motion determines and why not, and the calibration they make."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.core.messages import blocking
from umbmark.estimators.gyro_fit import DRIVING, PAIRED, REFERENCE, REST, LinearFit, Rows, fit_rows
from umbmark.estimators.gyro_fit import _antiderivative as antiderivative
from umbmark.estimators.gyro_mounting import gyro_mounting
from umbmark.estimators.gyro_result import FIGURES, GyroCalibration
from umbmark.estimators.scan_excitation import excitation
from umbmark.estimators.scan_matching import ScanCalibration
from umbmark.model.kinematics import WheelParams
from umbmark.scans.gyro_intervals import GyroIntervals, GyroReference

__all__ = ["calibration_of", "gyro_rows", "odometry_turns"]

#: A figure whose standard error exceeds this is not determined either: E_d 5 %, E_b 20 %,
#: k_g 20 %, the bias 1 deg/s.
_LOOSE = {
    "E_d": 0.05, "E_b_k_g": 0.2, "E_b": 0.2, "E_s": 0.2, "k_g": 0.2, "bias": math.radians(1.0),
}  # fmt: skip
#: The gyro's turning gain ``S = E_s / (E_b k_g)`` a robot's gyro can have: a wheelbase
#: and a gyro scale within a third of the nominal.
_GAIN = (0.6, 1.6)


# --- the rows ----------------------------------------------------------------------------


def odometry_turns(
    intervals: GyroIntervals, active: WheelParams
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(theta_odo, F, U_R^2 + U_L^2)`` of each interval (the module's documentation)."""
    b = active.wheelbase
    u_r = 0.5 * active.diameter_right * intervals.phi_right / b
    u_l = 0.5 * active.diameter_left * intervals.phi_left / b
    return u_r - u_l, u_r + u_l, u_r * u_r + u_l * u_l


def gyro_rows(
    intervals: GyroIntervals, active: WheelParams, reference: GyroReference | None
) -> Rows:
    """The rows of the fit (:mod:`umbmark.estimators.gyro_fit`): the gyro's intervals,
    then the reference's stretches, each the wheels' row (:data:`PAIRED`) and the
    reference's where the wheels over it are known, the reference's alone elsewhere. The
    columns: ``theta_odo``, ``F``, the reference's heading change (with one), then the
    gyro's delay's (minus the gyro's rate change across the row: one delay against the
    wheels and the reference alike, on one clock, so that it cancels in a pair's
    difference). The gyro's intervals mostly within paired stretches are left out
    (:data:`_COVERED`)."""
    theta, forward, wheel = odometry_turns(intervals, active)
    kind = np.where(intervals.rest, REST, DRIVING).astype(np.int64)
    wheel = np.where(intervals.rest, 0.0, wheel)
    change = intervals.rate_changes
    if reference is None:
        return Rows(
            y=intervals.yaw, x=np.column_stack([theta, forward, -change]),
            start=intervals.start, end=intervals.end, kind=kind, wheel=wheel,
            given=np.full(len(intervals), np.nan), delays=1,
        )  # fmt: skip
    paired = reference.paired
    covered = _covered(
        intervals.start, intervals.end, reference.start[paired], reference.end[paired]
    )
    own = covered <= _COVERED * intervals.duration
    n, m = int(own.sum()), len(reference)
    # the stretches' rows: each paired stretch twice (its wheels' row, then its reference's)
    stretch = np.repeat(np.arange(m), np.where(paired, 2, 1))
    first = np.concatenate([[True], stretch[1:] != stretch[:-1]])
    on_wheels = first & paired[stretch]
    u_r = 0.5 * active.diameter_right * _nan_zero(reference.phi_right, m) / active.wheelbase
    u_l = 0.5 * active.diameter_left * _nan_zero(reference.phi_left, m) / active.wheelbase
    size = n + stretch.size
    x = np.zeros((size, 4))
    x[:n, 0], x[:n, 1], x[:n, 3] = theta[own], forward[own], -change[own]
    x[n:, 0] = np.where(on_wheels, (u_r - u_l)[stretch], 0.0)
    x[n:, 1] = np.where(on_wheels, (u_r + u_l)[stretch], 0.0)
    x[n:, 2] = np.where(on_wheels, 0.0, reference.yaw[stretch])
    x[n:, 3] = -reference.rate_changes[stretch]
    kinds = np.where(on_wheels, PAIRED, REFERENCE).astype(np.int64)
    wheels = np.where(on_wheels, (u_r * u_r + u_l * u_l)[stretch], 0.0)
    return Rows(
        y=np.concatenate([intervals.yaw[own], reference.gyro_yaw[stretch]]),
        x=x,
        start=np.concatenate([intervals.start[own], reference.start[stretch]]),
        end=np.concatenate([intervals.end[own], reference.end[stretch]]),
        kind=np.concatenate([kind[own], kinds]),
        wheel=np.concatenate([wheel[own], wheels]),
        given=np.concatenate(
            [np.full(n, np.nan), np.where(on_wheels, np.nan, reference.variance[stretch])]
        ),
        noisy=2,
        delays=1,
    )


#: A gyro interval more than this share of which lies within the reference's paired
#: stretches is left out of the rows: the pairs hold its wheels and gyro.
_COVERED = 0.25


def _nan_zero(values: FloatArray | None, size: int) -> FloatArray:
    """``values`` with 0 for NaN (zeros of ``size`` for None)."""
    if values is None:
        return np.zeros(size)
    return np.asarray(np.where(np.isfinite(values), values, 0.0))


def _covered(
    start: FloatArray, end: FloatArray, begin: FloatArray, finish: FloatArray
) -> FloatArray:
    """``(n,)`` how long each ``[start, end]`` lies within the union of the stretches
    ``[begin, finish]`` [s]."""
    if begin.size == 0:
        return np.zeros(start.shape)
    order = np.argsort(begin)
    lows, highs = [float(begin[order[0]])], [float(finish[order[0]])]
    for a, b in zip(begin[order[1:]], finish[order[1:]], strict=True):
        if a <= highs[-1]:
            highs[-1] = max(highs[-1], float(b))
        else:
            lows.append(float(a))
            highs.append(float(b))
    low, high = np.array(lows), np.array(highs)
    before = np.concatenate([[0.0], np.cumsum(high - low)])

    def upto(t: FloatArray) -> FloatArray:
        i = np.searchsorted(low, t, side="right") - 1
        inside = np.clip(t - low[np.maximum(i, 0)], 0.0, (high - low)[np.maximum(i, 0)])
        return np.asarray(np.where(i >= 0, before[np.maximum(i, 0)] + inside, 0.0))

    return np.asarray(upto(end) - upto(start))


# --- the figures -------------------------------------------------------------------------


def _bias_gradient(fit: LinearFit, k: int, low: float, high: float) -> FloatArray:
    """The gradient of the bias's mean over ``[low, high]`` in the fit's unknowns."""
    g = np.zeros(k + fit.knots.size)
    ends = antiderivative(np.array([low, high]), fit.knots)
    g[k:] = (ends[1] - ends[0]) / (high - low)
    return g


def _figures(
    fit: LinearFit, k: int, span: tuple[float, float], reference: bool
) -> dict[str, tuple[float, FloatArray, tuple[int, ...]]]:
    """Each figure's value, gradient in the unknowns (``k`` coefficients, then the
    bias's knots), and the unknowns it needs."""
    c = fit.coefficients
    S, D = float(c[0]), float(c[1])
    size = k + fit.knots.size
    out: dict[str, tuple[float, FloatArray, tuple[int, ...]]] = {}

    def grad(**parts: float) -> FloatArray:
        g = np.zeros(size)
        for name, value in parts.items():
            g[{"S": 0, "D": 1, "s": 2}[name]] = value
        return g

    nan, none = math.nan, np.zeros(size)  # where the solution makes no figure (S = 0)
    diff = S - D
    if diff != 0.0 and S != 0.0:
        out["E_d"] = ((S + D) / diff, grad(S=-2 * D / diff**2, D=2 * S / diff**2), (0, 1))
        out["E_b_k_g"] = (1.0 / S, grad(S=-1.0 / S**2), (0,))
    else:
        out["E_d"], out["E_b_k_g"] = (nan, none, (0, 1)), (nan, none, (0,))
    if reference:
        s = float(c[2])
        out["k_g"] = (1.0 / s, grad(s=-1.0 / s**2), (2,)) if s != 0.0 else (nan, none, (2,))
        if S != 0.0:
            out["E_b"] = (s / S, grad(S=-s / S**2, s=1.0 / S), (0, 2))
        else:
            out["E_b"] = (nan, none, (0, 2))
    g = _bias_gradient(fit, k, *span)
    out["bias"] = (float(g @ np.concatenate([c, fit.bias])), g, (-1,))
    return out


#: An interval turns when the odometry turns it by this much [rad] ...
_TURN = 0.05
#: ... and drives when its wheels' forward rotation, in radians of heading, is this much.
_DRIVE = 0.05


@dataclass(frozen=True)
class _Held:
    """What the recording holds, for what it determines: intervals turning left and
    right, driving forward and backward, rests, the reference's stretches (and those
    turning)."""

    left: int
    right: int
    forward: int
    backward: int
    rests: int
    reference: int = 0
    reference_turns: int = 0

    @classmethod
    def of(
        cls, theta: FloatArray, drive: FloatArray, rest: BoolArray, reference: GyroReference | None
    ) -> _Held:
        moving = ~rest
        return cls(
            left=int((moving & (theta >= _TURN)).sum()),
            right=int((moving & (theta <= -_TURN)).sum()),
            forward=int((moving & (drive >= _DRIVE)).sum()),
            backward=int((moving & (drive <= -_DRIVE)).sum()),
            rests=int(rest.sum()),
            reference=0 if reference is None else len(reference),
            reference_turns=0 if reference is None else int((np.abs(reference.yaw) >= _TURN).sum()),
        )

    @property
    def driving(self) -> int:
        return self.forward + self.backward

    def open(self) -> set[int]:
        """The unknowns (0: ``S``, 1: ``D``, 2: ``s``, -1: the bias's level) that what is
        held leaves open, whatever the numbers: the bias is pinned by rests, a reference,
        turns both ways or driving both ways (each at least twice); ``S`` needs turns and
        the bias pinned, ``D`` driving and the bias pinned, ``s`` the reference turning."""
        pinned = (
            self.rests >= 2
            or self.reference >= 2
            or (self.left >= 2 and self.right >= 2)
            or (self.forward >= 2 and self.backward >= 2)
        )
        out = set() if pinned else {-1}
        if self.left + self.right == 0 or not pinned:
            out.add(0)
        if self.driving == 0 or not pinned:
            out.add(1)
        if self.reference_turns < 2:
            out.add(2)
        return out


def _why(name: str, held: _Held) -> str:
    """What to drive for an undetermined figure."""
    rest = (
        "rest the robot still for a few seconds between" if not held.rests else "rest more between"
    )
    if name in ("E_b_k_g", "E_b") and held.left + held.right == 0:
        return "no turns: drive turns on the spot or arcs"
    if name == "k_g":
        return "the reference saw no turn: turn while it measures"
    if name == "bias":
        return (
            "no rest, and nothing else fixes the gyro's bias: rest the robot still for a few "
            "seconds now and then"
        )
    if name == "E_d" and held.forward + held.backward == 0:
        return "no straights: drive straights"
    if name == "E_d":
        return (
            f"the straights' heading drift cannot be told from the gyro's bias: {rest} "
            "straights, or drive them at different speeds"
        )
    one_way = held.left == 0 or held.right == 0
    side = "left" if held.right == 0 else "right"
    said = f"every turn is to the {side}" if one_way else "the turns"
    return f"{said}: they cannot be told from the gyro's bias: {rest} turns, or turn both ways"


def _determine(
    fit: LinearFit,
    figures: dict[str, tuple[float, FloatArray, tuple[int, ...]]],
    held: _Held,
    first_order: Callable[[], tuple[float, float] | None],
) -> tuple[dict[str, float], dict[str, float], dict[str, str]]:
    """The determined figures' values and standard errors, and why the others are not.

    A figure is determined where what the recording holds leaves none of its unknowns
    open (:meth:`_Held.open`), its gradient lies clear of the combinations the rows leave
    open (:meth:`LinearFit.determined`) and its standard error is within :data:`_LOOSE`.
    ``E_d`` without turns (the turning gain ``S`` open, the straights' drift known) is the
    ratio where the rows fix it (straights the robot drove truly straight: ``E_d`` does
    not depend on ``S`` then) or ``first_order()``, whichever is the tighter."""
    values, errors, undetermined = {}, {}, {}
    open_ = held.open()
    names = {0: "E_b_k_g", 1: "E_d", 2: "k_g", -1: "bias"}
    for name, (value, gradient, needs) in figures.items():
        se = math.sqrt(fit.variance(gradient))
        numeric = math.isfinite(value) and fit.determined(gradient)
        numeric = numeric and math.isfinite(se) and se <= _LOOSE[name]
        structural = [i for i in needs if i in open_]
        if name == "E_d" and structural == [0]:  # no turns, the straights' drift known
            first = first_order()
            found = (value, se) if numeric else first
            if first is not None and numeric and first[1] < se:
                found = first
            if found is not None:
                values[name], errors[name] = found
                continue
        if numeric and not structural:
            values[name], errors[name] = value, se
            continue
        why = names[structural[0]] if structural else ("E_b_k_g" if name == "E_b" else name)
        said = _why(why, held)
        if not structural and math.isfinite(value) and fit.determined(gradient):
            said += f" (its standard error would be {se:.3g})"
        undetermined[name] = said
    return values, errors, undetermined


def _first_order(rows: Rows, spacing: float) -> tuple[float, float] | None:
    """``E_d`` without turns, to first order: the turning gain ``S`` taken as 1 (the
    rows refitted with it fixed), its standard error widened by what a gain within 20 %
    (a wheelbase and a gyro scale that far off) makes of it, ``0.4 |lambda|``, with
    ``lambda`` the straights' heading drift per radian of wheel rotation."""
    theta, drive = rows.x[:, 0], rows.x[:, 1]
    noisy = None if rows.noisy is None else rows.noisy - 1
    fixed = replace(rows, y=rows.y - theta, x=rows.x[:, 1:], noisy=noisy)
    fit = fit_rows(fixed, spacing)
    g = np.zeros(fit.coefficients.size + fit.knots.size)
    g[0] = 1.0
    D = float(fit.coefficients[0])
    se = math.sqrt(fit.variance(g))
    if not fit.determined(g) or abs(D) >= 0.5 or not se <= _LOOSE["E_d"]:
        return None
    driving = rows.kind == DRIVING
    c = float(theta[driving] @ drive[driving]) / max(float(drive[driving] @ drive[driving]), 1e-300)
    E_d = (1.0 + D) / (1.0 - D)
    return E_d, math.hypot(2.0 * se / (1.0 - D) ** 2, 0.4 * abs(D + c))


def _unit(index: int, k: int, fit: LinearFit) -> FloatArray:
    """The direction of the unknown ``index`` alone."""
    g = np.zeros(k + fit.knots.size)
    g[index] = 1.0
    return g


def calibration_of(
    intervals: GyroIntervals,
    active: WheelParams,
    rows: Rows,
    fit: LinearFit,
    reference: GyroReference | None,
    scale_tolerance: float,
    stated: FloatArray | None,
    extra: dict[str, tuple[float, float]] | None = None,
    scan: ScanCalibration | None = None,
    undetermined_extra: dict[str, str] | None = None,
) -> GyroCalibration:
    """The figures of a fit, with what they rest on; ``extra``: figures (and their
    standard errors) of a reference with distance, ``E_b`` and ``E_s`` among them."""
    k = fit.coefficients.size
    moving = ~intervals.rest
    found = excitation(intervals.phi_left[moving], intervals.phi_right[moving])
    n_rests = int(intervals.rest.sum())
    span = (float(intervals.start.min()), float(intervals.end.max()))
    theta, forward, _ = odometry_turns(intervals, active)
    held = _Held.of(theta, forward, intervals.rest, reference)
    spacing = float(fit.knots[1] - fit.knots[0])
    values, errors, undetermined = _determine(
        fit, _figures(fit, k, span, reference is not None), held,
        lambda: _first_order(rows, spacing),
    )  # fmt: skip
    delays = _delays(fit, rows)
    own: dict[str, float] = {}
    for name, (value, se) in (extra or {}).items():
        (values if name in FIGURES else own)[name] = value
        errors[name] = se
        undetermined.pop(name, None)
    for name, why in (undetermined_extra or {}).items():
        values.pop(name, None)
        errors.pop(name, None)
        undetermined[name] = why
    relative: tuple[str, ...] = ()
    warnings: list[str] = []
    if reference is None:
        relative = ("E_b",)
        if "E_b_k_g" in values:
            product, se = values["E_b_k_g"], errors["E_b_k_g"]
            widened = product * scale_tolerance / 1.959963984540054
            values["E_b"], errors["E_b"] = product, math.hypot(se, widened)
            if widened > se:
                warnings.append(
                    f"E_b is relative to the gyro (E_b k_g = {product:.5f} +- {se:.5f}): the "
                    f"gyro's scale, known to +-{100 * scale_tolerance:g} % "
                    "(--gyro-scale-tolerance), sets its interval, not the driving; a heading "
                    "reference (--scan-topic, motion capture) separates the two"
                )
        elif "E_b_k_g" in undetermined:
            undetermined["E_b"] = undetermined["E_b_k_g"]
    warnings += _implausible(fit, held, values)
    mounting = gyro_mounting(intervals, odometry_turns(intervals, active)[0], stated)
    warnings += mounting.notes(intervals.frame)
    times = fit.knots
    sel = np.arange(k, k + times.size)
    bias_errors = np.sqrt(np.clip(np.diag(fit.covariance)[sel], 0.0, None))
    kept_rows = fit.kept
    return GyroCalibration(
        values=values,
        standard_errors=errors,
        undetermined=undetermined,
        relative_to_gyro=relative,
        scale_tolerance=scale_tolerance,
        bias_times=times,
        bias_values=fit.bias,
        bias_errors=bias_errors,
        bias_walk=fit.walk,
        noise=fit.noise,
        mounting=mounting,
        reference="no reference"
        if reference is None
        else "heading changes"
        if reference.motion is None
        else "scan matching",
        n_intervals=len(intervals),
        n_rests=n_rests,
        n_reference=0 if reference is None else len(reference),
        n_outliers=int((~kept_rows).sum()),
        excitation=found,
        warnings=tuple(warnings),
        extra=own,
        scan=scan,
        delays=delays,
    )


#: A delay whose standard error exceeds this is not determined [s].
_LOOSE_DELAY = 0.05


def _delays(fit: LinearFit, rows: Rows) -> dict[str, tuple[float, float]]:
    """The gyro's delay where the rows determine it: ``gyro`` [s]."""
    out = {}
    k = fit.coefficients.size
    for j, name in zip(range(rows.delays), ("imu",), strict=False):
        g = _unit(rows.figures + j, k, fit)
        se = math.sqrt(fit.variance(g))
        if fit.determined(g) and math.isfinite(se) and se <= _LOOSE_DELAY:
            out[name] = (float(fit.coefficients[rows.figures + j]), se)
    return out


def _implausible(fit: LinearFit, held: _Held, values: dict[str, float]) -> list[str]:
    """A gyro that reads the turns backwards, or not as a gyro of a robot's turns can
    (frozen, another axis, another unit): never for applying.

    Where the robot turned, the gyro's turning gain ``S = E_s / (E_b k_g)`` is within
    :data:`_GAIN` of 1 for any wheelbase and gyro scale a robot has; ``180 / pi`` times
    that is a rate in degrees per second read as radians."""
    k_g = values.get("k_g")
    gain = float(fit.coefficients[0])
    turned = 0 not in held.open() and fit.determined(_unit(0, fit.coefficients.size, fit))
    fix = (
        "fix the IMU frame's transform (turned 180 deg about its x axis for an IMU upside "
        "down) and calibrate again"
    )
    if (k_g is not None and k_g < 0.0) or (turned and gain < 0.0):
        said = f"k_g = {k_g:.4f}" if k_g is not None else f"E_b k_g = {1.0 / gain:.4f}"
        reason = (
            f"the gyro reads the turns backwards ({said}): the IMU is mounted upside down, or "
            "its z axis reversed, and its stated transform does not say so"
        )
        return [blocking(reason, reason, fix)]
    if not turned or _GAIN[0] <= gain <= _GAIN[1]:
        return []
    if abs(gain * math.pi / 180.0 - 1.0) <= 0.1:
        why = "its rates are in degrees per second, read as radians per second"
    elif abs(gain * 180.0 / math.pi - 1.0) <= 0.1:
        why = "its rates are in radians per second, read as degrees per second"
    else:
        why = "frozen, its yaw not on the base's z axis, or its rates in another unit"
    reason = (
        f"the gyro reads {gain:.3g} times the turns the wheels make, which no gyro scale and "
        f"wheelbase explain: {why}"
    )
    return [blocking(reason, reason, "check the IMU's topic, its frame's transform and units")]

"""The gyro estimator's model and figures (:mod:`umbmark.estimators.gyro` says what
they are): the rows of its least squares, each figure's value and gradient, which of them
the motion determines and why not, and the calibration they make."""

from __future__ import annotations

import math

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.messages import blocking
from umbmark.estimators.gyro_fit import DRIVING, REFERENCE, REST, LinearFit, Rows
from umbmark.estimators.gyro_fit import _antiderivative as antiderivative
from umbmark.estimators.gyro_mounting import gyro_mounting
from umbmark.estimators.gyro_result import FIGURES, GyroCalibration
from umbmark.estimators.scan_excitation import Excitation, excitation
from umbmark.estimators.scan_matching import ScanCalibration
from umbmark.model.kinematics import WheelParams
from umbmark.scans.gyro_intervals import GyroIntervals, GyroReference

__all__ = ["calibration_of", "gyro_rows", "odometry_turns"]

#: A figure whose standard error exceeds this is not determined either: E_d 5 %, E_b 20 %,
#: k_g 20 %, the bias 1 deg/s.
_LOOSE = {
    "E_d": 0.05, "E_b_k_g": 0.2, "E_b": 0.2, "E_s": 0.2, "k_g": 0.2, "bias": math.radians(1.0),
}  # fmt: skip
#: k_g within this of -1 (or E_b k_g negative): an IMU upside down.
_REVERSED = 0.0


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
    theta, forward, wheel = odometry_turns(intervals, active)
    n = len(intervals)
    kind = np.where(intervals.rest, REST, DRIVING).astype(np.int64)
    columns = [theta, forward]
    if reference is None:
        return Rows(
            y=intervals.yaw, x=np.column_stack(columns), start=intervals.start,
            end=intervals.end, kind=kind, wheel=np.where(intervals.rest, 0.0, wheel),
            given=np.full(n, np.nan),
        )  # fmt: skip
    m = len(reference)
    x = np.zeros((n + m, 3))
    x[:n, 0], x[:n, 1], x[n:, 2] = theta, forward, reference.yaw
    return Rows(
        y=np.concatenate([intervals.yaw, reference.gyro_yaw]),
        x=x,
        start=np.concatenate([intervals.start, reference.start]),
        end=np.concatenate([intervals.end, reference.end]),
        kind=np.concatenate([kind, np.full(m, REFERENCE, dtype=np.int64)]),
        wheel=np.concatenate([np.where(intervals.rest, 0.0, wheel), np.zeros(m)]),
        given=np.concatenate([np.full(n, np.nan), reference.variance]),
    )


# --- the figures -------------------------------------------------------------------------


def _bias_gradient(fit: LinearFit, k: int, low: float, high: float) -> FloatArray:
    """The gradient of the bias's mean over ``[low, high]`` in the fit's unknowns."""
    g = np.zeros(k + fit.knots.size)
    ends = antiderivative(np.array([low, high]), fit.knots)
    g[k:] = (ends[1] - ends[0]) / (high - low)
    return g


def _figures(
    fit: LinearFit, k: int, span: tuple[float, float]
) -> dict[str, tuple[float, FloatArray, tuple[int, ...]]]:
    """Each figure's value, gradient in the unknowns, and the unknowns it needs."""
    c = fit.coefficients
    S, D = float(c[0]), float(c[1])
    size = k + fit.knots.size
    out: dict[str, tuple[float, FloatArray, tuple[int, ...]]] = {}

    def grad(**parts: float) -> FloatArray:
        g = np.zeros(size)
        for name, value in parts.items():
            g[{"S": 0, "D": 1, "s": 2}[name]] = value
        return g

    diff = S - D
    if diff != 0.0 and S != 0.0:
        out["E_d"] = ((S + D) / diff, grad(S=-2 * D / diff**2, D=2 * S / diff**2), (0, 1))
        out["E_b_k_g"] = (1.0 / S, grad(S=-1.0 / S**2), (0,))
    if k == 3:
        s = float(c[2])
        if s != 0.0:
            out["k_g"] = (1.0 / s, grad(s=-1.0 / s**2), (2,))
        if S != 0.0:
            out["E_b"] = (s / S, grad(S=-s / S**2, s=1.0 / S), (0, 2))
    g = _bias_gradient(fit, k, *span)
    out["bias"] = (float(g @ np.concatenate([c, fit.bias])), g, (-1,))
    return out


def _why(name: str, found: Excitation, n_rests: int, reference: bool) -> str:
    """What to drive for an undetermined figure."""
    turning = found.n_spot + found.n_arc
    rest = "rest the robot still for a few seconds between" if not n_rests else "rest more between"
    if name in ("E_b_k_g", "E_b") and turning == 0:
        return "no turns: drive turns on the spot or arcs"
    if name == "k_g":
        return "the reference saw no turn: turn while it measures"
    if name == "bias":
        return (
            "no rest, and nothing else fixes the gyro's bias: rest the robot still for a few "
            "seconds now and then"
        )
    if name == "E_d" and found.n_straight + found.n_arc == 0:
        return "no straights: drive straights"
    if name == "E_d":
        return (
            f"the straights' heading drift cannot be told from the gyro's bias: {rest} "
            "straights, or drive them at different speeds"
        )
    side = "left" if found.n_right == 0 else "right"
    one_way = found.n_left == 0 or found.n_right == 0
    said = f"every turn is to the {side}" if one_way else "the turns"
    return f"{said}: they cannot be told from the gyro's bias: {rest} turns, or turn both ways"


def _determine(
    fit: LinearFit,
    figures: dict[str, tuple[float, FloatArray, tuple[int, ...]]],
    found: Excitation,
    n_rests: int,
    reference: bool,
) -> tuple[dict[str, float], dict[str, float], dict[str, str]]:
    """The determined figures' values and standard errors, and why the others are not.

    A figure is determined where its gradient lies clear of the combinations the rows
    leave open (:meth:`LinearFit.determined`) and its standard error is within
    :data:`_LOOSE`. ``E_d`` without turns (the turning gain open, the straights' drift
    known) is given to first order, the gain taken as 1 and its standard error widened
    by a fifth of ``E_d - 1`` (a wheelbase and a gyro scale within 20 %)."""
    values, errors, undetermined = {}, {}, {}
    k = fit.coefficients.size
    for name, (value, gradient, _) in figures.items():
        se = math.sqrt(fit.variance(gradient))
        if fit.determined(gradient) and math.isfinite(se) and se <= _LOOSE[name]:
            values[name], errors[name] = value, se
            continue
        why = "E_b_k_g" if name == "E_b" else name
        if name == "E_d" and not fit.determined(_unit(0, k, fit)):
            first = _first_order(fit, k)
            if first is not None:
                values[name], errors[name] = first
                continue
            why = "E_b_k_g"
        if name == "E_d" and not fit.determined(_unit(1, k, fit)):
            why = "E_d"
        said = _why(why, found, n_rests, reference)
        if fit.determined(gradient):
            said += f" (its standard error would be {se:.3g})"
        undetermined[name] = said
    return values, errors, undetermined


def _first_order(fit: LinearFit, k: int) -> tuple[float, float] | None:
    """``E_d`` from the straights' drift ``D`` alone, the turning gain taken as 1."""
    g = _unit(1, k, fit)
    if not fit.determined(g):
        return None
    D = float(fit.coefficients[1])
    if abs(D) >= 1.0:
        return None
    E_d = (1.0 + D) / (1.0 - D)
    se = 2.0 / (1.0 - D) ** 2 * math.sqrt(fit.variance(g))
    return E_d, math.hypot(se, 0.2 * abs(E_d - 1.0))


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
    values, errors, undetermined = _determine(
        fit, _figures(fit, k, span), found, n_rests, reference is not None
    )
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
    warnings += _reversed(values, fit, found)
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
    )


def _reversed(values: dict[str, float], fit: LinearFit, found: Excitation) -> list[str]:
    """A gyro that reads the turns backwards: never for applying."""
    k_g = values.get("k_g")
    product = values.get("E_b_k_g")
    if (k_g is not None and k_g < _REVERSED) or (
        k_g is None and product is not None and product < 0
    ):
        said = f"k_g = {k_g:.4f}" if k_g is not None else f"E_b k_g = {product:.4f}"
        reason = (
            f"the gyro reads the turns backwards ({said}): the IMU is mounted upside down, or "
            "its z axis reversed, and its stated transform does not say so"
        )
        return [
            blocking(
                reason,
                reason,
                "fix the IMU frame's transform (turned 180 deg about its x axis for an IMU "
                "upside down) and calibrate again",
            )
        ]
    return []

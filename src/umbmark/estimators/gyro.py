"""The wheels and a gyro calibrated together: each figure said against what fixes it.

Over each interval of driving (:mod:`umbmark.scans.gyro_intervals`) the odometry's wheels
turned the robot by ``theta_odo = U_R - U_L`` and drove it ``F = U_R + U_L`` (``U = r phi /
b``, each wheel's rotation in radians of heading with the parameters the odometry used:
``r = D / 2`` and ``b`` active). The true heading change is ``(f_R U_R - f_L U_L) / E_b``
(``f = D_true / D_active`` per wheel, ``E_d = f_R / f_L``, ``E_s = (f_L + f_R) / 2``, ``E_b
= b_true / b_active``: ``docs/conventions.md``), and with ``omega_true = k_g (omega_read -
bias)`` the gyro reads

    psi = (true heading change) / k_g + integral of the bias
        = S theta_odo + D F + integral of the bias,

``S = E_s / (E_b k_g)``, ``D / S = (E_d - 1) / (E_d + 1)``: linear in ``S``, ``D`` and the
bias (a random walk: :mod:`umbmark.estimators.gyro_fit`). Rests (the wheels still) are
rows with ``theta_odo = F = 0``: the bias alone.

- **From the wheels and the gyro alone**: ``E_d = (S + D) / (S - D)``, the straights'
  heading drift per metre against the turns' gain; the gyro's scale multiplies ``S`` and
  ``D`` alike, so ``E_d`` does not depend on it at all (what it needs is the bias, known
  from the rests and the fit). Turning, the gyro sees the wheels' turns through its own
  scale, so what wheels and gyro alone identify is ``1 / S = E_b k_g / E_s``: the product
  ``E_b * k_g`` (with ``E_s`` taken as 1, as the square test assumes), not ``E_b`` and
  ``k_g`` apart. ``E_b`` is then relative to the gyro: its interval is widened by the gyro
  scale tolerance (``scale_tolerance``, default 3 %: MPU-6050's +-3 % at 25 C taken as its
  95 % bound, added in quadrature), and where that tolerance outweighs the driving's own
  uncertainty a warning says so (the verdict is then "apply with care" at best).
- **With an absolute heading reference** over the same recording (motion capture, a
  corner fix, scan matching's motion intervals), rows ``psi_ref = s rho + integral of the
  bias`` (``rho`` the reference's heading change, ``s = 1 / k_g``) join: ``k_g``, the
  bias, ``E_d`` and ``E_b / E_s = s / S`` are separated. The pair of rows (gyro against
  reference, gyro against wheels) holds all the reference's information on the wheels
  (their difference is the reference against the wheels, the bias cancelling), so the
  joint fit is as tight as the reference alone at least: where the wheels over each
  stretch are known (scan matching's intervals) the two rows are of one stretch, their
  covariance the gyro's own variance, their difference weighed as the reference alone
  weighs it (:mod:`umbmark.estimators.gyro_noise`). Where the reference gives distance too (scan
  matching's translations), :mod:`umbmark.estimators.gyro_scan` adds ``E_s`` and the
  laser's mounting.

A figure the motion does not determine (only straights: ``E_b``; turns one way only and
no rests: the turns cannot be told from the bias; no rests and no reference: the bias's
level with them) is marked undetermined, with what to drive, not a singular system.
"""

from __future__ import annotations

from umbmark.core.arrays import FloatArray
from umbmark.core.messages import blocking
from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.gyro_fit import fit_rows
from umbmark.estimators.gyro_model import calibration_of, gyro_rows
from umbmark.estimators.gyro_result import FIGURES, GyroCalibration
from umbmark.estimators.registry import GYRO
from umbmark.model.kinematics import WheelParams
from umbmark.model.systematic import alpha_from_E_b, beta_from_E_d
from umbmark.scans.gyro_intervals import GyroIntervals, GyroReference

__all__ = [
    "BIAS_WINDOW",
    "FIGURES",
    "MIN_INTERVALS",
    "SCALE_TOLERANCE",
    "GyroCalibration",
    "fit_gyro",
    "gyro_estimate",
    "widened_resolves",
]

#: The gyro scale tolerance where none is given: MPU-6050's sensitivity scale factor
#: tolerance, +-3 % at 25 C (InvenSense PS-MPU-6000A-00 rev. 3.4, table 6.1).
SCALE_TOLERANCE = 0.03
#: The bias's knots are this far apart [s].
BIAS_WINDOW = 10.0
#: Fewest intervals a calibration is made from.
MIN_INTERVALS = 10


def widened_resolves(E_b: float, se: float) -> bool:
    """Whether ``E_b`` relative to the gyro, its standard error ``se`` widened by the
    gyro's scale tolerance, says which way to correct: its 95 % interval does not hold
    both 1 (no correction) and ``2 - E_b`` (a correction that makes the wheelbase twice
    as wrong), the verdict's rule (:mod:`umbmark.calibration.verdict`)."""
    return 1.959963984540054 * se < 2.0 * abs(E_b - 1.0)


def fit_gyro(
    intervals: GyroIntervals,
    active: WheelParams,
    *,
    reference: GyroReference | None = None,
    scale_tolerance: float = SCALE_TOLERANCE,
    bias_window: float = BIAS_WINDOW,
    stated: FloatArray | None = None,
) -> GyroCalibration:
    """The wheels and the gyro calibrated together (the module's documentation).

    Parameters
    ----------
    intervals : GyroIntervals
        The recording cut into rests and driving.
    active : WheelParams
        What the odometry used (wheel diameters with their factors, the wheelbase).
    reference : GyroReference, optional
        An absolute heading reference over the same recording
        (:func:`umbmark.scans.gyro_intervals.gyro_reference`).
    scale_tolerance : float
        Without a reference: how far the gyro's scale may be off (a fraction).
    bias_window : float
        The bias's knots' spacing [s].
    stated : array, shape (3, 3), optional
        The stated rotation ``base <- imu`` (the mounting said in the IMU's frame too).

    Raises
    ------
    ValueError
        Fewer than :data:`MIN_INTERVALS` intervals, or a tolerance outside [0, 0.5).
    """
    if len(intervals) < MIN_INTERVALS:
        raise ValueError(
            f"{len(intervals)} interval(s) of rest and driving: the gyro calibration needs "
            f"at least {MIN_INTERVALS}"
        )
    if not 0.0 <= scale_tolerance < 0.5:
        raise ValueError(f"the gyro scale tolerance must be in [0, 0.5), got {scale_tolerance}")
    if reference is not None and reference.motion is not None:
        from umbmark.estimators.gyro_scan import fit_gyro_scan

        return fit_gyro_scan(intervals, active, reference, bias_window=bias_window, stated=stated)
    rows = gyro_rows(intervals, active, reference)
    fit = fit_rows(rows, bias_window)
    return calibration_of(intervals, active, rows, fit, reference, scale_tolerance, stated)


# --- against the active parameters -------------------------------------------------------


def gyro_estimate(
    intervals: GyroIntervals,
    active: WheelParams,
    side_length: float | None = None,
    *,
    reference: GyroReference | None = None,
    scale_tolerance: float = SCALE_TOLERANCE,
    bias_window: float = BIAS_WINDOW,
    stated: FloatArray | None = None,
) -> tuple[ErrorEstimate, GyroCalibration]:
    """The ``gyro`` estimator: :func:`fit_gyro`, as errors of ``active``.

    ``E_d`` and ``E_b`` as the calibration determines them (``E_b``: relative to the
    gyro without a reference, its interval widened by ``scale_tolerance``, and left at 1
    where that interval does not say which way to correct, :func:`widened_resolves`),
    ``E_s`` where the reference gives distance; an undetermined figure is left at 1 (no correction)
    with a warning saying what to drive, and where neither ``E_d`` nor ``E_b`` is
    determined a blocking warning says there is nothing to apply. ``alpha`` and
    ``beta`` are what the errors make of a square of side ``side_length`` (1 m by
    default). The components hold the gyro's figures: ``gyro_scale`` (``k_g``),
    ``gyro_bias`` [rad/s], ``E_b_gyro`` (``E_b k_g / E_s``), ``gyro_tilt`` [rad] and the
    counts.
    """
    cal = fit_gyro(
        intervals, active, reference=reference, scale_tolerance=scale_tolerance,
        bias_window=bias_window, stated=stated,
    )  # fmt: skip
    values, se = cal.values, cal.standard_errors
    E_d, E_b, E_s = values.get("E_d", 1.0), values.get("E_b", 1.0), values.get("E_s")
    warnings = list(cal.warnings)
    errors: dict[str, float] = {n: se[n] for n in ("E_d", "E_b", "E_s") if n in se}
    if E_b <= 0.0:  # a gyro that reads backwards (a blocking warning says so)
        E_b = 1.0
        errors.pop("E_b", None)
    elif "E_b" in cal.relative_to_gyro and "E_b" in errors and not widened_resolves(E_b, se["E_b"]):
        warnings.append(
            f"E_b is not corrected: relative to the gyro it is {E_b:.5f}, and the gyro's scale "
            f"tolerance (+-{100 * scale_tolerance:g} %) holds both no correction and one "
            "that would make the wheelbase twice as wrong: left at 1, E_d alone applied"
        )
        E_b = 1.0
        errors.pop("E_b")
    for name in ("E_d", "E_b"):
        if name in cal.undetermined:
            warnings.append(
                f"{name} is not determined ({cal.undetermined[name]}): left at 1, no correction"
            )
    if "E_d" not in values and "E_b" not in values:
        reason = "neither E_d nor E_b is determined: there is nothing to apply"
        warnings.append(blocking(reason, reason, cal.undetermined.get("E_d")))
    names = {"k_g": "gyro_scale", "bias": "gyro_bias", "E_b_k_g": "E_b_gyro"}
    components = {names[n]: values[n] for n in names if n in values}
    errors.update({names[n]: se[n] for n in names if n in values})
    for name, value in cal.extra.items():
        components[name] = value
        if name in se:
            errors[name] = se[name]
    if cal.mounting.tilt is not None:
        components["gyro_tilt"] = cal.mounting.tilt
    components.update(
        n_intervals=float(cal.n_intervals), n_rests=float(cal.n_rests),
        n_reference=float(cal.n_reference),
    )  # fmt: skip
    side = side_length or 1.0
    estimate = ErrorEstimate(
        method=GYRO.name,
        alpha=float(alpha_from_E_b(E_b, 1.0 if E_s is None else E_s)),
        beta=float(beta_from_E_d(E_d, side, active.wheelbase * E_b)),
        E_d=E_d,
        E_b=E_b,
        E_s=E_s,
        components=components,
        standard_errors=errors,
        warnings=tuple(warnings),
    )
    return estimate, cal

"""The figures of a stretch of driving, or of the window: the project's estimators on the
chunks' motion, each figure with its standard error, or what the motion does not determine.

- With a laser: the scan-matching estimator
  (:func:`umbmark.estimators.scan_matching.scan_matching_estimate`, Censi et al. 2013) on
  the matched intervals, against the controller's nominal geometry (multipliers 1): ``E_d
  = D_R / D_L``, ``E_b`` (the effective wheelbase over the nominal one) and ``E_s`` are
  what the robot *is*, whatever multipliers its controller runs with; the laser's x, y, yaw.
- With a gyro: the gyro estimator (:func:`umbmark.estimators.gyro.fit_gyro`), with the
  matched intervals as its heading reference where they are (its scale ``k_g`` and bias);
  without a laser it gives ``E_d`` and ``E_b`` (``E_b`` relative to the gyro's scale);
  where the laser's matches do not determine a stretch, ``E_d`` (which the gyro's scale
  does not touch) but not that ``E_b``: a figure of another quantity on ``E_b``'s course.
- Where the laser's matches turn too little to determine the wheelbase (straights, few
  turns) and a wheelbase and mounting are held (``held``: the window's, which turned both
  ways): ``E_d`` and ``E_s`` from the same matches with those held
  (:func:`umbmark.estimators.scan_radii.fit_radii`, their uncertainty carried), the other
  figures not determined, said so.

A figure the motion does not determine is said with why (:data:`NO_LASER`,
:data:`NO_GYRO`, :data:`STRAIGHT_ONLY`, :data:`ONE_WAY`, the estimator's own reason),
never raised.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.model.kinematics import WheelParams
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.monitor.chunks import Chunk, Driving, join_gyro, join_reference
from umbmark.monitor.status import FIGURES
from umbmark.robot.base import DriveParams

__all__ = [
    "HELD",
    "NO_GYRO",
    "NO_LASER",
    "ONE_WAY",
    "STRAIGHT_ONLY",
    "Estimate",
    "Held",
    "estimate",
]

NO_LASER = "no laser"
NO_GYRO = "no gyro"
STRAIGHT_ONLY = "straight only: turns on the spot or arcs determine it"
ONE_WAY = "turned one way only"
#: Fewest matched intervals a scan-matching estimate is made from (the estimator's own
#: minimum is 10).
MIN_INTERVALS = 12
_SCAN = ("E_d", "E_b", "E_s", "laser_x", "laser_y", "laser_yaw")
#: What a stretch's ``E_d`` and ``E_s`` rest on where its own motion fixes no wheelbase.
HELD = "the wheelbase and the laser's mounting held at the window's"


@dataclass(frozen=True)
class Held:
    """A wheelbase and a laser mounting found elsewhere (the window), for a stretch that
    turned too little: ``params`` ``(6,)`` in the order of
    :data:`umbmark.estimators.scan_matching.PARAMETERS`, ``covariance`` ``(4, 4)`` of the
    wheelbase [m] and the mounting's x, y [m] and yaw [rad]."""

    params: FloatArray
    covariance: FloatArray

    @classmethod
    def of(cls, fit: Estimate, nominal_wheelbase: float) -> Held | None:
        """The window's ``fit`` as held parameters (None: it determined no wheelbase)."""
        if fit.params is None or not all(n in fit.values for n in ("E_b", *_SCAN[3:])):
            return None
        se = [fit.values["E_b"][1] * nominal_wheelbase, *(fit.values[n][1] for n in _SCAN[3:])]
        return cls(np.asarray(fit.params, dtype=np.float64), np.diag(np.square(se)))


@dataclass
class Estimate:
    """The figures over some chunks.

    Attributes
    ----------
    values : dict of str to (float, float)
        Each determined figure of :data:`umbmark.monitor.status.FIGURES`: value and
        standard error (its unit).
    notes : dict of str to str
        Why a figure is not determined, or what it is relative to.
    params : array, shape (6,), or None
        The wheels and the laser (:data:`umbmark.estimators.scan_matching.PARAMETERS`:
        radii, wheelbase [m], the laser's x, y [m], yaw [rad]) where the laser determined
        them.
    intervals : int
        Matched intervals used.
    driving : Driving
        The driving of the chunks.
    warnings : tuple of str
        The estimators' warnings.
    held : bool
        ``E_d`` and ``E_s`` are the laser's with the wheelbase and the mounting held
        (:data:`HELD`).
    """

    values: dict[str, tuple[float, float]]
    notes: dict[str, str]
    params: FloatArray | None
    intervals: int
    driving: Driving
    warnings: tuple[str, ...] = field(default=())
    held: bool = False


def nominal_wheels(params: DriveParams) -> WheelParams:
    """The controller's nominal geometry (multipliers 1): the figures are the robot's."""
    return WheelParams(wheelbase=params.wheel_separation, wheel_diameter=2.0 * params.wheel_radius)


def _why(phi_left: FloatArray, phi_right: FloatArray, said: str) -> str:
    """Why scan matching does not determine the figures, for people."""
    from umbmark.estimators.scan_excitation import excitation

    found = excitation(phi_left, phi_right)
    if found.n_spot + found.n_arc == 0 and found.n_straight:
        return STRAIGHT_ONLY
    if found.n_straight == 0 and found.n_arc == 0 and found.n_spot:
        return "turns on the spot only: straights determine it"
    return said


def _scan_figures(
    chunks: Sequence[Chunk], nominal: WheelParams, out: Estimate, held: Held | None
) -> None:
    from umbmark.estimators.scan_matching import scan_matching_estimate

    parts = [c.motion for c in chunks if c.motion is not None]
    if not parts:
        for name in _SCAN:
            out.notes[name] = "no motion matched"
        return
    motion = MotionIntervals.concatenate(parts)
    if len(motion) < MIN_INTERVALS:
        for name in _SCAN:
            out.notes[name] = f"{len(motion)} motion intervals matched, {MIN_INTERVALS} needed"
        return
    try:
        est, cal = scan_matching_estimate(motion, nominal)
    except InputError as exc:
        said = _why(motion.phi_left, motion.phi_right, str(exc).split(": ", 1)[-1][:120])
        for name in _SCAN:
            out.notes[name] = said
        if held is not None:
            _held_figures(motion, nominal, out, held)
        return
    se = est.standard_errors
    for name in ("E_d", "E_b"):
        out.values[name] = (getattr(est, name), se[name])
    if est.E_s is not None:
        out.values["E_s"] = (est.E_s, se["E_s"])
    for name in ("laser_x", "laser_y", "laser_yaw"):
        out.values[name] = (est.components[name], se[name])
    if cal.excitation.n_left == 0 or cal.excitation.n_right == 0:
        for name in ("E_b", "laser_x", "laser_y"):
            out.notes[name] = ONE_WAY
    bad = [n for n, (v, s) in out.values.items() if not (math.isfinite(v) and s > 0.0 and
                                                          math.isfinite(s))]  # fmt: skip
    for name in bad:
        del out.values[name]
        out.notes[name] = "not determined by the motion"
    out.params = cal.values
    out.intervals = cal.n_used
    out.warnings = (*out.warnings, *est.warnings)


def _held_figures(motion: MotionIntervals, nominal: WheelParams, out: Estimate, held: Held) -> None:
    """``E_d`` and ``E_s`` of motion that fixes no wheelbase, with ``held``'s."""
    from umbmark.estimators.scan_radii import fit_radii

    try:
        fit = fit_radii(motion, held.params, held.covariance)
    except InputError:
        return
    found = fit.errors_of(0.5 * nominal.diameter_left, 0.5 * nominal.diameter_right)
    for name, (value, se) in found.items():
        if math.isfinite(value) and math.isfinite(se) and se > 0.0:
            out.values[name] = (value, se)
            out.notes[name] = HELD
    out.held = bool(out.values)
    out.intervals = int(fit.kept.sum())


def _gyro_figures(
    chunks: Sequence[Chunk], nominal: WheelParams, out: Estimate, laser: bool
) -> None:
    from umbmark.estimators.gyro import MIN_INTERVALS as GYRO_MIN
    from umbmark.estimators.gyro import fit_gyro

    gyro = join_gyro([c.gyro for c in chunks if c.gyro is not None])
    if gyro is None or len(gyro) < GYRO_MIN:
        why = NO_GYRO if gyro is None else f"{len(gyro)} gyro intervals, {GYRO_MIN} needed"
        out.notes.setdefault("k_g", why)
        out.notes.setdefault("gyro_bias", why)
        return
    refs = [c.reference for c in chunks if c.reference is not None]
    reference = join_reference(refs) if out.params is not None else None
    try:
        cal = fit_gyro(gyro, nominal, reference=reference)
    except (ValueError, InputError, np.linalg.LinAlgError) as exc:
        out.notes["k_g"] = out.notes["gyro_bias"] = str(exc)[:120]
        return
    values, se = cal.values, cal.standard_errors
    if "k_g" in values and "k_g" in se:
        out.values["k_g"] = (values["k_g"], se["k_g"])
    else:
        out.notes["k_g"] = cal.undetermined.get("k_g", "needs the laser as a heading reference")
    if "bias" in values and "bias" in se:
        out.values["gyro_bias"] = (values["bias"], se["bias"])
    else:
        out.notes["gyro_bias"] = cal.undetermined.get("bias", "not determined by the motion")
    if out.params is None:  # no laser's figures: the wheels from the gyro
        for name in ("E_d", "E_b"):
            if name == "E_b" and laser and "E_b" in cal.relative_to_gyro:
                continue  # E_b k_g / E_s, not the laser's E_b: not on its course
            if name in values and name in se:
                out.values[name] = (values[name], se[name])
                out.notes.pop(name, None)
            elif name in cal.undetermined:
                out.notes[name] = cal.undetermined[name]
        if "E_b" in cal.relative_to_gyro and "E_b" in out.values:
            out.notes["E_b"] = "relative to the gyro's scale"


def estimate(
    chunks: Sequence[Chunk], params: DriveParams, *, laser: bool, gyro: bool,
    held: Held | None = None,
) -> Estimate:  # fmt: skip
    """The figures over ``chunks`` (the module's notes): never raises for what the motion
    does not determine. ``held``: a wheelbase and mounting for motion that fixes none."""
    driving = Driving()
    for c in chunks:
        driving = driving + c.driving
    out = Estimate({}, {}, None, 0, driving)
    nominal = nominal_wheels(params)
    if laser:
        _scan_figures(chunks, nominal, out, held)
    else:
        for name in _SCAN:
            out.notes[name] = NO_LASER
    if gyro:
        _gyro_figures(chunks, nominal, out, laser)
    else:
        out.notes["k_g"] = out.notes["gyro_bias"] = NO_GYRO
    for name, _ in FIGURES:
        if name not in out.values:
            out.notes.setdefault(name, "not determined by the motion")
    return out

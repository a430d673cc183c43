"""The scale error ``E_s`` from straight runs measured against a tape (Sec. 2.2).

The paper assumes the average wheel diameter calibrated before UMBmark: drive straight by
the odometry, measure the distance really driven. Each straight run gives
``E_s = true distance / odometry distance``; the estimate is their mean, its standard
error the runs' spread over ``sqrt(n)`` (Student's t with ``n - 1`` degrees of freedom for
intervals). A square test then sees ``E_b / E_s`` in its turns
(:meth:`umbmark.estimators.base.ErrorEstimate.with_scale`).

Recorded runs with a ground truth show the scale too, roughly, in the path it moved
against their odometry's (:func:`observed_scale`); a scale near 2, 1/2 or a power of ten
is a wheel diameter given wrong (:func:`diameter_mixup`, :func:`unit_slip`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from umbmark.core.errors import option
from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.registry import STRAIGHT
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run

__all__ = [
    "OBSERVED_TOLERANCE",
    "UNIT_SLIPS",
    "ScaleEstimate",
    "diameter_mixup",
    "meant_diameter",
    "observed_scale",
    "scale_from_straights",
    "scale_only",
    "slipped_words",
    "unit_slip",
]

#: Shortest straight run that can measure a scale [m].
MIN_DISTANCE = 0.05
#: A scale error within this fraction of 2 or 1/2 is a radius taken for a diameter (the
#: usual ROS mix-up: ``diff_drive_controller`` takes ``wheel_radius``) or the reverse;
#: tyres and wear differ from their nominal diameter by per cent, not by half.
MIXUP_TOLERANCE = 0.15


#: The wheels' true diameter over the one given, for a diameter given in another unit
#: than metres (centimetres: 1/100; millimetres, 1/1000, exceed a diameter's bound of
#: 10 m) or with its decimal point slipped: no tyre or wear is a power of ten off, so
#: these are mistakes, not errors.
UNIT_SLIPS = (10.0, 100.0, 0.1, 0.01)
#: The unit a diameter given in it (for metres) is off by.
_SLIPPED_UNITS = {0.01: "centimetres"}


def unit_slip(E_s: float) -> float | None:
    """The power of ten of :data:`UNIT_SLIPS` that ``E_s`` (the wheels' true mean diameter
    over the one given) lies within :data:`MIXUP_TOLERANCE` of, or None."""
    if not math.isfinite(E_s):
        return None
    return next((f for f in UNIT_SLIPS if abs(E_s / f - 1.0) <= MIXUP_TOLERANCE), None)


_FRACTIONS = {10.0: "a tenth", 100.0: "a hundredth"}


def slipped_words(diameter: float, factor: float, evidence: str) -> str:
    """``the wheel diameter given, 1.5 m, is 10 times the wheels' (EVIDENCE): a unit or
    decimal-point slip``: a ``diameter`` [m] off by the power of ten ``factor`` (true over
    given, :data:`UNIT_SLIPS`)."""
    times = f"{1 / factor:g} times" if factor < 1 else f"{_FRACTIONS[factor]} of"
    unit = _SLIPPED_UNITS.get(factor)
    slip = f"a diameter in {unit}, not metres" if unit else "a unit or decimal-point slip"
    return f"the wheel diameter given, {diameter:g} m, is {times} the wheels' ({evidence}): {slip}"


def meant_diameter(diameter: float, factor: float) -> float:
    """The diameter [m] a ``diameter`` given off by ``factor`` (true over given) meant,
    without the binary digits the product adds (``1.5 * 0.1`` is 0.15)."""
    return float(f"{diameter * factor:.6g}")


def diameter_mixup(E_s: float, diameter: float | None, evidence: str) -> str | None:
    """The cause and the fix when the wheels' true mean diameter is about twice (or half)
    the ``diameter`` [m] given, or a power of ten off it (:func:`unit_slip`) (``E_s`` =
    true over given; ``evidence`` says how that is known); None otherwise."""
    if diameter is None or not math.isfinite(E_s):
        return None
    factor = unit_slip(E_s)
    if factor is not None:
        meant = meant_diameter(diameter, factor)
        return (
            f"{slipped_words(diameter, factor, evidence)}; pass "
            f"{option('wheel_diameter', meant)}, the diameter in metres"
        )
    if abs(E_s / 2.0 - 1.0) <= MIXUP_TOLERANCE:
        return (
            f"the wheel diameter given, {diameter:g} m, looks like the wheels' radius "
            f"({evidence}): pass {option('wheel_diameter', 2.0 * diameter)}, twice it"
        )
    if abs(2.0 * E_s - 1.0) <= MIXUP_TOLERANCE:
        return (
            f"the wheel diameter given, {diameter:g} m, looks like twice the wheels' "
            f"diameter ({evidence}): pass {option('wheel_diameter', 0.5 * diameter)}, half of it"
        )
    return None


#: The ground truth's path is sampled this often [s] to measure the scale the wheels'
#: odometry has against it: long enough that a reference's jitter adds little to it.
_SCALE_STEP = 0.5
#: A factor is tried only where the measured scale lies within this share of it.
OBSERVED_TOLERANCE = 0.25


def observed_scale(runs: Sequence[Run], params: WheelParams) -> float | None:
    """How far the ground truth moved over how far the wheels' odometry (with ``params``)
    says, along the runs, sampled every :data:`_SCALE_STEP` where the truth is known:
    about the wheels' true mean diameter over the one given, whatever their headings.
    None where it says little: the truth moved less than 0.1 m, or is known at fewer than
    half the wheel samples (a reference at the stops only cuts the path's corners)."""
    truth_path = odometry_path = 0.0
    samples = matched = 0
    for run in runs:
        log = run.log
        if log is None:
            continue
        known = np.flatnonzero(np.all(np.isfinite(log.truth[:, :2]), axis=1))
        samples, matched = samples + len(log.time), matched + known.size
        if known.size < 2:
            continue
        odometry = log.odometry(params)
        steps = np.floor((log.time[known] - log.time[known[0]]) / _SCALE_STEP)
        kept = known[np.flatnonzero(np.diff(steps, prepend=-1.0) > 0)]
        truth_path += float(np.sum(np.hypot(*np.diff(log.truth[kept, :2], axis=0).T)))
        odometry_path += float(np.sum(np.hypot(*np.diff(odometry[kept, :2], axis=0).T)))
    if truth_path < 0.1 or not odometry_path > 0.0 or 2 * matched < samples:
        return None
    return truth_path / odometry_path


@dataclass(frozen=True)
class ScaleEstimate:
    """``E_s`` from ``n`` straight runs, with its standard error (None for one run)."""

    E_s: float
    standard_error: float | None
    n: int

    @property
    def dof(self) -> int:
        """Degrees of freedom of the standard error."""
        return self.n - 1


def scale_from_straights(runs: Sequence[Run]) -> ScaleEstimate:
    """The mean ratio of measured to odometry distance of straight runs.

    Raises
    ------
    ValueError
        For a run too short to measure, or a ratio no robot has (a unit slip).
    """
    ratios = []
    for run in runs:
        counted = math.hypot(run.odometry_end.x, run.odometry_end.y)
        driven = math.hypot(run.true_end.x, run.true_end.y)
        if counted < MIN_DISTANCE:
            raise ValueError(
                f"{run.label or 'a straight run'}: its odometry distance {counted:.3g} m is too "
                f"short to measure a scale (at least {MIN_DISTANCE:g} m)"
            )
        ratio = driven / counted
        if not 0.5 < ratio < 2.0:
            raise ValueError(
                f"{run.label or 'a straight run'}: {driven:.4g} m measured against {counted:.4g} m "
                "counted is no scale error a robot has: are both in the same unit?"
            )
        ratios.append(ratio)
    values = np.array(ratios)
    se = float(values.std(ddof=1) / math.sqrt(values.size)) if values.size > 1 else None
    return ScaleEstimate(E_s=float(values.mean()), standard_error=se, n=int(values.size))


def scale_only(scale: ScaleEstimate) -> ErrorEstimate:
    """A calibration from straight runs alone: ``E_s``; ``E_d`` and ``E_b`` unmeasured (1)."""
    errors = {} if scale.standard_error is None else {"E_s": scale.standard_error}
    return ErrorEstimate(
        method=STRAIGHT,
        alpha=0.0,
        beta=0.0,
        E_d=1.0,
        E_b=1.0,
        E_s=scale.E_s,
        components={"n_straight": float(scale.n)},
        standard_errors=errors,
        warnings=(
            "straight runs measure the scale E_s only: the wheels' diameters are corrected, "
            "E_d and E_b are not measured. Drive UMBmark next, with these parameters active",
        ),
        dof=scale.dof,
    )

"""The scale error ``E_s`` from straight runs measured against a tape (Sec. 2.2).

The paper assumes the average wheel diameter calibrated before UMBmark: drive straight by
the odometry, measure the distance really driven. Each straight run gives
``E_s = true distance / odometry distance``; the estimate is their mean, its standard
error the runs' spread over ``sqrt(n)`` (Student's t with ``n - 1`` degrees of freedom for
intervals). A square test then sees ``E_b / E_s`` in its turns
(:meth:`umbmark.estimators.base.ErrorEstimate.with_scale`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from umbmark.core.errors import option
from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.registry import STRAIGHT
from umbmark.model.run import Run

__all__ = ["ScaleEstimate", "diameter_mixup", "scale_from_straights", "scale_only"]

#: Shortest straight run that can measure a scale [m].
MIN_DISTANCE = 0.05
#: A scale error within this fraction of 2 or 1/2 is a radius taken for a diameter (the
#: usual ROS mix-up: ``diff_drive_controller`` takes ``wheel_radius``) or the reverse;
#: tyres and wear differ from their nominal diameter by per cent, not by half.
MIXUP_TOLERANCE = 0.15


def diameter_mixup(E_s: float, diameter: float | None, evidence: str) -> str | None:
    """The cause and the fix when the wheels' true mean diameter is about twice (or half)
    the ``diameter`` [m] given (``E_s`` = true over given; ``evidence`` says how that is
    known); None otherwise."""
    if diameter is None or not math.isfinite(E_s):
        return None
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

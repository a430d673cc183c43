"""Whether the wheel diameter a square test is given is a robot's.

A square test measures ``E_d`` and ``E_b`` from the return errors (Sec. 4): the new
multipliers ``c_L``, ``c_R`` and ``wheel_separation_multiplier`` do not depend on the wheel
diameter, and UMBmark does not observe the wheels' mean diameter (``E_s``, calibrated
before it: Sec. 2.2). The diameter given only scales the new wheel diameters printed
(``c_L D``, ``c_R D``) and, for recorded wheels, the odometry the runs are integrated
with. So a diameter ten times off goes through the estimate, and the result would print
wheels of 1.5 m: :func:`diameter_warnings` names it, by the wheelbase
(:data:`umbmark.core.bounds.DIAMETER_PER_WHEELBASE`) and, where the runs have a ground
truth along them, by the path it moved against the odometry's
(:func:`umbmark.estimators.scale.observed_scale`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from umbmark.core.bounds import DIAMETER_PER_WHEELBASE, Origin
from umbmark.core.errors import option, with_flags
from umbmark.estimators.scale import meant_diameter, observed_scale, unit_slip
from umbmark.runs.read import SourceRuns

__all__ = ["diameter_warnings"]

#: The ratio of diameter to wheelbase the usual robots have: a diameter given in
#: another unit is told what it would be in metres where this power of ten brings it
#: nearest (geometrically).
_TYPICAL = 0.45


def diameter_warnings(read: SourceRuns) -> list[str]:
    """The warnings where the wheel diameter of square runs ``read`` is no robot's: outside
    :data:`~umbmark.core.bounds.DIAMETER_PER_WHEELBASE` times the wheelbase, or a power
    of ten off the wheels' as their ground truth's path shows; what it changes and what
    not, and what was likely meant (empty where it is plausible or not given)."""
    diameter = read.active.wheel_diameter
    if diameter is None and read.params is not None:
        diameter = read.params.wheel_diameter
    if diameter is None:
        return []
    wheelbase = read.active.wheelbase
    ratio = diameter / wheelbase
    low, high = DIAMETER_PER_WHEELBASE
    observed = None if read.params is None else observed_scale(read.runs, read.params)
    slip = None if observed is None else unit_slip(observed)
    if low <= ratio <= high and slip is None:
        return []
    named = _named(read.origins)
    if slip is not None:
        assert observed is not None
        meant = meant_diameter(diameter, slip)
        why = (
            f"the ground truth moved {observed:.3g} times as far as the odometry integrated "
            f"with it: the wheels are {meant:g} m ({option('wheel_diameter', meant)})"
        )
    else:
        meant = _nearest(diameter, wheelbase)
        side = "large" if ratio > high else "small"
        why = (
            f"no differential drive has wheels {ratio:.3g} times its wheelbase "
            f"({wheelbase:g} m; plausible: {low:g} to {high:g} times), too {side} by about "
            f"a power of ten: in another unit, or its decimal point slipped? "
            f"({option('wheel_diameter', meant)} would be {meant / wheelbase:.2g} times it)"
        )
    recorded = read.params is not None
    scales = "the new wheel diameters printed" + (
        " and the odometry the runs were integrated with" if recorded else ""
    )
    return [
        with_flags(
            f"the wheel diameter {diameter:g} m ({named}) is implausible: {why}. A square test "
            "does not observe the wheels' mean diameter (E_s): E_d, E_b and the multipliers "
            f"c_L, c_R and wheel_separation_multiplier come from the return errors, but "
            f"{scales} are only as right as it"
        )
    ]


def _named(origins: Mapping[str, Origin]) -> str:
    """Where the diameter came from: ``--wheel-diameter``, ``wheel_diameter in FILE``,
    ``twice wheel_radius in FILE``."""
    origin = origins.get("wheel_diameter", Origin(option("wheel_diameter")))
    named = origin.named()
    return f"twice {named}" if origin.field == "wheel_radius" else named


def _nearest(diameter: float, wheelbase: float) -> float:
    """The diameter [m] a power of ten (10 or 100, up or down) makes nearest to the usual
    robots' ratio to the wheelbase (:data:`_TYPICAL`)."""
    factors = (10.0, 100.0, 0.1, 0.01)
    best = min(factors, key=lambda f: abs(math.log10(diameter * f / wheelbase / _TYPICAL)))
    return meant_diameter(diameter, best)

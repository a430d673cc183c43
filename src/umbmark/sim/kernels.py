"""The numeric kernels of one sampling period of the vectorized simulator: the arcs'
sin(h)/h, slip and bumps on the floor, and the controller's braking profiles."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from umbmark.core.arrays import FloatArray, IntArray
from umbmark.sim.layout import Work

__all__ = [
    "SINC_SERIES_LIMIT",
    "braking",
    "cruise_threshold",
    "floor_noise",
    "half_sinc_series",
]


#: ``chord_step`` takes sin(h)/h in its series form when every ``|h|`` is below this.
SINC_SERIES_LIMIT = 0.01
#: The series' divisions: h^2/42, h^2/20, and h^2/12 = (h^2/6)/2 so that the series
#: yields half of sin(h)/h (halving is exact in binary).
_SERIES_DIVISORS = np.array([42.0, 20.0, 12.0]).reshape(3, 1, 1)


def half_sinc_series(
    h: FloatArray,
    h2: FloatArray,
    terms: FloatArray,
    ones: FloatArray,
    halves: FloatArray,
    out: FloatArray,
) -> Callable[[], None]:
    """A function writing ``0.5 * sin(h)/h`` of the current ``h`` into ``out``, by the
    series of :func:`umbmark.model.kinematics.chord_step` and to the same bits.

    ``h2`` (shaped as ``h``) and ``terms`` (3 by that) are work space; ``ones`` and
    ``halves`` (shaped as ``h``) hold 1 and 1/2.
    """
    multiply, subtract, divide = np.multiply, np.subtract, np.divide
    by42, by20, by12 = terms

    def evaluate() -> None:
        multiply(h, h, h2)
        divide(h2, _SERIES_DIVISORS, terms)
        # (1 - h2/6 (1 - h2/20 (1 - h2/42))) / 2
        subtract(ones, by42, by42)
        multiply(by42, by20, by42)
        subtract(ones, by42, by42)
        multiply(by42, by12, by42)
        subtract(halves, by42, out)

    return evaluate


def floor_noise(
    floor: FloatArray,
    noise: FloatArray,
    order: IntArray,
    rng: np.random.Generator,
    slip: bool,
    bumps: bool,
    work: Work,
) -> Callable[[], None]:
    """A function taking slip and bumps off the floor travel ``floor`` (left and right
    wheel, a column per run) for one period.

    ``noise`` holds the runs' slip, bump rate and bump size; ``order`` the caller's index
    of each column's run. The generator draws for every run of the call, in the caller's
    order, as the model's period does: slip then bumps of the left wheels, then of the
    right ones.
    """
    absolute, add, subtract, multiply = np.abs, np.add, np.subtract, np.multiply
    slip_rate, bump_rate, bump_size = noise
    normal, uniform = work.normal, work.uniform
    in_order = order.size == normal.shape[1] and bool(np.all(order == np.arange(order.size)))
    normal_here = normal if in_order else work.normal_here
    uniform_here = uniform if in_order else work.uniform_here
    travel, moved, direction = work.noise
    bumped = work.bumped

    def apply() -> None:
        if slip and bumps:
            rng.standard_normal(out=normal[0])
            rng.random(out=uniform[0])
            rng.standard_normal(out=normal[1])
            rng.random(out=uniform[1])
        elif slip:
            rng.standard_normal(out=normal)
        else:
            rng.random(out=uniform)
        absolute(floor, travel)
        if bumps:
            np.sign(floor, direction)
        if slip:  # Gaussian, of variance slip^2 * travel
            if not in_order:
                np.take(normal, order, axis=1, out=normal_here)
            np.sqrt(travel, moved)
            multiply(slip_rate, moved, moved)
            multiply(moved, normal_here, moved)
            add(floor, moved, floor)
        if bumps:  # at a rate per metre travelled, each turning the wheel without travel
            if not in_order:
                np.take(uniform, order, axis=1, out=uniform_here)
            multiply(bump_rate, travel, moved)
            np.less(uniform_here, moved, bumped)
            multiply(direction, bump_size, moved)
            multiply(moved, bumped, moved)
            subtract(floor, moved, floor)

    return apply


def braking(
    distance: FloatArray, half: FloatArray | float, hh: FloatArray | float, a2: FloatArray | float
) -> FloatArray:
    """Fastest speed from which a discrete stop (speed falling by ``a dt`` per period)
    ends within ``distance``: ``sqrt((a dt / 2)^2 + 2 a d) - a dt / 2``, given
    ``half = a dt / 2``, ``hh = half^2`` and ``a2 = 2 a`` (the operations of the
    controller, in its order)."""
    return np.asarray(np.sqrt(hh + a2 * distance) - half, dtype=np.float64)


def cruise_threshold(
    top: FloatArray,
    half: FloatArray,
    hh: FloatArray,
    a2: FloatArray,
    dt: float,
    stop: FloatArray,
) -> FloatArray:
    """Distance to go (per run) from which the controller's goal is its top speed ``top``.

    From there on the braking speed is at least ``top`` (it grows with the distance, also
    in floating point: every operation is monotonic), the one-period cap ``distance / dt``
    is at least twice ``top`` (so it binds neither the goal nor the speed, which never
    exceeds ``top``) and the target is beyond the stop tolerance ``stop``.
    """
    r = np.maximum(((top + half) ** 2 - hh) / a2, 0.0)
    r = np.maximum(np.maximum(r, 2.0 * top * dt), 2.0 * stop) * (1.0 + 1e-9)
    while True:
        short = (braking(r, half, hh, a2) < top) | (r / dt < 2.0 * top)
        if not short.any():
            return r
        r = np.where(short, r * (1.0 + 1e-9), r)

"""The plausible range of every physical parameter, wherever it comes from.

A parameter reaches umbmark as an option (``--wheelbase``), from a run log's
``metadata.yaml`` (``wheelbase``), an OptiOdom session's metadata (``Li``), a runs
table's ``# umbmark-active:`` line or a parameter file: each gets the same bound, written
here once, and the same check. Each check takes the parameter ``named`` as its source
names it: an option (:func:`umbmark.core.errors.option`, shown as the command line's flag
or the library's keyword) or a file's field, with the file (``source``). The square's
geometry (a wheelbase below half the side) is checked here too (:func:`check_square_geometry`).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import cast

from umbmark.core.errors import InputError, given, option

__all__ = [
    "DIAMETER_PER_WHEELBASE",
    "ENCODER_RESOLUTION_RANGE",
    "GEAR_RATIO_RANGE",
    "GYRO_BIAS_RANGE",
    "GYRO_BIAS_WALK_RANGE",
    "GYRO_FULL_SCALE_RANGE",
    "GYRO_NOISE_RANGE",
    "GYRO_SCALE_RANGE",
    "IMU_RATE_RANGE",
    "LENGTH_RANGE",
    "MAX_SIDE_LENGTH",
    "MAX_WHEELBASE",
    "MIN_LENGTH",
    "MULTIPLIER_RANGE",
    "Origin",
    "check_int_option",
    "check_length",
    "check_multiplier",
    "check_positive_option",
    "check_range",
    "finite_float",
    "in_metres",
    "option_float",
    "smallest_side",
]

#: Largest plausible square side [m]: beyond, a unit slip is likelier.
MAX_SIDE_LENGTH = 100.0
#: Largest plausible wheelbase or wheel diameter [m].
MAX_WHEELBASE = 10.0
#: Smallest plausible length [m].
MIN_LENGTH = 0.001
#: Bounds of a plausible configured wheelbase or wheel diameter [m].
LENGTH_RANGE = (MIN_LENGTH, MAX_WHEELBASE)
#: Bounds of a plausible wheel diameter over the wheelbase: 0.23 (TurtleBot3 Waffle) to
#: 0.6 (Husky) on the usual robots, 0.1 on a wide AGV with small wheels, 1.1 on a
#: wheelchair's drive wheels, under 2 on a balancing robot's. A diameter given ten times
#: too large or too small leaves it on a LabMate (0.15 / 0.34 m: 0.44), a Pioneer (0.51)
#: or a Kobuki (0.30).
DIAMETER_PER_WHEELBASE = (0.06, 2.0)
#: Bounds of a plausible wheel factor or multiplier (skid-steer wheelbases reach about 2).
MULTIPLIER_RANGE = (0.2, 5.0)
#: Encoder pulses per motor revolution.
ENCODER_RESOLUTION_RANGE = (1.0, 1e7)
#: Motor revolutions per wheel revolution.
GEAR_RATIO_RANGE = (1e-3, 1e4)
#: An IMU's readings a second [Hz] (ROS drivers publish 50 to 1000).
IMU_RATE_RANGE = (10.0, 1000.0)
#: A gyro's scale factor ``k_g`` (``omega_true = k_g (omega_read - bias)``): MEMS parts
#: are within a few per cent; 20 % off is a gyro set to another range than its driver
#: assumes.
GYRO_SCALE_RANGE = (0.8, 1.25)
#: A gyro's bias [deg/s] (MEMS parts: within 0.5 to 3; beyond 10, a broken part).
GYRO_BIAS_RANGE = (-10.0, 10.0)
#: A gyro bias's random walk [deg/s/sqrt(s)] (MEMS parts: about 1e-4 to 1e-3).
GYRO_BIAS_WALK_RANGE = (0.0, 0.05)
#: A gyro's white-noise density [deg/s/sqrt(Hz)] (MEMS parts: 0.004 to 0.02).
GYRO_NOISE_RANGE = (0.0, 0.5)
#: A gyro's full scale [deg/s] (MEMS parts: 125 to 2000, some 4000).
GYRO_FULL_SCALE_RANGE = (30.0, 4000.0)

Source = str | Path | None


@dataclass(frozen=True)
class Origin:
    """Where a parameter's value came from, for messages about it.

    Attributes
    ----------
    field : str
        The option (:func:`umbmark.core.errors.option`, which a message renders as the
        flag ``--wheelbase`` or the keyword ``wheelbase``) or the file's field
        (``wheelbase``, ``Li``).
    file : str or None
        The file that holds the field; None for an option.
    """

    field: str
    file: str | None = None

    def named(self, source: str | None = None) -> str:
        """``--wheelbase``, or ``Li in FILE`` (the field alone where ``source``, the file
        the message is about, is that file)."""
        if self.file is None or self.file == source:
            return self.field
        return f"{self.field} in {self.file}"


def option_float(named: str, value: float, source: Source = None) -> float:
    """An option's (or a field's) number as a float, refusing what is no number or too
    large for one (a Python ``int`` of hundreds of digits)."""
    if isinstance(value, bool):
        raise InputError(f"{named} must be a number, not {value!r}", source=source)
    try:
        return float(value)
    except OverflowError:
        digits = len(str(abs(int(value))))
        raise InputError(f"{named} is far too large ({digits} digits)", source=source) from None
    except (TypeError, ValueError):
        raise InputError(
            f"{named} must be a number, not {str(value)[:24]!r}", source=source
        ) from None


def finite_float(named: str, value: float, source: Source = None) -> float:
    """:func:`option_float`, refusing infinity and NaN (``--wheelbase inf``) as what they
    are rather than as out of a range."""
    number = option_float(named, value, source)
    if not math.isfinite(number):
        raise InputError(f"{named} must be a finite number, got {number}", source=source)
    return number


def check_positive_option(named: str, value: float, unit: str = "", source: Source = None) -> None:
    """Refuse a value that is not a positive finite number."""
    value = finite_float(named, value, source)
    if not value > 0:
        shown = f"{value:g} {unit}".strip()
        raise InputError(f"{named} must be > 0, got {shown}", source=source)


def check_int_option(named: str, value: int, low: int, high: int, source: Source = None) -> int:
    """A whole-number option within ``low`` to ``high`` (both included), refused as
    :func:`check_range` does (also a ``bool``, a float and an integer of any size); the
    number as an ``int``."""
    return int(check_range(named, value, (low, high), source, whole=True))


def check_length(
    named: str,
    value: float,
    largest: float,
    smallest: float = MIN_LENGTH,
    source: Source = None,
) -> None:
    """Refuse a length [m] that is not positive, or implausibly small or large (a unit
    slip); the message names the plausible range."""
    check_positive_option(named, value, "m", source)
    value = float(value)
    if value > largest:
        raise InputError(
            f"{given(named, value, 'm')} is implausibly large: lengths are in metres "
            f"(at most {largest:g} m here; plausible: {smallest:g} to {largest:g} m)",
            source=source,
        )
    if value < smallest:
        raise InputError(
            f"{given(named, value, 'm')} is implausibly small: lengths are in metres "
            f"(plausible: {smallest:g} to {largest:g} m)",
            source=source,
        )


def in_metres(named: str, value: float, plausible: tuple[float, float]) -> str:
    """What a length given in millimetres or centimetres is in metres, for each of the two
    that lands within ``plausible`` [m]: ``10 mm is --scatter 0.01, 10 cm is --scatter
    0.1`` (empty when neither does)."""
    low, high = plausible
    said = [
        f"{value:g} {unit} is {given(named, value * factor)}"
        for unit, factor in (("mm", 0.001), ("cm", 0.01))
        if low <= value * factor <= high
    ]
    return ", ".join(said)


def check_multiplier(named: str, value: float, source: Source = None) -> None:
    """Refuse a wheel factor or multiplier outside :data:`MULTIPLIER_RANGE`."""
    low, high = MULTIPLIER_RANGE
    value = finite_float(named, value, source)
    if not (math.isfinite(value) and low <= value <= high):
        raise InputError(
            f"{given(named, value)} is not a plausible factor: it must be within {low:g} to "
            f"{high:g}",
            source=source,
        )


def check_range(
    named: str,
    value: float,
    bounds: tuple[float, float],
    source: Source = None,
    *,
    unit: str = "",
    whole: bool = False,
) -> float:
    """Refuse a number outside ``bounds`` (both included) or not finite, or with ``whole``
    not a whole number; the one wording of a closed range, for options and files' fields
    alike: ``--runs must be 2 to 20, got 1``, ``--dt must be 0.0001 to 0.1 s, got 1 s``
    (from Python ``runs must be 2 to 20, got 1``). Returns the number (an ``int`` with
    ``whole``)."""
    low, high = bounds
    number: float
    if whole:
        try:
            if isinstance(value, bool):
                raise TypeError
            number = operator.index(cast("int", value))  # int and numpy integers
        except TypeError:
            raise InputError(
                f"{named} must be a whole number, not {str(value)[:24]!r}", source=source
            ) from None
        digits = len(str(abs(number))) if abs(number) >= 10**24 else 0
        shown = f"a number of {digits} digits" if digits else str(number)
        lowest, highest = (_whole(low), _whole(high))
    else:
        number = finite_float(named, value, source)
        shown, lowest, highest = format(number, "g"), format(low, "g"), format(high, "g")
    if not low <= number <= high:
        said = f" {unit}" if unit else ""
        raise InputError(
            f"{named} must be {lowest} to {highest}{said}, got {shown}{said}", source=source
        )
    return number


def _whole(bound: float) -> str:
    """A whole number's bound as written (``9223372036854775807``, not ``9.22337e+18``)."""
    return str(int(bound)) if math.isfinite(bound) and bound == int(bound) else format(bound, "g")


def smallest_side(wheelbase: float) -> float:
    """The side [m] a square must exceed for a robot of ``wheelbase`` [m] (the odometry's):
    twice the wheelbase (:func:`check_square_geometry`)."""
    return 2.0 * wheelbase


def check_square_geometry(
    side_length: float | None,
    wheelbase: float,
    origins: Mapping[str, Origin] | None = None,
    multiplier: float = 1.0,
) -> None:
    """Refuse a wheelbase [m] (the odometry's: the configured one times ``multiplier``)
    that is not below half the square's side [m] (:func:`smallest_side`).

    The rule is a plausibility check of the two numbers, not a limit of the robot or of
    the estimators (the virtual robot, its wheelbase 0.34 m, drives and calibrates 0.5 m
    squares with the rule left out): a wheelbase of
    half the side or more is usually swapped or mistyped ``--side-length`` and
    ``--wheelbase``, and on so small a square ``E_d`` bends the legs little (``beta``
    grows with ``L / b``). ``origins`` says where the values came from (``wheelbase``,
    ``separation_multiplier``, ``side_length``; options where not said); the message
    names those.
    """
    if side_length is None or side_length > smallest_side(wheelbase):
        return
    b_from, side_from, m_from, source = geometry_origins(origins, multiplier)
    if b_from.file is None and side_from.file is None and m_from is None:
        raise InputError(
            f"{option('wheelbase', wheelbase, 'm')} is not smaller than the square: it must be "
            f"below half the side ({option('side_length', side_length, 'm')}, so b < "
            f"{side_length / 2:g} m); "
            "are the two swapped or in other units?"
        )
    named = b_from.named(source)
    if m_from is not None:
        named += f" times {given(m_from.named(source), multiplier)}"
    raise InputError(
        f"the odometry's wheelbase {wheelbase:g} m ({named}) is not smaller than the square: "
        f"it must be below half the side ({given(side_from.named(source), side_length, 'm')}, so "
        f"b < {side_length / 2:g} m); are the two swapped or in other units?",
        source=source,
    )


def geometry_origins(
    origins: Mapping[str, Origin] | None, multiplier: float
) -> tuple[Origin, Origin, Origin | None, str | None]:
    """Where the wheelbase, the side and (unless 1) the multiplier came from, and the one
    file they all come from (None if they come from several, or from options only)."""
    origins = origins or {}
    b_from = origins.get("wheelbase", Origin(option("wheelbase")))
    side_from = origins.get("side_length", Origin(option("side_length")))
    m_from = origins.get("separation_multiplier") if multiplier != 1.0 else None
    files = {o.file for o in (b_from, side_from, m_from) if o is not None and o.file}
    return b_from, side_from, m_from, files.pop() if len(files) == 1 else None

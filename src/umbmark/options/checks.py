"""The checks of the option spec's newer kinds (:class:`~umbmark.options.spec.Spec`): a
list of values (``most``), a closed ``range`` (of a number or a whole number), a
``ratio``, and ``give`` (a closed range whose message says what to give). Each names the
option as :func:`umbmark.core.errors.option` does."""

from __future__ import annotations

import math
import operator
from collections.abc import Collection
from typing import cast

from umbmark.core.bounds import (
    check_int_option,
    check_positive_option,
    check_range,
    finite_float,
)
from umbmark.core.errors import InputError, given

__all__ = ["check_bounded", "check_give", "check_list"]


def check_list(named: str, value: object, most: int, source: str | None = None) -> list[object]:
    """The values of a list option: 1 to ``most`` of them (a text or a single number is
    no list)."""
    if isinstance(value, (str, bytes)) or not isinstance(value, Collection):
        raise InputError(
            f"{named} must list 1 to {most} values, not {str(value)[:24]!r}", source=source
        )
    values = list(value)
    if not 1 <= len(values) <= most:
        raise InputError(f"{named} must list 1 to {most} values, got {len(values)}", source=source)
    return values


def check_bounded(
    named: str,
    value: object,
    kind: str,
    bounds: tuple[float | None, float | None],
    unit: str = "",
    source: str | None = None,
) -> None:
    """Refuse a value outside ``bounds`` (``low``, ``high``; None: none that side):
    ``kind`` ``integer``, a whole number within them; ``range``, a number within them;
    ``ratio``, a positive number strictly between them."""
    low = -math.inf if bounds[0] is None else bounds[0]
    high = math.inf if bounds[1] is None else bounds[1]
    if kind == "integer":
        check_int_option(named, cast("int", value), cast("int", low), cast("int", high))
    elif kind == "range":
        check_range(named, cast("float", value), (low, high), source)
    else:
        check_positive_option(named, cast("float", value), unit, source)
        if not low < float(cast("float", value)) < high:
            raise InputError(
                f"{given(named, float(cast('float', value)), unit)} is not a plausible ratio "
                f"({low:g} to {high:g})",
                source=source,
            )


def check_give(
    named: str,
    value: object,
    whole: bool,
    bounds: tuple[float | None, float | None],
    unit: str = "",
    source: str | None = None,
) -> None:
    """Refuse a finite number (a whole one with ``whole``) outside ``bounds`` (``low``,
    ``high``, both included; None: none that side), saying what to give: ``--runs 1:
    give 2 to 20``, ``--side-length 0.1 m: give 0.5 to 20 m``."""
    low = -math.inf if bounds[0] is None else bounds[0]
    high = math.inf if bounds[1] is None else bounds[1]
    if whole:
        if isinstance(value, bool) or not hasattr(value, "__index__"):
            raise InputError(
                f"{named} must be a whole number, not {str(value)[:24]!r}", source=source
            )
        number: float = operator.index(cast("int", value))
        shown = str(number)
    else:
        number = finite_float(named, cast("float", value), source)
        shown = repr(number)
    if not low <= number <= high:
        said = f" {unit}" if unit else ""
        raise InputError(
            f"{given(named, shown, unit)}: give {low:g} to {high:g}{said}", source=source
        )

"""The checks of the option spec's newer kinds (:class:`~umbmark.options.spec.Spec`): a
list of values (``most``), a closed ``range`` (of a number or a whole number: the one
wording of :func:`umbmark.core.bounds.check_range`) and a ``ratio``. Each names the
option as :func:`umbmark.core.errors.option` does."""

from __future__ import annotations

import math
from collections.abc import Collection
from typing import cast

from umbmark.core.bounds import check_positive_option, check_range
from umbmark.core.errors import InputError, given

__all__ = ["check_bounded", "check_list"]


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
    whole: bool = False,
) -> None:
    """Refuse a value outside ``bounds`` (``low``, ``high``; None: none that side):
    ``kind`` ``range``, a number (a whole one with ``whole``) within them, both included
    (``--runs must be 2 to 20, got 1``); ``ratio``, a positive number strictly between
    them."""
    low = -math.inf if bounds[0] is None else bounds[0]
    high = math.inf if bounds[1] is None else bounds[1]
    if kind == "range":
        check_range(named, cast("float", value), (low, high), source, unit=unit, whole=whole)
        return
    check_positive_option(named, cast("float", value), unit, source)
    if not low < float(cast("float", value)) < high:
        raise InputError(
            f"{given(named, float(cast('float', value)), unit)} is not a plausible ratio "
            f"({low:g} to {high:g})",
            source=source,
        )

"""The checks of the option spec's newer kinds (:class:`~umbmark.options.spec.Spec`): a
list of values (``most``), a closed ``range`` (of a number or a whole number: the one
wording of :func:`umbmark.core.bounds.check_range`) and a ``ratio``. Each names the
option as :func:`umbmark.core.errors.option` does."""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass
from typing import Literal, cast

from umbmark.core.bounds import check_positive_option, check_range
from umbmark.core.errors import InputError, given

__all__ = ["Bound", "check_bounded", "check_list"]


@dataclass(frozen=True)
class Bound:
    """The values an option's number may take.

    Attributes
    ----------
    kind : {"factor", "positive", "length", "offset", "range", "ratio"}
        ``factor``: a wheel factor or multiplier
        (:data:`umbmark.core.bounds.MULTIPLIER_RANGE`); ``positive``: above 0 and, with
        ``high``, at most ``high``; ``length``: a plausible length up to ``high`` [m];
        ``offset``: every number within ``high`` of 0; ``range``: ``low`` to ``high``,
        both included (a whole number for an ``integer`` option), refused as ``--runs must
        be 2 to 20, got 1`` (:func:`umbmark.core.bounds.check_range`); ``ratio``: above 0
        and strictly between ``low`` and ``high`` (a true-over-nominal ratio).
    high : float or None
        The largest value, in the option's unit.
    low : float or None
        The smallest value of a ``range`` or ``ratio``.
    """

    kind: Literal["factor", "positive", "length", "offset", "range", "ratio"]
    high: float | None = None
    low: float | None = None


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

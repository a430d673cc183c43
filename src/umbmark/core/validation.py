"""Checks that values are what a physical parameter can be, with a message saying which."""

from __future__ import annotations

import math

__all__ = ["check_positive", "require_positive"]


def check_positive(name: str, value: float, *, allow_zero: bool = False, unit: str = "") -> None:
    """Raise ``ValueError`` unless ``value`` is finite and > 0 (>= 0 with ``allow_zero``)."""
    ok = math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        shown = f"{value!r} {unit}".strip()
        raise ValueError(f"{name.replace('_', ' ')} must be {bound}, got {shown}")


def require_positive(owner: object, *names: str, allow_zero: bool = False) -> None:
    """:func:`check_positive` for attributes of ``owner`` (a dataclass's ``__post_init__``)."""
    for name in names:
        check_positive(name, getattr(owner, name), allow_zero=allow_zero)

"""Field paths: naming a value inside a message of any type, and reading it.

The options ``left_field`` and ``right_field`` of
:class:`~umbmark.sources.bag.bag_options.BagOptions` name two numbers of a vendor's message
(``my_robot_msgs/msg/WheelEncoders``) by a path: field names separated by dots, each
optionally followed by one index, ``left_ticks``, ``wheels.left.position``,
``positions[0]``, ``wheels[1].angle``. :func:`parse_path` checks the syntax (the options
do before a bag is opened); :func:`~umbmark.sources.bag.custom.resolve_field` checks a
path against the type's definition; :func:`getter` and :func:`row_getter` read it from
deserialized messages.
"""

from __future__ import annotations

import keyword
import operator
import re
from collections.abc import Callable, Sequence
from typing import Any, cast

from umbmark.core.errors import InputError, given

__all__ = ["MAX_DEPTH", "MAX_INDEX", "Step", "attribute", "getter", "parse_path", "row_getter"]

#: Field names in a path, at most (``a.b.c`` has 3).
MAX_DEPTH = 8
#: Largest array index in a path.
MAX_INDEX = 65_535

_SEGMENT = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d{1,7})\])?")

Step = str | int
"""One step of a field path: an attribute name, or an index into an array."""


def parse_path(text: str, what: str = "field path") -> tuple[Step, ...]:
    """The steps of a field path: ``"wheels[1].position"`` is ``("wheels", 1, "position")``.

    Parameters
    ----------
    text : str
        Field names separated by dots, each optionally followed by one index ``[k]``,
        at most :data:`MAX_DEPTH` names, indexes at most :data:`MAX_INDEX`.
    what : str
        How messages name the path (``option("left_field")``,
        :func:`umbmark.core.errors.option`).

    Raises
    ------
    InputError
        The path is malformed, too deep, or has too large an index.
    """
    parts = text.strip().split(".")
    if len(parts) > MAX_DEPTH:
        raise InputError(f"{given(what, repr(text))} is deeper than {MAX_DEPTH} fields")
    steps: list[Step] = []
    for part in parts:
        match = _SEGMENT.fullmatch(part.strip())
        if match is None:
            raise InputError(
                f"{given(what, repr(text))} is not a field path: write field names separated "
                "by dots, "
                "each with at most one index, e.g. left_ticks, wheels.left.position, "
                "positions[0]"
            )
        steps.append(match.group(1))
        if match.group(2) is not None:
            index = int(match.group(2))
            if index > MAX_INDEX:
                raise InputError(
                    f"{given(what, repr(text))}: index {index} is larger than {MAX_INDEX}"
                )
            steps.append(index)
    return tuple(steps)


def attribute(name: str) -> str:
    """The attribute of rosbags' message class for the field ``name`` (``from_`` for a
    field named ``from``: rosbags appends ``_`` to Python keywords)."""
    return f"{name}_" if keyword.iskeyword(name) else name


def getter(steps: Sequence[Step]) -> Callable[[object], float]:
    """A function that follows ``steps`` into a deserialized message.

    Runs of names become one :func:`operator.attrgetter`, indexes an
    :func:`operator.itemgetter`; it raises IndexError where a sequence is too short.
    """
    parts: list[Callable[[Any], Any]] = []
    names: list[str] = []
    for step in steps:
        if isinstance(step, str):
            names.append(attribute(step))
            continue
        if names:
            parts.append(operator.attrgetter(".".join(names)))
            names = []
        parts.append(operator.itemgetter(step))
    if names:
        parts.append(operator.attrgetter(".".join(names)))
    if len(parts) == 1:
        return parts[0]

    def follow(msg: object) -> float:
        value: Any = msg
        for part in parts:
            value = part(value)
        return cast("float", value)

    return follow


def row_getter(paths: Sequence[Sequence[Step]]) -> Callable[[object], tuple[Any, ...]]:
    """A function that returns the values at all ``paths`` of a message, as a tuple.

    Paths of names only are read by one :func:`operator.attrgetter` (the common case,
    and the fastest); otherwise each path by its :func:`getter`.
    """
    if len(paths) > 1 and all(isinstance(step, str) for path in paths for step in path):
        get: Callable[[object], tuple[Any, ...]] = operator.attrgetter(
            *(".".join(attribute(name) for name in cast("Sequence[str]", path)) for path in paths)
        )
        return get
    getters = [getter(path) for path in paths]
    return lambda msg: tuple(get(msg) for get in getters)

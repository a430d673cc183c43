"""Wheel data in messages of any type: field paths, and definitions from ``.msg`` files.

A vendor's driver may publish its wheels in its own message, for example
``my_robot_msgs/msg/WheelEncoders``::

    std_msgs/Header header
    int32 left_ticks
    int32 right_ticks

The options ``left_field`` and ``right_field`` of
:class:`~umbmark.sources.bag.bag_options.BagOptions` name the two values in such a message by
a field path (:mod:`umbmark.sources.bag.fieldpath`): ``left_ticks``,
``wheels.left.position``, ``positions[0]``, ``wheels[1].angle``; :func:`resolve_field`
checks one against the type's definition.

Definitions
-----------
rosbags deserializes a message by its type's definition. ROS 1 bags carry the
definition of every type they hold, and so do ROS 2 bags that embed them (MCAP files,
and sqlite3 bags of rosbag2 Iron and later, bag metadata version 8 and up); rosbags'
``AnyReader`` takes them from the bag. Older ROS 2 bags (sqlite3, Humble and earlier)
carry none: rosbags then knows only the standard ROS 2 types, and a custom type's
definition must come from its ``.msg`` files, given as ``msg_dir``
(:func:`add_definitions`). Definitions in the bag win over files for the same type.

``msg_dir`` is searched recursively (hidden folders skipped, at most
:data:`MAX_MSG_FILES` files), so it can be a package (``my_robot_msgs/``), its ``msg/``
folder, or a workspace's ``src/``. A file's type name comes from where it lies:
``<pkg>/msg/<Name>.msg`` is ``<pkg>/msg/<Name>`` (the layout of a ROS package), and any
other ``<pkg>/<Name>.msg`` is ``<pkg>/msg/<Name>`` too (a flat folder per package). Only
the files of the types needed are read. Types they use that are neither in the bag nor in
``msg_dir`` (``std_msgs/Header``, ``geometry_msgs/Point``) come from rosbags' standard
ROS 2 types (ROS 1 Noetic's for ROS 1 bags).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError, given, option
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.fieldpath import Step, parse_path
from umbmark.sources.text import read_text

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = [
    "MAX_MSG_FILES",
    "Field",
    "add_definitions",
    "has_header",
    "missing_types",
    "resolve_field",
]

#: ``.msg`` files looked at in ``msg_dir``, at most.
MAX_MSG_FILES = 10_000

#: Number types a wheel value may have, and the bits of an integer counter that wraps
#: around (None: floating point, or 64-bit integers, taken as never wrapping).
NUMBER_BITS: dict[str, int | None] = {
    "byte": 8,
    "char": 8,
    "int8": 8,
    "uint8": 8,
    "int16": 16,
    "uint16": 16,
    "int32": 32,
    "uint32": 32,
    "int64": None,
    "uint64": None,
    "float32": None,
    "float64": None,
}
INTEGERS = frozenset(NUMBER_BITS) - {"float32", "float64"}

HEADER = "std_msgs/msg/Header"

# rosbags' parse tree node types (rosbags.interfaces.Nodetype), as plain ints so that
# this module needs rosbags only when reading a bag.
_BASE, _NAME, _ARRAY, _SEQUENCE = 1, 2, 3, 4

FieldDefs = Mapping[str, tuple[Any, Sequence[tuple[str, Any]]]]
"""rosbags' ``Typestore.fielddefs``: type name to ``(constants, [(field, node), ...])``."""


# --- fields checked against a definition ---------------------------------------------


@dataclass(frozen=True)
class Field:
    """A field path checked against a message type.

    Attributes
    ----------
    text : str
        The path as given.
    steps : tuple of (str or int)
        Attribute names and indexes, in order.
    base : str
        The value's number type (``"int32"``, ``"float64"``; :data:`NUMBER_BITS`).
    """

    text: str
    steps: tuple[Step, ...]
    base: str

    @property
    def integer(self) -> bool:
        """Whether the value is an integer (encoder counts, not an angle)."""
        return self.base in INTEGERS

    @property
    def wrap_bits(self) -> int | None:
        """Bits of the counter, if it wraps around (8-, 16- and 32-bit integers)."""
        return NUMBER_BITS[self.base]


def describe(node: tuple[int, Any]) -> str:
    """A parse-tree node as a type is written in a ``.msg`` file (``float64[]``)."""
    kind, detail = node
    if kind == _BASE:
        return str(detail[0])
    if kind == _NAME:
        return str(detail)
    sub, length = detail
    if kind == _ARRAY:
        return f"{describe(sub)}[{length}]"
    return f"{describe(sub)}[<={length}]" if length else f"{describe(sub)}[]"


def _fields_of(fielddefs: FieldDefs, msgtype: str) -> dict[str, tuple[int, Any]]:
    return {name: (int(node[0]), node[1]) for name, node in fielddefs[msgtype][1]}


def _field_list(fields: Mapping[str, tuple[int, Any]]) -> str:
    shown = [f"{name} ({describe(node)})" for name, node in fields.items()]
    return bag_reader.listing(shown) if shown else "none"


def resolve_field(fielddefs: FieldDefs, msgtype: str, text: str, what: str, of: str = "") -> Field:
    """Check the field path ``text`` against ``msgtype``: it must lead to a number.

    Parameters
    ----------
    fielddefs : mapping
        rosbags' type definitions (``typestore.fielddefs``), with ``msgtype`` and every
        type it uses.
    msgtype : str
        The message type (``my_robot_msgs/msg/WheelEncoders``).
    text : str
        The field path (:func:`parse_path`).
    what : str
        How messages name it (``"left field"``).
    of : str
        What it is a field of, for messages (``"/wheels"``).

    Raises
    ------
    InputError
        A field does not exist (the message lists the fields there are), an index is
        out of a fixed array's range or applied to what is no array, or the value is not
        a number (a message, a string, a bool, an array without an index).
    """
    steps = parse_path(text, what)
    name_it = given(what, repr(text)) + (f" of {of}" if of else "")
    fields: dict[str, tuple[int, Any]] | None = _fields_of(fielddefs, msgtype)
    where = msgtype
    node: tuple[int, Any] | None = None
    done = ""
    k = 0
    while k < len(steps):
        name = steps[k]
        assert isinstance(name, str)
        if fields is None:
            assert node is not None
            raise InputError(f"{name_it}: {done} is {describe(node)}, which has no field {name!r}")
        if name not in fields:
            raise InputError(
                f"{name_it}: {where} has no field {name!r}; its fields: {_field_list(fields)}"
            )
        node = fields[name]
        done = f"{done}.{name}" if done else name
        k += 1
        if k < len(steps) and isinstance(steps[k], int):
            index = steps[k]
            assert isinstance(index, int)
            kind, detail = node
            if kind not in (_ARRAY, _SEQUENCE):
                raise InputError(f"{name_it}: {done} is {describe(node)}, not an array")
            sub, length = detail
            if length and index >= length:
                bound = "has" if kind == _ARRAY else "has at most"
                raise InputError(
                    f"{name_it}: {done} ({describe(node)}) {bound} {length} entries, "
                    f"so index {index} is out of range"
                )
            node = (int(sub[0]), sub[1])
            done = f"{done}[{index}]"
            k += 1
        kind, detail = node
        if kind in (_ARRAY, _SEQUENCE):
            raise InputError(
                f"{name_it}: {done} is an array ({describe(node)}): give an index, e.g. {done}[0]"
            )
        if kind == _NAME:
            where = str(detail)
            fields = _fields_of(fielddefs, where)
        else:
            fields = None
    assert node is not None
    kind, detail = node
    if kind == _NAME:
        raise InputError(
            f"{name_it}: {done} is a message ({detail}), not a number; its fields: "
            f"{_field_list(_fields_of(fielddefs, str(detail)))}"
        )
    base = str(detail[0])
    if base not in NUMBER_BITS:
        raise InputError(f"{name_it}: {done} is {base}, not a number")
    return Field(text=text, steps=steps, base=base)


def has_header(fielddefs: FieldDefs, msgtype: str) -> bool:
    """Whether ``msgtype`` has a ``std_msgs/Header header`` as a field of its own."""
    node = _fields_of(fielddefs, msgtype).get("header")
    return node is not None and node[0] == _NAME and node[1] == HEADER


# --- definitions -----------------------------------------------------------------------


def _used_types(fields: Sequence[tuple[str, Any]]) -> list[str]:
    """Names of the message types the fields use."""
    out = []
    for _, node in fields:
        kind, detail = int(node[0]), node[1]
        if kind in (_ARRAY, _SEQUENCE):
            kind, detail = int(detail[0][0]), detail[0][1]
        if kind == _NAME:
            out.append(str(detail))
    return out


def missing_types(fielddefs: FieldDefs, msgtype: str) -> list[str]:
    """The types ``msgtype`` needs (itself included) that ``fielddefs`` lacks, in the
    order they are reached."""
    missing: list[str] = []
    seen = {msgtype}
    queue = [msgtype]
    while queue:
        name = queue.pop(0)
        if name not in fielddefs:
            missing.append(name)
            continue
        for used in _used_types(fielddefs[name][1]):
            if used not in seen:
                seen.add(used)
                queue.append(used)
    return missing


def type_name(path: Path) -> str:
    """The type a ``.msg`` file defines, by where it lies (see the module docstring)."""
    parent = path.parent
    package = parent.parent.name if parent.name == "msg" else parent.name
    return f"{package}/msg/{path.stem}"


def msg_files(msg_dir: Path) -> dict[str, list[Path]]:
    """The ``.msg`` files under ``msg_dir``, by the type they define (several files may
    define one type: a workspace's ``src/`` and ``install/``).

    Raises
    ------
    InputError
        ``msg_dir`` is no folder, cannot be read, or holds more than
        :data:`MAX_MSG_FILES` files.
    """
    src = str(msg_dir)
    if not msg_dir.is_dir():
        raise InputError("no such folder of .msg files", source=src)
    found: dict[str, list[Path]] = {}
    count = 0
    for top, dirs, files in os.walk(msg_dir.resolve()):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for name in sorted(files):
            if not name.endswith(".msg"):
                continue
            count += 1
            if count > MAX_MSG_FILES:
                raise InputError(
                    f"holds more than {MAX_MSG_FILES:,} .msg files: give the folder of the "
                    "robot's message package",
                    source=src,
                )
            path = Path(top) / name
            found.setdefault(type_name(path), []).append(path)
    return found


def _read_definition(paths: Sequence[Path], msgtype: str) -> dict[str, Any]:
    """The parse tree of ``msgtype`` from its ``.msg`` file(s); they must agree."""
    from rosbags.typesys import get_types_from_msg

    parsed: dict[str, Any] = {}
    first: Path | None = None
    for path in paths:
        text = read_text(path)  # bounded; names the file when it cannot be read
        try:
            types = get_types_from_msg(text, msgtype)
        except Exception as err:  # rosbags' parser: TypesysError, or its grammar's errors
            raise InputError(
                f"not a valid definition of {msgtype}: {bag_reader.one_line(err)}", source=path
            ) from None
        if first is None:
            parsed, first = dict(types), path
        elif types[msgtype][1] != parsed[msgtype][1]:
            raise InputError(
                f"defines {msgtype} differently from {first}: keep one of them in the folder",
                source=path,
            )
    return parsed


def add_definitions(
    reader: AnyReader, msgtype: str, msg_dir: Path | None, topic: str, src: str
) -> None:
    """Make sure rosbags can deserialize ``msgtype``: add what the bag lacks from ``msg_dir``.

    Parameters
    ----------
    reader : AnyReader
        The open bag; its ``typestore`` gets the missing definitions.
    msgtype : str
        The type of ``topic``.
    msg_dir : Path or None
        A folder of ``.msg`` files (see the module docstring).
    topic, src : str
        For error messages: the topic, and the bag's path.

    Raises
    ------
    InputError
        A type is defined neither in the bag nor in ``msg_dir``, or a ``.msg`` file is
        bad (the message names the file).
    """
    store = reader.typestore
    missing = missing_types(store.fielddefs, msgtype)
    if not missing:
        return
    needs = "" if missing[0] == msgtype else f", which uses {missing[0]}"
    if msg_dir is None:
        raise InputError(
            f"topic {topic} has type {msgtype}{needs}, whose definition the bag does not "
            f"carry: give {option('msg_dir')} with its .msg files",
            source=src,
        )
    from rosbags.typesys import Stores, get_typestore

    files = msg_files(msg_dir)
    standard = get_typestore(Stores.LATEST if reader.is2 else Stores.ROS1_NOETIC).fielddefs
    added: dict[str, Any] = {}
    queue = list(missing)
    while queue:
        name = queue.pop(0)
        if name in store.fielddefs or name in added:
            continue
        if name in files:
            added.update(_read_definition(files[name], name))
        elif name in standard:
            added[name] = standard[name]
        else:
            package, _, short = name.partition("/msg/")
            via = "" if name == msgtype else f" (used by {msgtype})"
            raise InputError(
                f"topic {topic} has type {msgtype}; the definition of {name}{via} is neither "
                f"in the bag nor in {option('msg_dir', str(msg_dir))} (looked for "
                f"{package}/msg/{short}.msg "
                f"and {package}/{short}.msg)",
                source=src,
            )
        queue.extend(_used_types(added[name][1]))
    try:
        store.register(added)
    except Exception as err:  # rosbags' code generation or a clash with the bag's types
        raise InputError(
            f"the definitions of {bag_reader.listing(sorted(added))} from "
            f"{option('msg_dir', str(msg_dir))} cannot be used: {bag_reader.one_line(err)}",
            source=src,
        ) from None

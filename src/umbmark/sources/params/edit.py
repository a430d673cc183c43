"""A user's controller parameter file changed in place: the three multipliers and nothing
else.

``selfcal --params-file FILE`` writes the new multipliers into the file the controller
loads, which a person wrote and tuned: its comments, units after values, blank lines,
flow lists, quotes and anchors stay as they are. The file is parsed with ruamel.yaml's
round-trip composer, which keeps where every key and value stands in the text; the
values of ``wheel_separation_multiplier``, ``left_wheel_radius_multiplier`` and
``right_wheel_radius_multiplier`` of the controller's block (ros2_control: under
``<controller>: ros__parameters:``, possibly under namespaces or ``/**``; ROS 1: the
controller's namespace keys) are replaced where they stand, a missing one is added as a
line of its own after the block's last, with the block's indentation, and every other byte
is kept. ROS 1's ``wheel_radius_multiplier`` line is removed: the controller would take
it for both wheels and ignore the left and right ones. The edited text is read again and
must hold exactly what was asked (the same document with those values), else nothing is
written.

:func:`edit_parameter_file` writes it atomically (:mod:`umbmark.core.atomic`) after
keeping the previous file beside it, ``FILE.bak`` (``FILE.bak.2``, ``.3``, ... when an
earlier one is there: no backup is ever replaced). A file that does not exist is
written new, holding the controller's block only.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from umbmark.core.atomic import atomic_path
from umbmark.core.errors import InputError

__all__ = ["EditedText", "ParamsEdit", "backup_path", "edit_parameter_file", "edit_parameters"]

#: The multipliers written, in the order a new block lists them.
WRITTEN = (
    "wheel_separation_multiplier",
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
)
#: ROS 1's one multiplier for both wheels: removed where the left and right ones are set.
BOTH_WHEELS = "wheel_radius_multiplier"
#: Keys that mark a mapping as a differential-drive controller's parameters.
_DIFF_DRIVE = frozenset(
    {*WRITTEN, BOTH_WHEELS, "wheel_separation", "wheel_radius", "left_wheel_names",
     "right_wheel_names", "open_loop"}
)  # fmt: skip
#: Most backups kept beside one file (``FILE.bak`` to ``FILE.bak.N``).
MAX_BACKUPS = 999
#: Deepest nesting searched for the controller's block.
_MAX_DEPTH = 16


@dataclass(frozen=True)
class EditedText:
    """A parameter file's text with new multipliers.

    Attributes
    ----------
    text : str
        The new text: the old one with only the values changed, the missing keys added and
        (ROS 1) ``wheel_radius_multiplier`` removed.
    key_path : tuple of str
        The keys of the controller's block (``ros__parameters`` left out).
    changes : tuple of (str, str or None, str)
        Each multiplier: its name, its old value as written (None: added) and its new one.
    removed : tuple of str
        The lines removed (ROS 1's ``wheel_radius_multiplier``), as they were.
    """

    text: str
    key_path: tuple[str, ...]
    changes: tuple[tuple[str, str | None, str], ...]
    removed: tuple[str, ...] = ()


@dataclass(frozen=True)
class ParamsEdit:
    """What :func:`edit_parameter_file` did to a file.

    Attributes
    ----------
    path : Path
        The file written.
    backup : Path or None
        Where the previous file is kept (None: there was none).
    edited : EditedText
        The change.
    """

    path: Path
    backup: Path | None
    edited: EditedText

    def line(self) -> str:
        """One line for people: the file, what changed in it, where the old one is."""
        keys = self.edited.key_path
        name = "/".join(k.strip("/") for k in keys) if "*" not in "".join(keys) else keys[0]
        what = ", ".join(
            f"{key} {old} -> {new}" if old is not None else f"{key} {new} (added)"
            for key, old, new in self.edited.changes
        )
        removed = "".join(f"; removed {line.strip()!r}" for line in self.edited.removed)
        if self.backup is None:
            return f"wrote {os.fspath(self.path)} (new): {name}'s {what}"
        return (
            f"changed {os.fspath(self.path)}: {name}'s {what}{removed}; every other byte "
            f"kept; the previous file kept as {os.fspath(self.backup)}"
        )


def _number(value: float) -> str:
    """A multiplier as the controller's double: always with a point (``1.0``), 10
    significant digits at most."""
    text = repr(float(f"{value:.10g}"))
    return text if any(c in text for c in ".eEn") else f"{text}.0"


def backup_path(path: Path) -> Path:
    """The first of ``FILE.bak``, ``FILE.bak.2``, ... that does not exist.

    Raises
    ------
    InputError
        All :data:`MAX_BACKUPS` exist.
    """
    for k in range(1, MAX_BACKUPS + 1):
        candidate = path.with_name(path.name + (".bak" if k == 1 else f".bak.{k}"))
        if not os.path.lexists(candidate):
            return candidate
    raise InputError(
        f"has {MAX_BACKUPS} backups beside it ({path.name}.bak ...): remove old ones",
        source=path,
    )


def edit_parameter_file(
    path: str | os.PathLike[str],
    values: Mapping[str, float],
    controller: str | None,
    *,
    ros2: bool,
) -> ParamsEdit:
    """Write the multipliers ``values`` into the controller's parameter file ``path``:
    in place, every other byte kept, the previous file kept beside it (module docstring);
    a new file where there is none.

    Parameters
    ----------
    path : path
        The YAML file the controller loads.
    values : mapping of str to float
        The three multipliers by their parameter names.
    controller : str or None
        The controller (``/robot1/diff_cont``, ``diff_cont``); None: the file's one
        diff-drive controller.
    ros2 : bool
        A new file or block is a ros2_control one (``ros__parameters``), else ROS 1; a
        block found keeps its own form.

    Raises
    ------
    InputError
        The file is not a parameter file, names several controllers and none was given,
        cannot be changed in place (the values behind an alias), or cannot be written.
    """
    target = Path(path)
    old = None
    if os.path.lexists(target):
        if target.is_dir():
            raise InputError("is a folder, not a parameter file", source=target)
        from umbmark.sources.params.reader import MAX_FILE_BYTES

        if target.stat().st_size > MAX_FILE_BYTES:
            raise InputError("is larger than any parameter file: not changed", source=target)
        try:
            raw = target.read_bytes()
        except OSError as exc:
            raise InputError(f"cannot be read ({exc.strerror or exc})", source=target) from None
        try:
            old = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise InputError("is not UTF-8 text: not a parameter file", source=target) from None
    edited = edit_parameters(old or "", values, controller, ros2=ros2, source=str(target))
    backup = None
    if old is not None:
        backup = backup_path(target)
        try:
            with open(backup, "xb") as kept:  # never replaces one that appeared meanwhile
                kept.write(raw)
        except OSError as exc:
            raise InputError(
                f"cannot keep the previous file as {backup} ({exc.strerror or exc}): not changed",
                source=target,
            ) from None
    try:
        with atomic_path(target) as tmp:
            tmp.write_bytes(edited.text.encode("utf-8"))
    except BaseException:  # the file is as it was: no copy of it left beside it
        if backup is not None:
            backup.unlink(missing_ok=True)
        raise
    return ParamsEdit(target, backup, edited)


# --- the text -----------------------------------------------------------------------------


def edit_parameters(
    text: str,
    values: Mapping[str, float],
    controller: str | None,
    *,
    ros2: bool,
    source: str = "",
) -> EditedText:
    """``text`` with the multipliers ``values`` in the controller's block (see
    :func:`edit_parameter_file`); an empty text becomes the block alone.

    Raises
    ------
    InputError
        As :func:`edit_parameter_file`, naming ``source``.
    """
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError

    try:
        root = YAML(typ="rt").compose(text)
    except YAMLError as exc:
        problem = getattr(exc, "problem", None) or str(exc)
        raise InputError(f"is not valid YAML ({problem})".splitlines()[0], source=source) from None
    except RecursionError:
        raise InputError("is nested too deep to be a parameter file", source=source) from None
    newline = "\r\n" if "\r\n" in text else "\n"
    wanted = {k: _number(values[k]) for k in WRITTEN}
    if root is None:  # empty, or comments only: they stay, the block follows them
        keys = _default_keys(controller)
        lead = "" if text.endswith(("\n", "\r")) or not text else newline
        body = lead + _block(keys, ros2, wanted, 0, newline)
        return _appended(text, body, keys, ros2, wanted, source)
    if not _is_mapping(root):
        raise InputError("is not a parameter file (not a YAML mapping)", source=source)
    found = _find(root, controller, ros2, source)
    if found is None:  # no block of this controller yet: added at the end
        keys = _default_keys(controller)
        if root.flow_style:
            raise InputError(
                "is one flow mapping ({...}): umbmark adds no block to it; add the "
                "controller's block by hand",
                source=source,
            )
        lead = "" if text.endswith(("\n", "\r")) or not text else newline
        body = lead + newline + _block(keys, ros2, wanted, 0, newline)
        return _appended(text, body, keys, ros2, wanted, source)
    keys, file_ros2, block, outer = found
    return _edit_block(text, keys, file_ros2, block, outer, wanted, newline, source)


def _edit_block(
    text: str,
    keys: tuple[str, ...],
    ros2: bool,
    block: Any,  # noqa: ANN401 (a ruamel MappingNode, or None: ros__parameters missing)
    outer: Any,  # noqa: ANN401 (the controller's own MappingNode)
    wanted: dict[str, str],
    newline: str,
    source: str,
) -> EditedText:
    """Replace, add and remove in the controller's block (spans of ``text``)."""
    spans: list[tuple[int, int, str]] = []  # (start, end, replacement), end exclusive
    changes: list[tuple[str, str | None, str]] = []
    removed: list[str] = []
    pairs = {} if block is None else {k.value: (k, v) for k, v in block.value}
    missing = {}
    for key in WRITTEN:
        if key not in pairs:
            missing[key] = wanted[key]
            changes.append((key, None, wanted[key]))
            continue
        knode, vnode = pairs[key]
        start, end = _value_span(text, knode, vnode, key, source)
        spans.append((start, end, wanted[key]))
        changes.append((key, text[start:end], wanted[key]))
    if not ros2 and BOTH_WHEELS in pairs:
        knode, vnode = pairs[BOTH_WHEELS]
        if block.flow_style:
            raise InputError(
                f"sets {BOTH_WHEELS} in a flow mapping: remove it by hand (ROS 1's "
                "controller would take it for both wheels)",
                source=source,
            )
        first = text.rfind("\n", 0, knode.start_mark.index) + 1
        last = _line_end(text, _value_span(text, knode, vnode, BOTH_WHEELS, source)[1])
        removed.append(text[first:last].rstrip("\r\n"))
        spans.append((first, last, ""))
    if missing:
        spans.append(_insertion(text, block, outer, missing, newline, source))
    new = text
    for start, end, replacement in sorted(spans, reverse=True):
        new = new[:start] + replacement + new[end:]
    edited = EditedText(new, keys, tuple(changes), tuple(removed))
    _verify(text, edited, ros2, wanted, source)
    return edited


def _value_span(
    text: str,
    knode: Any,  # noqa: ANN401
    vnode: Any,  # noqa: ANN401
    key: str,
    source: str,
) -> tuple[int, int]:
    """Where a multiplier's value stands in ``text`` (its anchor left before it)."""
    start, end = vnode.start_mark.index, vnode.end_mark.index
    if start < knode.end_mark.index or type(vnode).__name__ != "ScalarNode":
        raise InputError(
            f"{key} is not a number written there (an alias or a collection): umbmark changes "
            "it only in place; write the number at that key",
            source=source,
        )
    anchor = getattr(vnode, "anchor", None)
    if anchor and text.startswith(f"&{anchor}", start):
        start += len(anchor) + 1
        while start < end and text[start] in " \t":
            start += 1
    return start, end


def _insertion(
    text: str,
    block: Any,  # noqa: ANN401
    outer: Any,  # noqa: ANN401
    missing: dict[str, str],
    newline: str,
    source: str,
) -> tuple[int, int, str]:
    """The lines adding ``missing`` to the block: after its last line, indented as its
    keys; a flow mapping gets them before its ``}``. Without ``ros__parameters`` (ROS 2),
    that level is added to the controller's mapping."""
    target = block if block is not None else outer
    if block is None:
        body: dict[str, Any] = {"ros__parameters": missing}
    else:
        body = dict(missing)
    if target.flow_style:
        close = target.end_mark.index - 1
        if text[close] != "}":
            raise InputError("has a flow mapping umbmark cannot extend: add the keys by hand",
                             source=source)  # fmt: skip
        inner = ", ".join(f"{k}: {_flow(v)}" for k, v in body.items())
        lead = ", " if target.value else ""
        return close, close, lead + inner
    if not target.value:
        raise InputError("has an empty block umbmark cannot extend", source=source)
    column = target.value[0][0].start_mark.column
    step = _indent_step(target, column)
    end = _line_end(text, _last_index(target))
    lines = _lines(body, column, step, newline)
    prefix = "" if text[end - 1 : end] == "\n" else newline
    return end, end, prefix + lines


def _flow(value: object) -> str:
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_flow(v)}" for k, v in value.items()) + "}"
    return str(value)


def _indent_step(node: Any, column: int) -> int:  # noqa: ANN401
    """The file's indentation step: how far its nested blocks go in (2 by default)."""
    for _key, value in node.value:
        if _is_mapping(value) and not value.flow_style and value.value:
            inner = value.value[0][0].start_mark.column - column
            if inner > 0:
                return int(inner)
    return 2


def _lines(body: Mapping[str, Any], column: int, step: int, newline: str) -> str:
    out = []
    for key, value in body.items():
        if isinstance(value, Mapping):
            out.append(f"{' ' * column}{key}:{newline}")
            out.append(_lines(value, column + step, step, newline))
        else:
            out.append(f"{' ' * column}{key}: {value}{newline}")
    return "".join(out)


def _last_index(node: Any) -> int:  # noqa: ANN401
    """The end of the last scalar or flow collection written in ``node`` (a block
    collection's own end lies at the next token, past comments and blank lines)."""
    kind = type(node).__name__
    if kind == "ScalarNode" or getattr(node, "flow_style", False):
        return int(node.end_mark.index)
    items = node.value if kind == "SequenceNode" else [x for pair in node.value for x in pair]
    return max((_last_index(x) for x in items), default=int(node.start_mark.index))


def _line_end(text: str, index: int) -> int:
    """The index after the line break ending the line of ``index`` (the text's end)."""
    at = text.find("\n", index)
    return len(text) if at < 0 else at + 1


def _block(
    keys: Sequence[str], ros2: bool, wanted: Mapping[str, str], column: int, newline: str
) -> str:
    body: dict[str, Any] = dict(wanted)
    if ros2:
        body = {"ros__parameters": body}
    for key in reversed(keys):
        body = {key: body}
    return _lines(body, column, 2, newline)


def _default_keys(controller: str | None) -> tuple[str, ...]:
    from umbmark.sources.params.reader import DEFAULT_CONTROLLER, key_path_of

    return key_path_of(controller or DEFAULT_CONTROLLER)


def _appended(
    text: str, body: str, keys: tuple[str, ...], ros2: bool, wanted: dict[str, str], source: str
) -> EditedText:
    """``text`` with the controller's new block ``body`` after it, checked."""
    changes = tuple((k, None, v) for k, v in wanted.items())
    edited = EditedText(text + body, keys, changes)
    _verify(text, edited, ros2, wanted, source)
    return edited


# --- finding the block, checking the result ---------------------------------------------


def _is_mapping(node: Any) -> bool:  # noqa: ANN401
    return type(node).__name__ == "MappingNode"


def _find(
    root: Any,  # noqa: ANN401
    controller: str | None,
    ros2: bool,
    source: str,
) -> tuple[tuple[str, ...], bool, Any, Any] | None:
    """The controller's block: its keys, whether it is a ros2_control one, its
    parameters' mapping (None: no ``ros__parameters`` yet) and the controller's own
    mapping; None where the file has none of that name (as the reader finds it)."""
    blocks = _blocks(root, (), 0)
    candidates = {"/".join(k.strip("/") for k in b[0]): b for b in blocks}
    if controller is None:
        if len(candidates) == 1:
            return next(iter(candidates.values()))
        if not candidates:
            return None
        raise InputError(
            f"has several controllers ({', '.join(sorted(candidates))}); name one", source=source
        )
    wanted = controller.strip("/")
    matches = [n for n in candidates if wanted in (n, n.rsplit("/", 1)[-1])]
    if len(matches) > 1:
        raise InputError(
            f"has several controllers named {controller!r} ({', '.join(sorted(matches))})",
            source=source,
        )
    if matches:
        return candidates[matches[0]]
    wild = [n for n in candidates if "*" in n]  # ``/**``: every node's, this one's too
    if len(wild) == 1:
        return candidates[wild[0]]
    # a controller block without parameters yet (``diff_cont: {ros__parameters: {}}``)
    return _bare(root, _default_keys(controller), ros2)


def _bare(
    root: Any,  # noqa: ANN401
    keys: tuple[str, ...],
    ros2: bool,
) -> tuple[tuple[str, ...], bool, Any, Any] | None:
    """A block of the controller's keys that holds no diff-drive parameters yet (its
    keys as the file writes them)."""
    node, found = root, []
    for key in keys:
        pairs = {str(k.value): v for k, v in node.value if type(k).__name__ == "ScalarNode"}
        name = key if key in pairs else "/" + key
        inner = pairs.get(name)
        if inner is None or not _is_mapping(inner):
            return None
        node = inner
        found.append(name)
    params = {k.value: v for k, v in node.value}.get("ros__parameters")
    if params is not None and _is_mapping(params):
        return tuple(found), True, params, node
    return tuple(found), ros2, None if ros2 else node, node


def _blocks(
    node: Any,  # noqa: ANN401
    keys: tuple[str, ...],
    depth: int,
) -> list[tuple[tuple[str, ...], bool, Any, Any]]:
    found: list[tuple[tuple[str, ...], bool, Any, Any]] = []
    if not _is_mapping(node) or depth > _MAX_DEPTH:
        return found
    for knode, value in node.value:
        if not _is_mapping(value) or type(knode).__name__ != "ScalarNode":
            continue
        path = (*keys, str(knode.value))
        names = {k.value for k, _ in value.value}
        inner = {k.value: v for k, v in value.value}.get("ros__parameters")
        if (
            inner is not None
            and _is_mapping(inner)
            and _DIFF_DRIVE & {k.value for k, _ in inner.value}
        ):
            found.append((path, True, inner, value))
        elif _DIFF_DRIVE & names:
            found.append((path, False, value, value))
        else:
            found.extend(_blocks(value, path, depth + 1))
    return found


def _verify(
    old: str, edited: EditedText, ros2: bool, wanted: Mapping[str, str], source: str
) -> None:
    """The edited text, read again, is the old document with the controller's block
    holding ``wanted`` (and, ROS 1, no ``wheel_radius_multiplier``): else nothing is
    written (an anchor shared with other values, a layout the edit cannot follow)."""
    from umbmark.sources.text import load_yaml

    before = load_yaml(source or "<text>", old) if old.strip() else {}
    after = load_yaml(source or "<text>", edited.text)
    expected: Any = copy.deepcopy(before if isinstance(before, dict) else {})
    node = expected
    path = (*edited.key_path, "ros__parameters") if ros2 else edited.key_path
    for key in path:
        inner = node.get(key)
        if not isinstance(inner, dict):
            inner = node[key] = {}
        node = inner
    node.update({k: float(v) for k, v in wanted.items()})
    if edited.removed:
        node.pop(BOTH_WHEELS, None)
    if after != expected:
        raise InputError(
            "cannot be changed in place so that only the multipliers change (an anchor or "
            "merge shared with other values?): nothing written; set them by hand",
            source=source,
        )

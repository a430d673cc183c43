"""Reading text files: the one place every text reader (runs tables, run logs, OptiOdom
sessions, parameter files, results) gets its lines from.

Files are UTF-8, with or without a byte-order mark, of at most :data:`MAX_TEXT_BYTES`
(read with that bound, so ``/dev/zero`` or a FIFO cannot exhaust memory). YAML and JSON
are parsed with bounds on nesting (:data:`MAX_DEPTH`), on YAML aliases
(:data:`MAX_ALIASES`: an alias bomb cannot expand) and on the digits of a number
(:data:`MAX_DIGITS`). Line-oriented files (CSV) are read line by line
(:func:`iter_lines`), each line at most :data:`MAX_LINE_CHARS` long, so that a reader's
memory is what it keeps, not the text. Every failure to read becomes an
:class:`umbmark.core.errors.InputError` naming the file (and the row).
"""

from __future__ import annotations

import json
import math
from collections.abc import Generator
from pathlib import Path
from typing import Any

import yaml

from umbmark.core.errors import InputError

__all__ = [
    "MAX_ALIASES",
    "MAX_DEPTH",
    "MAX_DIGITS",
    "MAX_DOCUMENT_BYTES",
    "MAX_LINE_CHARS",
    "MAX_TEXT_BYTES",
    "finite",
    "first_content_line",
    "iter_content_lines",
    "iter_lines",
    "load_json",
    "load_yaml",
    "read_text",
]

#: Largest text file read line by line [bytes]: runs tables and logs are far smaller.
MAX_TEXT_BYTES = 512 * 1024 * 1024
#: Largest file read whole (:func:`read_text`: YAML, JSON, message definitions) [bytes]:
#: parameter files, metadata and results are kilobytes; a parser's objects for text this
#: large take tens of times its size.
MAX_DOCUMENT_BYTES = 16 * 1024 * 1024
#: Deepest nesting of YAML or JSON read.
MAX_DEPTH = 64
#: Most YAML aliases (``*name``) read in one file.
MAX_ALIASES = 16
#: Most digits of a JSON number.
MAX_DIGITS = 40
#: Longest line of a CSV file read [characters]: a row of numbers is far shorter (and
#: Python's csv module refuses cells over 128 KB with a traceback).
MAX_LINE_CHARS = 64 * 1024
#: Bytes read at a time by :func:`read_text`.
_CHUNK_BYTES = 1024 * 1024


def _unreadable(path: str | Path, exc: OSError | UnicodeDecodeError) -> InputError:
    """The one line for a file that cannot be read as text."""
    if isinstance(exc, FileNotFoundError):
        return InputError("no such file", source=path)
    if isinstance(exc, IsADirectoryError):
        return InputError("is a directory, not a file", source=path)
    if isinstance(exc, UnicodeDecodeError):
        return InputError("is not a UTF-8 text file", source=path)
    return InputError(f"cannot be read ({exc.strerror or exc})", source=path)


def read_text(path: str | Path) -> str:
    """Read a text file as UTF-8 (with or without a byte-order mark).

    Raises
    ------
    InputError
        If the file cannot be read or is not text.
    """
    try:
        # In chunks: ``read(MAX_DOCUMENT_BYTES + 1)`` would allocate the bound up front.
        chunks, size = [], 0
        with Path(path).open("rb") as file:
            while size <= MAX_DOCUMENT_BYTES and (chunk := file.read(_CHUNK_BYTES)):
                chunks.append(chunk)
                size += len(chunk)
        raw = b"".join(chunks)
        del chunks
        if len(raw) > MAX_DOCUMENT_BYTES:
            raise InputError(
                f"is larger than {MAX_DOCUMENT_BYTES // (1024 * 1024)} MB: not a file umbmark "
                "reads whole (a parameter, metadata or result file is kilobytes)",
                source=path,
            )
        return raw.decode("utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise _unreadable(path, exc) from None


def iter_lines(
    path: str | Path, max_line: int = MAX_LINE_CHARS
) -> Generator[tuple[int, str], None, None]:
    """The lines of a UTF-8 text file (a byte-order mark is fine), numbered from 1, read
    one at a time: memory is one line, whatever the file's size.

    Lines end at ``\n``, ``\r\n`` or ``\r``; the line ends are not part of the lines.

    Raises
    ------
    InputError
        If the file cannot be read, is not text, has a line longer than ``max_line``
        characters (naming the row) or is longer than :data:`MAX_TEXT_BYTES`.
    """
    number, total = 0, 0
    try:
        with Path(path).open(encoding="utf-8-sig", newline=None) as file:
            while True:
                line = file.readline(max_line + 1)
                if not line:
                    return
                number += 1
                total += len(line)
                if total > MAX_TEXT_BYTES:
                    raise InputError(
                        f"is larger than {MAX_TEXT_BYTES // (1024 * 1024)} MB: not a file "
                        "umbmark reads",
                        source=path,
                    )
                text = line.rstrip("\n")
                if len(text) > max_line:
                    raise InputError(
                        f"is longer than {max_line} characters: not a line umbmark reads "
                        "(a row of numbers is far shorter)",
                        source=path,
                        row=number,
                    )
                yield number, text
    except (OSError, UnicodeDecodeError) as exc:
        raise _unreadable(path, exc) from None


def iter_content_lines(
    path: str | Path, max_line: int = MAX_LINE_CHARS
) -> Generator[tuple[int, str], None, None]:
    """The lines of a text file that are neither blank nor ``#`` comments, numbered from 1,
    read one at a time (see :func:`iter_lines`).

    Raises
    ------
    InputError
        As :func:`iter_lines`.
    """
    for number, line in iter_lines(path, max_line):
        if line.strip() and not line.lstrip().startswith("#"):
            yield number, line


def first_content_line(path: str | Path) -> tuple[int, str] | None:
    """The first line that is neither blank nor a ``#`` comment (a header), or None.

    Raises
    ------
    InputError
        As :func:`iter_lines`, for the lines up to it.
    """
    lines = iter_content_lines(path)
    try:
        return next(lines, None)
    finally:
        lines.close()


def finite(value: object) -> float | None:
    """``value`` as a finite float, or None if it is no number, not finite, or too large.

    Booleans are no numbers; integers too large for a float (401 digits) are refused
    instead of raising ``OverflowError``.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


class _BoundedLoader(yaml.SafeLoader):
    """PyYAML's safe loader with bounds on nesting and aliases."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0
        self._aliases = 0

    def compose_node(self, parent: Any, index: Any) -> Any:  # noqa: ANN401 (PyYAML's API)
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise yaml.YAMLError(f"more than {MAX_ALIASES} aliases")
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise yaml.YAMLError(f"nested more than {MAX_DEPTH} deep")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def load_yaml(path: str | Path, text: str | None = None) -> object:
    """The YAML document of ``path`` (or ``text``, read from it), bounded.

    Raises
    ------
    InputError
        The file cannot be read, is not YAML, or exceeds the bounds.
    """
    content = read_text(path) if text is None else text
    try:
        return yaml.load(content, Loader=_BoundedLoader)
    except yaml.YAMLError as exc:
        problem = getattr(exc, "problem", None) or str(exc)
        mark = getattr(exc, "problem_mark", None)
        row = mark.line + 1 if mark is not None else None
        raise InputError(
            f"is not valid YAML ({problem})".splitlines()[0], source=path, row=row
        ) from None
    except RecursionError:
        raise InputError(f"is nested more than {MAX_DEPTH} deep", source=path) from None
    except (ValueError, OverflowError) as exc:  # an integer of thousands of digits
        raise InputError(f"has a value umbmark cannot read ({exc})"[:160], source=path) from None


def _bounded_number(text: str) -> float:
    if len(text.lstrip("-")) > MAX_DIGITS:
        raise ValueError(f"a number of more than {MAX_DIGITS} digits")
    return float(text)


def _depth(value: object, limit: int) -> int:
    """Nesting depth of parsed JSON, stopping past ``limit``."""
    depth, level = 0, [value]
    while level and depth <= limit:
        depth += 1
        level = [
            child
            for item in level
            if isinstance(item, dict | list)
            for child in (item.values() if isinstance(item, dict) else item)
        ]
        level = [item for item in level if isinstance(item, dict | list)]
    return depth


def load_json(path: str | Path) -> object:
    """The JSON document of ``path``, bounded in depth and in the digits of its numbers.

    Raises
    ------
    InputError
        The file cannot be read, is not JSON, or exceeds the bounds.
    """
    text = read_text(path)
    try:
        data = json.loads(
            text,
            parse_int=_bounded_number,
            parse_float=_bounded_number,
            parse_constant=lambda name: math.nan,
        )
    except json.JSONDecodeError as exc:
        raise InputError(f"is not JSON ({exc.msg})", source=path, row=exc.lineno) from None
    except ValueError as exc:
        raise InputError(f"is not JSON umbmark reads ({exc})", source=path) from None
    except RecursionError:
        raise InputError(f"is JSON nested more than {MAX_DEPTH} deep", source=path) from None
    if _depth(data, MAX_DEPTH) > MAX_DEPTH:
        raise InputError(f"is JSON nested more than {MAX_DEPTH} deep", source=path)
    return data

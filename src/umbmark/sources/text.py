"""Reading text files: the one place every text reader (runs tables, run logs, OptiOdom
sessions, parameter files, results) gets its lines from.

Files are UTF-8, with or without a byte-order mark. Every failure to read becomes an
:class:`umbmark.errors.InputError` naming the file.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError

__all__ = ["content_lines", "read_text"]


def read_text(path: str | Path) -> str:
    """Read a text file as UTF-8 (with or without a byte-order mark).

    Raises
    ------
    InputError
        If the file cannot be read or is not text.
    """
    try:
        return Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError("no such file", source=path) from None
    except IsADirectoryError:
        raise InputError("is a directory, not a file", source=path) from None
    except UnicodeDecodeError:
        raise InputError("is not a UTF-8 text file", source=path) from None
    except OSError as exc:
        raise InputError(f"cannot be read ({exc.strerror or exc})", source=path) from None


def content_lines(path: str | Path) -> list[tuple[int, str]]:
    """The lines of a text file that are neither blank nor ``#`` comments, numbered from 1.

    Raises
    ------
    InputError
        If the file cannot be read or is not text.
    """
    return [
        (number, line)
        for number, line in enumerate(read_text(path).splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]

"""SHA-256 of input files: what the HTML report lists and the history records."""

from __future__ import annotations

import hashlib
from collections.abc import Iterator
from pathlib import Path

__all__ = ["file_sha256", "path_sha256"]

_BLOCK = 1 << 20  # bytes read at a time


def _blocks(file: Path) -> Iterator[bytes]:
    with file.open("rb") as stream:
        yield from iter(lambda: stream.read(_BLOCK), b"")


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, as hex."""
    digest = hashlib.sha256()
    for block in _blocks(Path(path)):
        digest.update(block)
    return digest.hexdigest()


def path_sha256(path: Path) -> str | None:
    """SHA-256 of a file (its bytes, as :func:`file_sha256`), or of a folder's files
    (relative names and contents, sorted); None for a path that is neither."""
    if path.is_file():
        return file_sha256(path)
    if not path.is_dir():
        return None
    digest = hashlib.sha256()
    for file in sorted(p for p in path.rglob("*") if p.is_file()):
        digest.update(file.relative_to(path).as_posix().encode() + b"\0")
        for block in _blocks(file):
            digest.update(block)
    return digest.hexdigest()

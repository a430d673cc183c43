"""Write files whole or not at all: into a temporary file beside the target, then rename."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..errors import InputError

__all__ = ["atomic_path", "atomic_write_text"]


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success rename it onto ``target``.

    The temporary file keeps ``target``'s extension, so writers that choose a format by
    extension (matplotlib) still do. On an exception the temporary file is removed and
    ``target`` is left as it was.

    Raises
    ------
    InputError
        If ``target`` cannot be written (no such folder, no permission, a directory).
    """
    target = Path(target)
    if target.is_dir():
        raise InputError("is a directory; give a file name to write", source=target)
    try:
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{target.stem}.", suffix=target.suffix, dir=target.parent
        )
    except OSError as exc:
        raise InputError(f"cannot be written ({exc.strerror or exc})", source=target) from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        with contextlib.suppress(OSError):
            # mkstemp creates files readable only by their owner; give the usual mode.
            umask = os.umask(0)
            os.umask(umask)
            tmp.chmod(0o666 & ~umask)
        try:
            os.replace(tmp, target)
        except OSError as exc:
            raise InputError(f"cannot be written ({exc.strerror or exc})", source=target) from None
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def atomic_write_text(target: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``target`` atomically."""
    with atomic_path(target) as tmp:
        tmp.write_text(text, encoding="utf-8")

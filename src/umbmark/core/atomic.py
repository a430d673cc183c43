"""Write files whole or not at all: into a temporary file beside the target, then rename.

The guarantees of every file umbmark writes:

* the new contents appear at once (a temporary file in the same folder, flushed to disk
  with ``fsync``, then :func:`os.replace` onto the target), so a reader never sees half
  a file and a crash leaves the old file;
* a target that is a symbolic link keeps the link: the file it points to is replaced;
* a target that exists keeps its permission bits (a 0600 file stays 0600); a new file
  gets the usual mode (0666 less the umask);
* on any exception, ``KeyboardInterrupt`` included, the temporary file is removed.

A folder (a ROS 2 bag, a simulated fleet) is built the same way, whole in a hidden
folder beside its target and renamed onto it at the end (:func:`atomic_tree`).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from umbmark.core.errors import InputError

__all__ = ["atomic_path", "atomic_tree", "atomic_write_text", "fsync"]


def _new_mode(target: Path) -> int:
    """The mode for the file replacing ``target``: its own if it exists, else 0666 - umask."""
    try:
        return stat.S_IMODE(target.stat().st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def fsync(path: Path) -> None:
    """Flush ``path``'s contents to disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success rename it onto ``target``.

    The temporary file keeps ``target``'s extension, so writers that choose a format by
    extension (matplotlib) still do. On success it is flushed to disk, given ``target``'s
    mode (when ``target`` exists) and renamed onto ``target``; a symbolic link is
    followed, so the file it points to is replaced and the link kept. On any exception
    (``KeyboardInterrupt`` too) the temporary file is removed and ``target`` is left as
    it was.

    Raises
    ------
    InputError
        If ``target`` cannot be written (no such folder, no permission, a directory).
    """
    shown = Path(target)
    real = shown.resolve()  # follow links: replace the file, keep the link
    if real.is_dir():
        raise InputError("is a directory; give a file name to write", source=shown)
    try:
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{real.stem}.", suffix=real.suffix, dir=real.parent
        )
    except OSError as exc:
        raise InputError(f"cannot be written ({exc.strerror or exc})", source=shown) from None
    tmp = Path(tmp_name)
    try:
        os.close(fd)
        yield tmp
        fsync(tmp)
        with contextlib.suppress(OSError):
            tmp.chmod(_new_mode(real))
        try:
            os.replace(tmp, real)
        except OSError as exc:
            raise InputError(f"cannot be written ({exc.strerror or exc})", source=shown) from None
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def atomic_write_text(target: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``target`` atomically (see :func:`atomic_path`)."""
    with atomic_path(target) as tmp:
        tmp.write_text(text, encoding="utf-8")


@contextlib.contextmanager
def atomic_tree(target: str | Path) -> Iterator[Path]:
    """Yield a path to build a file or a folder at, in a new hidden folder beside
    ``target`` (the same file system); on success rename what was built there onto
    ``target``.

    The path is not made: the caller makes a folder, or a writer makes its file or
    folder, there (named as ``target``, for writers whose files take their folder's
    name). On success a folder at ``target`` is moved aside first (back again if the
    rename fails) and deleted with all it holds; a link at ``target`` is followed, as by
    :func:`atomic_path`. On any exception (``KeyboardInterrupt`` too) what was built is
    removed and ``target`` is left as it was. Whether ``target`` may be replaced is the
    caller's to check first.

    Raises
    ------
    InputError
        If ``target``'s folder cannot be written, or the rename fails.
    """
    shown = Path(target)
    real = shown.resolve()
    try:
        scratch = Path(tempfile.mkdtemp(prefix=f".{real.name}.", dir=real.parent))
    except OSError as exc:
        raise InputError(f"cannot be written ({exc.strerror or exc})", source=shown) from None
    try:
        fresh = scratch / real.name
        yield fresh
        try:
            _put(fresh, real, scratch)
        except OSError as exc:
            raise InputError(f"cannot be written ({exc.strerror or exc})", source=shown) from None
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _put(fresh: Path, target: Path, scratch: Path) -> None:
    """Rename ``fresh`` onto ``target``; a folder there is moved into ``scratch`` first,
    and back if the rename fails."""
    if not target.is_dir():
        os.replace(fresh, target)
        return
    old = scratch / ".replaced"
    target.rename(old)
    try:
        fresh.rename(target)
    except BaseException:
        old.rename(target)
        raise

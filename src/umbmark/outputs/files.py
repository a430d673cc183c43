"""The files a job is asked to write, checked together before any is written.

No file a user has is replaced unless the caller says so: :meth:`OutputPlan.of` refuses an
output file that exists and an output folder that holds files already (what would be
written into it would mix with what it holds), unless ``force`` (``--force``). This is
the one place every command and library function that writes checks it.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Iterable
from dataclasses import dataclass, fields
from pathlib import Path

from umbmark.core.errors import InputError, option

__all__ = [
    "FIGURE_FORMATS",
    "OutputPlan",
    "check_folder_output",
    "check_new_file",
    "check_new_folder",
    "fresh_folder",
]

#: File extensions a figure can be saved as.
FIGURE_FORMATS = (".png", ".svg", ".pdf")

_YAML = (".yaml", ".yml")
#: Outputs that are folders (made when missing); the others are files.
_FOLDERS = ("tum", "logs")


@dataclass(frozen=True)
class OutputPlan:
    """Where each requested output goes (None: not requested)."""

    output: Path | None = None
    yaml: Path | None = None
    ros1_yaml: Path | None = None
    plot: Path | None = None
    tum: Path | None = None
    logs: Path | None = None
    report: Path | None = None
    bag: Path | None = None

    @classmethod
    def of(
        cls,
        *,
        force: bool = False,
        inputs: Iterable[str | os.PathLike[str]] = (),
        **paths: str | os.PathLike[str] | None,
    ) -> OutputPlan:
        """Check the requested outputs' names; the folders ``tum`` and ``logs`` may be new.

        No output may be one of ``inputs`` or lie inside one (:meth:`check_not_inputs`),
        even with ``force``. Without ``force`` an output file that exists, or an output
        folder that holds files already, is refused (:func:`check_new_file`,
        :func:`check_new_folder`); a bag is checked by its writer
        (:func:`umbmark.sources.bag.writer.bag_target`).

        Raises
        ------
        InputError
            For a name of the wrong kind, two outputs onto one file, an output that cannot
            be written, or one that would replace a file (without ``force``).
        """
        plan = cls(**{k: None if v is None else Path(v) for k, v in paths.items()})
        for name in ("yaml", "ros1_yaml"):
            path = getattr(plan, name)
            if path is not None and path.suffix.lower() not in _YAML:
                raise InputError(
                    f"{option(name, str(path))}: the file name should end in .yaml or .yml"
                )
        if plan.plot is not None and plan.plot.suffix.lower() not in FIGURE_FORMATS:
            raise InputError(
                f"{option('plot', str(plan.plot))}: the file name should end in "
                f"{', '.join(FIGURE_FORMATS)}"
            )
        if plan.report is not None and plan.report.suffix.lower() not in (".html", ".htm"):
            raise InputError(
                f"{option('report', str(plan.report))}: the file name should end in .html or .htm"
            )
        seen: dict[Path, str] = {}
        for name, path in plan.requested():
            key = path.resolve()
            if key in seen:
                raise InputError(
                    f"{option(seen[key])} and {option(name)} both name {path}: "
                    "give each its own file"
                )
            seen[key] = name
        plan.check_writable()
        plan.check_not_inputs(inputs)
        if not force:
            for name, path in plan.requested():
                if name in _FOLDERS:
                    check_new_folder(path)
                elif name != "bag":
                    check_new_file(path)
        return plan

    def requested(self) -> list[tuple[str, Path]]:
        """``(keyword, path)`` of every requested output."""
        return [
            (f.name, getattr(self, f.name))
            for f in fields(self)
            if getattr(self, f.name) is not None
        ]

    def check_writable(self) -> None:
        """Check that every requested output can be written, before any is.

        A file's folder must exist and be writable, and the file must not be a folder; an
        output folder (``tum``, ``logs``) must be a folder or be creatable in a writable
        folder; a bag (a ``.bag`` file or a ROS 2 bag folder) needs a writable folder to be
        written in. A symbolic link is checked where it points.

        Raises
        ------
        InputError
            Naming the first output that cannot be written, and why.
        """
        for name, path in self.requested():
            target = path.resolve()
            if name in _FOLDERS:
                check_folder_output(path)
                continue
            if name == "bag":
                _check_folder(path, target.parent)
                continue
            if target.is_dir():
                raise InputError("is a directory; give a file name to write", source=path)
            _check_folder(path, target.parent)

    def check_not_inputs(self, inputs: Iterable[str | os.PathLike[str]]) -> None:
        """Refuse an output that would overwrite an input or write inside an input folder.

        Links are followed, so an output that is a link to an input is refused too.

        Raises
        ------
        InputError
            Naming the output and the input.
        """
        read = [Path(p).resolve() for p in inputs if Path(p).exists()]
        for name, path in self.requested():
            target = path.resolve()
            for source in read:
                if target == source:
                    raise InputError(
                        f"{option(name, str(path))} would overwrite an input ({source}); "
                        "write the output elsewhere"
                    )
                if source.is_dir() and target.is_relative_to(source):
                    raise InputError(
                        f"{option(name, str(path))} is inside an input folder ({source}); "
                        "write the output elsewhere"
                    )


def check_folder_output(folder: str | os.PathLike[str]) -> None:
    """Check that output folder ``folder`` is a folder or can be made, before writing.

    Raises
    ------
    InputError
        If ``folder`` is a file, or neither it nor its nearest existing parent is a
        writable folder.
    """
    path = Path(folder)
    target = path.resolve()
    if target.exists() and not target.is_dir():
        raise InputError("exists and is not a folder", source=path)
    _check_folder(path, _nearest_existing(target))


def check_new_file(path: str | os.PathLike[str]) -> None:
    """Refuse to replace ``path`` if it exists (a link counts, even a broken one).

    Raises
    ------
    InputError
        ``PATH: exists already; pass --force to replace it`` (``force=True`` from Python).
    """
    if os.path.lexists(path):
        raise InputError(f"exists already; pass {option('force')} to replace it", source=Path(path))


def check_new_folder(folder: str | os.PathLike[str]) -> None:
    """Refuse to write into ``folder`` if it holds anything: new files would mix with the
    ones it holds.

    Raises
    ------
    InputError
        ``FOLDER: is not empty ...; pass --force ...`` (``force=True`` from Python).
    """
    path = Path(folder)
    if path.is_dir() and any(path.iterdir()):
        raise InputError(
            "is not empty: what is written would mix with what it holds; choose a new or "
            f"empty folder, or pass {option('force')} to write into it",
            source=path,
        )


def fresh_folder(default: str | os.PathLike[str]) -> Path:
    """``default`` if it is new or empty, else the first new or empty of ``default-2``,
    ``default-3``, ...: where a command writes into its default folder when an earlier run
    left files in it (``umbmark demo``, ``umbmark selfcal``)."""
    base = Path(default)
    candidate, k = base, 1
    while candidate.exists() and (not candidate.is_dir() or any(candidate.iterdir())):
        k += 1
        candidate = base.with_name(f"{base.name}-{k}")
    return candidate


def _nearest_existing(path: Path) -> Path:
    """``path`` or its nearest ancestor that exists (what a ``mkdir -p`` would start from)."""
    while not path.exists() and path.parent != path:
        path = path.parent
    return path


def _check_folder(output: Path, folder: Path) -> None:
    """Refuse ``output`` unless ``folder`` (where it would be written) is a writable folder.

    The reasons are the system's words, as a failed write would give them.
    """
    if not folder.exists():
        reason = errno.ENOENT
    elif not folder.is_dir():
        reason = errno.ENOTDIR
    elif not os.access(folder, os.W_OK | os.X_OK):
        reason = errno.EACCES
    else:
        return
    raise InputError(f"cannot be written ({os.strerror(reason)})", source=output)

"""The bundled examples: a runs table of a virtual LabMate (in mm), and two real OptiOdom
sessions (a square and circles, with motion-capture ground truth; MIT licence)."""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from umbmark.core.errors import InputError, option

__all__ = ["EXAMPLE_RUNS", "REAL_SESSIONS", "example", "example_sessions"]

#: The bundled example, in ``umbmark/data``.
EXAMPLE_RUNS = "labmate_runs_mm.csv"
#: The real sessions shipped in ``umbmark/data/optiodom``, as written out.
REAL_SESSIONS = ("square/230620202042", "circular/250620202104")


def example(
    path: str | os.PathLike[str] | None = None, *, force: bool = False, real: bool = False
) -> str:
    """The bundled example runs table; written to ``path`` when given.

    Its header says where its numbers come from. Calibrate it with
    ``umbmark.calibrate(path, side_length=4, wheelbase=0.34, unit="mm")``.

    With ``real``, ``path`` is a folder that receives the two real OptiOdom sessions
    (:func:`example_sessions`), and the text returned is their README.

    Raises
    ------
    InputError
        If ``path`` exists and ``force`` is not set, or cannot be written.
    """
    from umbmark.core.atomic import atomic_write_text

    if real:
        if path is None:
            raise InputError(f"{option('real')} needs the folder to write the sessions into")
        example_sessions(path, force=force)
        return str(
            resources.files("umbmark.data").joinpath("optiodom/README.md").read_text("utf-8")
        )

    text = resources.files("umbmark.data").joinpath(EXAMPLE_RUNS).read_text(encoding="utf-8")
    if path is not None:
        from umbmark.outputs.files import OutputPlan

        target = Path(path)
        OutputPlan.of(force=force, output=target)  # writable; new unless force
        atomic_write_text(target, text)
    return text


def example_sessions(folder: str | os.PathLike[str], *, force: bool = False) -> tuple[Path, ...]:
    """Write the two real OptiOdom sessions shipped with umbmark into ``folder``.

    ``folder/square/230620202042`` (a 0.75 m UMBmark square, 3 cw + 3 ccw runs) and
    ``folder/circular/250620202104`` (6 circles) of the OptiOdom data set, with its
    ``LICENSE`` (MIT) and a ``README.md`` saying where they come from. Calibrate with
    ``umbmark.calibrate(folder / "square/230620202042")``.

    Returns
    -------
    tuple of Path
        The session folders written, in the order of :data:`REAL_SESSIONS`.

    Raises
    ------
    InputError
        If ``folder`` holds files already and ``force`` is not set, or cannot be written.
    """
    from umbmark.core.atomic import atomic_path
    from umbmark.outputs.files import check_folder_output, check_new_folder

    def write(path: Path, data: bytes) -> None:
        with atomic_path(path) as tmp:
            tmp.write_bytes(data)

    target = Path(folder)
    check_folder_output(target)
    if not force:
        check_new_folder(target)
    shipped = resources.files("umbmark.data").joinpath("optiodom")
    sessions = []
    try:
        target.mkdir(parents=True, exist_ok=True)
        for name in ("LICENSE", "README.md"):
            write(target / name, shipped.joinpath(name).read_bytes())
        for session in REAL_SESSIONS:
            source = shipped.joinpath(session)
            out = target / session
            out.mkdir(parents=True, exist_ok=True)
            for item in sorted(source.iterdir(), key=lambda entry: entry.name):
                if item.name.endswith(".csv"):
                    write(out / item.name, item.read_bytes())
            sessions.append(out)
    except OSError as exc:
        raise InputError(f"cannot be written ({exc.strerror or exc})", source=target) from None
    return tuple(sessions)

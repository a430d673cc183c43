"""Writing umbmark run logs (the format is described in :mod:`umbmark.sources.runlog.reader`)."""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError
from umbmark.sources.runlog.reader import FORMAT_NAME, LOG_COLUMNS, METADATA_FILE, LogMetadata

__all__ = [
    "as_written",
    "clear_run_log",
    "format_metadata",
    "run_file_name",
    "write_log_csv",
    "write_metadata",
]

#: The run files of a whole run log written by umbmark: ``run-01.csv``, ``run-02.csv``, ...
#: (``simulate --logs``), ``run-01-cw.csv``, ... (a self-calibration's pass).
_RUN_FILE = re.compile(r"run-\d{2,}(-cw|-ccw)?\.csv")


def _pose_cells(x: float, y: float, theta: float) -> list[str]:
    """A ground-truth pose's cells as a run file holds them: ``x, y`` to the micrometre,
    ``theta`` to 1e-8 rad."""
    return [f"{x:.6f}", f"{y:.6f}", f"{theta:.8f}"]


def as_written(x: float, y: float, theta: float) -> tuple[float, float, float]:
    """A ground-truth pose as :func:`write_log_csv` writes it and a reader reads it back
    [m, rad]: what a figure computed before writing must use to equal the reader's."""
    a, b, c = (float(cell) for cell in _pose_cells(x, y, theta))
    return a, b, c


def run_file_name(k: int) -> str:
    """The name of run ``k`` (from 1) of a whole run log: ``run-01.csv``."""
    return f"run-{k:02d}.csv"


def clear_run_log(folder: str | Path, *, remove: bool) -> list[Path]:
    """The files of the run log umbmark wrote into ``folder`` (``metadata.yaml`` and
    ``run-NN.csv`` or ``run-NN-cw.csv``), removed when ``remove``: a new run log replaces
    them whole, never mixed with them. Files of other kinds are kept.

    Raises
    ------
    InputError
        If ``folder`` holds another ``.csv`` (read as a run with the new ones): it is
        not removed, and nothing is.
    """
    path = Path(folder)
    if not path.is_dir():
        return []
    mine = [f for f in path.iterdir() if f.name == METADATA_FILE or _RUN_FILE.fullmatch(f.name)]
    other = sorted(f.name for f in path.iterdir() if f.suffix.lower() == ".csv" and f not in mine)
    if other:
        raise InputError(
            f"holds {other[0]}, not a run of a run log umbmark wrote: it would be read "
            "with the new runs; choose a new or empty folder",
            source=path,
        )
    if remove:
        for f in mine:
            f.unlink()
    return mine


def format_metadata(metadata: LogMetadata) -> str:
    """The text of a run log's ``metadata.yaml``."""
    body: dict[str, Any] = {
        "format": FORMAT_NAME,
        "version": 1,
        "wheel_data": metadata.wheel_data,
        "wheel_diameter": metadata.wheel_diameter,
        "wheelbase": metadata.wheelbase,
        "encoder_resolution": metadata.encoder_resolution,
        "gear_ratio": metadata.gear_ratio,
    }
    if metadata.side_length is not None:
        body["side_length"] = metadata.side_length
    body["c_left"] = metadata.c_left
    body["c_right"] = metadata.c_right
    body["wheel_separation_multiplier"] = metadata.separation_multiplier
    body.update(metadata.extra)
    header = "# umbmark run log: lengths in metres, angles in radians, time in seconds\n"
    return header + yaml.safe_dump(body, sort_keys=False)


def write_metadata(folder: str | Path, metadata: LogMetadata) -> Path:
    """Write ``metadata.yaml`` into ``folder`` (created if missing)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / METADATA_FILE
    atomic_write_text(path, format_metadata(metadata))
    return path


def write_log_csv(
    path: str | Path,
    time: NDArray[np.float64],
    pose: NDArray[np.float64] | None,
    wheels: NDArray[np.float64] | NDArray[np.int64],
    comment: str = "",
) -> None:
    """Write one run-log CSV.

    Parameters
    ----------
    time : array, shape (n,)
        Seconds.
    pose : array, shape (n, 3), or None
        Ground truth ``x, y, theta`` [m, rad]; a row of NaN leaves its cells empty.
    wheels : array, shape (n, 2)
        Cumulative ``left, right`` counts (integers) or wheel angles [rad].
    """
    out = io.StringIO()
    out.write("".join(f"# {line}\n" for line in comment.splitlines()))
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(LOG_COLUMNS)
    integer = np.issubdtype(np.asarray(wheels).dtype, np.integer)
    for i in range(len(time)):
        row: list[str] = [f"{time[i]:.6f}"]
        if pose is None or np.isnan(pose[i]).any():
            row += ["", "", ""]
        else:
            row += _pose_cells(float(pose[i, 0]), float(pose[i, 1]), float(pose[i, 2]))
        w: Sequence[Any] = wheels[i]
        row += [str(int(v)) for v in w] if integer else [f"{float(v):.9f}" for v in w]
        writer.writerow(row)
    atomic_write_text(path, out.getvalue())

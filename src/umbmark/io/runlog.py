"""The umbmark run log: recorded runs as CSV time series plus a small metadata file.

Format
------
A folder holding ``metadata.yaml`` and one or more CSV files (``*.csv``). Each CSV has a
header with these columns, one row per sample, in time order:

=========  ===========================================================================
column     meaning
=========  ===========================================================================
time       seconds (any origin)
x, y       ground-truth position [m], in any fixed frame (motion capture, map)
theta      ground-truth heading [rad]
left       left wheel: cumulative encoder counts, or cumulative wheel angle [rad]
right      right wheel: the same
=========  ===========================================================================

A row may leave the ground-truth cells or the wheel cells empty when the two are sampled
at different times; umbmark associates them by time and says how well they matched. A
file may hold one run or several (separated by rests near the start point).

``metadata.yaml`` (lengths in metres)::

    format: umbmark-runlog
    version: 1
    wheel_data: counts        # counts (encoder pulses) or angles (wheel radians)
    wheel_diameter: 0.15      # nominal D_n
    wheelbase: 0.34           # nominal b
    encoder_resolution: 2000  # pulses per motor revolution (counts only)
    gear_ratio: 20            # motor revolutions per wheel revolution (counts only)
    side_length: 4.0          # optional: the square's side, for UMBmark
    c_left: 1.0               # optional: wheel factors active during the runs
    c_right: 1.0

Further keys (``truth``, ``notes``) are kept as they are and otherwise ignored.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from .atomic import atomic_write_text

__all__ = ["LOG_COLUMNS", "METADATA_FILE", "LogMetadata", "write_log_csv", "write_metadata"]

LOG_COLUMNS = ("time", "x", "y", "theta", "left", "right")
METADATA_FILE = "metadata.yaml"
FORMAT_NAME = "umbmark-runlog"


@dataclass(frozen=True)
class LogMetadata:
    """The wheel parameters of a run log (see the module's documentation)."""

    wheel_diameter: float
    wheelbase: float
    wheel_data: str = "counts"
    encoder_resolution: float = 1.0
    gear_ratio: float = 1.0
    side_length: float | None = None
    c_left: float = 1.0
    c_right: float = 1.0
    extra: Mapping[str, Any] = field(default_factory=dict)

    def to_yaml(self) -> str:
        """The metadata file's text."""
        body: dict[str, Any] = {
            "format": FORMAT_NAME,
            "version": 1,
            "wheel_data": self.wheel_data,
            "wheel_diameter": self.wheel_diameter,
            "wheelbase": self.wheelbase,
            "encoder_resolution": self.encoder_resolution,
            "gear_ratio": self.gear_ratio,
        }
        if self.side_length is not None:
            body["side_length"] = self.side_length
        body["c_left"] = self.c_left
        body["c_right"] = self.c_right
        body.update(self.extra)
        header = "# umbmark run log: lengths in metres, angles in radians, time in seconds\n"
        return header + yaml.safe_dump(body, sort_keys=False)


def write_metadata(folder: str | Path, metadata: LogMetadata) -> Path:
    """Write ``metadata.yaml`` into ``folder`` (created if missing)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / METADATA_FILE
    atomic_write_text(path, metadata.to_yaml())
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
            row += [f"{pose[i, 0]:.6f}", f"{pose[i, 1]:.6f}", f"{pose[i, 2]:.8f}"]
        w: Sequence[Any] = wheels[i]
        row += [str(int(v)) for v in w] if integer else [f"{float(v):.9f}" for v in w]
        writer.writerow(row)
    atomic_write_text(path, out.getvalue())

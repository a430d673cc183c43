"""Reading the umbmark run log: recorded runs as CSV time series plus a small metadata file.

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
    wheel_separation_multiplier: 1.0  # optional: active; the odometry used b times this

Where ``c_left``, ``c_right`` or ``wheel_separation_multiplier`` are given, they are the
parameters active during the runs: :func:`umbmark.calibrate` composes its correction with
them unless a ``--current-...`` option says otherwise.

Two further keys say how the runs were recorded (what ``umbmark selfcal`` writes)::

    runs: one per file        # each CSV holds exactly one run (no splitting at rests)
    truth: at stops           # ground truth measured only where the robot stood

Other keys (``notes``, ...) are kept as they are and otherwise ignored.
:mod:`umbmark.sources.runlog.writer` writes run logs.
"""

from __future__ import annotations

import csv
import io
import itertools
import math
from array import array
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from umbmark.core.bounds import (
    ENCODER_RESOLUTION_RANGE,
    GEAR_RATIO_RANGE,
    MAX_SIDE_LENGTH,
    MAX_WHEELBASE,
    check_length,
    check_multiplier,
    check_range,
)
from umbmark.core.errors import InputError
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import PoseSeries, Recording, WheelSeries
from umbmark.sources.text import finite, first_content_line, iter_content_lines, load_yaml

__all__ = [
    "FORMAT_NAME",
    "LOG_COLUMNS",
    "MAX_SAMPLES",
    "METADATA_FILE",
    "LogMetadata",
    "is_runlog",
    "read_metadata",
    "read_runlog",
]

LOG_COLUMNS = ("time", "x", "y", "theta", "left", "right")
METADATA_FILE = "metadata.yaml"
FORMAT_NAME = "umbmark-runlog"
#: Most rows (samples) read from one run file: 14 hours at 100 Hz, 83 minutes at 1 kHz.
#: The file is read line by line and only the numbers are kept (56 bytes a row).
MAX_SAMPLES = 5_000_000
#: The metadata's lengths and their largest plausible values [m] (as ``--wheel-diameter``,
#: ``--wheelbase`` and ``--side-length``), ...
_LENGTH_BOUNDS = {
    "wheel_diameter": MAX_WHEELBASE,
    "wheelbase": MAX_WHEELBASE,
    "side_length": MAX_SIDE_LENGTH,
}
#: ... its encoder's figures (as ``umbmark simulate``'s options); the rest are wheel
#: factors and multipliers (as ``--current-c-l`` and its kin).
_RANGES = {"encoder_resolution": ENCODER_RESOLUTION_RANGE, "gear_ratio": GEAR_RATIO_RANGE}


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
    separation_multiplier: float = 1.0
    active_recorded: bool = False

    @property
    def one_run_per_file(self) -> bool:
        """``runs: one per file``: each CSV is one run, not split at rests."""
        return self.extra.get("runs") == "one per file"

    @property
    def truth_at_stops(self) -> bool:
        """``truth: at stops``: ground truth measured only where the robot stood."""
        return self.extra.get("truth") == "at stops"

    @property
    def params(self) -> WheelParams:
        """The odometry parameters of the runs (wheelbase times the multiplier)."""
        return WheelParams(
            wheelbase=self.wheelbase * self.separation_multiplier,
            wheel_diameter=self.wheel_diameter,
            encoder_resolution=self.encoder_resolution,
            gear_ratio=self.gear_ratio,
            c_left=self.c_left,
            c_right=self.c_right,
        )


def is_runlog(path: Path) -> bool:
    """Whether ``path`` is a run-log folder, or a CSV inside one."""
    folder = path if path.is_dir() else path.parent
    return (folder / METADATA_FILE).is_file()


def read_metadata(path: str | Path) -> LogMetadata:
    """Read a run log's ``metadata.yaml``.

    Raises
    ------
    InputError
        For a missing file, invalid YAML, or missing or implausible values.
    """
    path = Path(path)
    data = load_yaml(path)
    if not isinstance(data, dict):
        raise InputError("is not a mapping of keys to values", source=path)
    wheel_data = str(data.get("wheel_data", "counts"))
    if wheel_data not in ("counts", "angles"):
        raise InputError(f"wheel_data is {wheel_data!r}; use counts or angles", source=path)

    def number(key: str, default: float | None = None) -> float:
        value = data.get(key, default)
        if value is None:
            raise InputError(f"has no {key}", source=path)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(f"{key} is {value!r}, not a number", source=path)
        number = finite(value)
        if number is None or number <= 0:
            raise InputError(f"{key} is {f'{value!r}'[:24]}, not a positive number", source=path)
        # The same bounds as the options that give these values.
        if key in _LENGTH_BOUNDS:
            check_length(key, number, _LENGTH_BOUNDS[key], source=path)
        elif key in _RANGES:
            check_range(key, number, _RANGES[key], source=path)
        else:
            check_multiplier(key, number, source=path)
        return number

    counts = wheel_data == "counts"
    side = data.get("side_length")
    known = {
        "format",
        "version",
        "wheel_data",
        "wheel_diameter",
        "wheelbase",
        "encoder_resolution",
        "gear_ratio",
        "side_length",
        "c_left",
        "c_right",
        "wheel_separation_multiplier",
    }
    return LogMetadata(
        wheel_diameter=number("wheel_diameter"),
        wheelbase=number("wheelbase"),
        wheel_data=wheel_data,
        encoder_resolution=number("encoder_resolution") if counts else 1.0,
        gear_ratio=number("gear_ratio", 1.0) if counts else 1.0,
        side_length=None if side is None else number("side_length"),
        c_left=number("c_left", 1.0),
        c_right=number("c_right", 1.0),
        extra={k: v for k, v in data.items() if k not in known},
        separation_multiplier=number("wheel_separation_multiplier", 1.0),
        active_recorded=any(
            k in data for k in ("c_left", "c_right", "wheel_separation_multiplier")
        ),
    )


def read_runlog(path: str | Path) -> tuple[list[Recording], LogMetadata]:
    """Read a run log: a folder (every ``*.csv`` in it) or one CSV file of it.

    Raises
    ------
    InputError
        Naming the file (and row) and the problem.
    """
    path = Path(path)
    folder = path if path.is_dir() else path.parent
    meta_path = folder / METADATA_FILE
    if not meta_path.is_file():
        raise InputError(
            f"has no {METADATA_FILE} beside it: a run log needs one (see umbmark docs)",
            source=path,
        )
    metadata = read_metadata(meta_path)
    if path.is_dir():
        candidates = sorted(folder.glob("*.csv"))
        if not candidates:
            raise InputError("holds no .csv run files", source=folder)
        files = [f for f in candidates if _is_log_csv(f)]
        if not files:
            raise InputError(
                "holds runs tables but no run files (header time,x,y,theta,left,right)",
                source=folder,
            )
    else:
        files = [path]
    scale = 1.0 if metadata.wheel_data == "angles" else metadata.params.radians_per_pulse
    recordings = [_read_log_csv(f, scale, metadata.params, metadata.side_length) for f in files]
    if metadata.truth_at_stops:
        recordings = [replace(r, truth_at_stops=True) for r in recordings]
    return recordings, metadata


def _is_log_csv(path: Path) -> bool:
    """Whether ``path`` is a run file (its first non-comment line a run-log header).

    A runs table beside the logs (a ``direction`` column) is not, and is left alone; any
    other file is refused rather than left out without a word, for a run file that cannot
    be read (another encoding, a misspelt header, another delimiter) would otherwise drop
    its runs from the calibration.

    Raises
    ------
    InputError
        For a ``.csv`` that is neither: naming it and what its first line is.
    """
    if not path.is_file():
        raise InputError("is not a file: a run-log folder holds run files (.csv)", source=path)
    first = first_content_line(path)  # raises, naming the file, when it cannot be read
    if first is None:
        raise InputError("is empty: a run file needs the header time,x,y,theta,left,right",
                         source=path)  # fmt: skip
    cells = {c.strip().lower() for c in first[1].replace(";", ",").split(",")}
    if set(LOG_COLUMNS) <= cells:
        return True
    if "direction" in cells:  # a runs table kept beside the logs
        return False
    missing = [c for c in LOG_COLUMNS if c not in cells]
    if len(missing) <= len(LOG_COLUMNS) // 2:  # a run file's header, short of columns
        raise InputError(
            f"missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} (a run "
            f"file's header is {','.join(LOG_COLUMNS)})",
            source=path,
            row=first[0],
        )
    shown = first[1] if len(first[1]) <= 60 else first[1][:57] + "..."
    raise InputError(
        f"is not a run file: its header {shown!r} is not {','.join(LOG_COLUMNS)} (fix "
        "it, or move the file out of the run-log folder)",
        source=path,
        row=first[0],
    )


def _read_log_csv(
    path: Path, scale: float, params: WheelParams, side_length: float | None
) -> Recording:
    lines = iter_content_lines(path)
    try:
        wheel_columns, truth_columns = _read_samples(path, lines, scale)
    finally:
        lines.close()
    wheels = np.column_stack([np.frombuffer(c, dtype=np.float64) for c in wheel_columns])
    truth = np.column_stack([np.frombuffer(c, dtype=np.float64) for c in truth_columns])
    if wheels.shape[0] < 2:
        raise InputError("has fewer than 2 rows with wheel data", source=path)
    if not np.all(np.isfinite(wheels)):
        raise InputError(
            f"wheel angles overflow: the wheel data times {scale:.3g} rad per count are not "
            "finite numbers",
            source=path,
        )
    for name, series in (("wheel", wheels), ("ground-truth", truth)):
        if series.shape[0] > 1 and not np.all(np.diff(series[:, 0]) > 0):
            raise InputError(f"{name} time does not increase from row to row", source=path)
    return Recording(
        name=path.name,
        wheels=WheelSeries(time=wheels[:, 0], angles=wheels[:, 1:]),
        truth=PoseSeries(time=truth[:, 0], poses=truth[:, 1:]) if truth.shape[0] >= 2 else None,
        params=params,
        side_length=side_length,
        path=str(path),
    )


def _read_samples(
    path: Path, lines: Iterator[tuple[int, str]], scale: float
) -> tuple[list[array[float]], list[array[float]]]:
    """The samples of a run file, one compact column each: wheels ``time, left, right``
    (``left`` and ``right`` times ``scale``), ground truth ``time, x, y, theta``.

    Raises
    ------
    InputError
        Naming the row and the problem.
    """
    first = next(lines, None)
    if first is None:
        raise InputError("is empty", source=path)
    header_row, header_line = first
    header = [c.strip().lower() for c in next(csv.reader([header_line]))]
    missing = [c for c in LOG_COLUMNS if c not in header]
    if missing:
        raise InputError(
            f"missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
            f"(a run log has {', '.join(LOG_COLUMNS)})",
            source=path,
            row=header_row,
        )
    index = [header.index(c) for c in LOG_COLUMNS]
    wheel: list[array[float]] = [array("d") for _ in range(3)]
    truth: list[array[float]] = [array("d") for _ in range(4)]
    samples = 0
    while chunk := list(itertools.islice(lines, _CHUNK)):
        if samples + len(chunk) <= MAX_SAMPLES and _whole_chunk(
            chunk, index, len(header), scale, wheel, truth
        ):
            samples += len(chunk)
            continue
        for number, line in chunk:
            samples += 1
            if samples > MAX_SAMPLES:
                raise InputError(
                    f"has more than {MAX_SAMPLES} samples: umbmark reads at most {MAX_SAMPLES} "
                    "rows of a run file (split the recording into runs)",
                    source=path,
                    row=number,
                )
            _read_row(path, number, line, index, len(header), scale, wheel, truth)
    return wheel, truth


#: Rows read at a time: each block is parsed whole (numpy's parser, in C) where every row
#: has all six numbers, finite, and no quoting; else row by row, as :func:`_read_row` says.
_CHUNK = 4096


def _whole_chunk(
    chunk: list[tuple[int, str]],
    index: list[int],
    cells: int,
    scale: float,
    wheel: list[array[float]],
    truth: list[array[float]],
) -> bool:
    """Append the rows of ``chunk`` to ``wheel`` and ``truth`` if every one has ``cells``
    cells, no quotes, and a finite number in each of the columns ``index`` (the rows then
    read exactly as :func:`_read_row` reads them); False, appending nothing, otherwise."""
    texts = [line for _, line in chunk]
    commas = cells - 1
    if any(t.count(",") != commas or '"' in t for t in texts):
        return False
    try:
        values = np.loadtxt(
            io.StringIO("\n".join(texts)),
            dtype=np.float64,
            delimiter=",",
            comments=None,
            usecols=index,
            ndmin=2,
        )
    except ValueError:  # an empty cell, a word, a digit Python reads and numpy does not
        return False
    if values.shape != (len(texts), len(index)) or not np.all(np.isfinite(values)):
        return False
    t, x, y, theta, left, right = values.T
    for column, data in zip(wheel, (t, left * scale, right * scale), strict=True):
        column.frombytes(np.ascontiguousarray(data).tobytes())
    for column, data in zip(truth, (t, x, y, theta), strict=True):
        column.frombytes(np.ascontiguousarray(data).tobytes())
    return True


def _read_row(
    path: Path,
    number: int,
    line: str,
    index: list[int],
    width: int,
    scale: float,
    wheel: list[array[float]],
    truth: list[array[float]],
) -> None:
    """Append row ``number`` (``line``) of a run file to ``wheel`` and ``truth`` (see
    :func:`_read_samples`), or refuse it naming the row and the problem."""
    cells = next(csv.reader([line]))
    if len(cells) < width:
        raise InputError(f"has {len(cells)} cells, the header has {width}", source=path, row=number)
    values = []
    for name, i in zip(LOG_COLUMNS, index, strict=True):
        text = cells[i].strip()
        if not text:
            values.append(math.nan)
            continue
        try:
            value = float(text)
        except ValueError:
            shown = repr(text) if len(text) <= 40 else repr(text[:40]) + "..."
            raise InputError(f"{name} {shown} is not a number", source=path, row=number) from None
        if not math.isfinite(value):
            raise InputError(f"{name} is {text[:40]}", source=path, row=number)
        values.append(value)
    t, x, y, theta, left, right = values
    if math.isnan(t):
        raise InputError("time is empty", source=path, row=number)
    has_wheels = not (math.isnan(left) or math.isnan(right))
    has_truth = not (math.isnan(x) or math.isnan(y) or math.isnan(theta))
    if not has_wheels and not has_truth:
        raise InputError("has neither wheel data nor ground truth", source=path, row=number)
    if has_wheels:
        for column, value in zip(wheel, (t, left * scale, right * scale), strict=True):
            column.append(value)
    if has_truth:
        for column, value in zip(truth, (t, x, y, theta), strict=True):
            column.append(value)

"""The OptiOdom session layout (Sousa, Petry, Moreira, Costa; MIT licence).

A session is a folder ``<id>/`` holding

- ``<id>_metadata.csv``: one key per row, values in the following cells (trailing cells
  empty): ``ngear`` (gear ratio), ``encRes`` (encoder pulses per motor revolution), ``Li``
  (nominal wheelbase [m]), ``Di`` (nominal wheel diameters [m], two values), ``N`` (runs),
  ``L`` (square side [m], square sessions only); other rows describe the capture.
- ``<id>_run-NN.csv``, no header: ``time [s], x_gt [m], y_gt [m], theta_gt [rad],
  ticks_right, ticks_left``; the ticks are encoder **increments per cycle**, not counts,
  and ground truth starts at (0, 0, 0) in the run's start frame.
- ``<id>_run-NN_odo.csv``: the robot's own odometry logs (not used).

Files may begin with a UTF-8 byte-order mark. Each run file is one run. The two ``Di``
values are taken in the order of the tick columns (right, left); in the published
sessions they are equal.
"""

from __future__ import annotations

import csv
import datetime as dt
import math
import re
from array import array
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from umbmark.core.bounds import (
    ENCODER_RESOLUTION_RANGE,
    GEAR_RATIO_RANGE,
    MAX_SIDE_LENGTH,
    MAX_WHEELBASE,
    check_length,
    check_range,
)
from umbmark.core.errors import InputError
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import PoseSeries, Recording, WheelSeries
from umbmark.sources.text import iter_lines

__all__ = [
    "MAX_METADATA_ROWS",
    "MAX_SAMPLES",
    "OptiOdomSession",
    "is_optiodom_session",
    "is_session_listing",
    "read_optiodom",
    "session_start",
]

#: Most rows (samples) read from one run file; it is read line by line, only the numbers
#: kept (48 bytes a row). The published runs have a few thousand.
MAX_SAMPLES = 5_000_000
#: Most rows read from a session's metadata file (the published ones have about 20).
MAX_METADATA_ROWS = 10_000

#: The metadata's lengths and their largest plausible values [m]: ``Li`` as
#: ``--wheelbase``, ``Di`` as ``--wheel-diameter``, ``L`` as ``--side-length``; ...
_LENGTH_BOUNDS = {"Li": MAX_WHEELBASE, "Di": MAX_WHEELBASE, "L": MAX_SIDE_LENGTH}
#: ... the encoder's figures as ``umbmark simulate``'s options.
_RANGES = {"encRes": ENCODER_RESOLUTION_RANGE, "ngear": GEAR_RATIO_RANGE}

_RUN = re.compile(r"^(?P<id>.+)_run-(?P<n>\d+)\.csv$")


class OptiOdomSession:
    """The metadata of a session, read from the file ``path`` (named in messages)."""

    def __init__(self, path: Path, meta: dict[str, list[str]]) -> None:
        self.path = path
        self.meta = meta

    def number(self, key: str, index: int = 0) -> float:
        """A metadata value as a float.

        Raises
        ------
        InputError
            If it is missing or not a positive number.
        """
        values = self.meta.get(key, [])
        if len(values) <= index or not values[index].strip():
            raise InputError(f"metadata has no value {index + 1} for {key}", source=self.path)
        try:
            value = float(values[index])
        except ValueError:
            raise InputError(
                f"metadata {key} {values[index]!r} is not a number", source=self.path
            ) from None
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"metadata {key} = {value:g} is not positive", source=self.path)
        # The same bounds as the options that give these values (--wheelbase, ...).
        if key in _LENGTH_BOUNDS:
            check_length(key, value, _LENGTH_BOUNDS[key], source=self.path)
        elif key in _RANGES:
            check_range(key, value, _RANGES[key], source=self.path)
        return value

    @property
    def params(self) -> WheelParams:
        """Nominal wheel parameters (``Di`` taken as right, left)."""
        d_right, d_left = self.number("Di", 0), self.number("Di", 1)
        d = 0.5 * (d_left + d_right)
        return WheelParams(
            wheelbase=self.number("Li"),
            wheel_diameter=d,
            encoder_resolution=self.number("encRes"),
            gear_ratio=self.number("ngear"),
            c_left=d_left / d,
            c_right=d_right / d,
        )

    @property
    def side_length(self) -> float | None:
        """The square's side [m], for square sessions."""
        values = self.meta.get("L", [])
        return self.number("L") if values and values[0].strip() else None


#: A session's id: the capture's day and time, ``DDMMYYYYhhmm`` (``230620202042``).
_SESSION_ID = re.compile(r"^(\d{2})(\d{2})(\d{4})(\d{2})(\d{2})$")


def session_start(folder: str | Path) -> float | None:
    """When a session was captured [s since 1970]: the data set names each session by its
    capture's day and time (``230620202042``: 23 June 2020, 20:42), taken as UTC (the
    lab's zone is not recorded); None for an id that is no such time."""
    meta = _metadata_file(Path(folder))
    found = None if meta is None else _SESSION_ID.match(meta.name.removesuffix("_metadata.csv"))
    if found is None:
        return None
    day, month, year, hour, minute = (int(g) for g in found.groups())
    try:
        when = dt.datetime(year, month, day, hour, minute, tzinfo=dt.timezone.utc)
    except ValueError:
        return None
    return when.timestamp()


def _metadata_file(folder: Path) -> Path | None:
    found = sorted(folder.glob("*_metadata.csv"))
    return found[0] if found else None


def is_optiodom_session(path: Path) -> bool:
    """Whether ``path`` is a folder in the OptiOdom layout."""
    return path.is_dir() and is_session_listing(p.name for p in path.iterdir())


def is_session_listing(names: Iterable[str]) -> bool:
    """Whether a folder's file names are an OptiOdom session's (``<id>_metadata.csv`` and
    ``<id>_run-NN.csv``): for a folder listed elsewhere (at a URL) as for a local one."""
    names = list(names)
    return any(n.endswith("_metadata.csv") for n in names) and any(_RUN.match(n) for n in names)


def read_optiodom(folder: str | Path) -> tuple[list[Recording], OptiOdomSession]:
    """Read every run of an OptiOdom session folder.

    Returns
    -------
    recordings : list of Recording
        One per run file, in run order, with wheel angles and ground truth.
    session : OptiOdomSession

    Raises
    ------
    InputError
        Naming the file and the problem.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError("is not a folder (an OptiOdom session is one)", source=folder)
    meta_path = _metadata_file(folder)
    if meta_path is None:
        raise InputError("has no *_metadata.csv: not an OptiOdom session", source=folder)
    meta: dict[str, list[str]] = {}
    for number, line in iter_lines(meta_path):
        if number > MAX_METADATA_ROWS:
            raise InputError(
                f"has more than {MAX_METADATA_ROWS} rows: not an OptiOdom metadata file",
                source=meta_path,
                row=number,
            )
        row = next(csv.reader([line]), [])
        if row and row[0].strip():
            meta[row[0].strip()] = [c.strip() for c in row[1:] if c.strip()]
    session = OptiOdomSession(meta_path, meta)
    params = session.params
    runs = sorted((int(m.group("n")), p) for p in folder.iterdir() if (m := _RUN.match(p.name)))
    if not runs:
        raise InputError("has no *_run-NN.csv files", source=folder)
    rad_per_tick = params.radians_per_pulse
    recordings = []
    for number, path in runs:
        data = _read_run(path)
        ticks = data[:, [5, 4]]  # left, right
        with np.errstate(over="ignore", invalid="ignore"):
            angles = np.cumsum(ticks, axis=0) * rad_per_tick
        if not np.all(np.isfinite(angles)):
            raise InputError(
                f"wheel angles overflow: the ticks times {rad_per_tick:.3g} rad per tick "
                "(from encRes and ngear in the metadata) are not finite numbers",
                source=path,
            )
        time = data[:, 0]
        recordings.append(
            Recording(
                name=f"run-{number:02d}",
                wheels=WheelSeries(time=time, angles=angles),
                truth=PoseSeries(time=time.copy(), poses=data[:, 1:4].copy()),
                params=params,
                side_length=session.side_length,
                path=str(path),
            )
        )
    return recordings, session


def _read_run(path: Path) -> np.ndarray:
    """A run file's samples, shape (n, 6): time, x, y, theta, ticks_right, ticks_left."""
    columns = [array("d") for _ in range(6)]
    samples = 0
    for number, line in iter_lines(path):
        if not line.strip():
            continue
        samples += 1
        if samples > MAX_SAMPLES:
            raise InputError(
                f"has more than {MAX_SAMPLES} samples: umbmark reads at most {MAX_SAMPLES} "
                "rows of a run file",
                source=path,
                row=number,
            )
        cells = line.split(",")
        if len(cells) < 6:
            raise InputError(
                f"has {len(cells)} cells; an OptiOdom run row has 6 (time, x, y, theta, "
                "ticks_right, ticks_left)",
                source=path,
                row=number,
            )
        try:
            values = [float(c) for c in cells[:6]]
        except ValueError:
            raise InputError("has a cell that is not a number", source=path, row=number) from None
        if not all(math.isfinite(v) for v in values):
            raise InputError("has a value that is not a finite number", source=path, row=number)
        for column, value in zip(columns, values, strict=True):
            column.append(value)
    if samples < 2:
        raise InputError("has fewer than 2 samples", source=path)
    data = np.column_stack([np.frombuffer(c, dtype=np.float64) for c in columns])
    if not np.all(np.diff(data[:, 0]) > 0):
        bad = int(np.argmax(np.diff(data[:, 0]) <= 0)) + 2
        raise InputError("time does not increase", source=path, row=bad)
    return data

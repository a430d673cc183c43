"""Tuple files: motion intervals of the wheels against a sensor's own motion.

The format of the reference implementation of Censi et al. 2013 (``AndreaCensi/calibration``,
its ``reference-output/*.tuple``): one JSON object a line, one interval each::

    { "T": 0.794396, "phi_l": 0.14018, "phi_r": -0.13732, "sm": [0.00109, -0.00051, -0.02749] }

- ``T``: the interval's duration [s] (> 0);
- ``phi_l``, ``phi_r``: the left and right wheel's **average angular velocity** over the
  interval [rad/s], positive driving forward (the rotation is ``T * phi``);
- ``sm``: the sensor's displacement ``[x, y, theta]`` over the interval, in the sensor
  frame at its start [m, m, rad] (scan matching).

Other keys are ignored. Blank lines and ``#`` comment lines are skipped; objects written
back to back on one line (the reference files have such lines, where logs were
concatenated without a final line end) are read one after the other. The reader
returns :class:`~umbmark.model.motion_intervals.MotionIntervals` (wheel rotations, not
velocities); the writer takes them back.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError, option
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.sources.text import iter_content_lines

__all__ = ["MAX_INTERVALS", "looks_like_tuples", "read_tuples", "write_tuples"]

#: The most intervals a tuple file may hold (an hour at 20 Hz is 72 000).
MAX_INTERVALS = 1_000_000
#: Longest line [characters]: an interval is about 120.
_MAX_LINE = 4096
#: Bounds of one interval: duration [s], wheel speed [rad/s], sensor motion [m], [rad].
_MAX_T = 3600.0
_MAX_SPEED = 1e4
_MAX_SHIFT = 1e3
_MAX_TURN = 100.0


def _number(value: object, key: str, bound: float, path: str, row: int) -> float:
    """``value`` as a finite float within ``[-bound, bound]``, else the one-line error."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{key!r} is {value!r}, not a number", source=path, row=row)
    number = float(value)
    if not math.isfinite(number):
        raise InputError(f"{key!r} is {value}: not a finite number", source=path, row=row)
    if abs(number) > bound:
        raise InputError(f"{key!r} = {number:g} is beyond +/-{bound:g}", source=path, row=row)
    return number


_DECODER = json.JSONDecoder(parse_constant=float)
_NOT_JSON = "is not a JSON object (a tuple file has one a line: T, phi_l, phi_r, sm)"


def _objects(line: str, path: str, row: int) -> list[object]:
    """The JSON values of a line: one, or several written back to back (the reference
    files hold such lines where two logs were concatenated without a line end)."""
    found, at = [], 0
    while at < len(line):
        if line[at].isspace():
            at += 1
            continue
        try:
            value, at = _DECODER.raw_decode(line, at)
        except (ValueError, RecursionError):
            raise InputError(_NOT_JSON, source=path, row=row) from None
        found.append(value)
    return found


def _parse(obj: object, path: str, row: int) -> tuple[float, float, float, float, float, float]:
    """One interval ``(T, phi_l, phi_r, x, y, theta)`` of a JSON value."""
    if not isinstance(obj, dict):
        raise InputError(_NOT_JSON, source=path, row=row)
    missing = [k for k in ("T", "phi_l", "phi_r", "sm") if k not in obj]
    if missing:
        raise InputError(f"has no {', '.join(repr(k) for k in missing)}", source=path, row=row)
    duration = _number(obj["T"], "T", _MAX_T, path, row)
    if duration <= 0.0:
        raise InputError(f"'T' = {duration:g} s: an interval lasts > 0 s", source=path, row=row)
    phi_l = _number(obj["phi_l"], "phi_l", _MAX_SPEED, path, row)
    phi_r = _number(obj["phi_r"], "phi_r", _MAX_SPEED, path, row)
    sm = obj["sm"]
    if not isinstance(sm, list) or len(sm) != 3:
        raise InputError(f"'sm' is {str(sm)[:60]}, not [x, y, theta]", source=path, row=row)
    x = _number(sm[0], "sm[0]", _MAX_SHIFT, path, row)
    y = _number(sm[1], "sm[1]", _MAX_SHIFT, path, row)
    theta = _number(sm[2], "sm[2]", _MAX_TURN, path, row)
    return duration, phi_l, phi_r, x, y, theta


def read_tuples(path: str | os.PathLike[str]) -> MotionIntervals:
    """The motion intervals of a tuple file (module documentation).

    Raises
    ------
    InputError
        Naming the file and line: not JSON, a key missing, a value not a finite number or
        out of bounds, more than :data:`MAX_INTERVALS` lines, or no interval at all.
    """
    where = os.fspath(path)
    rows: list[tuple[float, float, float, float, float, float]] = []
    for number, line in iter_content_lines(where, _MAX_LINE):
        for obj in _objects(line, where, number):
            if len(rows) >= MAX_INTERVALS:
                raise InputError(f"holds more than {MAX_INTERVALS} intervals", source=where)
            rows.append(_parse(obj, where, number))
    if not rows:
        raise InputError(
            "holds no interval (one JSON object a line: T, phi_l, phi_r, sm)", source=where
        )
    data = np.array(rows, dtype=np.float64)
    duration = data[:, 0]
    return MotionIntervals(
        duration=duration,
        phi_left=duration * data[:, 1],
        phi_right=duration * data[:, 2],
        sensor_motion=data[:, 3:6].copy(),
        source=where,
    )


def write_tuples(
    path: str | os.PathLike[str], intervals: MotionIntervals, *, force: bool = False
) -> Path:
    """Write ``intervals`` as a tuple file (velocities: rotation over duration).

    Raises
    ------
    InputError
        When the file exists and ``force`` is False.
    """
    target = Path(path)
    if target.exists() and not force:
        raise InputError(f"exists: pass {option('force')} to replace it", source=target)
    lines = []
    for k in range(len(intervals)):
        t = float(intervals.duration[k])
        x, y, theta = (float(v) for v in intervals.sensor_motion[k])
        item = {
            "T": t,
            "phi_l": float(intervals.phi_left[k]) / t,
            "phi_r": float(intervals.phi_right[k]) / t,
            "sm": [x, y, theta],
        }
        lines.append(json.dumps(item))
    atomic_write_text(target, "\n".join(lines) + "\n")
    return target


def looks_like_tuples(path: str | os.PathLike[str]) -> bool:
    """Whether a file's first content line is a tuple-file interval (format detection)."""
    try:
        for number, line in iter_content_lines(os.fspath(path), _MAX_LINE):
            objs = _objects(line, os.fspath(path), number)
            return bool(objs) and all(_parse(o, os.fspath(path), number) for o in objs)
    except InputError:
        return False
    return False

"""Reading the runs table: one row per run, typed in by hand or written by ``umbmark simulate``.

Format
------
A CSV file (comma, semicolon or tab separated; UTF-8, a byte-order mark is fine) whose
first non-comment line is a header. Lines starting with ``#`` and blank lines are skipped.

=============  ========  ==================================================
column         required  meaning
=============  ========  ==================================================
direction      yes       ``cw`` or ``ccw`` (any case); ``straight`` for a straight run
x_abs, y_abs   yes       true (measured) end position
x_odo, y_odo   yes       end position computed by the robot's odometry
theta_abs      no        true end heading (with theta_odo)
theta_odo      no        odometry end heading
=============  ========  ==================================================

``x_calc``, ``y_calc``, ``theta_calc`` (the paper's names) are accepted for the odometry
columns. A ``straight`` run (driven straight by the odometry, from the origin along x)
compares the distance the odometry counted, ``|(x_odo, y_odo)|``, with the distance
measured, ``|(x_abs, y_abs)|``: their ratio is the scale error ``E_s`` (Sec. 2.2); straight
and square runs may share a table. Other columns are ignored. Lengths are in metres and
headings in radians unless the caller says otherwise. Rows are numbered as the file's
lines, from 1.

Numbers are ASCII decimals (``-12.5``, ``1e-3``): ``1_000``, other scripts' digits and
``0x10`` are refused, though Python would read them. A semicolon-separated table may use
decimal commas (``-12,5``), as European spreadsheets write them; a row with more
non-empty cells than the header is refused.

The file is read line by line, keeping only the runs: at most :data:`MAX_ROWS` rows, each
line at most :data:`umbmark.sources.text.MAX_LINE_CHARS` characters.

Active parameters
-----------------
A comment line before the header may record the odometry parameters that were active
while the runs were driven (``umbmark simulate -o`` writes one)::

    # umbmark-active: wheelbase=0.34 c_L=1.0004 c_R=0.9996 wheel_separation_multiplier=1.0114

``wheelbase`` is the configured ``b`` (ros2_control ``wheel_separation``) [m],
``wheel_diameter`` the nominal ``D_n`` [m] (both optional), ``c_L`` and ``c_R`` the wheel
factors (``left/right_wheel_radius_multiplier``), ``wheel_separation_multiplier`` the
factor on ``b`` (optional, default 1). :func:`read_table_active` reads it;
:func:`umbmark.calibrate` uses it where no ``--current-...`` option says otherwise.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path

from umbmark.core.bounds import LENGTH_RANGE, MULTIPLIER_RANGE, Origin
from umbmark.core.conventions import Direction, angle_to_rad, length_to_m
from umbmark.core.errors import InputError, option
from umbmark.model.run import EndPose, Run
from umbmark.sources.text import iter_content_lines, iter_lines

__all__ = [
    "ACTIVE_TAG",
    "MAX_ROWS",
    "OPTIONAL_COLUMNS",
    "REQUIRED_COLUMNS",
    "RecordedActive",
    "read_runs_table",
    "read_table_active",
]

REQUIRED_COLUMNS = ("direction", "x_abs", "y_abs", "x_odo", "y_odo")
#: Direction labels of straight runs (measured against a tape for the scale error E_s).
STRAIGHT_LABELS = ("straight", "line")
OPTIONAL_COLUMNS = ("theta_abs", "theta_odo")
_ALIASES = {"x_calc": "x_odo", "y_calc": "y_odo", "theta_calc": "theta_odo"}
#: Most runs (rows) read from one table: a UMBmark table has tens; beyond this bound a
#: file is no runs table (and would cost memory for nothing).
MAX_ROWS = 250_000
#: The comment that records the active parameters (``# umbmark-active: c_L=1.0 ...``).
ACTIVE_TAG = "umbmark-active:"
#: Most lines before the header searched for :data:`ACTIVE_TAG`.
MAX_PREAMBLE_LINES = 1000
#: The keys of the active-parameter line, and whether each is a length [m].
_ACTIVE_KEYS = {
    "wheelbase": True,
    "wheel_diameter": True,
    "c_L": False,
    "c_R": False,
    "wheel_separation_multiplier": False,
}
#: Headings beyond this many radians are taken for degrees given as radians: a square
#: run's unwrapped heading stays within two turns even for a robot whose turns reach half
#: a turn (E_b of 0.5) and whose legs bend by up to half a turn each; a square's heading in
#: degrees is about 360.
_MAX_PLAUSIBLE_RAD = 8.0 * math.pi


def read_runs_table(
    path: str | Path,
    *,
    unit: str = "m",
    angle_unit: str = "rad",
) -> list[Run]:
    """Read a runs table into runs, converting to metres and radians.

    Parameters
    ----------
    path : path
        The CSV file.
    unit : {"m", "cm", "mm"}
        Unit of the length columns.
    angle_unit : {"rad", "deg"}
        Unit of the heading columns.

    Raises
    ------
    InputError
        Naming the file, the row and the problem.
    """
    lines = iter_content_lines(path)
    try:
        return _read_rows(path, lines, unit, angle_unit)
    finally:
        lines.close()


def _read_rows(
    path: str | Path, lines: Iterator[tuple[int, str]], unit: str, angle_unit: str
) -> list[Run]:
    """The runs of a table whose content lines (header first) ``lines`` yields."""
    first = next(lines, None)
    if first is None:
        raise InputError("is empty: expected a header and one row per run", source=path)
    header_number, header_line = first
    dialect = _sniff(header_line)
    comma = dialect.delimiter == ";"
    header = [_column_name(cell) for cell in next(csv.reader([header_line], dialect))]
    duplicated = sorted({h for h in header if h and header.count(h) > 1})
    if duplicated:
        raise InputError(
            f"column {duplicated[0]} appears more than once", source=path, row=header_number
        )
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise InputError(
            f"missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
            f"(the header has: {', '.join(h for h in header if h) or 'nothing'})",
            source=path,
            row=header_number,
        )
    has_theta = [c in header for c in OPTIONAL_COLUMNS]
    if any(has_theta) and not all(has_theta):
        present, absent = OPTIONAL_COLUMNS if has_theta[0] else OPTIONAL_COLUMNS[::-1]
        raise InputError(
            f"column {present} needs column {absent} as well", source=path, row=header_number
        )
    index = {
        name: header.index(name)
        for name in (*REQUIRED_COLUMNS, *OPTIONAL_COLUMNS)
        if name in header
    }

    runs: list[Run] = []
    for number, line in lines:
        if len(runs) >= MAX_ROWS:
            raise InputError(
                f"has more than {MAX_ROWS} runs: a UMBmark table has tens, and umbmark "
                f"reads at most {MAX_ROWS} rows",
                source=path,
                row=number,
            )
        cells = next(csv.reader([line], dialect))
        if len(cells) < len(header) or any(cell.strip() for cell in cells[len(header) :]):
            hint = (
                " (a decimal comma? only ;-separated tables may use one)"
                if len(cells) > len(header) and dialect.delimiter == ","
                else ""
            )
            raise InputError(
                f"has {len(cells)} cells, the header has {len(header)}{hint}",
                source=path,
                row=number,
            )
        label = cells[index["direction"]]
        straight = label.strip().lower() in STRAIGHT_LABELS
        try:
            direction = Direction.CCW if straight else Direction.parse(label)
        except ValueError as exc:
            raise InputError(
                f"{exc} (nor straight, for a straight run)", source=path, row=number
            ) from None
        value = {
            name: _number(cells[index[name]], name, path, number, comma)
            for name in REQUIRED_COLUMNS[1:]
        }
        theta = {
            name: _number(cells[index[name]], name, path, number, comma)
            if cells[index[name]].strip()
            else None
            for name in OPTIONAL_COLUMNS
            if name in index
        }
        for name, angle in theta.items():
            if angle is not None and angle_unit == "rad" and abs(angle) > _MAX_PLAUSIBLE_RAD:
                raise InputError(
                    f"{name} = {angle:g} is not a plausible heading in radians; "
                    f"are the headings in degrees? (use {option('angle_unit', 'deg')})",
                    source=path,
                    row=number,
                )
        theta_abs, theta_odo = theta.get("theta_abs"), theta.get("theta_odo")
        if (theta_abs is None) != (theta_odo is None):
            raise InputError(
                "gives one of theta_abs and theta_odo but not the other", source=path, row=number
            )
        if theta_odo is not None:
            loop = angle_to_rad(theta_odo, angle_unit)
            # An unwrapped odometry heading beyond half a turn tells the direction driven.
            if abs(loop) > math.pi and (loop > 0) != (direction is Direction.CCW):
                raise InputError(
                    f"labelled {direction.value}, but theta_odo = {theta_odo:g} "
                    f"{angle_unit} is a {'left (ccw)' if loop > 0 else 'right (cw)'} loop; "
                    "check the direction column or the sign of the headings",
                    source=path,
                    row=number,
                )
        run = Run(
            direction=direction,
            true_end=EndPose(
                length_to_m(value["x_abs"], unit),
                length_to_m(value["y_abs"], unit),
                None if theta_abs is None else angle_to_rad(theta_abs, angle_unit),
            ),
            odometry_end=EndPose(
                length_to_m(value["x_odo"], unit),
                length_to_m(value["y_odo"], unit),
                None if theta_odo is None else angle_to_rad(theta_odo, angle_unit),
            ),
            label=f"row {number}",
            kind="straight" if straight else "square",
        )
        runs.append(run)
    if not runs:
        raise InputError("has a header but no runs", source=path)
    return runs


@dataclass(frozen=True)
class RecordedActive:
    """The odometry parameters a source records as active while its runs were driven.

    Attributes
    ----------
    c_left, c_right : float
        Wheel factors ``c_L``, ``c_R``.
    separation_multiplier : float
        ``wheel_separation_multiplier``.
    wheelbase : float or None
        Configured wheelbase ``b`` [m] (before the multiplier), if recorded.
    wheel_diameter : float or None
        Nominal wheel diameter ``D_n`` [m], if recorded.
    where : str
        What recorded them, for messages (``"the table's header"``).
    path : str or None
        The file that records them, for messages.
    prefix : str
        What precedes a field's name in that file (``"umbmark-active: "``).
    """

    c_left: float
    c_right: float
    separation_multiplier: float = 1.0
    wheelbase: float | None = None
    wheel_diameter: float | None = None
    where: str = "the source"
    path: str | None = None
    prefix: str = ""

    def origin(self, field: str) -> Origin:
        """Where the record's ``field`` (``wheelbase``, ...) is written, for messages."""
        return Origin(f"{self.prefix}{field}", self.path)


def read_table_active(path: str | Path) -> RecordedActive | None:
    """The active parameters a runs table's ``# umbmark-active:`` line records, if any.

    Only the comment lines before the header are searched (at most
    :data:`MAX_PREAMBLE_LINES` lines).

    Raises
    ------
    InputError
        If the file cannot be read, or the line is malformed (naming the row).
    """
    lines = iter_lines(path)
    try:
        for number, line in lines:
            if number > MAX_PREAMBLE_LINES:
                return None
            text = line.strip()
            if not text:
                continue
            if not text.startswith("#"):
                return None  # the header: no active parameters recorded
            body = text[1:].strip()
            if body.startswith(ACTIVE_TAG):
                found = _parse_active(body[len(ACTIVE_TAG) :], path, number)
                return replace(found, path=str(path), prefix=f"{ACTIVE_TAG} ")
        return None
    finally:
        lines.close()


def _parse_active(text: str, path: str | Path, row: int) -> RecordedActive:
    values: dict[str, float] = {}
    for item in text.split():
        key, equals, cell = item.partition("=")
        if not equals or key not in _ACTIVE_KEYS:
            shown = repr(item) if len(item) <= 40 else repr(item[:40]) + "..."
            raise InputError(
                f"{ACTIVE_TAG} {shown} is not one of {', '.join(f'{k}=' for k in _ACTIVE_KEYS)}",
                source=path,
                row=row,
            )
        if key in values:
            raise InputError(f"{ACTIVE_TAG} gives {key} twice", source=path, row=row)
        value = _number(cell, f"{ACTIVE_TAG} {key}", path, row)
        low, high = LENGTH_RANGE if _ACTIVE_KEYS[key] else MULTIPLIER_RANGE
        if not low <= value <= high:
            unit = " m" if _ACTIVE_KEYS[key] else ""
            raise InputError(
                f"{ACTIVE_TAG} {key} = {value:g}{unit} is outside {low:g} to {high:g}{unit}",
                source=path,
                row=row,
            )
        values[key] = value
    missing = [k for k in ("c_L", "c_R") if k not in values]
    if missing:
        raise InputError(f"{ACTIVE_TAG} has no {' and no '.join(missing)}", source=path, row=row)
    return RecordedActive(
        c_left=values["c_L"],
        c_right=values["c_R"],
        separation_multiplier=values.get("wheel_separation_multiplier", 1.0),
        wheelbase=values.get("wheelbase"),
        wheel_diameter=values.get("wheel_diameter"),
        where="the table's header",
    )


def _sniff(header_line: str) -> type[csv.Dialect] | csv.Dialect:
    try:
        return csv.Sniffer().sniff(header_line, delimiters=",;\t")
    except csv.Error:
        return csv.excel


def _column_name(cell: str) -> str:
    name = cell.strip().lower()
    return _ALIASES.get(name, name)


#: A number as the table may write it: ASCII decimal digits only (no ``1_000``, no other
#: scripts' digits, which Python's ``float`` would take), optionally with an exponent.
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
#: The same with a decimal comma (``1,5``), as spreadsheets write it beside ``;``.
_COMMA_NUMBER = re.compile(r"[+-]?\d+,\d+(?:[eE][+-]?\d+)?", re.ASCII)


def _number(cell: str, name: str, path: str | Path, row: int, decimal_comma: bool = False) -> float:
    """A cell as a finite number, refusing anything but ASCII decimals.

    Parameters
    ----------
    cell : str
        The cell's text.
    name : str
        Its column, for messages.
    path : path
        The file, for messages.
    row : int
        Its line, for messages.
    decimal_comma : bool
        The table is separated by ``;``: ``1,5`` is one and a half.

    Raises
    ------
    InputError
        If the cell is empty, no number, or not finite.
    """
    text = cell.strip()
    if not text:
        raise InputError(f"{name} is empty", source=path, row=row)
    if decimal_comma and _COMMA_NUMBER.fullmatch(text):
        text = text.replace(",", ".")
    if text.lower().lstrip("+-") in ("nan", "inf", "infinity"):
        raise InputError(f"{name} is {text} (not a finite number)", source=path, row=row)
    if not _NUMBER.fullmatch(text):
        shown = repr(text) if len(text) <= 40 else repr(text[:40]) + "..."
        raise InputError(f"{name} {shown} is not a number", source=path, row=row)
    value = float(text)
    if not math.isfinite(value):
        raise InputError(f"{name} is {text} (not a finite number)", source=path, row=row)
    return value

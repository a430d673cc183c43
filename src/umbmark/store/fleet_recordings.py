"""The fleet's recordings in the calibration history: every recording looked at, by its
digest and the reading options it was read with, with what it gave.

A recording that gave a calibration is also a calibration of its robot in the history
(``umbmark history NAME`` lists it, with the recording's time and digest as its input);
its row here holds the whole outcome (every figure, the laser's mounting) as JSON, which
the fleet's summary is made from. A recording already here with the same digest and
options, calibrated or left out, is not done again; one that failed is tried again.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from umbmark.core.errors import InputError
from umbmark.sources.remote import identity as remote_identity
from umbmark.sources.remote import is_url, redacted
from umbmark.store.history import History
from umbmark.store.records import NewCalibration

__all__ = [
    "RecordingRow",
    "Status",
    "done_recordings",
    "identity",
    "options_key",
    "read_recordings",
    "record_recording",
]

Status = Literal["calibrated", "left out", "failed"]


@dataclass(frozen=True)
class RecordingRow:
    """One recording as the history holds it.

    Attributes
    ----------
    robot, path : str
    digest : str or None
        SHA-256 of its bytes.
    identity : str
        Its path, size and modification time, or its URL (redacted), size and version
        (:func:`identity`): a recording seen before is known by it without reading its
        bytes again.
    options_key : str
        The reading options it was read with (:func:`options_key`).
    start : float or None
        When it started [s since 1970, UTC].
    hours : float
    status : {"calibrated", "left out", "failed"}
    reason : str or None
        Why it was left out or failed.
    outcome : dict
        Everything it gave (JSON-ready; the fleet's outcome).
    calibration : int or None
        Its calibration's id in the history.
    """

    robot: str
    path: str
    digest: str | None
    identity: str
    options_key: str
    start: float | None
    hours: float
    status: Status
    reason: str | None
    outcome: dict[str, Any]
    calibration: int | None = None


def options_key(options: Mapping[str, Any]) -> str:
    """A short digest of reading options (their keywords and values, sorted): the same
    options give the same key."""
    text = json.dumps({k: options[k] for k in sorted(options)}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def identity(path: str) -> str:
    """A recording's path, size and modification time, as one text (a folder's: of its
    files): what tells a recording seen before without reading its bytes.

    A recording at a URL: the URL, its size and what its filesystem says of its version
    (ETag, last modification, ...: :func:`umbmark.sources.remote.identity`); an empty
    text, which matches no recording done, where that cannot be read (it is done again,
    and fails there with its reason if it cannot be read at all)."""
    if is_url(path):
        try:
            return remote_identity(path)
        except InputError:
            return ""
    where = Path(path)
    files = sorted(p for p in where.rglob("*") if p.is_file()) if where.is_dir() else [where]
    stats = [(p.stat().st_size, p.stat().st_mtime_ns) for p in files]
    size, newest = sum(s for s, _ in stats), max((m for _, m in stats), default=0)
    return f"{os.path.abspath(path)}|{size}|{newest}"


def done_recordings(history: History) -> dict[str, dict[str, str]]:
    """The recordings already calibrated or left out (a failed one is tried again): by
    identity (:func:`identity`), the options keys it was read with and the robot it was
    found to be with each."""
    with history.transaction() as db:
        rows = db.execute(
            "SELECT identity, options_key, robot FROM recordings WHERE status != 'failed'"
        ).fetchall()
    done: dict[str, dict[str, str]] = {}
    for ident, key, robot in rows:
        if ident:
            done.setdefault(str(ident), {})[str(key)] = str(robot)
    return done


def record_recording(
    history: History, row: RecordingRow, calibration: NewCalibration | None
) -> int | None:
    """Record one recording (a URL's credentials masked: :func:`_redacted`), and its
    calibration (with the recording as its input, its digest not read again) when it gave
    one; a calibration whose nominal geometry is not the robot's first is recorded all the
    same (the fleet's summary compares it on the robot's latest nominal, and says the
    configuration changed).

    Returns
    -------
    int or None
        The calibration's id in the history.
    """
    row = _redacted(row)
    id = None
    if calibration is not None:
        digests = {row.path: row.digest}
        id = history.record(row.robot, calibration, [row.path], digests=digests,
                            same_nominal=False)  # fmt: skip
    now = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    with history.transaction(write=True) as db:
        db.execute(
            "INSERT INTO recordings (robot, path, digest, identity, options_key, start, hours, "
            "status, reason, calibration, outcome, recorded) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (
                row.robot,
                row.path,
                row.digest,
                row.identity,
                row.options_key,
                row.start,
                row.hours,
                row.status,
                row.reason,
                id,
                json.dumps(row.outcome),
                now,
            ),
        )
    return id


def _redacted(row: RecordingRow) -> RecordingRow:
    """The row as it is kept: a URL's credentials masked in its path, identity, reason and
    outcome (:func:`umbmark.sources.remote.redacted`; the fleet's outcomes come so already:
    this is the last line before the file)."""
    from dataclasses import replace

    where = row.identity.rsplit("|", 2)  # the path or URL, its size, its version
    return replace(
        row,
        path=redacted(row.path),
        identity="|".join([redacted(where[0]), *where[1:]]),
        reason=None if row.reason is None else redacted(row.reason),
        outcome=_redacted_values(row.outcome),
    )


def _redacted_values(value: Any) -> Any:  # noqa: ANN401 (JSON-ready)
    """Every text in a JSON-ready value redacted (not its JSON text: a URL there runs on
    into the escapes after it)."""
    if isinstance(value, str):
        return redacted(value)
    if isinstance(value, dict):
        return {k: _redacted_values(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_redacted_values(v) for v in value]
    return value


def read_recordings(history: History, robots: Sequence[str] = ()) -> list[RecordingRow]:
    """The recordings of ``robots`` (all when empty), oldest first; of a recording
    recorded more than once (tried again after a failure) the latest row. Rows of one
    recording under other keys (a digest first unknown, other reading options) come in
    the order they were last recorded."""
    query = (
        "SELECT robot, path, digest, identity, options_key, start, hours, status, reason, "
        "outcome, calibration FROM recordings"
    )
    args: tuple[str, ...] = ()
    if robots:
        query += f" WHERE robot IN ({', '.join('?' * len(robots))})"
        args = tuple(robots)
    with history.transaction() as db:
        rows = db.execute(query + " ORDER BY id", args).fetchall()
    latest: dict[tuple[str, str, str], RecordingRow] = {}
    for r in rows:
        row = RecordingRow(
            str(r[0]),
            str(r[1]),
            None if r[2] is None else str(r[2]),
            str(r[3] or ""),
            str(r[4]),
            None if r[5] is None else float(r[5]),
            float(r[6]),
            r[7],
            None if r[8] is None else str(r[8]),
            json.loads(r[9]),
            None if r[10] is None else int(r[10]),
        )
        key = (row.robot, row.digest or row.path, row.options_key)
        latest.pop(key, None)  # kept in the order last recorded
        latest[key] = row
    return sorted(latest.values(), key=lambda row: (row.start or 0.0, row.path))

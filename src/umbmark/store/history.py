"""A robot's calibration history in an SQLite file (standard library :mod:`sqlite3`).

:class:`History` keeps, per robot (a name with its nominal wheelbase and wheel
diameter), every calibration recorded: when, by which method, from which inputs (with
their SHA-256), the errors found with their standard errors, the parameters active during
the runs and the new ones, and whether they were applied. The file carries a schema
version (``PRAGMA user_version``) and is brought up to date by :data:`MIGRATIONS`, applied
in order; it is written in WAL mode with a busy timeout, so that several processes may
record into it at once.

What the robot is, as opposed to what a pass measured relative to the parameters active
during it, and whether that drifts: :mod:`umbmark.store.drift`.

The default file is ``$UMBMARK_HISTORY``, else ``$XDG_DATA_HOME/umbmark/history.sqlite3``
(``~/.local/share/umbmark/history.sqlite3``).
"""

from __future__ import annotations

import datetime as dt
import json
import os
import sqlite3
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from umbmark.core.digest import path_sha256
from umbmark.core.errors import InputError, option
from umbmark.store.drift import DEFINITIONS, DRIFT_MIN_CALIBRATIONS, drift_verdict
from umbmark.store.records import CalibrationRecord, NewCalibration, RobotRecord

if TYPE_CHECKING:
    from umbmark.calibration.verdict import Verdict
    from umbmark.runs.read_options import SourceOptions

__all__ = [
    "DEFINITIONS",
    "DRIFT_MIN_CALIBRATIONS",
    "MIGRATIONS",
    "SCHEMA_VERSION",
    "CalibrationRecord",
    "History",
    "RobotRecord",
    "compose_last_applied",
    "default_history_path",
    "drift_verdict",
    "utc_stamp",
]

#: How long a writer waits for another one's lock [s].
BUSY_TIMEOUT = 30.0
#: How far a robot's nominal wheelbase or wheel diameter may differ (relative).
IDENTITY_TOLERANCE = 1e-6


def _migrate_1(db: sqlite3.Connection) -> None:
    """Version 1: the robots and their calibrations."""
    db.execute(
        """CREATE TABLE robots (
            name TEXT PRIMARY KEY,
            wheelbase REAL NOT NULL,
            wheel_diameter REAL,
            created TEXT NOT NULL
        )"""
    )
    db.execute(
        """CREATE TABLE calibrations (
            id INTEGER PRIMARY KEY AUTOINCREMENT,
            robot TEXT NOT NULL REFERENCES robots(name),
            time TEXT NOT NULL,
            method TEXT NOT NULL,
            inputs TEXT NOT NULL,
            E_d REAL NOT NULL,
            E_b REAL NOT NULL,
            E_s REAL,
            e_max_syst REAL,
            standard_errors TEXT NOT NULL,
            active TEXT NOT NULL,
            new TEXT NOT NULL,
            applied INTEGER NOT NULL DEFAULT 0
        )"""
    )
    db.execute("CREATE INDEX calibrations_robot ON calibrations(robot, id)")


def _migrate_2(db: sqlite3.Connection) -> None:
    """Version 2: each calibration's verdict (``{"level", "reasons", "instead"}`` as JSON;
    NULL for the calibrations recorded before, whose verdict is unknown)."""
    db.execute("ALTER TABLE calibrations ADD COLUMN verdict TEXT")


def _migrate_3(db: sqlite3.Connection) -> None:
    """Version 3: the controller each calibration is for, with its namespace
    (``/robot1/diff_cont``; NULL where nothing named it, and for the calibrations
    recorded before)."""
    db.execute("ALTER TABLE calibrations ADD COLUMN controller TEXT")


def _migrate_4(db: sqlite3.Connection) -> None:
    """Version 4: the fleet's recordings (``umbmark fleet``): each recording looked at,
    by identity, digest and reading options, with what it gave
    (:mod:`umbmark.store.fleet_recordings`)."""
    db.execute(
        """CREATE TABLE recordings (
            id INTEGER PRIMARY KEY AUTOINCREMENT,
            robot TEXT NOT NULL,
            path TEXT NOT NULL,
            digest TEXT,
            identity TEXT,
            options_key TEXT NOT NULL,
            start REAL,
            hours REAL NOT NULL,
            status TEXT NOT NULL,
            reason TEXT,
            calibration INTEGER REFERENCES calibrations(id),
            outcome TEXT NOT NULL,
            recorded TEXT NOT NULL
        )"""
    )
    db.execute("CREATE INDEX recordings_done ON recordings(options_key, identity)")
    db.execute("CREATE INDEX recordings_robot ON recordings(robot, start)")


def _migrate_5(db: sqlite3.Connection) -> None:
    """Version 5: each robot's monitor (``umbmark monitor``): its odometer as it last
    said it and where it last applied a change, so that a monitor started again (killed,
    say) goes on from there (:mod:`umbmark.store.monitor_stretches`)."""
    db.execute(
        """CREATE TABLE monitors (
            robot TEXT PRIMARY KEY,
            odometer REAL NOT NULL,
            applied_odometer REAL,
            updated TEXT NOT NULL
        )"""
    )


#: The schema's migrations: ``MIGRATIONS[k]`` takes a file from version ``k`` to ``k + 1``.
MIGRATIONS: tuple[Callable[[sqlite3.Connection], None], ...] = (
    _migrate_1,
    _migrate_2,
    _migrate_3,
    _migrate_4,
    _migrate_5,
)
#: The schema version this umbmark writes.
SCHEMA_VERSION = len(MIGRATIONS)


def default_history_path() -> Path:
    """The history file used when none is given.

    Returns
    -------
    Path
        ``$UMBMARK_HISTORY``, else ``$XDG_DATA_HOME/umbmark/history.sqlite3``, else
        ``~/.local/share/umbmark/history.sqlite3``.
    """
    given = os.environ.get("UMBMARK_HISTORY")
    if given:
        return Path(given)
    data = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(data) / "umbmark" / "history.sqlite3"


def utc_stamp() -> str:
    """Now, as the history's files stamp their rows (UTC, ISO 8601, microseconds)."""
    return dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= IDENTITY_TOLERANCE * max(abs(a), abs(b), 1e-12)


class History:
    """The calibration history in one SQLite file.

    Parameters
    ----------
    path : path, optional
        The file; :func:`default_history_path` when None.
    read_only : bool
        Only read it: the file must exist (nothing is created) and is opened read-only
        (SQLite ``mode=ro``); otherwise it is created with its folder when missing.

    Raises
    ------
    InputError
        When the file is not an SQLite database, is of a newer schema, or (``read_only``)
        does not exist.
    """

    def __init__(
        self, path: str | os.PathLike[str] | None = None, *, read_only: bool = False
    ) -> None:
        self.path = Path(path) if path is not None else default_history_path()
        self.read_only = read_only
        if self.path.is_dir():
            raise InputError("is a folder, not a history file", source=self.path)
        if read_only:
            if not self.path.exists():
                raise InputError(
                    f"no history here (umbmark calibrate {option('robot', 'NAME')} records one)",
                    source=self.path,
                )
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        self._migrate()

    def _open(self) -> sqlite3.Connection:
        """A connection: read-only (``mode=ro``, never creating the file) when
        :attr:`read_only`."""
        if self.read_only:
            uri = f"{self.path.resolve().as_uri()}?mode=ro"
            return sqlite3.connect(uri, uri=True, timeout=BUSY_TIMEOUT, isolation_level=None)
        return sqlite3.connect(self.path, timeout=BUSY_TIMEOUT, isolation_level=None)

    @contextmanager
    def _connect(self, *, write: bool = False) -> Iterator[sqlite3.Connection]:
        """A connection in one transaction (``BEGIN IMMEDIATE`` when writing)."""
        if write and self.read_only:
            raise InputError("opened to read only: cannot write to it", source=self.path)
        try:
            db = self._open()
        except sqlite3.Error as exc:
            raise InputError(f"cannot open the history: {exc}", source=self.path) from None
        try:
            db.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT * 1000)}")
            db.execute("PRAGMA foreign_keys = ON")
            db.execute("BEGIN IMMEDIATE" if write else "BEGIN")
            try:
                yield db
            except BaseException:
                db.execute("ROLLBACK")
                raise
            db.execute("COMMIT")
        except sqlite3.DatabaseError as exc:
            raise InputError(f"not a usable history file ({exc})", source=self.path) from None
        finally:
            db.close()

    def _migrate(self) -> None:
        """Set WAL mode and bring the schema to :data:`SCHEMA_VERSION`. Read-only, a file
        of this schema is only read; an older one (it exists: nothing is created) is
        brought up to date first, as it must be to be read."""
        if self.read_only:
            with self._connect() as db:
                version = int(db.execute("PRAGMA user_version").fetchone()[0])
            if version == SCHEMA_VERSION:
                return
            self.read_only = False
            try:
                self._migrate()
            finally:
                self.read_only = True
            return
        try:
            db = self._open()
            try:
                db.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT * 1000)}")
                if db.execute("PRAGMA journal_mode").fetchone()[0] != "wal":
                    db.execute("PRAGMA journal_mode = WAL")
            finally:
                db.close()
        except sqlite3.DatabaseError as exc:
            raise InputError(f"not a usable history file ({exc})", source=self.path) from None
        with self._connect(write=True) as db:
            version = int(db.execute("PRAGMA user_version").fetchone()[0])
            if version > SCHEMA_VERSION:
                raise InputError(
                    f"history schema version {version} is newer than this umbmark's "
                    f"({SCHEMA_VERSION}): upgrade umbmark",
                    source=self.path,
                )
            for number, migration in enumerate(MIGRATIONS[version:], start=version + 1):
                migration(db)
                db.execute(f"PRAGMA user_version = {number}")

    @property
    def schema_version(self) -> int:
        """The file's schema version (``PRAGMA user_version``)."""
        with self._connect() as db:
            return int(db.execute("PRAGMA user_version").fetchone()[0])

    @contextmanager
    def transaction(self, *, write: bool = False) -> Iterator[sqlite3.Connection]:
        """A connection in one transaction (``BEGIN IMMEDIATE`` when writing), for the
        store's other tables (:mod:`umbmark.store.fleet_recordings`)."""
        with self._connect(write=write) as db:
            yield db

    def record(
        self,
        robot: str,
        calibration: NewCalibration,
        inputs: Sequence[str | os.PathLike[str]] = (),
        *,
        digests: Mapping[str, str | None] | None = None,
        same_nominal: bool = True,
    ) -> int:
        """Record a calibration of ``robot``; a new robot is added with the calibration's
        nominal wheelbase and wheel diameter.

        Parameters
        ----------
        robot : str
            The robot's name.
        calibration : NewCalibration
            The calibration, as the job that made it says it.
        inputs : sequence of path
            Its inputs (hashed with SHA-256 when they are files or folders).
        digests : mapping of str to str, optional
            SHA-256 of inputs hashed already (by name): not read again.
        same_nominal : bool
            Refuse a calibration whose nominal geometry is not the robot's (True); False
            records it all the same, its own nominal kept with it (a fleet, whose robots'
            configured geometry may change between recordings: it says so).

        Returns
        -------
        int
            The calibration's id.

        Raises
        ------
        InputError
            When ``robot`` exists with another nominal wheelbase or wheel diameter (a
            diameter unknown on either side is no difference; the first one known is the
            robot's from then on).
        """
        if not robot.strip():
            raise InputError(f"{option('robot')}: give a non-empty name")
        ours = (calibration.wheelbase, calibration.wheel_diameter)
        known = digests or {}
        hashed = [
            {
                "name": os.fspath(p),
                "sha256": known[os.fspath(p)]
                if os.fspath(p) in known
                else path_sha256(Path(os.fspath(p))),
            }
            for p in inputs
        ]
        with self._connect(write=True) as db:
            row = db.execute(
                "SELECT wheelbase, wheel_diameter FROM robots WHERE name = ?", (robot,)
            ).fetchone()
            if row is None:
                db.execute(
                    "INSERT INTO robots (name, wheelbase, wheel_diameter, created) "
                    "VALUES (?, ?, ?, ?)",
                    (robot, calibration.wheelbase, calibration.wheel_diameter, utc_stamp()),
                )
            else:
                if same_nominal:
                    self._check(robot, ours, (row[0], row[1]))
                if row[1] is None and calibration.wheel_diameter is not None:
                    db.execute(  # the first calibration that knows it says the diameter
                        "UPDATE robots SET wheel_diameter = ? WHERE name = ?",
                        (calibration.wheel_diameter, robot),
                    )
            cursor = db.execute(
                "INSERT INTO calibrations (robot, time, method, inputs, E_d, E_b, E_s, "
                "e_max_syst, standard_errors, active, new, applied, verdict, controller) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, 0, ?, ?)",
                (
                    robot,
                    calibration.time.astimezone(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
                    calibration.method,
                    json.dumps(hashed),
                    calibration.E_d,
                    calibration.E_b,
                    calibration.E_s,
                    calibration.e_max_syst,
                    json.dumps(calibration.standard_errors),
                    json.dumps(calibration.active),
                    json.dumps(calibration.new),
                    json.dumps(calibration.verdict),
                    calibration.controller,
                ),
            )
            return int(cursor.lastrowid or 0)

    def recorded_line(
        self, robot: str, id: int, verdict: Verdict | None = None, *, overridden: bool = False
    ) -> str:
        """One line saying that calibration ``id`` of ``robot`` was recorded, and how to
        mark it applied; for a ``verdict`` "do not apply", that it is not to be applied
        (``overridden``: its parameters were written all the same, and the command that
        marks it applied needs ``--override-verdict``)."""
        import shlex

        given = self.path != default_history_path()
        mark = f"umbmark history {shlex.quote(robot)}"
        mark += f" --history {shlex.quote(str(self.path))}" if given else ""
        said = f"recorded as calibration {id} of robot {robot} in {self.path}"
        if verdict is not None and not verdict.applies:
            if overridden:
                return (
                    f"{said}; its verdict is do not apply; if its new parameters are "
                    f"configured on the robot all the same: {mark} --applied {id} "
                    "--override-verdict"
                )
            return f"{said}; its verdict is do not apply: not to be configured on the robot"
        return f"{said}; once its new parameters are configured on the robot: {mark} --applied {id}"

    def check_identity(self, robot: str, wheelbase: float, wheel_diameter: float | None) -> None:
        """Refuse a calibration whose nominal parameters (``wheelbase`` and
        ``wheel_diameter`` [m], the ones active during its runs) are not those of ``robot``.

        Raises
        ------
        InputError
            When ``robot`` is known with another nominal wheelbase or wheel diameter
            (an unknown robot passes: :meth:`record` adds it; so does a diameter unknown
            to the robot or to the calibration).
        """
        if not robot.strip():
            raise InputError(f"{option('robot')}: give a non-empty name")
        known = self.robot(robot)
        if known is not None:
            self._check(robot, (wheelbase, wheel_diameter), (known.wheelbase, known.wheel_diameter))

    def _check(
        self, robot: str, given: tuple[float, float | None], nominal: tuple[float, float | None]
    ) -> None:
        for what, theirs, ours in (
            ("wheelbase", nominal[0], given[0]),
            ("wheel diameter", nominal[1], given[1]),
        ):
            if theirs is not None and ours is not None and not _same(theirs, ours):
                raise InputError(
                    f"this calibration is not robot {robot}: nominal {what} "
                    f"{ours:g} m vs {theirs:g} m (give another {option('robot')} name)",
                    source=self.path,
                )

    def robots(self) -> list[RobotRecord]:
        """Every robot, by name, with its number of calibrations and their first and last
        time."""
        with self._connect() as db:
            rows = db.execute(
                "SELECT r.name, r.wheelbase, r.wheel_diameter, r.created, COUNT(c.id), "
                "MIN(c.time), MAX(c.time) "
                "FROM robots r LEFT JOIN calibrations c ON c.robot = r.name "
                "GROUP BY r.name ORDER BY r.name"
            ).fetchall()
        return [RobotRecord(*row) for row in rows]

    def robot(self, name: str) -> RobotRecord | None:
        """The robot of this name, or None."""
        return next((r for r in self.robots() if r.name == name), None)

    def calibrations(self, robot: str) -> list[CalibrationRecord]:
        """The robot's calibrations, oldest first (by their time: a fleet's are its
        recordings', recorded in the order they finished), empty for an unknown robot."""
        with self._connect() as db:
            rows = db.execute(
                "SELECT id, robot, time, method, inputs, E_d, E_b, E_s, e_max_syst, "
                "standard_errors, active, new, applied, verdict, controller FROM calibrations "
                "WHERE robot = ? ORDER BY time, id",
                (robot,),
            ).fetchall()
        return [_calibration(row) for row in rows]

    def mark_applied(self, robot: str, id: int, *, override_verdict: bool = False) -> None:
        """Mark calibration ``id`` of ``robot`` as applied to the robot.

        Parameters
        ----------
        robot : str
        id : int
        override_verdict : bool
            Mark it even when its verdict was "do not apply".

        Raises
        ------
        InputError
            When the robot has no calibration ``id``, or its verdict was "do not apply"
            (without ``override_verdict``).
        """
        with self._connect(write=True) as db:
            row = db.execute(
                "SELECT verdict FROM calibrations WHERE robot = ? AND id = ?", (robot, id)
            ).fetchone()
            verdict = None if row is None or row[0] is None else json.loads(row[0])
            if (
                verdict is not None
                and verdict.get("level") == "do-not-apply"
                and not override_verdict
            ):
                reasons = "; ".join(verdict.get("reasons") or [])
                raise InputError(
                    f"{option('applied', id)}: calibration {id} of {robot} was judged do not "
                    f"apply ({reasons}): its parameters are not to be configured on the robot; "
                    f"{option('override_verdict')} marks it applied all the same",
                    source=self.path,
                )
            cursor = db.execute(
                "UPDATE calibrations SET applied = 1 WHERE robot = ? AND id = ?", (robot, id)
            )
            if cursor.rowcount != 1:
                raise InputError(
                    f"{option('applied', id)}: robot {robot} has no calibration {id}",
                    source=self.path,
                )

    def last_applied(self, robot: str) -> CalibrationRecord | None:
        """The robot's latest calibration marked applied, or None."""
        applied = [c for c in self.calibrations(robot) if c.applied]
        return applied[-1] if applied else None

    def drift(self, robot: str) -> str | None:
        """:func:`drift_verdict` of the robot's calibrations."""
        return drift_verdict(self.calibrations(robot))


def _calibration(row: Sequence[Any]) -> CalibrationRecord:
    return CalibrationRecord(
        id=int(row[0]),
        robot=str(row[1]),
        time=str(row[2]),
        method=str(row[3]),
        inputs=json.loads(row[4]),
        E_d=float(row[5]),
        E_b=float(row[6]),
        E_s=None if row[7] is None else float(row[7]),
        e_max_syst=None if row[8] is None else float(row[8]),
        standard_errors=json.loads(row[9]),
        active=json.loads(row[10]),
        new=json.loads(row[11]),
        applied=bool(row[12]),
        verdict=None if row[13] is None else json.loads(row[13]),
        controller=None if row[14] is None else str(row[14]),
    )


def compose_last_applied(
    store: History, robot: str, options: SourceOptions
) -> tuple[SourceOptions, str | None]:
    """Take the robot's last applied calibration as the parameters active during the runs.

    Only when the options say nothing of them (no ``current_params``, ``current_c_l``,
    ``current_c_r`` or ``current_separation_multiplier``): a second pass then composes
    with what the robot runs now.

    Parameters
    ----------
    store : History
    robot : str
    options : SourceOptions
        The source options of :func:`umbmark.calibrate`.

    Returns
    -------
    options : SourceOptions
        The options, with the multipliers of the last applied calibration when taken,
        and its controller where the options name none.
    note : str or None
        A note saying so, when taken.
    """
    given = (
        options.get("current_params"),
        options.get("current_c_l"),
        options.get("current_c_r"),
        options.get("current_separation_multiplier"),
    )
    if any(value is not None for value in given):
        return options, None
    last = store.last_applied(robot)
    if last is None:
        return options, None
    c_left = float(last.new["c_L"])
    c_right = float(last.new["c_R"])
    separation = float(last.new["wheel_separation_multiplier"])
    composed = options.copy()
    composed["current_c_l"] = c_left
    composed["current_c_r"] = c_right
    composed["current_separation_multiplier"] = separation
    controller = ""
    if options.get("controller") is None and last.controller is not None:
        composed["controller"] = last.controller  # the overlays keyed as the last one was
        controller = f", for controller {last.controller}"
    from umbmark.core.messages import info

    note = info(
        f"robot {robot}: taken as active during the runs, the new parameters of its last "
        f"applied calibration {last.id} ({last.time[:19]}Z{controller}): c_L {c_left:.6f}, "
        f"c_R {c_right:.6f}, wheel_separation_multiplier {separation:.6f} (give "
        "--current-params or --current-c-l/--current-c-r/--current-separation-multiplier "
        "to say otherwise)"
    )
    return composed, note

"""The fleet job: every new recording of every robot calibrated by what it holds, on a
distributed engine, recorded in the history; the fleet's page and JSON.

:func:`fleet` is what ``umbmark fleet`` does. Each recording is calibrated by
:func:`umbmark.fleets.outcome.calibrate_recording`, a plain function, handed to the engine
(:func:`umbmark.fleets.cluster.run_each`: a local cluster of this machine's cores, or an
existing Dask scheduler); this process is the one writer of the history, recording each
outcome as it comes back. A recording already in the history with the same reading
options (its path, size and time unchanged) is not done again. What the fleet shows is
made from the history, so a nightly run that calibrates only the new recordings still
shows every robot's whole course.
"""

from __future__ import annotations

import datetime as dt
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError
from umbmark.core.jsontext import JsonText
from umbmark.fleets.naming import NO_ROBOT, UNNAMED
from umbmark.fleets.outcome import RecordingOutcome, RecordingTask
from umbmark.fleets.summary import FleetSummary
from umbmark.runs.read_options import SourceOptions

if TYPE_CHECKING:
    from typing_extensions import Unpack

    from umbmark.fleets.recordings import FleetRecording

__all__ = ["FleetProgress", "FleetReport", "FleetStopped", "fleet", "fleet_stopped"]


@dataclass(frozen=True)
class FleetProgress:
    """How far a fleet run is (handed to ``progress`` after each recording).

    Attributes
    ----------
    done, total : int
        Recordings finished, and to do in this run.
    robots : int
        Robots with a recording finished.
    hours : float
        Hours of recordings finished.
    elapsed : float
        Wall time since the run began [s] (the engine's start included).
    """

    done: int
    total: int
    robots: int
    hours: float
    elapsed: float = 0.0

    def counts(self) -> str:
        """``3 of 10 recordings, 2 robots, 16 h recorded``."""
        from umbmark.core.messages import duration_words

        robots = f"{self.robots} robot{'' if self.robots == 1 else 's'}"
        recorded = duration_words(self.hours * 3600.0)
        return f"{self.done} of {self.total} recordings, {robots}, {recorded} recorded"

    def text(self) -> str:
        """:meth:`counts` and the wall time since the run began: ``..., 25 s elapsed``."""
        from umbmark.core.messages import duration_words

        return f"{self.counts()}, {duration_words(self.elapsed)} elapsed"


@dataclass(frozen=True)
class FleetStopped:
    """What a fleet run stopped mid-way (Ctrl-C) kept: every recording finished before is
    in the history; the same run again does only the rest. It rides on the exception that
    stopped the run (:func:`fleet_stopped`).

    Attributes
    ----------
    done, total : int
        Recordings finished and recorded, and to do in this run.
    history : str
        The history file they are in.
    """

    done: int
    total: int
    history: str

    def text(self) -> str:
        """What was kept and how to finish, without the cause."""
        kept = (
            f"{self.done} of the {self.total} recordings to do are done, recorded in the "
            f"history ({self.history})"
        )
        left = self.total - self.done
        if left <= 0:
            return f"{kept}; run the same command again for the summary (nothing is done again)"
        return f"{kept}; to finish, run the same command again: only the other {left} are done"


def fleet_stopped(exc: BaseException) -> FleetStopped | None:
    """The :class:`FleetStopped` a fleet run left on the exception that stopped it."""
    found = getattr(exc, "umbmark_fleet_stopped", None)
    return found if isinstance(found, FleetStopped) else None


@dataclass(frozen=True)
class FleetReport(JsonText):
    """What a fleet run did and what the fleet shows.

    Attributes
    ----------
    summary : FleetSummary
        Every robot of the recordings given, from all its recordings in the history.
    found : int
        Recordings found under the sources.
    done : tuple of RecordingOutcome
        The recordings calibrated, left out or failed in this run.
    skipped : int
        Recordings already in the history with the same options (not done again).
    history : str
        The history file.
    files : tuple of str
        The files written (the page, the JSON).
    warnings : tuple of str
        What may be quietly wrong: a ``robot_from`` pattern that did not match every
        recording, a ``robot_options`` entry for a robot not found
        (:mod:`umbmark.fleets.naming`), a ``tcp://`` scheduler while Dask's configuration
        gives TLS certificates.
    """

    summary: FleetSummary
    found: int
    done: tuple[RecordingOutcome, ...]
    skipped: int
    history: str
    files: tuple[str, ...] = ()
    command: str | None = field(default=None, compare=False)
    warnings: tuple[str, ...] = ()

    @property
    def failed(self) -> tuple[RecordingOutcome, ...]:
        """The recordings of this run that could not be read."""
        return tuple(o for o in self.done if o.failed)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (metres, radians, seconds): what ``fleet --json`` prints."""
        return {
            "summary": self.summary.line(),
            **self.summary.to_dict(),
            "recordings_found": self.found,
            "recordings_done": len(self.done),
            "recordings_skipped": self.skipped,
            "failed": [{"path": o.path, "reason": o.reason} for o in self.failed],
            "history": self.history,
            "warnings": list(self.warnings),
        }


def _calibration(outcome: RecordingOutcome) -> Any:  # noqa: ANN401 (NewCalibration)
    """What the history records of a calibrated recording: the recording's time."""
    from umbmark.store.records import NewCalibration

    record = outcome.record
    when = (
        dt.datetime.fromtimestamp(outcome.start, dt.timezone.utc)
        if outcome.start is not None
        else dt.datetime.now(dt.timezone.utc)
    )
    figures = outcome.figures
    return NewCalibration(
        when,
        str(outcome.method),
        figures["E_d"][0],
        figures["E_b"][0] if "E_b" in figures else figures["E_b_gyro"][0],  # said by its errors
        figures["E_s"][0] if "E_s" in figures else None,
        outcome.e_max_syst,
        dict(record.get("standard_errors") or {}),
        dict(record.get("active") or {}),
        dict(record.get("new") or {}),
        dict(record.get("verdict") or {}),
        float(outcome.wheelbase or 0.0),
        record.get("wheel_diameter"),
    )


def _tasks(
    found: Sequence[Any],
    common: Mapping[str, Any],
    per_robot: Mapping[str, Mapping[str, Any]],
) -> list[RecordingTask]:
    """A task per recording: a robot the pattern names carries its own options only; one
    to be named by its recording carries every robot's (it is known only when read)."""
    tasks = []
    for f in found:
        own = per_robot if f.robot is None else {f.robot: per_robot.get(f.robot, {})}
        tasks.append(RecordingTask(f.path, f.robot, f.day, common, own))
    return tasks


def _default(name: str) -> object:
    """A reading option's default (None for none, or an unknown name)."""
    from umbmark.options.spec import READ

    spec = READ.get(name)
    return None if spec is None else spec.default


def _options_key(task: RecordingTask, robot: str) -> str:
    """The key of the options ``task`` is read with as a recording of ``robot``."""
    from umbmark.store.fleet_recordings import options_key

    return options_key(task.options_for(robot))


def _done_as(task: RecordingTask, seen: Mapping[str, str]) -> str | None:
    """The robot a recording already in the history (``seen``: its options keys and the
    robot each found) was found to be, read with the options it would be read with now;
    None where it was not."""
    for key, robot in seen.items():
        if key == _options_key(task, task.robot or robot):
            return robot
    return None


def _not_done(
    store: Any,  # noqa: ANN401 (History)
    tasks: Sequence[RecordingTask],
) -> tuple[list[RecordingTask], dict[str, str]]:
    """The tasks not done before (with the same options), and the robot each of those
    done before was found to be (by path)."""
    from umbmark.store.fleet_recordings import done_recordings, identity

    to_do, before = [], {}
    seen = done_recordings(store)  # one look into the history
    for task in tasks:
        robot = _done_as(task, seen.get(identity(task.path), {}))
        if robot is None:
            to_do.append(task)
        else:
            before[task.path] = robot
    return to_do, before


def fleet(
    *sources: str | os.PathLike[str],
    robot_from: str | None = None,
    robot_options: str | os.PathLike[str] | None = None,
    history: str | os.PathLike[str] | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    report: str | os.PathLike[str] | None = None,
    output: str | os.PathLike[str] | None = None,
    force: bool = False,
    command: str | None = None,
    progress: Callable[[FleetProgress], None] | None = None,
    wheelbase: float | None = None,
    **options: Unpack[SourceOptions],
) -> FleetReport:
    """Calibrate every new recording of a fleet and say what the fleet shows.

    Parameters
    ----------
    *sources : path, glob or URL
        Recordings (ROS 1 and 2 bags, MCAP, run logs, OptiOdom sessions), folders to
        search, globs; local, or at URLs fsspec reads (the ``remote`` extra).
    robot_from : str, optional
        A pattern of the recordings' paths naming the robot and the day
        (``{robot}/{date}/*.mcap``); else the robot comes from the recording.
    robot_options : path, optional
        A YAML file of per-robot reading options
        (:func:`umbmark.sources.robot_options.read_robot_options`).
    history : path, optional
        The history file (default ``$UMBMARK_HISTORY``, else the per-user file).
    scheduler : str, optional
        An existing Dask scheduler (``tcp://host:8786``); default
        ``$DASK_SCHEDULER_ADDRESS``, else a local cluster of this machine's cores.
    workers : int, optional
        Workers of the local cluster.
    report : path, optional
        Write the fleet's page (.html).
    output : path, optional
        Write the JSON.
    force : bool
        Replace ``report`` and ``output`` if they exist.
    command : str, optional
        The command line that ran (shown on the page, its URLs redacted).
    progress : callable, optional
        Called with a :class:`FleetProgress` after each recording.
    wheelbase : float, optional
        The wheelbase the odometry used [m], where a recording does not say it.
    **options
        Reading options for every recording (as :func:`umbmark.calibrate` takes them:
        ``truth_topic``, ``scan_topic``, ``wheelbase``, ``wheel_diameter``, ...).

    Returns
    -------
    FleetReport

    Raises
    ------
    InputError
        No recording found, a bad pattern, options file or output, the engine missing or
        its scheduler not answering.
    """
    from umbmark.fleets.cluster import run_each
    from umbmark.fleets.outcome import calibrate_recording
    from umbmark.fleets.recordings import find_recordings
    from umbmark.options.fleet import FLEET
    from umbmark.outputs.files import OutputPlan
    from umbmark.runs.read_options import ReadOptions
    from umbmark.sources.remote import redacted
    from umbmark.sources.robot_options import read_robot_options
    from umbmark.store.history import History

    FLEET["workers"].check(workers)
    ReadOptions.of(dict(options))  # checked once, before anything is read
    # The options given. One not given (None), or at its default (the command line passes
    # every default, the library none), leaves a recording's own candidates to be used (a
    # namespaced /amr1/joint_states), and the same options make the same key either way.
    reading: dict[str, Any] = {
        k: v for k, v in options.items() if v is not None and v != _default(k)
    }
    if wheelbase is not None:
        reading["wheelbase"] = wheelbase
    plan = OutputPlan.of(force=force, inputs=sources, report=report, output=output)
    per_robot = read_robot_options(robot_options) if robot_options is not None else {}
    found = find_recordings(sources, robot_from)
    store = History(history)
    tasks, before = _not_done(store, _tasks(found, reading, per_robot))
    skipped = len(before)
    done: list[RecordingOutcome] = []
    robots: set[str] = set()
    began = time.monotonic()

    def record(finished: Any) -> None:  # noqa: ANN401 (Done)
        outcome = finished.result or _engine_failed(finished)
        outcome = _recorded(store, finished.item, outcome)
        done.append(outcome)
        robots.add(outcome.robot)
        if progress is not None:
            hours = sum(o.hours for o in done)
            elapsed = time.monotonic() - began
            progress(FleetProgress(len(done), len(tasks), len(robots), hours, elapsed))

    engine: list[str] = []  # the engine's warnings
    try:
        run_each(calibrate_recording, tasks, record, scheduler=scheduler, workers=workers,
                 notes=engine)  # fmt: skip
    except KeyboardInterrupt as exc:  # what finished is recorded: said, on the exception
        _mark_stopped(exc, FleetStopped(len(done), len(tasks), str(store.path)))
        raise
    named = _named(store, found, tasks, done, before)
    names = sorted({*(o.robot for o in named), *before.values()} - {NO_ROBOT})
    warnings = _naming_warnings(robot_from, robot_options, per_robot, found, named, before)
    result = FleetReport(
        _summary(store, names), len(found), tuple(named), skipped, str(store.path),
        command=None if command is None else redacted(command),
        warnings=(*engine, *warnings),
    )  # fmt: skip
    return _written(result, plan)


def _engine_failed(finished: Any) -> RecordingOutcome:  # noqa: ANN401 (Done)
    """The outcome of a recording whose task the engine could not run (it raised, or lost
    its workers): failed with the engine's one line, its URL and the line redacted."""
    from umbmark.sources.remote import redacted

    task = finished.item
    return RecordingOutcome(
        redacted(task.path), task.robot or UNNAMED, None, 0.0, None,
        reason=None if finished.error is None else redacted(finished.error), failed=True,
    )  # fmt: skip


def _mark_stopped(exc: BaseException, stop: FleetStopped) -> None:
    """Leave ``stop`` on ``exc`` for :func:`fleet_stopped`."""
    exc.umbmark_fleet_stopped = stop  # type: ignore[attr-defined]


def _unplaced(task: RecordingTask, outcome: RecordingOutcome) -> bool:
    """A recording that could not be read and that no pattern named: its robot is known
    only once every recording's is (:func:`_named`)."""
    return outcome.failed and task.robot is None and outcome.robot == UNNAMED


def _named(
    store: Any,  # noqa: ANN401 (History)
    found: Sequence[FleetRecording],
    tasks: Sequence[RecordingTask],
    done: Sequence[RecordingOutcome],
    before: Mapping[str, str],
) -> list[RecordingOutcome]:
    """``done`` with each recording that could not be read and that no pattern named
    given the robot its path names among the robots found (this run's, the pattern's and
    those done before), else none (:data:`~umbmark.fleets.naming.NO_ROBOT`), and
    recorded."""
    from dataclasses import replace

    from umbmark.fleets.naming import robot_in_path
    from umbmark.sources.remote import redacted

    # An outcome names its recording redacted (a URL without its credentials).
    by_path = {redacted(t.path): t for t in tasks}
    parts = {redacted(f.path): f.parts for f in found}
    robots = {*before.values(), *(f.robot for f in found if f.robot)}
    robots |= {o.robot for o in done if not _unplaced(by_path[o.path], o)}
    named = []
    for outcome in done:
        task = by_path[outcome.path]
        if not _unplaced(task, outcome):
            named.append(outcome)
            continue
        robot = robot_in_path(parts.get(outcome.path, ()), robots)
        how = None if robot is None else "path"
        placed = replace(outcome, robot=robot or NO_ROBOT, named_by=how)
        named.append(_stored(store, task, placed))
    return named


def _naming_warnings(
    robot_from: str | None,
    robot_options: str | os.PathLike[str] | None,
    per_robot: Mapping[str, Any],
    found: Sequence[FleetRecording],
    named: Sequence[RecordingOutcome],
    before: Mapping[str, str],
) -> tuple[str, ...]:
    """The warnings of a pattern that did not match every recording and of per-robot
    options for robots not found (:mod:`umbmark.fleets.naming`), as messages say them."""
    from umbmark.core.messages import split_messages
    from umbmark.fleets.naming import options_warning, pattern_warning
    from umbmark.sources.remote import redacted

    messages = []
    robots = {*(o.robot for o in named), *before.values()} - {NO_ROBOT}
    if robot_from is not None:
        how = {o.path: "none" if o.robot == NO_ROBOT else o.named_by for o in named}
        missed = [f for f in found if not f.matched]
        ways: dict[str | None, int] = {}
        for f in missed:
            way = "history" if f.path in before else how.get(redacted(f.path), "none")
            ways[way] = ways.get(way, 0) + 1
        example = "/".join(missed[0].parts) if missed else ""
        messages.append(
            pattern_warning(robot_from, len(found), len(found) - len(missed), ways, example)
        )
    if per_robot:
        messages.append(options_warning(per_robot, robots, os.fspath(robot_options or "")))
    return split_messages(m for m in messages if m is not None)[1]


def _recorded(store: Any, task: RecordingTask, outcome: RecordingOutcome) -> RecordingOutcome:  # noqa: ANN401
    """Record one outcome as it comes back (:func:`_stored`), but one whose robot is not
    known yet (:func:`_unplaced`: recorded by :func:`_named`)."""
    if _unplaced(task, outcome):
        return outcome
    return _stored(store, task, outcome)


def _stored(store: Any, task: RecordingTask, outcome: RecordingOutcome) -> RecordingOutcome:  # noqa: ANN401
    """Record one outcome (the one writer); a calibration the history refuses (a robot
    known with another nominal geometry) is recorded as failed with why."""
    from dataclasses import replace

    from umbmark.store.fleet_recordings import RecordingRow, identity, record_recording

    calibration = _calibration(outcome) if outcome.calibrated else None
    try:
        ident = identity(task.path)
    except OSError:
        ident = ""
    row = RecordingRow(
        outcome.robot, outcome.path, outcome.digest, ident, _options_key(task, outcome.robot),
        outcome.start, outcome.hours, outcome.status,  # type: ignore[arg-type]
        outcome.reason, outcome.to_dict(),
    )  # fmt: skip
    try:
        record_recording(store, row, calibration)
    except InputError as exc:
        failed = replace(outcome, method=None, reason=str(exc), failed=True)
        row = replace(row, status="failed", reason=failed.reason, outcome=failed.to_dict())
        record_recording(store, row, None)
        return failed
    return outcome


def _summary(store: Any, robots: Sequence[str]) -> FleetSummary:  # noqa: ANN401 (History)
    from umbmark.fleets.summary import summarize
    from umbmark.store.fleet_recordings import read_recordings

    rows = read_recordings(store, robots) if robots else []
    return summarize([RecordingOutcome.of_dict(r.outcome) for r in rows])


def _written(result: FleetReport, plan: Any) -> FleetReport:  # noqa: ANN401 (OutputPlan)
    from dataclasses import replace

    from umbmark.core.atomic import atomic_write_text
    from umbmark.fleets.page import fleet_page

    files = []
    if plan.report is not None:
        atomic_write_text(plan.report, fleet_page(result.summary, made=result.command or ""))
        files.append(str(plan.report))
    if plan.output is not None:
        atomic_write_text(plan.output, result.to_json())
        files.append(str(plan.output))
    if not files:
        return result
    return replace(result, files=tuple(files))

"""The whole fleet job (``umbmark.fleet``) on a real Dask cluster whose workers are killed
mid-run: a scheduler and two workers started as separate processes with Dask's own
command-line programs on a free port of this machine (``tests/dask_cluster.py``), the
recordings a small simulated fleet (ROS 2 bags of ordinary driving with wheels and a
laser, calibrated by scan matching, about a second each on a worker).

What is checked: a worker killed with SIGKILL (by its PID) while it calibrates a recording
loses nothing: the recording is redone on the other worker, every recording is done
exactly once in the run's report and in the history, none failed, the figures are those
of a local run of the same recordings (``workers=1``, no scheduler) to the last bit, and
the killed worker's process is dead; the same for a worker of the local cluster the job
starts itself (no scheduler given). Both workers killed mid-run, or the scheduler: the
job does not wait forever but stops with one line, keeping what finished (and recording
nothing as failed), and the next run does the rest, losing nothing either.
"""

from __future__ import annotations

import json
import os
import re
import signal
import sqlite3
import subprocess
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

from distributed import Client

import umbmark
from umbmark.store.fleet_recordings import read_recordings
from umbmark.store.history import History

import fleet_tasks
from dask_cluster import Cluster

ROBOTS, DAYS = 2, 3
#: Each recording's driving [min]: about a second of scan matching on one worker.
MINUTES = 4.0
PATTERN = "{robot}/{date}/*"
T = TypeVar("T")
#: When an overlay was written, in its first line: what two runs of a recording differ in.
WRITTEN = re.compile(r" on \d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}Z ")


def _but_when(outcome: dict[str, Any]) -> dict[str, Any]:
    """A recording's outcome (``RecordingOutcome.to_dict()``) without the time its overlay
    was written."""
    record = dict(outcome["record"])
    if "overlay" in record:
        record["overlay"] = WRITTEN.sub(" on (when) ", record["overlay"], count=1)
    return {**outcome, "record": record}


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("faults") / "fleet"
    umbmark.simulate_fleet(folder, fleet=ROBOTS, days=DAYS, minutes=MINUTES, seed=4)
    return folder


@pytest.fixture(scope="module")
def expected(recordings: Path) -> set[str]:
    """Every recording's path, as the simulator that wrote them lists them."""
    truth = json.loads((recordings / "truth.json").read_text(encoding="utf-8"))
    paths = {r["path"] for r in truth["recordings"]}
    assert len(paths) == ROBOTS * DAYS
    return paths


@pytest.fixture(scope="module")
def local(recordings: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The local run's outcome of every recording (one worker, no scheduler), by path, each
    without the time its overlay was written."""
    history = tmp_path_factory.mktemp("local") / "h.sqlite3"
    report = umbmark.fleet(recordings, robot_from=PATTERN, history=history, workers=1)
    return {o.path: _but_when(o.to_dict()) for o in report.done}


def _busy_worker(watch: Client) -> tuple[str, str, str]:
    """A worker calibrating a recording right now, by its own state: its address, the
    task's key and the recording's path (waits until one is; a worker between two
    recordings has none)."""
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        running = watch.run(fleet_tasks.executing)
        for address in sorted(running):
            for key, path in running[address].items():
                return address, key, path
        time.sleep(0.02)
    raise AssertionError("no worker was calibrating a recording")


def _history(path: Path) -> tuple[Counter[str], Counter[str], int]:
    """The history's recordings by path, as read back by the store (its latest row of
    each) and as its table holds them (every row), and how many calibrations it holds."""
    read = Counter(row.path for row in read_recordings(History(path)))
    with sqlite3.connect(path) as db:
        rows = Counter(str(r[0]) for r in db.execute("SELECT path FROM recordings"))
        calibrations = int(db.execute("SELECT count(*) FROM calibrations").fetchone()[0])
    return read, rows, calibrations


@pytest.mark.slow
def test_a_worker_killed_mid_recording_loses_nothing(
    recordings: Path, expected: set[str], local: dict[str, Any], cluster: Cluster, tmp_path: Path
):
    """The kill comes from the job's own ``progress`` callback once the first recording has
    come back, while the other recordings are in flight on both workers. How we know it
    lands mid-recording: just before the SIGKILL the worker itself says (its own state,
    asked through ``Client.run``) that it is executing the task of recording P in its
    thread, not merely holding it; after it, the scheduler's own record of the worker's
    removal lists that task among those it was processing (not finished); and P had not
    come back to the job by then (it comes back later, once, from the other worker)."""
    history = tmp_path / "h.sqlite3"
    kill: dict[str, Any] = {}
    with Client(cluster.address, timeout=60) as watch:
        pids = watch.run(os.getpid)  # each worker's PID, by its address
        assert sorted(pids.values()) == sorted(proc.pid for proc in cluster.workers)

        def progress(p: umbmark.FleetProgress) -> None:
            if kill:
                return
            address, key, path = _busy_worker(watch)
            kill.update(address=address, key=key, path=path, after=p.done)
            kill["status"] = cluster.kill(pids[address])

        report = umbmark.fleet(recordings, robot_from=PATTERN, history=history,
                               scheduler=cluster.address, progress=progress)  # fmt: skip
        events = [e for _, e in watch.get_events(kill["address"])]
        removed = [e for e in events if e["action"] == "remove-worker"]
        left = set(watch.nthreads())

    # The worker was killed mid-recording, and is dead.
    assert kill["path"] in expected
    assert kill["after"] == 1
    assert kill["status"] == -signal.SIGKILL
    with pytest.raises(ProcessLookupError):
        os.kill(pids[kill["address"]], 0)
    assert [kill["key"] in e["processing-tasks"] for e in removed] == [True]
    assert [e["expected"] for e in removed] == [False]
    assert left == set(pids) - {kill["address"]}
    paths = [o.path for o in report.done]
    assert kill["path"] not in paths[: kill["after"]]
    assert kill["path"] in paths[kill["after"] :]
    # Nothing lost, nothing twice, nothing failed.
    assert Counter(paths) == Counter(expected)
    assert report.failed == ()
    assert [o.status for o in report.done] == ["calibrated"] * len(expected)
    assert _history(history) == (Counter(expected), Counter(expected), len(expected))
    # The figures, and all else each recording gave, are the local run's.
    assert {o.path: _but_when(o.to_dict()) for o in report.done} == local


def _children() -> set[int]:
    """This process's child processes, by their PIDs (Linux's ``/proc``)."""
    found = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:  # gone meanwhile
            continue
        if int(fields[1]) == os.getpid():
            found.add(int(stat.parent.name))
    return found


def _within(seconds: float, holds: Callable[[], bool]) -> bool:
    """Whether ``holds()`` comes true within ``seconds`` (processes end a while after they
    are told to, later on a loaded machine)."""
    deadline = time.monotonic() + seconds
    while not holds():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def _dead(pid: int, within: float = 30.0) -> bool:
    """Whether process ``pid`` is gone (reaped by its parent) within ``within`` seconds."""

    def gone() -> bool:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        return False

    return _within(within, gone)


@pytest.mark.slow
def test_a_worker_of_the_default_local_cluster_killed_mid_recording_loses_nothing(
    recordings: Path, expected: set[str], local: dict[str, Any], tmp_path: Path
):
    """No scheduler given: the job starts its own local cluster (two worker processes,
    each under a nanny that starts another in its place: ``umbmark.fleets.cluster``). The
    kill comes from the job's ``progress`` callback as above, through the job's own client
    (``distributed.default_client()``: the client the job made is its process's default),
    and the proof that it lands mid-recording is the same: the worker says it is executing
    recording P's task just before the SIGKILL, the scheduler's record of its removal
    lists that task as processing (taken at the later callbacks, before the job closes its
    cluster), and P comes back once, after the kill, from another worker. Nothing lost or
    twice, in the report and the history, the local run's figures to the last bit, and
    no worker left running after the job."""
    from distributed import default_client

    history = tmp_path / "h.sqlite3"
    kill: dict[str, Any] = {}
    removed: list[dict[str, Any]] = []
    workers: set[int] = set()

    def progress(p: umbmark.FleetProgress) -> None:
        watch = default_client()
        pids = watch.run(os.getpid)  # each worker's PID, by its address
        workers.update(pids.values())
        if not kill:
            address, key, path = _busy_worker(watch)
            kill.update(address=address, key=key, path=path, after=p.done, pid=pids[address])
            os.kill(pids[address], signal.SIGKILL)
        elif not removed:
            events = [e for _, e in watch.get_events(kill["address"])]
            removed.extend(e for e in events if e["action"] == "remove-worker")

    before = _children()
    report = umbmark.fleet(recordings, robot_from=PATTERN, history=history, workers=2,
                           progress=progress)  # fmt: skip

    # The worker was killed mid-recording, and is dead; so is every worker once the job
    # has closed its cluster, and no process it started is left.
    assert kill["path"] in expected
    assert kill["after"] == 1
    assert _dead(kill["pid"])
    assert [kill["key"] in e["processing-tasks"] for e in removed] == [True], (kill, removed)
    assert [e["expected"] for e in removed] == [False]
    assert len(workers) >= 2
    assert all(_dead(pid) for pid in workers)
    assert _within(30.0, lambda: _children() <= before), _children() - before
    paths = [o.path for o in report.done]
    assert kill["path"] not in paths[: kill["after"]]
    assert kill["path"] in paths[kill["after"] :]
    # Nothing lost, nothing twice, nothing failed.
    assert Counter(paths) == Counter(expected)
    assert report.failed == ()
    assert [o.status for o in report.done] == ["calibrated"] * len(expected)
    assert _history(history) == (Counter(expected), Counter(expected), len(expected))
    # The figures, and all else each recording gave, are the local run's of one worker.
    assert {o.path: _but_when(o.to_dict()) for o in report.done} == local


def _all_busy(watch: Client, workers: int) -> dict[str, str]:
    """Every worker calibrating a recording right now, by its own state: the recording's
    path by the worker's address (waits until all ``workers`` are)."""
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        running = watch.run(fleet_tasks.executing)
        paths = {a: p for a, r in running.items() for p in r.values()}
        if len(paths) == workers:
            return paths
        time.sleep(0.02)
    raise AssertionError("the workers were not all calibrating a recording")


def _killed_mid_run(
    args: list[str], history: Path, kill: Callable[[], T], env: dict[str, str] | None = None
) -> tuple[T, int, str, str]:
    """Start ``umbmark ARGS``, ``kill()`` once the first recording is in the history, and
    wait for it to end: what ``kill`` gave, the exit status, stdout and stderr."""
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env)  # fmt: skip
    try:
        deadline = time.monotonic() + 300
        while fleet_tasks.recorded_rows(history) < 1:
            assert time.monotonic() < deadline, "no recording came back"
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        killed = kill()
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:  # it waits forever
            proc.kill()
            proc.communicate()
    return killed, proc.returncode, out, err


def _kept(history: Path, expected: set[str], in_flight: set[str]) -> Counter[str]:
    """What a run stopped mid-way kept: some recordings, each once, none failed, none of
    those in flight when it was stopped."""
    kept = _history(history)
    assert kept[0] == kept[1]  # none twice
    assert set(kept[0].values()) == {1}
    assert kept[2] == len(kept[0])
    assert 1 <= len(kept[0]) < len(expected)
    assert set(kept[0]) <= expected
    assert not in_flight & set(kept[0])
    with sqlite3.connect(history) as db:
        assert {r[0] for r in db.execute("SELECT status FROM recordings")} == {"calibrated"}
    return kept[0]


def _does_the_rest(
    args: list[str], history: Path, expected: set[str], kept: Counter[str], local: dict[str, Any]
) -> None:
    """``umbmark ARGS`` again does only what was not kept; the history then holds every
    recording once, none failed, each with the local run's outcome."""
    again = subprocess.run(args, capture_output=True, text=True, timeout=600, check=False)
    assert again.returncode == 0, again.stderr
    data = json.loads(again.stdout)
    assert (data["recordings_done"], data["recordings_skipped"]) == (
        len(expected) - len(kept),
        len(kept),
    )
    assert data["failed"] == []
    assert _history(history) == (Counter(expected), Counter(expected), len(expected))
    rows = {row.path: row for row in read_recordings(History(history))}
    assert {p: row.status for p, row in rows.items()} == dict.fromkeys(expected, "calibrated")
    assert {p: _but_when(row.outcome) for p, row in rows.items()} == json.loads(json.dumps(local))


def _said(err: str) -> list[str]:
    """stderr's lines but the progress lines (stderr is no terminal here: the recordings
    done, as they finish)."""
    return [line for line in err.splitlines() if not line.startswith("umbmark: progress: ")]


def _fleet_args(recordings: Path, history: Path, scheduler: str) -> list[str]:
    from helpers import umbmark_command

    return [umbmark_command(), "fleet", str(recordings), "--robot-from", PATTERN,
            "--history", str(history), "--scheduler", scheduler, "--json"]  # fmt: skip


@pytest.mark.slow
def test_all_workers_killed_mid_run_stop_the_job_with_one_line_and_lose_nothing(
    recordings: Path, expected: set[str], local: dict[str, Any], cluster: Cluster, tmp_path: Path
):
    """``umbmark fleet --scheduler`` with both workers killed (SIGKILL), each while it
    calibrates a recording (the workers' own state says so just before), once the first
    recording is in the history: the scheduler is left with no worker, and the job does not
    wait for one forever. After Dask's own ``distributed.scheduler.no-workers-timeout``
    (here 2 s, through Dask's environment variable for it) it stops with one line naming
    the scheduler and exit status 2; what came back before is in the history once and
    nothing is recorded failed. With workers started again on the same scheduler, the next
    run does only the rest, and the history then holds every recording once, none failed,
    each with the local run's outcome."""
    history = tmp_path / "h.sqlite3"
    args = _fleet_args(recordings, history, cluster.address)
    env = {**os.environ, "DASK_DISTRIBUTED__SCHEDULER__NO_WORKERS_TIMEOUT": "2s"}
    with Client(cluster.address, timeout=60) as watch:
        pids = watch.run(os.getpid)

        def kill() -> dict[str, tuple[str, int]]:
            busy = _all_busy(watch, len(pids))
            statuses = cluster.kill_all([pids[a] for a in busy])
            return {a: (path, s) for (a, path), s in zip(busy.items(), statuses, strict=True)}

        killed, status, out, err = _killed_mid_run(args, history, kill, env)
    assert [s for _, s in killed.values()] == [-signal.SIGKILL] * len(pids)
    kept = _kept(history, expected, {path for path, _ in killed.values()})
    assert (status, out) == (2, ""), err
    assert _said(err) == [
        f"umbmark: error: {cluster.address}: the Dask scheduler has had no worker for 2 s, "
        f"with {len(expected) - len(kept)} of {len(expected)} tasks not done: stopped "
        f"(what finished is kept; start workers: dask worker {cluster.address})"
    ], err
    # Workers again on the same scheduler: the next run does only the rest.
    cluster.add_workers(2)
    _does_the_rest(args, history, expected, kept, local)


@pytest.mark.slow
def test_the_scheduler_killed_mid_run_stops_the_job_with_one_line_and_loses_nothing(
    recordings: Path, expected: set[str], local: dict[str, Any], cluster: Cluster, tmp_path: Path
):
    """``umbmark fleet --scheduler`` with the scheduler killed (SIGKILL) once the first
    recording is in the history, while both workers calibrate one (their own state says so
    just before): the job stops with one line naming the scheduler and exit status 2, not
    with Dask's tracebacks, nor with the recordings not done recorded as failed; what came
    back before is in the history once. The next run, on a new cluster, does only the
    rest, and the history then holds every recording once, none failed, each with the local
    run's outcome."""
    history = tmp_path / "h.sqlite3"
    args = _fleet_args(recordings, history, cluster.address)
    with Client(cluster.address, timeout=60) as watch:
        pids = watch.run(os.getpid)

        def kill() -> tuple[set[str], int]:
            busy = _all_busy(watch, len(pids))
            return set(busy.values()), cluster.kill(cluster.scheduler.pid)

        (in_flight, killed), status, out, err = _killed_mid_run(args, history, kill)
    assert killed == -signal.SIGKILL
    kept = _kept(history, expected, in_flight)
    assert (status, out) == (2, ""), err
    assert _said(err) == [
        f"umbmark: error: {cluster.address}: the Dask scheduler cancelled this run's tasks "
        f"(lost, or restarted), with {len(expected) - len(kept)} of {len(expected)} not done: "
        "stopped (what finished is kept)"
    ], err
    # The next run, on a new cluster, does only the rest.
    (tmp_path / "again").mkdir()
    again = Cluster(tmp_path / "again", workers=2)
    try:
        _does_the_rest(_fleet_args(recordings, history, again.address), history, expected, kept,
                       local)  # fmt: skip
    finally:
        again.close()

"""The fleet's engine, Dask distributed, started for real: a local cluster of worker
processes, and a scheduler and workers started as separate processes with Dask's own
command-line programs on free ports of this machine.

What is checked: every item comes back once, to this process, in the order they finish;
an item whose function raises comes back failed with its one-line reason while the others
go on; the same work on an existing cluster (``scheduler=``, and Dask's own
``DASK_SCHEDULER_ADDRESS``) gives the same results as the local run; a worker killed
mid-item loses nothing (its item is redone on another worker), nor does one killed holding a
finished result not yet fetched, also inside the caller's own ``with Client(...)``; a
cluster left with no worker stops the run with one line instead of waiting forever; a local
cluster starts while Dask's default dashboard port is taken.
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

from distributed import Client

from umbmark.core.errors import InputError
from umbmark.fleets.cluster import Done, run_each

import fleet_tasks
from dask_cluster import Cluster, free_port


def _collect(fn, items, **kw) -> list[Done]:  # type: ignore[no-untyped-def]
    done: list[Done] = []
    assert run_each(fn, items, done.append, **kw) == len(items)
    return done


@pytest.mark.slow
def _run_waiting_for_workers(cluster: Cluster, items, on_done) -> list[BaseException]:  # type: ignore[no-untyped-def]
    """``run_each`` of ``slow_square`` on the cluster, Dask's ``no-workers-timeout`` 1 s, in
    a thread of its own, so that waiting forever fails the test: what it raised."""
    import threading

    import dask

    raised: list[BaseException] = []

    def run() -> None:
        try:
            with dask.config.set({"distributed.scheduler.no-workers-timeout": "1s"}):
                run_each(fleet_tasks.slow_square, items, on_done, scheduler=cluster.address)
        except BaseException as exc:  # handed to the test
            raised.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout=120)
    assert not thread.is_alive(), "the run waits for a worker forever"
    return raised


@pytest.mark.slow
def test_a_local_cluster_returns_every_item_once_and_names_the_failed_one():
    items = [3, -1, 4, 0, 7]
    done = _collect(fleet_tasks.square_or_refuse, items, workers=2)
    assert sorted(d.index for d in done) == list(range(len(items)))
    by = {d.index: d for d in done}
    for k, n in enumerate(items):
        if n < 0:
            assert by[k].result is None
            assert by[k].error == f"rec-{n}.bag: item {n} cannot be read"
        else:
            assert by[k].result == n * n
            assert by[k].error is None


@pytest.mark.slow
def test_a_local_cluster_starts_without_a_warning_while_port_8787_is_taken():
    """Dask's default dashboard port taken (by another fleet run on this machine): the local
    cluster's HTTP server takes a free port instead of warning (warnings are errors)."""
    import socket

    holder = socket.socket()
    try:
        holder.bind(("127.0.0.1", 8787))
        holder.listen()
    except OSError:  # taken already: the same situation
        pass
    try:
        done = _collect(fleet_tasks.square_or_refuse, [3], workers=1)
    finally:
        holder.close()
    assert [(d.result, d.error) for d in done] == [(9, None)]


@pytest.mark.slow
def test_an_existing_cluster_gives_what_the_local_run_gives(cluster: Cluster, monkeypatch):
    items = list(range(-2, 9))
    local = {
        d.index: (d.result, d.error)
        for d in _collect(fleet_tasks.square_or_refuse, items, workers=1)
    }
    remote = {
        d.index: (d.result, d.error)
        for d in _collect(fleet_tasks.square_or_refuse, items, scheduler=cluster.address)
    }
    assert remote == local
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", cluster.address)  # Dask's own variable
    by_env = {d.index: (d.result, d.error) for d in _collect(fleet_tasks.square_or_refuse, items)}
    assert by_env == local


@pytest.mark.slow
def test_a_worker_killed_mid_item_loses_nothing(cluster: Cluster, tmp_path: Path):
    marks = tmp_path / "marks"
    marks.mkdir()
    items = [(n, str(marks), 2.0) for n in range(4)]
    pids = {proc.pid for proc in cluster.workers}
    killed: list[int] = []

    import threading

    def killer() -> None:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not killed:
            for mark in marks.iterdir():
                pid = int(mark.name.rsplit("-", 1)[1])
                if pid in pids:
                    os.kill(pid, signal.SIGKILL)
                    killed.append(pid)
                    return
            time.sleep(0.05)

    thread = threading.Thread(target=killer)
    thread.start()
    done = _collect(fleet_tasks.slow_square, items, scheduler=cluster.address)
    thread.join()
    assert killed, "no worker was killed"
    assert sorted(d.index for d in done) == [0, 1, 2, 3]
    assert all(d.error is None for d in done), [d.error for d in done]
    assert {d.index: d.result[0] for d in done} == {n: n * n for n in range(4)}
    # The killed worker's item was redone by the other worker.
    assert all(d.result[1] != killed[0] for d in done)


@pytest.mark.slow
def test_a_result_lost_with_its_worker_is_computed_again_inside_the_callers_client(
    cluster: Cluster, tmp_path: Path
):
    """Item 1 finished on a worker, which is killed before this process fetched its result:
    it is computed again on the other worker, also where the caller runs the engine inside
    ``with Client(...)`` of its own (that client is then Dask's current one)."""
    items = [(0, str(tmp_path), 0.0), (1, str(tmp_path), 1.0)]
    done: list[Done] = []
    killed: list[int] = []
    with Client(cluster.address, timeout=60) as own:
        pids = own.run(os.getpid)

        def on_done(d: Done) -> None:
            done.append(d)
            if killed:
                return
            deadline = time.monotonic() + 60
            while not (held := own.run_on_scheduler(fleet_tasks.holders, 1)):
                assert time.monotonic() < deadline, "item 1 did not finish"
                time.sleep(0.02)
            killed.append(pids[held[0]])
            assert cluster.kill(killed[0]) == -signal.SIGKILL

        assert run_each(fleet_tasks.slow_square, items, on_done, scheduler=cluster.address) == 2
    assert [d.index for d in done] == [0, 1]
    assert [d.error for d in done] == [None, None]
    assert done[1].result is not None
    assert done[1].result[0] == 1
    assert done[1].result[1] != killed[0]  # computed again, by the other worker


@pytest.mark.slow
def test_a_cluster_left_with_no_worker_stops_the_run_with_one_line(
    cluster: Cluster, tmp_path: Path
):
    """Both workers killed once the first item came back: the scheduler alone would wait
    for a worker forever; the run stops after Dask's ``no-workers-timeout`` (1 s here),
    having handed over what finished, and names the scheduler."""

    items = [(n, str(tmp_path), 0.0 if n == 0 else 2.0) for n in range(4)]
    done: list[Done] = []
    pids = [proc.pid for proc in cluster.workers]

    def on_done(d: Done) -> None:
        done.append(d)
        for pid in pids:
            if cluster.kill(pid) != -signal.SIGKILL:
                raise AssertionError(f"worker {pid} did not die of SIGKILL")
        pids.clear()

    raised = _run_waiting_for_workers(cluster, items, on_done)
    assert [d.index for d in done] == [0]
    assert [type(e) for e in raised] == [InputError]
    assert str(raised[0]) == (
        f"{cluster.address}: the Dask scheduler has had no worker for 1 s, with 3 of 4 tasks "
        f"not done: stopped (what finished is kept; start workers: dask worker "
        f"{cluster.address})"
    )


@pytest.mark.slow
def test_a_result_lost_with_the_last_worker_stops_the_run_with_one_line(
    cluster: Cluster, tmp_path: Path
):
    """Item 1 finished on a worker (the scheduler holds its result there) when every worker
    is killed, before this process fetched it: its result waits to be computed again, for a
    worker that does not come; the run stops after Dask's ``no-workers-timeout`` (1 s here)
    as it does while no item finishes."""

    items = [(0, str(tmp_path), 0.0), (1, str(tmp_path), 0.5), (2, str(tmp_path), 5.0)]
    done: list[Done] = []
    raised: list[BaseException] = []
    with Client(cluster.address, timeout=60) as own:
        pids = own.run(os.getpid)

        def on_done(d: Done) -> None:
            done.append(d)
            deadline = time.monotonic() + 60
            while not own.run_on_scheduler(fleet_tasks.holders, 1):
                assert time.monotonic() < deadline, "item 1 did not finish"
                time.sleep(0.02)
            for pid in pids.values():
                assert cluster.kill(pid) == -signal.SIGKILL

        raised += _run_waiting_for_workers(cluster, items, on_done)
    assert [d.index for d in done] == [0]
    assert [type(e) for e in raised] == [InputError]
    assert str(raised[0]).startswith(
        f"{cluster.address}: the Dask scheduler has had no worker for 1 s, with 2 of 3 tasks "
    )


def test_no_scheduler_at_the_address_is_one_line():
    port = free_port()
    with pytest.raises(InputError, match=f"no Dask scheduler answers at tcp://127.0.0.1:{port}"):
        run_each(
            fleet_tasks.square_or_refuse,
            [1],
            lambda d: None,
            scheduler=f"tcp://127.0.0.1:{port}",
            connect_timeout=1.0,
        )

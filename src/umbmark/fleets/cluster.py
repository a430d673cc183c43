"""The distributed engine a fleet's recordings are calibrated on: Dask distributed, at the
edge of the package.

This is the one module of umbmark that imports Dask (``tests/test_architecture.py`` holds
it). What it runs knows nothing of Dask: :func:`run_each` hands a plain function and its
items to the engine and gives back each outcome, in the order they finish, to one caller
in this process (the one writer of the history).

- Without an address it starts a local cluster on this machine's cores (one process per
  worker, one thread each: the work is numpy and Python), no set-up needed; with
  ``scheduler`` (``--scheduler ADDRESS``, else Dask's own ``DASK_SCHEDULER_ADDRESS``) it
  sends the same work to an existing cluster, whose workers must have umbmark installed
  and see the files.
- A worker that dies mid-item has the item redone on another worker (the scheduler does
  this, up to :data:`ALLOWED_FAILURES` deaths per item); an item whose function raises is
  reported as failed with its one-line reason, and the others go on.
- Ctrl-C (``KeyboardInterrupt``) cancels what has not finished and re-raises: what
  finished has already been handed to the caller.
"""

from __future__ import annotations

import logging
import os
import tempfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from umbmark.core.errors import InputError, option

__all__ = [
    "ALLOWED_FAILURES",
    "ENGINE_MISSING",
    "SCHEDULER_ENV",
    "Done",
    "engine_address",
    "run_each",
]

T = TypeVar("T")
R = TypeVar("R")

#: Dask's own environment variable for the scheduler's address (``dask.config``'s
#: ``scheduler-address``).
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"
#: How often an item may lose its worker before it counts as failed (Dask's
#: ``distributed.scheduler.allowed-failures``; its default is 3).
ALLOWED_FAILURES = 3
#: Most local workers (a machine's cores beyond this add little for bag reading).
MAX_LOCAL_WORKERS = 64
#: Seconds to wait for an existing scheduler to answer.
CONNECT_TIMEOUT = 30.0
#: What to install when the engine is missing.
ENGINE_MISSING = (
    "the fleet runs on Dask distributed, which is not installed: python -m pip install "
    "'dask[distributed]' (or, in umbmark's checkout, python -m pip install '.[fleet]')"
)


@dataclass(frozen=True)
class Done(Generic[T, R]):
    """One item finished.

    Attributes
    ----------
    index : int
        Its place in the items given.
    item : T
        The item.
    result : R or None
        What the function returned; None when it failed.
    error : str or None
        Why it failed (one line), None when it did not.
    """

    index: int
    item: T
    result: R | None
    error: str | None = None


def engine_address(scheduler: str | None) -> str | None:
    """The scheduler to use: ``scheduler`` if given, else ``$DASK_SCHEDULER_ADDRESS``,
    else None (a local cluster)."""
    if scheduler is not None and scheduler.strip():
        return scheduler.strip()
    return os.environ.get(SCHEDULER_ENV) or None


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    first = text[0] if text else ""
    if isinstance(exc, InputError):
        return first
    return f"{type(exc).__name__}: {first}" if first else type(exc).__name__


@contextmanager
def _client(address: str | None, workers: int | None, timeout: float) -> Iterator[Any]:
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError(ENGINE_MISSING) from None
    settings = {
        "distributed.scheduler.allowed-failures": ALLOWED_FAILURES,
        "distributed.worker.daemon": False,  # a worker's own pool may start processes
        "distributed.admin.system-monitor.gil.enabled": False,
    }
    with dask.config.set(settings):
        if address is not None:
            try:
                client = Client(address, timeout=timeout)
            except (OSError, TimeoutError) as exc:
                raise InputError(
                    f"no Dask scheduler answers at {address} ({_one_line(exc)})",
                    source=address,
                ) from None
            try:
                yield client
            finally:
                client.close()
            return
        n = workers if workers is not None else min(os.cpu_count() or 1, MAX_LOCAL_WORKERS)
        if not 1 <= n <= MAX_LOCAL_WORKERS:
            raise InputError(f"{option('workers', n)} must be 1 to {MAX_LOCAL_WORKERS}")
        with tempfile.TemporaryDirectory(prefix="umbmark-dask-") as scratch:
            cluster = LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                # Its HTTP server on a free port: Dask's default, 8787, is taken by any
                # other cluster on this machine (another fleet run), and then it warns.
                dashboard_address=":0",
                silence_logs=logging.ERROR,
                local_directory=scratch,  # the workers' scratch space, removed after
            )
            client = Client(cluster)
            try:
                yield client
            finally:
                client.close()
                cluster.close()


def run_each(
    fn: Callable[[T], R],
    items: Sequence[T],
    on_done: Callable[[Done[T, R]], None],
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    connect_timeout: float = CONNECT_TIMEOUT,
) -> int:
    """Run ``fn`` on every item on the engine; hand each outcome to ``on_done`` as it
    finishes, in this process.

    Parameters
    ----------
    fn : callable
        A plain function of one item, importable by the workers (a module's function).
    items : sequence
        Its items (picklable).
    on_done : callable
        Called once per item, in the order they finish, with a :class:`Done`.
    scheduler : str, optional
        An existing scheduler's address (``tcp://host:8786``); default
        ``$DASK_SCHEDULER_ADDRESS``, else a local cluster.
    workers : int, optional
        Workers of the local cluster (default: this machine's cores).
    connect_timeout : float
        Seconds to wait for an existing scheduler to answer.

    Returns
    -------
    int
        How many items finished (all of them, unless interrupted).

    Raises
    ------
    InputError
        Dask is not installed, or no scheduler answers at the address.
    KeyboardInterrupt
        After cancelling what had not finished.
    """
    if not items:
        return 0
    address = engine_address(scheduler)
    with _client(address, workers, connect_timeout) as client:
        from distributed import as_completed

        futures = client.map(fn, list(items), pure=False)
        where = {future.key: k for k, future in enumerate(futures)}
        finished = 0
        try:
            # On this client's own event loop: by default as_completed takes the current
            # client's, which is the caller's where it runs inside ``with Client(...)``, and
            # a result lost with its worker is then waited for on the wrong loop (a
            # RuntimeError, the item reported failed) instead of being computed again.
            for future in as_completed(futures, loop=client.loop):
                k = where[future.key]
                try:
                    done: Done[T, R] = Done(k, items[k], future.result())
                except KeyboardInterrupt:
                    raise
                except Exception as exc:  # the item failed, or lost too many workers
                    done = Done(k, items[k], None, _one_line(exc))
                on_done(done)
                finished += 1
        except KeyboardInterrupt:
            client.cancel([f for f in futures if not f.done()])
            raise
        return finished

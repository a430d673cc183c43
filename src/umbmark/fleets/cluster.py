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
  and see the files. A ``tls://`` scheduler is connected to with the security Dask's own
  configuration gives (``distributed.comm.tls.*``; :func:`_security`), its certificates
  checked and one handshake tried first (:mod:`umbmark.fleets.tls`), so that a cluster
  that does not let this client in says so, and why, in one line.
- A worker that dies mid-item has the item redone on another worker (the scheduler does
  this, up to :data:`ALLOWED_FAILURES` deaths per item); an item whose function raises is
  reported as failed with its one-line reason, and the others go on.
- A cluster left with no worker (all died or were stopped) is waited for
  :data:`NO_WORKERS_TIMEOUT` seconds (Dask's ``distributed.scheduler.no-workers-timeout``,
  where set), then the run stops with one line (an :class:`InputError`): what finished has
  already been handed to the caller; the scheduler alone would wait forever. A scheduler
  lost mid-run (its tasks cancelled) stops it at once, the same way, rather than report
  the items not done as failed; Dask's client, which logs a lost scheduler's tracebacks,
  is kept quiet.
- Ctrl-C (``KeyboardInterrupt``) cancels what has not finished and re-raises: what
  finished has already been handed to the caller. The local cluster's workers hear
  nothing of a terminal's Ctrl-C (sent to the whole process group): they start with
  SIGINT blocked and their engine logs quiet, and this process closes them.
"""

from __future__ import annotations

import logging
import os
import signal
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from umbmark.core.errors import InputError, option

__all__ = [
    "ALLOWED_FAILURES",
    "ENGINE_MISSING",
    "NO_WORKERS_TIMEOUT",
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
#: A scheduler's port where its address names none (Dask's).
DEFAULT_PORT = 8786
#: Seconds a run waits while the cluster has no worker and items are not done, before it
#: stops (Dask's ``distributed.scheduler.no-workers-timeout`` instead, where set): time for
#: a worker to be restarted, not forever.
NO_WORKERS_TIMEOUT = 60.0
#: Seconds between two looks at how many workers the cluster has, while a run waits.
LOOK_EVERY = 1.0
#: How often a finished item's result is asked for, its scheduler answering, before the
#: item counts as failed with why it could not be fetched.
FETCH_TRIES = 3
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


def _no_workers_timeout() -> float:
    """Seconds to wait for a worker: Dask's ``no-workers-timeout`` if set, else ours."""
    import dask
    from dask.utils import parse_timedelta

    value = dask.config.get("distributed.scheduler.no-workers-timeout", None)
    return NO_WORKERS_TIMEOUT if value is None else float(parse_timedelta(value, default="s"))


class _Watch:
    """The cluster watched from a thread of its own while a run waits for its tasks: once
    it has had no worker for :func:`_no_workers_timeout` seconds, the watch cancels the
    tasks not done, which ends the wait (Dask's own waits are never cut short by a timeout:
    one that is leaves Dask's inner waits behind, logging tracebacks at exit)."""

    def __init__(self, client: Any, address: str | None, futures: list[Any]) -> None:  # noqa: ANN401
        self.client, self.address, self.futures = client, address, futures
        self.left = len(futures)  # tasks not handed over yet
        self.patience = _no_workers_timeout()
        self.idle = False  # whether it cancelled the tasks, the cluster without a worker
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="umbmark-watch", daemon=True)

    def __enter__(self) -> _Watch:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _workers(self) -> int | None:
        """How many workers the scheduler has; None when it cannot say (not answering)."""
        try:
            return len(self.client.nthreads())
        except Exception:  # the scheduler lost: its futures come back cancelled
            return None

    def _run(self) -> None:
        since: float | None = None  # when the cluster was first seen with no worker
        while not self._stop.wait(LOOK_EVERY):
            now = time.monotonic()
            if self._workers() != 0:
                since = None
            elif since is None:
                since = now
            elif now - since >= self.patience:
                self.idle = True
                self.client.cancel([f for f in self.futures if not f.done()])
                return

    def stopped(self) -> InputError:
        """Why the run stopped, its tasks cancelled: the cluster without a worker, else its
        scheduler lost (or restarted)."""
        where = "the local Dask cluster" if self.address is None else "the Dask scheduler"
        total = len(self.futures)
        if self.idle:
            start = "" if self.address is None else f"; start workers: dask worker {self.address}"
            text = (
                f"{where} has had no worker for {self.patience:g} s, with {self.left} of "
                f"{total} tasks not done: stopped (what finished is kept{start})"
            )
        else:
            text = (
                f"{where} cancelled this run's tasks (lost, or restarted), with {self.left} of "
                f"{total} not done: stopped (what finished is kept)"
            )
        return InputError(text, source=self.address)


def _outcome(watch: _Watch, future: Any) -> tuple[Any, str | None]:  # noqa: ANN401
    """A finished future's result, or why its item failed (one line); an
    :class:`InputError` when the run's tasks were cancelled (the cluster without a worker,
    or its scheduler lost: the item is not at fault, and no other will finish)."""
    import asyncio

    tries = 0
    while True:
        try:
            # Its result lost with its worker before it was fetched: computed again, or
            # cancelled by the watch.
            return future.result(), None
        except KeyboardInterrupt:
            raise
        except (Exception, asyncio.CancelledError) as exc:
            if future.status == "error":  # the item raised, or lost too many workers
                return None, _one_line(exc)
            if future.cancelled() or watch.client.status != "running":
                raise watch.stopped() from None  # only the engine cancels what this run wants
            tries += 1  # finished, but its result not fetched
            if tries >= FETCH_TRIES:
                return None, _one_line(exc)
            time.sleep(LOOK_EVERY)


@contextmanager
def _quiet(name: str) -> Iterator[None]:
    """Logger ``name`` silent but for CRITICAL: the client logs a lost scheduler's
    tracebacks, which :func:`run_each` says in one line instead."""
    logger = logging.getLogger(name)
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logger.setLevel(level)


def _security(address: str, timeout: float, notes: list[str] | None) -> Any:  # noqa: ANN401
    """The security Dask's own configuration gives a client of ``address``, as Dask's
    client takes it (``distributed.client.security-loader``'s, where set, else a
    ``Security`` of the ``distributed.comm.tls.*`` keys), checked before connecting.

    A ``tls://`` address: its files checked and one TLS handshake tried
    (:mod:`umbmark.fleets.tls`); a ``tcp://`` one where Dask's configuration requires
    encryption is refused, and one while it gives a client certificate warns (in
    ``notes``): the connection would not be encrypted.

    Raises
    ------
    InputError
        In one line: no certificate set for ``tls://``, a file that cannot be read or
        used, the scheduler's or this client's certificate refused, a scheduler that does
        not speak TLS, encryption required on ``tcp://``, a bad setting.
    """
    import dask
    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.security import Security
    from distributed.utils import import_term

    from umbmark.fleets import tls

    try:
        loader = dask.config.get("distributed.client.security-loader", None)
        security = import_term(loader)({"address": address}) if loader else None
        security = security or Security()
        scheme, location = parse_address(address)
    except Exception as exc:  # a bad setting (tls.min-version), a loader that fails
        raise InputError(
            f"Dask's security settings cannot be used ({_one_line(exc)})", source=address
        ) from None
    if scheme != "tls":
        if scheme == "tcp" and security.require_encryption:
            raise InputError(
                f"Dask's configuration requires encryption ({tls.REQUIRE_ENCRYPTION}), and "
                "tcp:// is not encrypted: give the scheduler's tls:// address",
                source=address,
            )
        if scheme == "tcp" and security.tls_client_cert and notes is not None:
            notes.append(tls.unencrypted(address, _pem_or_path(security.tls_client_cert)))
        return security
    files = {
        tls.CA_FILE: security.tls_ca_file,
        tls.CLIENT_CERT: security.tls_client_cert,
        tls.CLIENT_KEY: security.tls_client_key,
    }
    tls.check_files(address, files)
    shown = {key: None if value is None else _pem_or_path(value) for key, value in files.items()}
    try:
        context = security.get_connection_args("client")["ssl_context"]
        host, port = parse_host_port(location, DEFAULT_PORT)
    except (OSError, ValueError) as exc:  # ssl.SSLError is an OSError
        raise tls.unusable(address, shown, exc) from None
    tls.handshake(address, host, int(port), context, shown, timeout)
    return security


def _pem_or_path(value: str) -> str:
    """A TLS setting as it is named: its path, or ``(PEM text)`` where it is the text."""
    return "(PEM text)" if "\n" in value else value


def _unanswered(address: str, exc: BaseException) -> InputError:
    """No scheduler answers at ``address``; a ``tcp://`` connection reset is said as what
    it likely is, a scheduler that takes TLS."""
    seen: BaseException | None = exc
    for _ in range(8):  # the exception's causes
        if seen is None:
            break
        if address.startswith("tcp://") and (
            isinstance(seen, ConnectionResetError) or "ConnectionResetError" in str(seen)
        ):
            return InputError(
                f"the Dask scheduler at {address} reset the connection, as one that takes TLS "
                "does: give its tls:// address, with Dask's TLS settings (docs/fleet.md)",
                source=address,
            )
        seen = seen.__cause__ or seen.__context__
    return InputError(f"no Dask scheduler answers at {address} ({_one_line(exc)})", source=address)


def _local_security() -> Any:  # noqa: ANN401
    """The local cluster's security: Dask's configuration, but never requiring encryption
    (``distributed.comm.require-encryption`` is for connections off this machine; the
    local cluster's scheduler and workers listen on 127.0.0.1 only)."""
    from distributed.security import Security

    return Security(require_encryption=False)


@contextmanager
def _client(
    address: str | None, workers: int | None, timeout: float, notes: list[str] | None = None
) -> Iterator[Any]:
    try:
        import dask
        from distributed import Client
    except ImportError:
        raise InputError(ENGINE_MISSING) from None
    settings = {
        "distributed.scheduler.allowed-failures": ALLOWED_FAILURES,
        "distributed.worker.daemon": False,  # a worker's own pool may start processes
        "distributed.admin.system-monitor.gil.enabled": False,
    }
    with dask.config.set(settings), _quiet("distributed.client"):
        if address is not None:
            security = _security(address, timeout, notes)
            try:
                client = Client(address, timeout=timeout, security=security)
            except (OSError, TimeoutError) as exc:
                raise _unanswered(address, exc) from None
            try:
                yield client
            finally:
                client.close()
            return
        n = workers if workers is not None else min(os.cpu_count() or 1, MAX_LOCAL_WORKERS)
        if not 1 <= n <= MAX_LOCAL_WORKERS:
            raise InputError(f"{option('workers', n)} must be 1 to {MAX_LOCAL_WORKERS}")
        with _local_client(n) as client:
            yield client


#: The engine's loggers a local worker keeps quiet (but for CRITICAL).
WORKER_LOGGERS = ("distributed", "tornado")


def dask_setup(worker: Any) -> None:  # noqa: ANN401 (Dask's hook: its Worker)
    """Run by Dask in each worker process of the local cluster as it starts (this module
    is the workers' preload; also when a worker is restarted): the engine's loggers kept
    quiet but for CRITICAL. A worker closed while it calibrates (after a Ctrl-C) can log a
    heartbeat cut short, with its traceback, on this process's stderr; what the run needs
    to say, a failed item's reason, comes back with the item."""
    for name in WORKER_LOGGERS:
        logging.getLogger(name).setLevel(logging.CRITICAL)


@contextmanager
def _deaf_to_ctrl_c() -> Iterator[None]:
    """SIGINT blocked in this thread for the block: the threads started meanwhile (the local
    cluster's event loop and those that start its worker processes, now and when a worker
    is restarted) and the worker processes inherit the mask. A terminal's Ctrl-C goes to
    the whole process group: so it reaches this process alone, which stops the cluster,
    and not the workers, which each printed a traceback of their own.

    Python's resource tracker, started first (the first process started would start it),
    unblocks SIGINT in the thread that starts it; once it runs, it is left alone. A
    SIGINT that came meanwhile is raised as the block ends."""
    if not hasattr(signal, "pthread_sigmask"):  # not POSIX: no process groups to share it
        yield
        return
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


@contextmanager
def _local_client(n: int) -> Iterator[Any]:
    """A client of a local cluster of ``n`` worker processes (one thread each), its
    scratch space a temporary folder; all of it closed and removed after, also after a
    Ctrl-C while it starts."""
    from distributed import Client, LocalCluster

    with tempfile.TemporaryDirectory(prefix="umbmark-dask-") as scratch, ExitStack() as stack:
        with _deaf_to_ctrl_c():
            cluster = LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                # Its HTTP server on a free port: Dask's default, 8787, is taken by any
                # other cluster on this machine (another fleet run), and then it warns.
                dashboard_address=":0",
                silence_logs=logging.ERROR,
                local_directory=scratch,  # the workers' scratch space, removed after
                preload=[__name__],  # dask_setup: each worker's engine logs quiet
                security=_local_security(),
            )
            stack.callback(cluster.close)
            client = Client(cluster)
            stack.callback(client.close)
        yield client


def run_each(
    fn: Callable[[T], R],
    items: Sequence[T],
    on_done: Callable[[Done[T, R]], None],
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    connect_timeout: float = CONNECT_TIMEOUT,
    notes: list[str] | None = None,
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
    notes : list of str, optional
        Warnings are appended to it (a ``tcp://`` scheduler while Dask's configuration
        gives TLS certificates).

    Returns
    -------
    int
        How many items finished (all of them, unless interrupted).

    Raises
    ------
    InputError
        Dask is not installed, or no scheduler answers at the address, or a ``tls://``
        scheduler and this client do not take each other's certificates (or none is
        configured: :func:`_security`), or the cluster has
        had no worker for :data:`NO_WORKERS_TIMEOUT` seconds, or its scheduler was lost
        (after cancelling what had not finished).
    KeyboardInterrupt
        After cancelling what had not finished.
    """
    if not items:
        return 0
    address = engine_address(scheduler)
    with _client(address, workers, connect_timeout, notes) as client:
        from distributed import as_completed

        futures = client.map(fn, list(items), pure=False)
        where = {future.key: k for k, future in enumerate(futures)}
        finished = 0
        with _Watch(client, address, futures) as watch:
            try:
                # On this client's own event loop: by default as_completed takes the
                # current client's, which is the caller's where it runs inside ``with
                # Client(...)``, and a result lost with its worker is then waited for on
                # the wrong loop (a RuntimeError, the item reported failed) instead of
                # being computed again.
                for future in as_completed(futures, loop=client.loop):
                    k = where[future.key]
                    result, error = _outcome(watch, future)
                    on_done(Done(k, items[k], result, error))
                    finished += 1
                    watch.left -= 1
            except (KeyboardInterrupt, InputError):
                client.cancel([f for f in futures if not f.done()])
                raise
        return finished

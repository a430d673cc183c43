"""A Dask scheduler and workers started as separate processes with Dask's own command-line
programs (``dask scheduler``, ``dask worker``) on a free port of this machine, for the
fleet's tests; ended by their PIDs."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
DASK = Path(sys.executable).with_name("dask")
#: Dask's environment variables of a client's TLS files, by the file they name.
CLIENT_TLS = {
    "DASK_DISTRIBUTED__COMM__TLS__CA_FILE": "ca.pem",
    "DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT": "client.pem",
    "DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY": "client.key",
}


def make_certificates(folder: Path) -> Path:
    """A cluster's CA and the scheduler's, a worker's and a client's keys and certificates
    it signed, made in ``folder`` by the commands of docs/fleet.md's block that makes them
    (its ``openssl`` commands, run one by one as written); returns ``folder``."""
    from test_readme import blocks, commands

    page = (ROOT / "docs" / "fleet.md").read_text(encoding="utf-8")
    (block,) = [b for b in blocks(page) if b.lang == "bash" and "openssl req -x509" in b.body]
    folder.mkdir(parents=True, exist_ok=True)
    for command in commands(block.body):
        subprocess.run(["bash", "-c", command], cwd=folder, check=True, capture_output=True,
                       timeout=120)  # fmt: skip
    return folder


def client_environment(certificates: Path, **files: str) -> dict[str, str]:
    """This environment with Dask's TLS settings of a client of ``certificates`` (their
    ``ca.pem``, ``client.pem``, ``client.key``; ``files`` overrides a variable's path)."""
    tls = {name: str(certificates / file) for name, file in CLIENT_TLS.items()}
    return {**os.environ, **tls, **files}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _env() -> dict[str, str]:
    path = os.pathsep.join([str(TESTS), str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path}


class Cluster:
    """``dask scheduler`` and ``dask worker`` processes on localhost, ended by PID."""

    def __init__(self, tmp: Path, workers: int, tls: Path | None = None) -> None:
        """``tls``: a folder of :func:`make_certificates`: the scheduler and the workers
        over TLS with its certificates (the address ``tls://``)."""
        self.logs = tmp
        self.tls = tls
        self.files: list = []  # type: ignore[type-arg]
        self.workers: list[subprocess.Popen[bytes]] = []
        try:
            for _ in range(3):  # a free port can be taken before the scheduler binds it
                self.port = free_port()
                self.address = f"{'tcp' if tls is None else 'tls'}://127.0.0.1:{self.port}"
                self.scheduler = self._start(
                    "scheduler", "--host", "127.0.0.1", "--port", str(self.port),
                    "--dashboard-address", ":0", "--no-show", *self._tls("scheduler"),
                )  # fmt: skip
                if self._wait_for_port():
                    break
            else:
                raise AssertionError("the scheduler did not start (its port taken, 3 times)")
            self.add_workers(workers)
        except BaseException:
            self.close()
            raise

    def add_workers(self, n: int) -> None:
        """Start ``n`` more workers (one process and one thread each) and wait until the
        scheduler has them all."""
        first = len(self.workers)
        self.workers += [
            self._start("worker", self.address, "--nworkers", "1", "--nthreads", "1",
                        "--no-nanny", "--dashboard-address", ":0", "--name", f"w{k}",
                        "--local-directory", str(self.logs), *self._tls("worker"))
            for k in range(first, first + n)
        ]  # fmt: skip
        self._wait_for_workers(sum(proc.poll() is None for proc in self.workers))

    def _tls(self, role: str) -> list[str]:
        """The command-line options of a scheduler's or a worker's TLS (docs/fleet.md's)."""
        if self.tls is None:
            return []
        options = ["--protocol", "tls"] if role == "scheduler" else []
        return [*options, "--tls-ca-file", str(self.tls / "ca.pem"),
                "--tls-cert", str(self.tls / f"{role}.pem"),
                "--tls-key", str(self.tls / f"{role}.key")]  # fmt: skip

    def kill(self, pid: int) -> int:
        """SIGKILL one of its processes, a worker or the scheduler, by its PID (no goodbye),
        wait until it is dead; returns its exit status (``-SIGKILL``)."""
        (proc,) = [p for p in [*self.workers, self.scheduler] if p.pid == pid]
        os.kill(pid, signal.SIGKILL)
        return proc.wait(timeout=30)

    def kill_all(self, pids: list[int]) -> list[int]:
        """SIGKILL several of its processes at once (every signal sent before any is
        waited for: none has the time to finish what it does while another dies), wait
        until all are dead; their exit statuses, in order."""
        procs = [p for pid in pids for p in [*self.workers, self.scheduler] if p.pid == pid]
        assert len(procs) == len(pids), pids
        for pid in pids:
            os.kill(pid, signal.SIGKILL)
        return [proc.wait(timeout=30) for proc in procs]

    def _start(self, *args: str) -> subprocess.Popen[bytes]:
        log = open(self.logs / f"{args[0]}-{time.monotonic_ns()}.log", "wb")  # noqa: SIM115
        self.files.append(log)
        return subprocess.Popen([str(DASK), *args], env=_env(), stdout=log, stderr=log)

    def _wait_for_port(self) -> bool:
        """Whether the scheduler listens on its port; False when it ended (the port was
        taken)."""
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if self.scheduler.poll() is not None:
                return False
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", self.port)) == 0:
                    return self.scheduler.poll() is None
            time.sleep(0.1)
        raise AssertionError("the scheduler did not start")

    def _wait_for_workers(self, n: int) -> None:
        from distributed import Client
        from distributed.security import Security

        security = None
        if self.tls is not None:
            security = Security(
                tls_ca_file=str(self.tls / "ca.pem"), require_encryption=True,
                tls_client_cert=str(self.tls / "client.pem"),
                tls_client_key=str(self.tls / "client.key"),
            )  # fmt: skip
        with Client(self.address, timeout=60, security=security) as client:
            client.wait_for_workers(n, timeout=60)

    def close(self) -> None:
        """End the workers, then the scheduler (a worker told to stop while its scheduler
        goes away can hang in its own closing, here until it is killed 30 s later)."""
        scheduler = getattr(self, "scheduler", None)  # none yet: it failed to start
        for group in (self.workers, [scheduler] if scheduler is not None else []):
            for proc in group:
                if proc.poll() is None:
                    proc.send_signal(signal.SIGTERM)
            for proc in group:
                try:
                    proc.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        for log in self.files:
            log.close()


@pytest.fixture
def cluster(tmp_path: Path) -> Iterator[Cluster]:
    made = Cluster(tmp_path, workers=2)
    try:
        yield made
    finally:
        made.close()

"""``umbmark fleet --scheduler tls://...``: an existing Dask cluster over TLS, a scheduler
and workers started as processes with certificates made by the openssl commands
docs/fleet.md gives (run as written), and this client pointed at its own with Dask's own
settings (the ``DASK_DISTRIBUTED__COMM__TLS__*`` environment variables, or
``dask.config``).

What is checked: the whole fleet job over TLS gives the local run's figures; the cluster
lets no one in without a certificate its CA signed (a client without one is refused by the
scheduler itself), and every way of not being let in is one line, exit status 2, naming
the setting and the file: no certificate set, a file that cannot be read, a key that is not
the certificate's, a client certificate another CA signed (refused by the scheduler), a
scheduler whose certificate this client's CA did not sign, ``tls://`` to a plain
scheduler and ``tcp://`` to a TLS one; a ``tcp://`` scheduler while certificates are set
is a warning, and refused where Dask's configuration requires encryption; the local
cluster runs whatever the TLS settings say.
"""

from __future__ import annotations

import json
import os
import socket
import ssl
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

import dask

import umbmark
from umbmark.core.errors import InputError
from umbmark.fleets.cluster import run_each

from dask_cluster import Cluster, client_environment, free_port, make_certificates
from helpers import run_cli

PATTERN = "{robot}/{date}/*"
#: A client's TLS settings, by Dask's configuration keys, and the file of each.
CLIENT_FILES = {
    "distributed.comm.tls.ca-file": "ca.pem",
    "distributed.comm.tls.client.cert": "client.pem",
    "distributed.comm.tls.client.key": "client.key",
}


@pytest.fixture(scope="module")
def certificates(tmp_path_factory) -> Path:
    return make_certificates(tmp_path_factory.mktemp("tls") / "ours")


@pytest.fixture(scope="module")
def strangers(tmp_path_factory) -> Path:
    """Another CA's certificates, made by the same commands."""
    return make_certificates(tmp_path_factory.mktemp("tls") / "theirs")


@pytest.fixture(scope="module")
def secure(certificates: Path, tmp_path_factory) -> Iterator[Cluster]:
    made = Cluster(tmp_path_factory.mktemp("secure"), workers=2, tls=certificates)
    try:
        yield made
    finally:
        made.close()


def _settings(folder: Path, **files: str) -> dict[str, str]:
    """Dask's configuration of a client's TLS files in ``folder`` (``files``: a file in
    place of one, by its key's last part: ``cert``, ``key``, ``ca_file``)."""
    out = {key: str(folder / name) for key, name in CLIENT_FILES.items()}
    for part, path in files.items():
        (key,) = [k for k in out if k.endswith(part.replace("_", "-"))]
        out[key] = path
    return out


def _refused(address: str, settings: dict[str, object]) -> str:
    """What ``run_each`` on ``address`` says with these Dask settings (it must refuse)."""
    with dask.config.set(settings), pytest.raises(InputError) as raised:
        run_each(abs, [1], lambda d: None, scheduler=address, connect_timeout=20.0)
    text = str(raised.value)
    assert len(text.splitlines()) == 1
    return text


def test_a_tls_address_without_certificates_or_with_bad_files_is_one_line(
    certificates: Path, tmp_path: Path
):
    """Refused before any connection (nothing listens at the address)."""
    address = f"tls://127.0.0.1:{free_port()}"
    start = time.monotonic()
    said = _refused(address, {})
    assert said == (
        f"{address}: the scheduler takes TLS, and Dask's configuration gives this client no "
        "certificate (distributed.comm.tls.ca-file and distributed.comm.tls.client.cert not "
        "set): set distributed.comm.tls.ca-file, distributed.comm.tls.client.cert, "
        "distributed.comm.tls.client.key in a Dask configuration file or as "
        "DASK_DISTRIBUTED__COMM__TLS__CA_FILE, DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT, "
        "DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY (docs/fleet.md)"
    )
    only_ca = {"distributed.comm.tls.ca-file": str(certificates / "ca.pem")}
    assert "(distributed.comm.tls.client.cert not set)" in _refused(address, only_ca)
    gone = str(tmp_path / "gone.pem")
    assert _refused(address, _settings(certificates, cert=gone)) == (
        f"{address}: {gone} (distributed.comm.tls.client.cert) cannot be read: "
        "No such file or directory"
    )
    # The worker's key with the client's certificate: OpenSSL's own words.
    wrong_key = _settings(certificates, key=str(certificates / "worker.key"))
    assert "cannot be used (key values mismatch)" in _refused(address, wrong_key)
    not_pem = _settings(certificates, ca_file=str(certificates / "client.csr"))
    assert "cannot be used (" in _refused(address, not_pem)
    bad = {**_settings(certificates), "distributed.comm.tls.min-version": 1.1}
    assert "Dask's security settings cannot be used (ValueError: " in _refused(address, bad)
    # Encryption required: a tcp:// address is refused rather than tried.
    plain = f"tcp://127.0.0.1:{free_port()}"
    assert _refused(plain, {"distributed.comm.require-encryption": True}) == (
        f"{plain}: Dask's configuration requires encryption "
        "(distributed.comm.require-encryption), and tcp:// is not encrypted: give the "
        "scheduler's tls:// address"
    )
    assert time.monotonic() - start < 10  # not a connection waited for


@pytest.mark.slow
def test_the_command_without_certificates_is_one_line_and_exit_2(tmp_path: Path):
    """Before any recording is read (the one found here is not even a bag inside)."""
    address = f"tls://127.0.0.1:{free_port()}"
    env = {k: v for k, v in os.environ.items() if not k.startswith("DASK_DISTRIBUTED__COMM")}
    (tmp_path / "amr1" / "2026-11-02").mkdir(parents=True)
    (tmp_path / "amr1" / "2026-11-02" / "drive.bag").write_bytes(b"#ROSBAG V2.0\n")
    proc = run_cli("fleet", str(tmp_path), "--scheduler", address, "--history",
                   str(tmp_path / "h.sqlite3"), env=env)  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith(f"umbmark: error: {address}: the scheduler takes TLS, and Dask's ")


@pytest.mark.slow
def test_the_cluster_lets_in_only_clients_its_ca_signed(
    secure: Cluster, certificates: Path, strangers: Path
):
    # The scheduler itself: a TLS client that trusts the cluster's CA but shows no
    # certificate of its own is refused (TLS 1.3: after the handshake, at the first read).
    context = ssl.create_default_context(cafile=str(certificates / "ca.pem"))
    context.check_hostname = False
    with (
        socket.create_connection(("127.0.0.1", secure.port), timeout=10) as raw,
        context.wrap_socket(raw) as conn,
    ):
        conn.settimeout(10)
        with pytest.raises(ssl.SSLError, match="CERTIFICATE"):
            conn.recv(1)
    address = secure.address
    # A client certificate another CA signed: the scheduler refuses it. (Made by the same
    # commands, the other CA bears the cluster's CA's name: each side takes it for the CA
    # it trusts and finds the signature wrong, where a CA of another name is unknown.)
    theirs = _settings(strangers, ca_file=str(certificates / "ca.pem"))
    assert _refused(address, theirs) == (
        f"{address}: the scheduler refused this client's certificate (tlsv1 alert decrypt "
        f"error; distributed.comm.tls.client.cert: {strangers / 'client.pem'}): it takes "
        "certificates signed by the CA it was started with (its --tls-ca-file)"
    )
    # This client trusting another CA: the scheduler's certificate is refused here.
    assert _refused(address, _settings(strangers)) == (
        f"{address}: the scheduler's certificate is not signed by the CA this client trusts "
        f"(distributed.comm.tls.ca-file: {strangers / 'ca.pem'}): certificate signature failure"
    )
    # tcp:// to the TLS scheduler: it resets the connection, which is said as what it is.
    tcp = address.replace("tls://", "tcp://")
    assert _refused(tcp, _settings(certificates)) == (
        f"{tcp}: the Dask scheduler at {tcp} reset the connection, as one that takes TLS "
        "does: give its tls:// address, with Dask's TLS settings (docs/fleet.md)"
    )
    # With its own certificates the same client is let in.
    done: list[object] = []
    with dask.config.set(_settings(certificates)):
        assert run_each(abs, [-1, 2, -3], done.append, scheduler=address) == 3
    assert sorted(d.result for d in done) == [1, 2, 3]  # type: ignore[attr-defined]


@pytest.fixture(scope="module")
def recordings(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("fleet") / "fleet"
    umbmark.simulate_fleet(folder, fleet=2, days=2, minutes=0.5, seed=3)
    return folder


def _fleet(recordings: Path, history: Path, *extra: str, env: dict[str, str] | None = None):  # type: ignore[no-untyped-def]
    return run_cli("fleet", str(recordings), "--robot-from", PATTERN, "--history",
                   str(history), "--json", *extra, env=env, timeout=600)  # fmt: skip


def _figures(data: dict) -> dict:  # type: ignore[type-arg]
    return {
        r["robot"]: {
            n: (f["value"], f["standard_error"], f["change"]) for n, f in r["figures"].items()
        }
        for r in data["robots"]
    }


@pytest.mark.slow
def test_the_fleet_job_over_tls_gives_the_local_figures(
    secure: Cluster, certificates: Path, strangers: Path, recordings: Path, tmp_path: Path
):
    local = _fleet(recordings, tmp_path / "local.sqlite3", "--workers", "1")
    assert local.returncode == 0, local.stderr
    env = client_environment(certificates)
    over_tls = _fleet(recordings, tmp_path / "tls.sqlite3", "--scheduler", secure.address,
                      env=env)  # fmt: skip
    assert over_tls.returncode == 0, over_tls.stderr
    ours, theirs = json.loads(local.stdout), json.loads(over_tls.stdout)
    assert theirs["recordings_done"] == 4
    assert (theirs["failed"], theirs["warnings"]) == ([], [])
    assert _figures(theirs) == _figures(ours)
    assert "warning" not in over_tls.stderr
    # A client with another CA's certificate: the scheduler refuses it, one line, exit 2.
    refused = _fleet(recordings, tmp_path / "refused.sqlite3", "--scheduler", secure.address,
                     env=client_environment(strangers, DASK_DISTRIBUTED__COMM__TLS__CA_FILE=str(
                         certificates / "ca.pem")))  # fmt: skip
    assert refused.returncode == 2
    (line,) = refused.stderr.strip().splitlines()
    assert line.startswith(
        f"umbmark: error: {secure.address}: the scheduler refused this client's certificate"
    )


@pytest.mark.slow
def test_tcp_while_certificates_are_set_warns_and_tls_to_a_plain_scheduler_is_refused(
    certificates: Path, recordings: Path, tmp_path: Path
):
    plain = Cluster(tmp_path, workers=1)
    try:
        env = client_environment(certificates)
        proc = _fleet(recordings, tmp_path / "h.sqlite3", "--scheduler", plain.address, env=env)
        tls = plain.address.replace("tcp://", "tls://")
        with dask.config.set(_settings(certificates)):
            said = _refused(tls, {})
    finally:
        plain.close()
    assert proc.returncode == 0, proc.stderr
    warning = (
        "Dask's configuration gives this client a TLS certificate "
        f"(distributed.comm.tls.client.cert: {certificates / 'client.pem'}), but the "
        f"scheduler's address {plain.address} is tcp://: the connection is not encrypted"
    )
    assert json.loads(proc.stdout)["warnings"][0].startswith(warning)
    assert f"umbmark: warning: {warning}" in proc.stderr
    assert said == (
        f"{tls}: the scheduler answers, but not with TLS (wrong version number): is it a "
        "tcp:// scheduler?"
    )


@pytest.mark.slow
def test_the_local_cluster_runs_whatever_the_tls_settings_say(certificates: Path):
    settings = {**_settings(certificates), "distributed.comm.require-encryption": True}
    done: list[object] = []
    with dask.config.set(settings):
        assert run_each(abs, [-4, 5], done.append, workers=1) == 2
    assert sorted(d.result for d in done) == [4, 5]  # type: ignore[attr-defined]

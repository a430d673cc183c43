"""``umbmark fleet`` on recordings at URLs: a simulated fleet (ROS 2 bag folders of two
robots over two days) served by ``python -m http.server`` started as a process, and the
same folder as ``file://``, give the figures the local run gives; the nightly run skips
every recording (known by the server's size and Last-Modified); a URL that 404s is a failed
recording with one line while the others go on; the workers' temporary copies are gone; the
command exits 0, and 2 with one line for a URL that matches nothing or when fsspec is
missing; an existing cluster's workers stream the recordings themselves; a fleet behind a
password in its URL is read with it and the password is in no line, history, page or
JSON; recordings at signed URLs are known again when signed again."""

from __future__ import annotations

import json
import os
import re
import sqlite3
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")
pytest.importorskip("fsspec", reason="the remote extra: pip install '.[remote]'")
pytest.importorskip("aiohttp", reason="the remote extra: pip install '.[remote]'")

import umbmark

from dask_cluster import Cluster
from helpers import ROOT, run_cli
from http_served import WITHOUT_FSSPEC, Guarded, Served

PATTERN = "{robot}/{date}/*"


@pytest.fixture(scope="module")
def fleet(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("remote") / "fleet"
    umbmark.simulate_fleet(folder, fleet=2, days=2, minutes=0.5, seed=3)
    return folder


@pytest.fixture(scope="module")
def served(fleet: Path, tmp_path_factory) -> Iterator[str]:
    """The fleet's parent folder over HTTP; the fleet is at ``URL/fleet/``."""
    with Served(fleet.parent, tmp_path_factory.mktemp("log") / "http.log") as server:
        yield server.url


@pytest.fixture(scope="module")
def local(fleet: Path, tmp_path_factory) -> umbmark.FleetReport:
    history = tmp_path_factory.mktemp("local") / "h.sqlite3"
    return umbmark.fleet(fleet, robot_from=PATTERN, history=history, workers=2)


def _by_recording(report: umbmark.FleetReport, prefix: str) -> dict:  # type: ignore[type-arg]
    """Each outcome as a dict, by its path below ``prefix``, without the path."""
    out = {}
    for o in report.done:
        data = o.to_dict()
        rel = data.pop("path").removeprefix(prefix).strip("/")
        if data["reason"]:
            data["reason"] = data["reason"].replace(prefix.rstrip("/"), "FLEET")
        if data["record"].get("overlay"):  # its provenance: the recording, when written
            said = data["record"]["overlay"].replace(prefix.rstrip("/"), "FLEET")
            data["record"]["overlay"] = re.sub(r" on \S+Z from ", " on TIME from ", said)
        out[rel] = data
    return out


def _every_figure(data: dict, prefix: str) -> dict:  # type: ignore[type-arg]
    """Each robot's figures as the JSON gives them (``data``: ``fleet --json``'s, or a
    report's ``to_dict()``), its recordings' paths below ``prefix``."""

    def below(path: str | None) -> str | None:
        return None if path is None else path.removeprefix(prefix).strip("/")

    out = {}
    for r in data["robots"]:
        if not r["usable"]:
            continue
        figures = {}
        for name, given in r["figures"].items():
            f = {**given, "since": below(given.get("since"))}
            if "paths" in f:
                f["paths"] = [below(p) for p in f["paths"]]
            figures[name] = f
        out[r["robot"]] = figures
    return out


def _figures(report: umbmark.FleetReport) -> dict:  # type: ignore[type-arg]
    return {
        r["robot"]: {n: (f["value"], f["change"]) for n, f in r["figures"].items()}
        for r in report.to_dict()["robots"]
    }


@pytest.mark.slow
def test_a_served_fleet_gives_the_local_figures_and_is_done_once(
    fleet: Path, served: str, local: umbmark.FleetReport, tmp_path: Path, monkeypatch
):
    scratch = tmp_path / "scratch"  # the workers' temporary folder
    scratch.mkdir()
    monkeypatch.setenv("TMPDIR", str(scratch))
    history = tmp_path / "h.sqlite3"
    url, gone = f"{served}/fleet/", f"{served}/fleet/robot09/2026-11-02/gone.mcap"
    copies: set[str] = set()
    done = threading.Event()

    def watch() -> None:  # the copies the workers make while they calibrate
        while not done.is_set():
            copies.update(p.name for p in scratch.glob("umbmark-remote-*"))
            time.sleep(0.01)

    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        remote = umbmark.fleet(url, gone, robot_from=PATTERN, history=history, workers=2)
    finally:
        done.set()
        watcher.join()
    assert len(copies) == 4  # one for each recording read, in the workers' TMPDIR
    assert (local.found, len(local.done)) == (4, 4)
    assert (remote.found, len(remote.done), remote.skipped) == (5, 5, 0)
    by_url = _by_recording(remote, url)
    failed = by_url.pop("robot09/2026-11-02/gone.mcap")
    # Every recording as the local run had it: robot, day, digest, figures, reason.
    assert by_url == _by_recording(local, str(fleet))
    assert all(len(o.digest or "") == 64 for o in remote.done if not o.failed)
    assert (failed["status"], failed["robot"]) == ("failed", "robot09")
    assert [(o.path, o.reason) for o in remote.failed] == [
        (gone, f"{gone}: cannot be read (HTTP 404 File not found)")
    ]
    assert _figures(remote) == {**_figures(local), "robot09": {}}
    assert list(scratch.glob("umbmark-remote-*")) == []  # each deleted after
    # The nightly run: every recording known by its URL, size and Last-Modified; the
    # failed one tried again.
    again = umbmark.fleet(url, gone, robot_from=PATTERN, history=history, workers=1)
    assert (again.skipped, [o.path for o in again.done]) == (4, [gone])
    # A recording changed on the server (its time) is done again, alone.
    changed = next(fleet.glob("robot01/2026-11-02/drive/metadata.yaml"))
    stat = changed.stat()
    os.utime(changed, (stat.st_atime, stat.st_mtime + 60))
    third = umbmark.fleet(url, robot_from=PATTERN, history=history, workers=1)
    assert [o.path for o in third.done] == [f"{url}robot01/2026-11-02/drive/"]


@pytest.mark.slow
def test_file_urls_give_the_local_figures(fleet: Path, local: umbmark.FleetReport, tmp_path: Path):
    url = f"file://{fleet}"
    remote = umbmark.fleet(url, robot_from=PATTERN, history=tmp_path / "h.sqlite3", workers=1)
    assert _by_recording(remote, url) == _by_recording(local, str(fleet))
    again = umbmark.fleet(url, robot_from=PATTERN, history=tmp_path / "h.sqlite3", workers=1)
    assert (again.skipped, again.done) == (4, ())


@pytest.mark.slow
def test_the_command_reads_a_url_and_refuses_one_that_matches_nothing(
    fleet: Path, served: str, local: umbmark.FleetReport, tmp_path: Path
):
    history = str(tmp_path / "h.sqlite3")
    proc = run_cli("fleet", f"{served}/fleet/", "--robot-from", PATTERN, "--history", history,
                   "--workers", "1", "--json", timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert (data["recordings_done"], data["failed"]) == (4, [])
    assert _every_figure(data, f"{served}/fleet/") == _every_figure(local.to_dict(), str(fleet))
    nothing = f"{served}/fleet/*/1999-*"
    refused = run_cli("fleet", nothing, "--history", history, "--workers", "1")
    assert refused.returncode == 2
    assert refused.stderr.strip().splitlines() == [
        f"umbmark: error: {nothing}: matches no file or folder"
    ]


def test_without_fsspec_a_url_is_one_line_and_exit_2(tmp_path: Path):
    """fsspec made unimportable (an import hook that finds it nowhere): the command says
    what to install, exit status 2."""
    code = (
        WITHOUT_FSSPEC
        + "sys.argv = ['umbmark', 'fleet', 'https://example.invalid/fleet/', '--history', "
        f"{str(tmp_path / 'h.sqlite3')!r}]\n"
        "from umbmark._entry import main\n"
        "main()\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=False, timeout=120)  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith("umbmark: error: https://example.invalid/fleet/: a URL is read")
    assert "pip install" in line


@pytest.mark.slow
def test_an_existing_clusters_workers_stream_the_recordings(
    fleet: Path, served: str, local: umbmark.FleetReport, tmp_path: Path
):
    cluster = Cluster(tmp_path, workers=2)
    try:
        history = tmp_path / "h.sqlite3"
        remote = umbmark.fleet(
            f"{served}/fleet/", robot_from=PATTERN, history=history, scheduler=cluster.address
        )
    finally:
        cluster.close()
    assert _by_recording(remote, f"{served}/fleet/") == _by_recording(local, str(fleet))


@pytest.mark.slow
def test_real_sessions_over_http_give_their_local_figures(tmp_path: Path):
    """The OptiOdom sessions umbmark ships (real runs, motion capture), served over HTTP,
    are found as the folders they are, copied and fitted as the local ones are."""
    from helpers import BUNDLED_OPTIODOM

    local = umbmark.fleet(BUNDLED_OPTIODOM, history=tmp_path / "l.sqlite3", workers=1)
    with Served(BUNDLED_OPTIODOM, tmp_path / "http.log") as server:
        remote = umbmark.fleet(server.url + "/", history=tmp_path / "r.sqlite3", workers=1)
    assert len(local.done) == 2
    assert _by_recording(remote, server.url) == _by_recording(local, str(BUNDLED_OPTIODOM))


@pytest.mark.slow
def test_a_fleet_behind_a_password_is_read_and_the_password_is_shown_nowhere(
    fleet: Path, local: umbmark.FleetReport, tmp_path: Path
):
    """The fleet behind HTTP basic authentication, its URL holding the user and password:
    read with them (the local figures), and neither in any line printed, the history (its
    rows and its file's bytes), the page or the JSON: the URL is shown as
    ``http://***@host/...``, and known again by that on the next run."""
    user, password, wrong = "fleet-reader", "Pa55-w0rd-xyzzy", "not-it-qwerty"
    history, page, out = tmp_path / "h.sqlite3", tmp_path / "fleet.html", tmp_path / "fleet.json"
    gone, refused = "/fleet/robot09/2026-11-02/gone.mcap", "/fleet/robot08/2026-11-02/x.mcap"
    with Guarded(fleet.parent, tmp_path / "http.log", user, password) as server:
        host = server.url.removeprefix("http://")
        given, shown = f"http://{user}:{password}@{host}", f"http://***@{host}"
        sources = [f"{given}/fleet/", f"{given}{gone}", f"http://{user}:{wrong}@{host}{refused}"]
        options = ["--robot-from", PATTERN, "--history", str(history)]
        first = run_cli("fleet", *sources, *options, "--workers", "2", "--report", str(page),
                        "-o", str(out), "--json", timeout=600)  # fmt: skip
        again = run_cli("fleet", *sources, *options, "--workers", "1", timeout=600)
    listed = run_cli("history", "robot01", "--history", str(history))
    assert first.returncode == 0, first.stderr
    data = json.loads(first.stdout)
    assert _every_figure(data, f"{shown}/fleet/") == _every_figure(local.to_dict(), str(fleet))
    failed = {
        f"{shown}{gone}": f"{shown}{gone}: cannot be read (HTTP 404 File not found)",
        f"{shown}{refused}": f"{shown}{refused}: cannot be read (HTTP 401 Unauthorized)",
    }
    assert {f["path"]: f["reason"] for f in data["failed"]} == failed
    assert sorted(line for line in first.stderr.splitlines() if "failed" in line) == [
        f"umbmark: failed: {reason}" for reason in sorted(failed.values())
    ]
    # The nightly run: the recordings known again by their redacted URLs; the failed ones
    # tried again (and shown as such on the terminal).
    assert again.returncode == 0, again.stderr
    assert again.stdout.startswith("6 recordings found: 2 done now, 4 done before")
    assert f"robot08: no usable recording ({failed[shown + refused]})" in again.stdout
    with sqlite3.connect(history) as db:
        kept = "\n".join(db.iterdump())
        paths = {row[0] for row in db.execute("SELECT path FROM recordings")}
    assert paths == {f"{shown}{p}" for p in (gone, refused)} | {
        f"{shown}/fleet/{rel}/" for rel in _by_recording(local, str(fleet))
    }
    seen = {
        "first's stdout": first.stdout, "first's stderr": first.stderr,
        "again's stdout": again.stdout, "again's stderr": again.stderr,
        "history's lines": listed.stdout + listed.stderr,
        "page": page.read_text(encoding="utf-8"), "JSON": out.read_text(encoding="utf-8"),
        "history's rows": kept, "history's bytes": history.read_bytes().decode("latin-1"),
    }  # fmt: skip
    assert shown in seen["page"]  # its command line, redacted
    for secret in (user, password, wrong):
        assert [name for name, text in seen.items() if secret in text] == [], secret


@pytest.mark.slow
def test_recordings_at_signed_urls_are_known_again_when_signed_again(
    fleet: Path, served: str, tmp_path: Path
):
    """Each recording's MCAP at a URL signed as S3 signs it (the server ignores the
    query): the second night's URLs, signed again (another signature, credential date and
    expiry), are the same recordings, none done again; no signature is kept."""
    files = sorted(fleet.glob("*/*/drive/drive.mcap"))

    def signed(night: int) -> list[str]:
        query = (
            f"?X-Amz-Algorithm=AWS4-HMAC-SHA256&X-Amz-Credential=AKIAEXAMPLEKEY%2F2026110"
            f"{night}%2Feu-west-1%2Fs3%2Faws4_request&X-Amz-Date=2026110{night}T020000Z"
            f"&X-Amz-Expires={3600 * night}&X-Amz-SignedHeaders=host"
            f"&X-Amz-Signature=night{night}signature"
        )
        return [f"{served}/{p.relative_to(fleet.parent).as_posix()}{query}" for p in files]

    history = tmp_path / "h.sqlite3"
    pattern = "{robot}/{date}/drive/*.mcap"
    first = umbmark.fleet(*signed(2), robot_from=pattern, history=history, workers=2)
    second = umbmark.fleet(*signed(3), robot_from=pattern, history=history, workers=1)
    assert len(first.done) == 4
    assert [o for o in first.done if o.failed] == []  # each read (calibrated or left out)
    assert (second.done, second.skipped) == ((), 4)
    masked = (
        "?X-Amz-Algorithm=***&X-Amz-Credential=***&X-Amz-Date=***&X-Amz-Expires=***"
        "&X-Amz-SignedHeaders=***&X-Amz-Signature=***"
    )
    assert sorted(o.path for o in first.done) == sorted(
        f"{served}/{p.relative_to(fleet.parent).as_posix()}{masked}" for p in files
    )
    kept = history.read_bytes().decode("latin-1")
    assert [s for s in ("night2signature", "AKIAEXAMPLEKEY", "20261102T") if s in kept] == []

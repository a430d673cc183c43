"""``umbmark fleet`` on recordings at URLs: a simulated fleet (ROS 2 bag folders of two
robots over two days) served by ``python -m http.server`` started as a process, and the
same folder as ``file://``, give the figures the local run gives; the nightly run skips
every recording (known by the server's size and Last-Modified); a URL that 404s is a failed
recording with one line while the others go on; the workers' temporary copies are gone; the
command exits 0, and 2 with one line for a URL that matches nothing or when fsspec is
missing; and an existing cluster's workers stream the recordings themselves."""

from __future__ import annotations

import json
import os
import re
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
from http_served import WITHOUT_FSSPEC, Served

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
    served: str, local: umbmark.FleetReport, tmp_path: Path
):
    history = str(tmp_path / "h.sqlite3")
    proc = run_cli("fleet", f"{served}/fleet/", "--robot-from", PATTERN, "--history", history,
                   "--workers", "1", "--json", timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert (data["recordings_done"], data["failed"]) == (4, [])
    assert {r["robot"]: r["figures"] for r in data["robots"]} == {
        r["robot"]: r["figures"] for r in local.to_dict()["robots"]
    }
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

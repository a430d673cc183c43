"""``umbmark simulate --fleet``'s folder is written whole or not at all: a run that fails
midway (a write that fails, Ctrl-C) leaves nothing behind, not even the parent folders it
made, and an existing fleet is replaced only with --force, and only at the end."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.core.errors import InputError
from umbmark.jobs import simulate_fleet as sf

from helpers import umbmark_command


def _fail_after_first(monkeypatch: pytest.MonkeyPatch, error: BaseException) -> list[Path]:
    """Make the second recording's write raise ``error`` (the first is written for real);
    the paths the recordings were written at."""
    real, paths = sf._record, []

    def record(path: Path, *args: object) -> None:
        paths.append(path)
        if len(paths) > 1:
            raise error
        real(path, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(sf, "_record", record)
    return paths


def _files(folder: Path) -> dict[str, bytes]:
    return {
        p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()
    }


@pytest.mark.parametrize(
    "error",
    [
        InputError("cannot be written (No space left on device)", source="drive"),
        KeyboardInterrupt(),
    ],
    ids=["disk-full", "ctrl-c"],
)
def test_a_run_failing_after_the_first_robot_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, error: BaseException
):
    paths = _fail_after_first(monkeypatch, error)
    target = tmp_path / "new" / "deeper" / "fleet"
    with pytest.raises(type(error)):
        sf.simulate_fleet(target, fleet=2, days=1, minutes=0.2)
    # The first robot was written (in the folder being built, not in the target) ...
    assert len(paths) == 2
    assert paths[0].parts[-3:] == ("robot01", "2026-11-02", "drive")
    assert paths[0].parent.parent.parent.name == "fleet"
    assert paths[0].parent.parent.parent != target
    # ... and nothing is left: no fleet, no hidden folder, no parent folder made for it.
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_an_existing_fleet_is_replaced_only_with_force_and_only_at_the_end(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    target = tmp_path / "fleet"
    sf.simulate_fleet(target, fleet=1, days=1, minutes=0.2, seed=3)
    before = _files(target)
    assert sorted(before) == ["robot01/2026-11-02/drive/drive.mcap",
                              "robot01/2026-11-02/drive/metadata.yaml", "truth.json"]  # fmt: skip
    with pytest.raises(InputError, match=r"is not empty; .* pass force=True"):
        umbmark.simulate_fleet(target, fleet=1, days=1, minutes=0.2)
    assert _files(target) == before
    # Forced, and failing midway: the earlier fleet stays as it was.
    _fail_after_first(monkeypatch, InputError("cannot be written (Input/output error)"))
    with pytest.raises(InputError, match="Input/output error"):
        sf.simulate_fleet(target, fleet=2, days=1, minutes=0.2, seed=4, force=True)
    assert _files(target) == before
    assert [p.name for p in tmp_path.iterdir()] == ["fleet"]


@pytest.mark.slow
def test_force_replaces_a_simulated_fleet_whole_and_nothing_else(tmp_path: Path):
    target = tmp_path / "fleet"
    sf.simulate_fleet(target, fleet=2, days=1, minutes=0.2, seed=3)
    made = sf.simulate_fleet(target, fleet=1, days=2, minutes=0.2, seed=4, force=True)
    # The earlier fleet's second robot is gone with it: only the new fleet is there.
    assert sorted(p.name for p in target.iterdir()) == ["robot01", "truth.json"]
    assert sorted(p.name for p in (target / "robot01").iterdir()) == ["2026-11-02", "2026-11-03"]
    truth = json.loads((target / "truth.json").read_text(encoding="utf-8"))
    assert [r["path"] for r in truth["recordings"]] == [r.path for r in made.recordings]
    assert all(Path(r.path).is_dir() for r in made.recordings)
    assert [p.name for p in tmp_path.iterdir()] == ["fleet"]
    # A folder holding anything else (the user's page) is not replaced, even with force.
    (target / "fleet.html").write_text("<p>mine</p>\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"holds fleet\.html: not a simulated fleet's"):
        sf.simulate_fleet(target, fleet=1, days=1, minutes=0.2, force=True)
    assert (target / "fleet.html").read_text(encoding="utf-8") == "<p>mine</p>\n"
    assert len(list((target / "robot01").iterdir())) == 2


@pytest.mark.slow
def test_ctrl_c_midway_through_the_command_leaves_nothing(tmp_path: Path):
    """A real SIGINT to ``umbmark simulate --fleet`` once its first recording is written:
    exit status 130, one line, and no folder left (the one being built removed)."""
    proc = subprocess.Popen(
        [umbmark_command(), "simulate", "--fleet", "3", "--days", "3", "--minutes", "1",
         "--out", "fleet"],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True,
    )  # fmt: skip
    try:
        end = time.monotonic() + 300  # a loaded machine writes its first recording late
        while not list(tmp_path.glob(".fleet.*/fleet/robot01/*/drive/metadata.yaml")):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < end, "no recording written in 300 s"
            time.sleep(0.05)
        assert not (tmp_path / "fleet").exists()  # being built beside it
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "umbmark: interrupted"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_every_robot_records_an_imu_and_one_gyros_scale_changes(tmp_path: Path):
    """truth.json holds each robot's gyro per day; robot05's ``k_g`` steps by
    ``GYRO_STEP`` on the second day, the others' stay; each bag's IMU is mounted as its
    truth says (read back by the reader)."""
    import math

    from umbmark.sources.bag.bag_options import BagOptions
    from umbmark.sources.bag.imu import read_imu

    target = tmp_path / "fleet"
    sf.simulate_fleet(target, fleet=5, days=2, minutes=0.2, seed=2)
    truth = json.loads((target / "truth.json").read_text(encoding="utf-8"))
    assert truth["events"]["robot05"] == "gyro scale changed on day 2: k_g +0.015"
    by = {(r["robot"], r["day"]): r["imu"] for r in truth["recordings"]}
    for robot in ("robot01", "robot02", "robot03", "robot04", "robot05"):
        first, second = by[(robot, "2026-11-02")], by[(robot, "2026-11-03")]
        assert 0.97 <= first["k_g"] <= 1.03
        assert abs(first["bias"][2]) <= math.radians(0.5)
        assert all(abs(a) <= math.radians(1.0) for a in first["mounting"]["rpy"][:2])
        assert first["rate"] == sf.IMU_RATE
        assert first["topic"] == "/imu"
        step = second["k_g"] - first["k_g"]
        assert step == pytest.approx(sf.GYRO_STEP if robot == "robot05" else 0.0, abs=1e-12)
    path = target / "robot05" / "2026-11-03" / "drive"
    read = read_imu(path, BagOptions(imu_topic="/imu"))
    roll, pitch, yaw = read.mounting.rpy
    want = by[("robot05", "2026-11-03")]["mounting"]["rpy"]
    np.testing.assert_allclose([roll, pitch, yaw], want, atol=1e-9)
    assert read.gyro.time.size == by[("robot05", "2026-11-03")]["readings"]

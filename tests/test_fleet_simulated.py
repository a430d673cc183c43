"""A simulated fleet (``umbmark simulate --fleet``: robots driving ordinary missions in a
warehouse with wheels and a laser, no squares) watched by ``umbmark fleet``: every robot
calibrated by scan matching, the truth in ``truth.json`` recovered, the changed wheel and
the knocked laser flagged as steps at the day they happened, the wearing tyres as a trend
of about their true rate, and the steady robot not flagged."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

from helpers import run_cli

ROBOTS, DAYS = 4, 6


@pytest.fixture(scope="module")
def fleet(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("sim") / "fleet"
    proc = run_cli("simulate", "--fleet", str(ROBOTS), "--days", str(DAYS), "--minutes", "1.5",
                   "--out", str(folder), timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "robot02: right wheel changed on day 4" in proc.stdout
    return folder


@pytest.mark.slow
def test_the_simulated_fleet_is_watched(fleet: Path, tmp_path: Path):
    truth = json.loads((fleet / "truth.json").read_text())
    assert len(truth["recordings"]) == ROBOTS * DAYS
    proc = run_cli("fleet", str(fleet), "--robot-from", "{robot}/{date}/*",
                   "--history", str(tmp_path / "h.sqlite3"), "--workers", "2", "--json",
                   timeout=900)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert data["recordings_done"] == ROBOTS * DAYS
    assert data["drifted"] == ["robot02", "robot03", "robot04"]
    by = {r["robot"]: r for r in data["robots"]}
    assert all(f["change"] == "steady" for f in by["robot01"]["figures"].values())
    wheel, laser = by["robot02"]["figures"]["E_d"], by["robot03"]["figures"]["laser_yaw"]
    for step in (wheel, laser):
        assert step["change"] == "step"
        assert "2026-11-05" in step["since"]  # day 4 of 6, from 2026-11-02
    assert wheel["size"] == pytest.approx(-0.006, abs=5 * wheel["size_standard_error"])
    assert laser["size"] == pytest.approx(0.05236, abs=5 * laser["size_standard_error"])
    wear = by["robot04"]["figures"]["E_s"]
    assert wear["change"] == "trend"
    assert wear["size"] == pytest.approx(-0.0008 * 7, abs=4 * wear["size_standard_error"])
    # The latest figures are the truth's, within their intervals (E_d of every robot).
    last = {r["robot"]: r for r in truth["recordings"] if r["day"] == "2026-11-07"}
    for robot, r in by.items():
        low, high = r["figures"]["E_d"]["interval_95"]
        assert low - 1e-4 <= last[robot]["E_d"] <= high + 1e-4, robot
    # The knocked laser's mounting to declare is its true one, and is said to be wrong.
    knocked = by["robot03"]["mounting"]
    true_x, true_y, true_yaw = last["robot03"]["laser"]
    assert knocked["xyz"][:2] == pytest.approx([true_x, true_y], abs=1.5e-3)
    assert knocked["rpy"][2] == pytest.approx(true_yaw, abs=1e-3)
    assert "correct the stated mounting" in knocked["verdict"]
    assert "nothing to change" in by["robot01"]["mounting"]["verdict"]
    # What to apply is the latest calibration's overlay, keyed by the controller.
    assert "ros__parameters" in by["robot02"]["latest"]["overlay"]

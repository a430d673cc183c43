"""A fleet's quiet naming mistakes are said, through the command (one warning line on
stderr, exit status 0) and through the library (the report's ``warnings``): a
``--robot-from`` pattern that matches no recording, a ``--robot-options`` entry for a
robot never found; and a recording that cannot be read stays with the robot its path
names (it made a phantom robot "unnamed" on the page and in the JSON).

The fleet: two simulated robots (``robot01``, ``robot02``: named by their recordings'
robot descriptions), one recording each, and two recordings that cannot be read: one in
robot02's folder, one in a folder that names no robot.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

import umbmark

from helpers import run_cli

pytestmark = pytest.mark.slow

#: A ROS 1 bag's first line and nothing more: no bag reader reads it.
BROKEN = b"#ROSBAG V2.0\n" + b"\0" * 64
#: The pattern of a user who took the simulated bags for .mcap files (they are folders).
WRONG = "{robot}/{date}/*.mcap"


@pytest.fixture(scope="module")
def fleet(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("naming") / "fleet"
    umbmark.simulate_fleet(folder, fleet=2, days=1, minutes=0.3, seed=7)
    for rel in ("robot02/2026-11-03/drive.bag", "spare/2026-11-03/drive.bag"):
        (folder / rel).parent.mkdir(parents=True)
        (folder / rel).write_bytes(BROKEN)
    return folder


def _warnings(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("umbmark: warning:")]


def _fleet(*args: str) -> tuple[dict, list[str]]:  # type: ignore[type-arg]
    proc = run_cli("fleet", *args, "--workers", "1", "--json", timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    return json.loads(proc.stdout), _warnings(proc.stderr)


def test_a_pattern_that_matches_no_recording_warns(fleet: Path, tmp_path: Path):
    history = tmp_path / "h.sqlite3"
    data, warned = _fleet(str(fleet), "--robot-from", WRONG, "--history", str(history))
    # One line: 0 of the 4 matched; the two readable ones named by their robot
    # description, robot02's unreadable one by its folder, the other by nothing.
    assert warned == [
        f"umbmark: warning: --robot-from '{WRONG}' matched 0 of the 4 recordings found (not "
        "robot01/2026-11-02/drive, for one); the 4 others are named: 2 by their robot "
        "description, 1 by a robot's name in their path (unreadable) and 1 not at all "
        "(unreadable, and their path names no robot found)"
    ]
    assert data["warnings"] == [warned[0].removeprefix("umbmark: warning: ")]
    assert [r["robot"] for r in data["robots"]] == ["robot01", "robot02"]
    # The library says the same; the two readable recordings are now done before.
    report = umbmark.fleet(fleet, robot_from=WRONG, history=history, workers=1)
    (said,) = report.warnings
    assert said.startswith(f"--robot-from '{WRONG}' matched 0 of the 4 recordings found")
    assert said.endswith(
        "the 4 others are named: 1 by a robot's name in their path (unreadable), 2 as before "
        "(done before, in the history) and 1 not at all (unreadable, and their path names no "
        "robot found)"
    )
    # A pattern that matches every recording warns of nothing.
    right = umbmark.fleet(fleet, robot_from="{robot}/{date}/*", history=history, workers=1)
    assert right.warnings == ()


def test_an_entry_for_a_robot_never_found_warns(fleet: Path, tmp_path: Path):
    entries = tmp_path / "robots.yaml"
    entries.write_text("robot01:\n  scan_topic: /scan\namr9:\n  scan_topic: /front/scan\n",
                       encoding="utf-8")  # fmt: skip
    history = tmp_path / "h.sqlite3"
    _, warned = _fleet(str(fleet), "--robot-options", str(entries), "--history", str(history))
    assert warned == [
        f"umbmark: warning: --robot-options {entries}: no robot found is named amr9, so its "
        "entry is used for no recording; the robots found: robot01 and robot02"
    ]
    report = umbmark.fleet(fleet, robot_options=entries, history=history, workers=1)
    assert [w.split(": no robot", 1)[1] for w in report.warnings] == [
        " found is named amr9, so its entry is used for no recording; the robots found: "
        "robot01 and robot02"
    ]


def test_an_unreadable_recording_stays_with_the_robot_its_path_names(fleet: Path, tmp_path: Path):
    history, page = tmp_path / "h.sqlite3", tmp_path / "fleet.html"
    data, warned = _fleet(str(fleet), "--history", str(history), "--report", str(page))
    assert warned == []
    assert sorted(f["path"] for f in data["failed"]) == [
        str(fleet / "robot02/2026-11-03/drive.bag"),
        str(fleet / "spare/2026-11-03/drive.bag"),
    ]
    # Two robots, no phantom: robot02 holds its unreadable recording, the other is no
    # robot's (it is among the failed ones).
    by = {r["robot"]: r for r in data["robots"]}
    assert sorted(by) == ["robot01", "robot02"]
    assert (by["robot01"]["recordings"], by["robot02"]["recordings"]) == (1, 2)
    assert [p["path"] for p in by["robot02"]["left_out"]] == [
        str(fleet / "robot02/2026-11-03/drive.bag")
    ]
    assert "unnamed" not in page.read_text(encoding="utf-8")
    with sqlite3.connect(history) as db:
        rows = dict(db.execute("SELECT path, robot FROM recordings WHERE status = 'failed'"))
    assert rows == {
        str(fleet / "robot02/2026-11-03/drive.bag"): "robot02",
        str(fleet / "spare/2026-11-03/drive.bag"): "",
    }
    # The library, run again on the same history (the failed ones tried again): the same.
    report = umbmark.fleet(fleet, history=history, workers=1)
    assert [r.robot for r in report.summary.robots] == ["robot01", "robot02"]
    assert sorted((o.robot, o.named_by) for o in report.failed) == [("", None), ("robot02", "path")]

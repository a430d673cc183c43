"""The controller's name travels with the calibration (issue 29, item 4): read from the
user's parameter file or ``--controller``, it keys every overlay (``--yaml``,
``--ros1-yaml``, report.html's, the self-calibration's ``overlay.yaml``), is the
``controller`` of the JSON and of the history, and comes back from a first pass's
``result.json`` and from the history's last applied calibration. Where nothing names it
the overlays are keyed ``diff_drive_controller`` and a note says so.

The robot is the simulator's (E_d 1.002, E_b 0.98); what is checked is the keys the
YAML written holds, read back with PyYAML, against the name the test gave."""

from __future__ import annotations

import html
import json
import re
import sqlite3
from pathlib import Path

import pytest
import yaml

import umbmark
from umbmark.store.history import History

from helpers import run_cli

CONTROLLERS = """\
# hand-tuned, do not lose these comments!
controller_manager:
  ros__parameters:
    update_rate: 100  # Hz

diff_cont:
  ros__parameters:
    wheel_separation: 0.34  # m
    wheel_radius: 0.075  # m
    left_wheel_names: ["left_wheel_joint"]
    right_wheel_names: ["right_wheel_joint"]
"""


def _runs(seed: int, params: object = None) -> list[umbmark.Run]:
    kwargs = {} if params is None else {"params": params}
    return list(umbmark.simulate(E_d=1.002, E_b=0.98, seed=seed, **kwargs).runs)


def _keys(path: Path) -> list[str]:
    return list(yaml.safe_load(path.read_text()))


def _page_overlay(page: str) -> dict[str, object]:
    found = re.search(r'<pre id="overlay-yaml">(.*?)</pre>', page, re.S)
    assert found is not None
    loaded: dict[str, object] = yaml.safe_load(html.unescape(found[1]))
    return loaded


@pytest.mark.slow
def test_the_controller_travels_through_a_first_passs_result(tmp_path: Path) -> None:
    params = tmp_path / "my_controllers.yaml"
    params.write_text(CONTROLLERS)
    pass1, overlay1 = tmp_path / "pass1.json", tmp_path / "overlay1.yaml"
    first = umbmark.calibrate(
        _runs(1), side_length=4, wheelbase=0.34, current_params=params, output=pass1,
        yaml=overlay1,
    )  # fmt: skip
    assert json.loads(pass1.read_text())["controller"] == "/diff_cont"
    assert _keys(overlay1) == ["diff_cont"]
    overlay2, ros1 = tmp_path / "overlay2.yaml", tmp_path / "ros1.yaml"
    second = umbmark.calibrate(
        _runs(2, first), side_length=4, wheelbase=0.34, current_params=pass1, yaml=overlay2,
        ros1_yaml=ros1,
    )  # fmt: skip
    assert second.to_dict()["controller"] == "/diff_cont"
    assert _keys(overlay2) == ["diff_cont"]
    assert _keys(ros1) == ["diff_cont"]
    assert list(_page_overlay(second.html())) == ["diff_cont"]
    assert not any("no controller named" in n for n in second.notes)


@pytest.mark.slow
def test_a_namespaced_controller_keys_the_overlays_by_its_namespace(tmp_path: Path) -> None:
    pass1, overlay = tmp_path / "pass1.json", tmp_path / "overlay.yaml"
    first = umbmark.calibrate(
        _runs(1), side_length=4, wheelbase=0.34, controller="/robot1/diff_cont", output=pass1
    )
    assert first.to_dict()["controller"] == "/robot1/diff_cont"
    umbmark.calibrate(
        _runs(2, first), side_length=4, wheelbase=0.34, current_params=pass1, yaml=overlay
    )
    written = yaml.safe_load(overlay.read_text())
    assert list(written) == ["robot1"]
    assert list(written["robot1"]) == ["diff_cont"]
    assert "wheel_separation_multiplier" in written["robot1"]["diff_cont"]["ros__parameters"]


def test_the_controller_travels_through_the_history(tmp_path: Path) -> None:
    params, db = tmp_path / "my_controllers.yaml", tmp_path / "history.sqlite3"
    params.write_text(CONTROLLERS)
    first = umbmark.calibrate(
        _runs(1), side_length=4, wheelbase=0.34, current_params=params, robot="R", history=db
    )
    History(db).mark_applied("R", 1)
    overlay = tmp_path / "overlay.yaml"
    second = umbmark.calibrate(
        _runs(2, first), side_length=4, wheelbase=0.34, robot="R", history=db, yaml=overlay
    )
    assert _keys(overlay) == ["diff_cont"]
    assert second.to_dict()["controller"] == "/diff_cont"
    assert [c.controller for c in History(db).calibrations("R")] == ["/diff_cont"] * 2
    assert History(db).calibrations("R")[0].to_dict()["controller"] == "/diff_cont"
    assert any("for controller /diff_cont" in n for n in second.notes)


def test_an_older_history_is_read_with_no_controller(tmp_path: Path) -> None:
    """A schema-2 file (before the controller was kept), made with SQL as umbmark 2 wrote
    it, is brought up to date and read: its calibrations name no controller."""
    db = tmp_path / "old.sqlite3"
    with sqlite3.connect(db) as raw:
        raw.executescript(
            """
            CREATE TABLE robots (name TEXT PRIMARY KEY, wheelbase REAL NOT NULL,
                wheel_diameter REAL, created TEXT NOT NULL);
            CREATE TABLE calibrations (id INTEGER PRIMARY KEY AUTOINCREMENT,
                robot TEXT NOT NULL REFERENCES robots(name), time TEXT NOT NULL,
                method TEXT NOT NULL, inputs TEXT NOT NULL, E_d REAL NOT NULL,
                E_b REAL NOT NULL, E_s REAL, e_max_syst REAL, standard_errors TEXT NOT NULL,
                active TEXT NOT NULL, new TEXT NOT NULL, applied INTEGER NOT NULL DEFAULT 0,
                verdict TEXT);
            INSERT INTO robots VALUES ('R', 0.34, 0.15, '2026-01-01T00:00:00Z');
            INSERT INTO calibrations (robot, time, method, inputs, E_d, E_b, standard_errors,
                active, new, applied) VALUES ('R', '2026-01-02T00:00:00Z', 'paper', '[]',
                1.002, 0.98, '{}', '{}', '{"c_L": 0.999, "c_R": 1.001,
                "wheel_separation_multiplier": 0.98}', 1);
            PRAGMA user_version = 2;
            """
        )
    raw.close()
    (old,) = History(db, read_only=True).calibrations("R")
    assert old.controller is None
    assert old.new["wheel_separation_multiplier"] == 0.98
    assert History(db).schema_version == 5


def test_with_nothing_naming_it_the_default_is_said(tmp_path: Path) -> None:
    pass1, overlay = tmp_path / "pass1.json", tmp_path / "overlay.yaml"
    report = umbmark.calibrate(_runs(1), side_length=4, wheelbase=0.34, output=pass1, yaml=overlay)
    assert json.loads(pass1.read_text())["controller"] is None
    assert _keys(overlay) == ["diff_drive_controller"]
    said = "no controller named: keyed diff_drive_controller; give --controller"
    assert any(n.startswith(said) for n in report.notes)
    assert f"# {said}" in overlay.read_text()


@pytest.mark.slow
def test_the_command_line_says_the_default_where_it_writes_an_overlay(tmp_path: Path) -> None:
    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    args = ("calibrate", str(table), "-L", "4", "--wheelbase", "0.34", "--unit", "mm")
    done = run_cli(*args, "--yaml", str(tmp_path / "one.yaml"))
    assert done.returncode == 0, done.stderr
    assert "no controller named: keyed diff_drive_controller; give --controller" in done.stderr
    named = run_cli(*args, "--yaml", str(tmp_path / "two.yaml"), "--controller", "/diff_cont")
    assert named.returncode == 0, named.stderr
    assert "no controller named" not in named.stderr
    assert "diff_cont:" in named.stdout


@pytest.mark.slow
def test_selfcal_keys_its_overlay_and_page_by_the_controller(tmp_path: Path) -> None:
    """The virtual robot's self-calibration with ``controller="/diff_cont"``: its
    ``overlay.yaml`` and report.html's overlay are keyed ``diff_cont``, and its history
    records the name."""
    out, db = tmp_path / "out", tmp_path / "history.sqlite3"
    robot = umbmark.VirtualRobot(E_d=1.004, E_b=0.97, slip=0.0004, seed=3)
    umbmark.selfcal(
        robot, out=out, side_length=1.0, runs=2, max_passes=1, verify=False, coarse=False,
        controller="/diff_cont", robot_name="R", history=db,
    )  # fmt: skip
    assert _keys(out / "overlay.yaml") == ["diff_cont"]
    assert list(_page_overlay((out / "report.html").read_text())) == ["diff_cont"]
    assert [c.controller for c in History(db).calibrations("R")] == ["/diff_cont"]

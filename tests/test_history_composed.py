"""The history compares what the robot is, not what the passes measured: a pass on
odometry already corrected measures what the correction left, and composed with the
parameters active during it gives the robot's own errors again. Also: a calibration with
an unknown nominal wheel diameter is not another robot, and success lines are no
warnings."""

from __future__ import annotations

import math
import shlex
import sqlite3
from pathlib import Path

import pytest

import umbmark
from umbmark.store.history import History

from helpers import api_error, cli_json, run_cli

#: The robot's true errors: D_R / D_L and its wheelbase over the nominal one.
TRUE_E_D, TRUE_E_B = 1.002, 0.98


def _passes(db: Path, later_E_b: float = TRUE_E_B) -> list[umbmark.CalibrationReport]:
    """Pass 1 on the nominal parameters, marked applied; passes 2 and 3 driven on the
    corrected odometry (the simulated robot's odometry uses pass 1's parameters) by a
    robot whose true E_b is then ``later_E_b``. calibrate takes the active parameters
    from the history (the last applied calibration)."""
    first = umbmark.simulate(E_d=TRUE_E_D, E_b=TRUE_E_B, seed=1)
    reports = [umbmark.calibrate(first.runs, side_length=4, wheelbase=0.34, robot="R", history=db)]
    History(db).mark_applied("R", 1)
    for seed in (2, 3):
        sim = umbmark.simulate(E_d=TRUE_E_D, E_b=later_E_b, seed=seed, params=reports[0])
        reports.append(
            umbmark.calibrate(sim.runs, side_length=4, wheelbase=0.34, robot="R", history=db)
        )
    return reports


@pytest.mark.slow
def test_passes_on_corrected_odometry_are_no_drift(tmp_path: Path) -> None:
    db = tmp_path / "history.sqlite3"
    reports = _passes(db)
    verdict = History(db).drift("R")
    assert verdict is not None
    assert verdict.startswith("no drift: robot E_d")
    assert "robot E_b 0.97" in verdict
    assert "over 3 calibrations (1 to 3)" in verdict
    records = History(db).calibrations("R")
    first = reports[0].calibration
    for record in records[1:]:
        # Recorded with pass 1's new parameters active, measuring what they left: E_b
        # near 0.98 / 0.9797 = 1.0003 (the passes' standard errors are about 5e-4).
        assert record.active["wheel_separation_multiplier"] == first.new_separation_multiplier
        assert record.E_b == pytest.approx(1.0, abs=0.003)
        assert record.E_d == pytest.approx(1.0, abs=5e-4)
    for record in records:
        # Composed by hand: E_d c_R / c_L and E_b x multiplier of the active parameters.
        active = record.active
        assert record.robot_E_d == pytest.approx(
            record.E_d * active["c_R"] / active["c_L"], rel=1e-12
        )
        assert record.robot_E_b == pytest.approx(
            record.E_b * active["wheel_separation_multiplier"], rel=1e-12
        )
        # ... and that is the robot, within 4 of its standard errors of the truth.
        se = record.robot_standard_errors
        assert abs(record.robot_E_b - TRUE_E_B) < 4 * se["E_b"]
        assert abs(record.robot_E_d - TRUE_E_D) < 4 * se["E_d"]
        assert se["E_b"] == pytest.approx(
            record.standard_errors["E_b"] * active["wheel_separation_multiplier"], rel=1e-12
        )


@pytest.mark.slow
def test_a_robot_that_changed_is_drift_though_the_passes_look_alike(tmp_path: Path) -> None:
    # After pass 1 was applied the wheelbase shrank by 2 % more (true E_b 0.98 x 0.98):
    # on the corrected odometry the passes measure E_b near 0.9604 / 0.9797 = 0.980, as
    # pass 1 did on the nominal one; the robot went from 0.98 to 0.9604.
    db = tmp_path / "history.sqlite3"
    _passes(db, later_E_b=TRUE_E_B * TRUE_E_B)
    verdict = History(db).drift("R")
    assert verdict is not None
    # Passes 2 and 3 agree on the changed robot: a step at pass 2, confirmed by pass 3.
    assert verdict.startswith("drift: robot E_b stepped from 0.97")
    after = float(verdict.split(" to ")[1].split()[0])
    assert abs(after - TRUE_E_B * TRUE_E_B) < 2e-3  # two passes of se about 1e-3
    assert "at calibration 2" in verdict
    assert "confirmed by 2" in verdict
    assert "within noise: robot E_d" in verdict
    records = History(db).calibrations("R")
    assert records[2].E_b == pytest.approx(records[0].E_b, abs=0.003)  # alike
    last = records[2]
    assert abs(last.robot_E_b - TRUE_E_B * TRUE_E_B) < 4 * last.robot_standard_errors["E_b"]


def _hand_built(db: Path, rows: list[tuple[float, float, float, float, float]]) -> History:
    """A history with calibrations written row by row as umbmark wrote them before the
    robot's values were composed (schema 1): ``(E_d, E_b, c_L, c_R, multiplier)`` each,
    standard errors 1e-4 (E_d) and 5e-4 (E_b)."""
    import json

    store = History(db)
    with sqlite3.connect(db) as raw:
        raw.execute(
            "INSERT INTO robots (name, wheelbase, wheel_diameter, created) "
            "VALUES ('H', 0.4, NULL, '2026-01-01T00:00:00.000000Z')"
        )
        for k, (E_d, E_b, c_left, c_right, separation) in enumerate(rows, start=1):
            active = {"wheelbase": 0.4, "wheel_separation_multiplier": separation,
                      "effective_wheelbase": 0.4 * separation, "c_L": c_left, "c_R": c_right,
                      "wheel_diameter": None}  # fmt: skip
            raw.execute(
                "INSERT INTO calibrations (robot, time, method, inputs, E_d, E_b, E_s, "
                "e_max_syst, standard_errors, active, new, applied) "
                "VALUES ('H', ?, 'exact', '[]', ?, ?, NULL, 0.1, ?, ?, '{}', 0)",
                (f"2026-0{k}-01T00:00:00.000000Z", E_d, E_b,
                 json.dumps({"E_d": 1e-4, "E_b": 5e-4}), json.dumps(active)),
            )  # fmt: skip
    raw.close()
    return store


def test_hand_built_history_is_composed(tmp_path: Path) -> None:
    # Pass 1 on the nominal parameters finds E_d 1.004, E_b 0.97; its correction is
    # c_L = 2 / 2.004, c_R = 2 / (1 / 1.004 + 1) (Eqs. 4.31-4.32), multiplier 0.97.
    # Passes 2 and 3 on it find what is left, 1.0 and 1.0 (and 1.0001, 0.9998).
    c_left, c_right = 2 / 2.004, 2 / (1 / 1.004 + 1)
    store = _hand_built(
        tmp_path / "old.sqlite3",
        [
            (1.004, 0.97, 1.0, 1.0, 1.0),
            (1.0, 1.0, c_left, c_right, 0.97),
            (1.0001, 0.9998, c_left, c_right, 0.97),
        ],
    )
    verdict = store.drift("H")
    assert verdict is not None
    assert verdict.startswith("no drift: robot E_d")
    records = store.calibrations("H")
    assert [r.robot_E_d for r in records] == pytest.approx([1.004, 1.004, 1.0001 * 1.004])
    assert [r.robot_E_b for r in records] == pytest.approx([0.97, 0.97, 0.9998 * 0.97])
    assert records[2].robot_wheelbase == pytest.approx(0.9998 * 0.97 * 0.4)
    assert records[2].robot_standard_errors["E_b"] == pytest.approx(5e-4 * 0.97)
    assert records[2].robot_standard_errors["E_d"] == pytest.approx(1e-4 * 1.004)
    # The same passes, all on the nominal parameters: the robot moved by 0.03 in E_b.
    changed = _hand_built(
        tmp_path / "changed.sqlite3",
        [(1.004, 0.97, 1.0, 1.0, 1.0), (1.0, 1.0, 1.0, 1.0, 1.0), (1.004, 1.0, 1.0, 1.0, 1.0)],
    )
    verdict = changed.drift("H")
    assert verdict is not None
    # E_b 0.97, then 1.0 twice: a step at calibration 2, confirmed by calibration 3.
    assert verdict.startswith("drift: robot E_b stepped from 0.970000 to 1.000000")


@pytest.mark.slow
def test_history_columns_say_what_they_compare(tmp_path: Path) -> None:
    db = tmp_path / "history.sqlite3"
    _passes(db)
    records = History(db).calibrations("R")
    listed = cli_json("history", "R", "--history", str(db))
    for entry, record in zip(listed["calibrations"], records, strict=True):
        assert entry["E_b"] == record.E_b  # what the pass measured, as before
        assert entry["robot_E_b"] == pytest.approx(
            record.E_b * record.active["wheel_separation_multiplier"], rel=1e-12
        )
        assert entry["robot_E_d"] == pytest.approx(
            record.E_d * record.active["c_R"] / record.active["c_L"], rel=1e-12
        )
        assert entry["robot_wheelbase"] == pytest.approx(entry["robot_E_b"] * 0.34)
        assert set(entry["robot_standard_errors"]) == {"E_d", "E_b"}
    assert "composed with the active" in listed["definitions"]["robot_E_b"]
    assert "relative to the odometry parameters active" in listed["definitions"]["E_b"]
    text = run_cli("history", "R", "--history", str(db))
    assert text.returncode == 0, text.stderr
    for header in ("pass E_b (measured)", "robot E_b (composed)", "robot E_d (composed)"):
        assert header in text.stdout
    assert "robot E_b: what the robot is" in text.stdout
    assert "no drift: robot E_d" in text.stdout
    # The trend: the robot's values, and the passes' measured ones beside them.
    fig = umbmark.history("R", history=db).figure()
    for ax, name in zip(fig.axes[:2], ("E_d", "E_b"), strict=False):
        (robot,) = [line for line in ax.get_lines() if line.get_label() == f"robot {name}"]
        expected = [getattr(r, f"robot_{name}") for r in records]
        assert list(robot.get_ydata()) == pytest.approx(expected, rel=1e-12)
        (passes,) = [
            line for line in ax.get_lines() if "measured by the pass" in str(line.get_label())
        ]
        assert list(passes.get_ydata()) == pytest.approx([getattr(r, name) for r in records])
        assert "composed with the active" in ax.get_title(loc="left")
    assert "drift" not in fig._suptitle.get_text()


def test_unknown_wheel_diameter_is_not_another_robot(tmp_path: Path) -> None:
    table, db = tmp_path / "runs.csv", tmp_path / "history.sqlite3"
    umbmark.example(str(table))

    def calibrate(robot: str, wheelbase: float = 0.34, **more: float) -> object:
        return umbmark.calibrate(str(table), side_length=4, wheelbase=wheelbase, unit="mm",
                                 robot=robot, history=db, **more)  # fmt: skip

    calibrate("known", wheel_diameter=0.15)
    calibrate("known")  # a runs table that does not say the diameter
    assert len(History(db).calibrations("known")) == 2
    calibrate("later")
    calibrate("later", wheel_diameter=0.15)  # the first one known is the robot's
    robot = History(db).robot("later")
    assert robot is not None
    assert robot.wheel_diameter == 0.15
    message = api_error(calibrate, "later", wheel_diameter=0.2)
    assert "is not robot later: nominal wheel diameter 0.2 m vs 0.15 m" in message
    message = api_error(calibrate, "later", wheelbase=0.3)
    assert "is not robot later: nominal wheelbase 0.3 m vs 0.34 m" in message
    assert len(History(db).calibrations("later")) == 2


def test_marked_applied_is_not_a_warning(tmp_path: Path) -> None:
    table, db = tmp_path / "runs.csv", tmp_path / "history.sqlite3"
    umbmark.example(str(table))
    umbmark.calibrate(str(table), side_length=4, wheelbase=0.34, unit="mm", robot="r1",
                      history=db)  # fmt: skip
    marked = run_cli("history", "r1", "--history", str(db), "--applied", "1")
    assert marked.returncode == 0, marked.stderr
    assert marked.stderr == "umbmark: calibration 1 of r1 marked applied\n"


@pytest.mark.slow
def test_calibrate_says_where_it_recorded(tmp_path: Path) -> None:
    table, db = tmp_path / "runs.csv", tmp_path / "history.sqlite3"
    umbmark.example(str(table))
    args = ("calibrate", str(table), "-L", "4", "-b", "0.34", "--unit", "mm", "--json")
    proc = run_cli(*args, "--robot", "my bot", "--history", str(db))
    assert proc.returncode == 0, proc.stderr
    (line,) = [x for x in proc.stderr.splitlines() if "recorded" in x]
    assert line.startswith(f"umbmark: recorded as calibration 1 of robot my bot in {db}")
    # The command the line suggests marks it applied, and says so plainly.
    suggested = shlex.split(line.split("configured on the robot: umbmark ", 1)[1])
    assert suggested == ["history", "my bot", "--history", str(db), "--applied", "1"]
    marked = run_cli(*suggested)
    assert marked.returncode == 0, marked.stderr
    assert marked.stderr == "umbmark: calibration 1 of my bot marked applied\n"
    assert History(db).calibrations("my bot")[0].applied
    assert math.isfinite(History(db).calibrations("my bot")[0].robot_E_b)

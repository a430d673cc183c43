"""The robot history (SQLite): recording calibrations, listing them, refusing another
robot's parameters, the schema version, drift, and concurrent writers."""

from __future__ import annotations

import datetime as dt
import json
import multiprocessing
import os
import sqlite3
from pathlib import Path

import pytest
from click.testing import CliRunner

import umbmark
from umbmark.cli.main import cli
from umbmark.store.history import SCHEMA_VERSION, History, default_history_path
from umbmark.store.records import NewCalibration

from helpers import api_error, cli_error, cli_json, run_cli


def _table(tmp_path: Path) -> Path:
    path = tmp_path / "runs.csv"
    umbmark.example(str(path))
    return path


def _calibrate(table: Path, db: Path, robot: str = "r1", wheelbase: float = 0.34):  # type: ignore[no-untyped-def]
    return umbmark.calibrate(
        str(table), side_length=4, wheelbase=wheelbase, unit="mm", robot=robot, history=db
    )


def test_calibrate_records_and_api_lists(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    report = _calibrate(table, db)
    _calibrate(table, db)
    store = History(db)
    assert [r.name for r in store.robots()] == ["r1"]
    assert store.robots()[0].wheelbase == 0.34
    assert store.robots()[0].calibrations == 2
    calibrations = store.calibrations("r1")
    assert [c.id for c in calibrations] == [1, 2]
    first = calibrations[0]
    assert first.method == "exact"
    assert first.E_d == pytest.approx(report.estimate.E_d)
    assert first.E_b == pytest.approx(report.estimate.E_b)
    assert first.e_max_syst == pytest.approx(report.e_max_syst)
    assert first.standard_errors["E_d"] == pytest.approx(report.estimate.standard_errors["E_d"])
    assert first.new["c_L"] == pytest.approx(report.calibration.new_c_left)
    assert first.active["wheelbase"] == 0.34
    assert first.inputs[0]["name"] == str(table)
    assert len(first.inputs[0]["sha256"]) == 64
    assert not first.applied
    assert store.last_applied("r1") is None
    store.mark_applied("r1", 1)
    last = store.last_applied("r1")
    assert last is not None
    assert last.id == 1
    # Two calibrations are compared on their intervals (the same runs: no drift).
    assert store.drift("r1").startswith("no drift: robot E_d")  # type: ignore[union-attr]
    assert "over 2 calibrations (1 to 2)" in store.drift("r1")  # type: ignore[operator]
    assert store.calibrations("nobody") == []


@pytest.mark.slow
def test_history_command_lists_robots_and_calibrations(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    for _ in range(3):
        _calibrate(table, db)
    robots = cli_json("history", "--history", str(db))
    assert [r["name"] for r in robots["robots"]] == ["r1"]
    listed = cli_json("history", "r1", "--history", str(db))
    assert listed["robot"] == "r1"
    assert len(listed["calibrations"]) == 3
    for key in ("time", "method", "E_d", "E_b", "e_max_syst", "applied"):
        assert key in listed["calibrations"][0]
    assert listed["drift"].startswith("no drift")  # the same runs three times
    marked = cli_json("history", "r1", "--history", str(db), "--applied", "2")
    assert [c["applied"] for c in marked["calibrations"]] == [False, True, False]
    text = run_cli("history", "r1", "--history", str(db))
    assert text.returncode == 0, text.stderr
    assert "E_max,syst [mm]" in text.stdout
    assert "no drift" in text.stdout
    report = umbmark.history("r1", history=db)
    assert json.loads(report.to_json()) == report.to_dict()
    assert "no calibration 9" in cli_error("history", "r1", "--history", str(db), "--applied", "9")
    assert "no robot 'r2'" in api_error(umbmark.history, "r2", history=db)
    assert "not a usable history file" in api_error(umbmark.history, history=table)


@pytest.mark.slow
def test_calibrate_command_records(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    args = ("calibrate", str(table), "-L", "4", "-b", "0.34", "--unit", "mm")
    cli_json(*args, "--robot", "bot", "--history", str(db))
    assert [c.method for c in History(db).calibrations("bot")] == ["exact"]
    line = cli_error(
        *args[:-4], "-b", "0.30", "--unit", "mm", "--robot", "bot", "--history", str(db)
    )
    assert "is not robot bot: nominal wheelbase 0.3 m vs 0.34 m" in line


def test_refuses_another_robots_parameters(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    _calibrate(table, db)
    message = api_error(_calibrate, table, db, wheelbase=0.30)
    assert "is not robot r1: nominal wheelbase 0.3 m vs 0.34 m" in message
    assert len(History(db).calibrations("r1")) == 1  # nothing recorded
    _calibrate(table, db, robot="r2", wheelbase=0.30)  # under its own name it is fine
    assert [r.name for r in History(db).robots()] == ["r1", "r2"]


def test_schema_version_and_wal(tmp_path: Path) -> None:
    db = tmp_path / "deep" / "history.sqlite3"
    assert History(db).schema_version == SCHEMA_VERSION == 5
    with sqlite3.connect(db) as raw:
        assert raw.execute("PRAGMA user_version").fetchone()[0] == 5
        assert raw.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        raw.execute("PRAGMA user_version = 99")
    raw.close()
    assert "newer than this umbmark's" in api_error(History, db)


def test_default_location(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("UMBMARK_HISTORY", str(tmp_path / "h.db"))
    assert default_history_path() == tmp_path / "h.db"
    monkeypatch.delenv("UMBMARK_HISTORY")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    assert default_history_path() == tmp_path / "data" / "umbmark" / "history.sqlite3"
    monkeypatch.delenv("XDG_DATA_HOME")
    monkeypatch.setenv("HOME", str(tmp_path))
    assert default_history_path() == tmp_path / ".local/share/umbmark/history.sqlite3"


def test_drift_is_flagged(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    for _ in range(3):
        _calibrate(table, db)
    with sqlite3.connect(db) as raw:  # the robot's wheels wore: E_b moved by far more than 3 se
        raw.execute("UPDATE calibrations SET E_b = E_b + 0.01 WHERE id = 3")
    raw.close()
    verdict = History(db).drift("r1")
    assert verdict is not None
    # The newest alone off the two before it: a change to be confirmed by the next.
    assert verdict.startswith("drift: robot E_b changed in the latest calibration, 3")
    assert "to be confirmed by the next" in verdict


def test_a_changed_nominal_wheelbase_is_no_drift_and_time_orders_the_calibrations(
    tmp_path: Path,
) -> None:
    """A fleet's calibrations, recorded in the order they finished, are listed by their
    recordings' time; the robot (effective wheelbase 0.2016 m) calibrated against 0.2 m,
    then 0.205 m, has not drifted: its E_b is compared on the last nominal."""
    import datetime as dt

    from umbmark.store.records import NewCalibration

    store = History(tmp_path / "h.sqlite3")
    for day, nominal in ((3, 0.205), (1, 0.2), (2, 0.2)):  # finished out of order
        when = dt.datetime(2026, 11, day, tzinfo=dt.timezone.utc)
        store.record("amr", NewCalibration(
            when, "trajectory", 1.0, 0.2016 / nominal, None, None,
            {"E_d": 1e-4, "E_b": 1e-4},
            {"wheelbase": nominal, "c_L": 1.0, "c_R": 1.0, "wheel_separation_multiplier": 1.0},
            {}, {}, nominal, 0.084,
        ), same_nominal=False)  # fmt: skip
    assert [c.time[:10] for c in store.calibrations("amr")] == [
        "2026-11-01", "2026-11-02", "2026-11-03",
    ]  # fmt: skip
    verdict = store.drift("amr")
    assert verdict is not None
    assert verdict.startswith("no drift: robot E_d")
    assert "robot E_b 0.983415 ± " in verdict  # 0.2016 / 0.205 each time
    assert "over 3 calibrations (2 to 1)" in verdict  # by time


def _record_ten(table: str, db: str) -> None:
    for _ in range(10):
        umbmark.calibrate(table, side_length=4, wheelbase=0.34, unit="mm", robot="r1", history=db)


@pytest.mark.slow
def test_concurrent_writers(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    workers = [context.Process(target=_record_ten, args=(str(table), str(db))) for _ in range(4)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(timeout=60)
        assert worker.exitcode == 0
    assert len(History(db).calibrations("r1")) == 40
    with sqlite3.connect(db) as raw:
        assert raw.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        assert raw.execute("SELECT COUNT(*) FROM robots").fetchone()[0] == 1
    raw.close()


def test_second_pass_composes_with_last_applied(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    first = _calibrate(table, db)
    History(db).mark_applied("r1", 1)
    second = _calibrate(table, db)
    active = second.calibration.active
    assert active.c_left == pytest.approx(first.calibration.new_c_left)
    assert active.c_right == pytest.approx(first.calibration.new_c_right)
    assert active.separation_multiplier == pytest.approx(
        first.calibration.new_separation_multiplier
    )
    assert any("last applied calibration 1" in note for note in second.notes)
    # Said otherwise: the options win.
    third = umbmark.calibrate(
        str(table), side_length=4, wheelbase=0.34, unit="mm", robot="r1", history=db,
        current_c_l=1.0, current_c_r=1.0, current_separation_multiplier=1.0,
    )  # fmt: skip
    assert third.calibration.active.c_left == 1.0
    assert not any("last applied" in note for note in third.notes)


# The trend plot: three calibrations of a robot whose wheels wear (known E_d, E_b).

#: True (E_d, E_b) of each calibration's runs, and the date it is set to.
WEAR = (
    (1.000, 0.990, "2026-01-05T10:00:00.000000Z"),
    (1.002, 0.980, "2026-03-10T15:30:00.000000Z"),
    (1.004, 0.970, "2026-06-20T08:00:00.000000Z"),
)


def _wearing_robot(db: Path, robot: str = "wear-bot") -> list[float]:
    """Record three calibrations of simulated runs with the errors of :data:`WEAR`, dated
    as there, the second marked applied. Returns each calibration's E_max,syst [m]."""
    e_max = []
    for seed, (E_d, E_b, _) in enumerate(WEAR, start=1):
        sim = umbmark.simulate(E_d=E_d, E_b=E_b, seed=seed)
        report = umbmark.calibrate(sim.runs, side_length=4, wheelbase=0.34, robot=robot, history=db)
        e_max.append(report.e_max_syst)
    with sqlite3.connect(db) as raw:
        for id, (_, _, time) in enumerate(WEAR, start=1):
            raw.execute("UPDATE calibrations SET time = ? WHERE id = ?", (time, id))
    raw.close()
    History(db).mark_applied(robot, 2)
    return e_max


def _line(ax, label: str):  # type: ignore[no-untyped-def]
    (line,) = [line for line in ax.get_lines() if line.get_label() == label]
    return line


@pytest.mark.slow
def test_trend_figure_draws_the_recorded_calibrations(tmp_path: Path) -> None:
    import datetime as dt

    from matplotlib.dates import date2num

    db = tmp_path / "history.sqlite3"
    e_max = _wearing_robot(db)
    fig = umbmark.history("wear-bot", history=db).figure()
    e_d_ax, e_b_ax, e_max_ax = fig.axes[:3]
    days = [date2num(dt.datetime(2026, 1, 5, 10)), date2num(dt.datetime(2026, 3, 10, 15, 30))]
    days.append(date2num(dt.datetime(2026, 6, 20, 8)))
    for ax, name, column, tolerance in ((e_d_ax, "E_d", 0, 3e-4), (e_b_ax, "E_b", 1, 2e-3)):
        line = _line(ax, f"robot {name}")  # all on the nominal parameters: as measured
        assert list(line.get_xdata()) == pytest.approx(days)
        # The estimates of noisy runs: within a few standard errors of the truth, which
        # moves by 0.002 (E_d) and 0.01 (E_b) between calibrations.
        truth = [w[column] for w in WEAR]
        assert list(line.get_ydata()) == pytest.approx(truth, abs=tolerance)
        assert list(_line(ax, "applied").get_xdata()) == pytest.approx(days[1:2])
        assert list(_line(ax, "not applied").get_xdata()) == pytest.approx(days[::2])
        assert "[dimensionless]" in ax.get_ylabel()
        (bars,) = [c for c in ax.containers if c.get_label() == "±1.96 standard errors (95 %)"]
        records = History(db).calibrations("wear-bot")
        _, _, (collection,) = bars.lines
        for segment, record in zip(collection.get_segments(), records, strict=True):
            half = (segment[1][1] - segment[0][1]) / 2
            assert half == pytest.approx(1.96 * record.standard_errors[name], rel=1e-9)
    line = _line(e_max_ax, "E_max,syst")
    assert list(line.get_ydata()) == pytest.approx([1000 * e for e in e_max])
    assert "[mm]" in e_max_ax.get_ylabel()
    assert "UTC" in e_max_ax.get_xlabel()
    title = fig._suptitle.get_text()
    assert "wear-bot" in title
    assert "340.00 mm" in title  # the nominal wheelbase
    # E_b moved by 0.01 (~15 se) each time, E_d by 0.002: the newest is off both before it
    said = " ".join(title.split("\n")[1:])  # wrapped to the figure's width
    assert said.startswith("drift: robot E_d changed in the latest")
    assert "robot E_b changed in the latest calibration, 3" in said


@pytest.mark.slow
def test_history_plot_command_writes_png_svg_pdf(tmp_path: Path) -> None:
    from matplotlib.image import imread

    db = tmp_path / "history.sqlite3"
    _wearing_robot(db)
    png = tmp_path / "trend.png"
    proc = run_cli("history", "wear-bot", "--history", str(db), "--plot", str(png))
    assert proc.returncode == 0, proc.stderr
    assert f"umbmark: wrote {png}" in proc.stderr
    pixels = imread(png)[..., :3]
    assert min(pixels.shape[:2]) > 500
    assert float(pixels.std()) > 0.05  # not blank
    assert float((pixels.min(axis=2) < 0.5).mean()) > 0.01  # dark ink: text, lines
    svg, pdf = tmp_path / "trend.svg", tmp_path / "trend.pdf"
    cli_json("history", "wear-bot", "--history", str(db), "--plot", str(svg))
    cli_json("history", "wear-bot", "--history", str(db), "--plot", str(pdf))
    assert "<svg" in svg.read_text(encoding="utf-8")
    assert pdf.read_bytes().startswith(b"%PDF")


@pytest.mark.slow
def test_history_plot_refusals(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.png"  # a history named like a figure
    _calibrate(table, db)
    before = db.read_bytes()
    line = cli_error("history", "r1", "--history", str(db), "--plot", str(db))
    assert "would overwrite an input" in line
    assert History(db).calibrations("r1")[0].method == "exact"  # still a history
    assert db.read_bytes() == before
    line = cli_error("history", "r1", "--history", str(db), "--plot", str(tmp_path / "t.txt"))
    assert line.startswith("umbmark: error: --plot")
    assert ".png" in line
    line = cli_error("history", "--history", str(db), "--plot", str(tmp_path / "t.png"))
    assert "needs the robot's NAME" in line
    # Refused before the calibration is marked applied.
    cli_error("history", "r1", "--history", str(db), "--applied", "1", "--plot", str(db))
    assert not History(db).calibrations("r1")[0].applied
    assert not (tmp_path / "t.png").exists()
    assert not (tmp_path / "t.txt").exists()


def test_trend_figure_of_one_calibration(tmp_path: Path) -> None:
    table, db = _table(tmp_path), tmp_path / "history.sqlite3"
    report = _calibrate(table, db)
    fig = umbmark.history("r1", history=db).figure()
    assert list(_line(fig.axes[0], "robot E_d").get_ydata()) == pytest.approx([report.estimate.E_d])
    lo, hi = fig.axes[2].get_xlim()
    assert hi - lo == pytest.approx(1.0)  # one instant: a day's span around it
    assert "drift" not in fig._suptitle.get_text()


def _fleet_calibration(when: str) -> NewCalibration:
    """A fleet's calibration of a recording made at ``when`` (UTC, ISO 8601)."""
    time = dt.datetime.fromisoformat(when).replace(tzinfo=dt.timezone.utc)
    return NewCalibration(time, "scan-matching", 1.002, 0.98, 1.0, 0.1, {"E_d": 1e-4},
                          {}, {}, {}, 0.34, 0.15)  # fmt: skip


def _recorded_in_march(db: Path) -> None:
    """A fleet's run today over three recordings of March, recorded as they finished (not
    in the order they were made)."""
    store = History(db)
    for when in ("2026-03-05T08:00:00", "2026-03-01T08:00:00", "2026-03-03T08:00:00"):
        store.record("amr1", _fleet_calibration(when), same_nominal=False)


def test_robots_are_dated_by_their_calibrations_not_by_the_day_they_were_recorded(tmp_path):
    db = tmp_path / "h.sqlite3"
    _recorded_in_march(db)
    (robot,) = History(db).robots()
    assert (robot.calibrations, robot.first, robot.last) == (
        3, "2026-03-01T08:00:00.000000Z", "2026-03-05T08:00:00.000000Z"
    )  # fmt: skip
    assert not robot.created.startswith("2026-03")  # the day the history learnt of it
    listed = umbmark.history(history=db).to_dict()["robots"][0]
    assert (listed["first_calibration"], listed["last_calibration"]) == (robot.first, robot.last)
    shown = CliRunner().invoke(cli, ["history", "--history", str(db)])
    assert shown.exit_code == 0, shown.output
    (row,) = [line.split() for line in shown.output.splitlines() if "amr1" in line]
    assert row == ["amr1", "0.3400", "0.1500", "3", "2026-03-01", "2026-03-05"]
    assert "first calibration (UTC)" in shown.output
    assert robot.created[:10] not in shown.output


ELSEWHERE = "a history written elsewhere (umbmark fleet ... --history FILE"


def test_the_default_history_without_robots_says_where_another_is_read(tmp_path, monkeypatch):
    """A fleet's records are in the file its --history named: the default history, missing
    or without the robot, says to name that file (--history FILE); a history named already
    does not."""
    fleet = tmp_path / "fleet.sqlite3"
    _recorded_in_march(fleet)
    default = tmp_path / "default.sqlite3"
    monkeypatch.setenv("UMBMARK_HISTORY", str(default))
    (missing,) = umbmark.history().notes
    assert missing.startswith(f"{default}: nothing is recorded yet")
    assert ELSEWHERE in missing
    assert missing.endswith("is read with umbmark history --history FILE")
    assert "umbmark.history(history=file)" in api_error(umbmark.history, "amr1")
    History(default).robots()  # the default history made, with no robot in it
    (empty,) = umbmark.history().notes
    assert empty.startswith(f"{default}: nothing is recorded yet")
    assert ELSEWHERE in empty
    assert "umbmark.history(history=file)" in api_error(umbmark.history, "amr1")
    # Named: no hint of another file.
    assert umbmark.history(history=default).notes == ()
    assert ELSEWHERE not in api_error(umbmark.history, "amr1", history=default)
    assert [r.name for r in umbmark.history(history=fleet).robots] == ["amr1"]


@pytest.mark.slow
def test_the_command_names_the_option_for_another_history(tmp_path):
    env = {**os.environ, "UMBMARK_HISTORY": str(tmp_path / "none.sqlite3")}
    listed = run_cli("history", env=env)
    assert listed.returncode == 0, listed.stderr
    assert listed.stderr.endswith("is read with umbmark history --history FILE\n")
    asked = run_cli("history", "amr1", env=env)
    assert asked.returncode == 2
    assert asked.stderr.count("\n") == 1
    assert asked.stderr.endswith("is read with umbmark history --history FILE\n")


def _gyro_history(path: Path) -> History:
    """A robot calibrated four days with its gyro and laser (E_b 1.02, its gyro's k_g
    0.98, then 0.995: a changed gyro), and twice with the gyro alone (E_b k_g = 1.02 x
    0.98 = 0.9996, 0.02 below E_b: relative to the gyro)."""
    from umbmark.store.records import NewCalibration

    store = History(path)
    active = {"wheelbase": 0.34, "c_L": 1.0, "c_R": 1.0, "wheel_separation_multiplier": 1.0}
    days = [(1, 0.98), (2, 0.98), (3, 0.995), (4, 0.995), (5, None), (6, None)]
    for day, k_g in days:
        when = dt.datetime(2026, 11, day, tzinfo=dt.timezone.utc)
        se = {"E_d": 1e-4, "E_b": 5e-4} | ({"gyro_scale": 2e-4} if k_g else {"E_b_gyro": 2e-4})
        E_b = 1.02 if k_g else 1.02 * 0.98
        new = {"gyro_scale_multiplier": k_g, "gyro_bias": 0.005}
        verdict = {"level": "apply" if k_g else "care", "reasons": [], "instead": None}
        made = NewCalibration(when, "gyro", 1.003, E_b, None, None, se, active, new, verdict,
                              0.34, 0.15)  # fmt: skip
        store.record("amr", made, same_nominal=False)
    return store


def test_e_b_relative_to_the_gyro_stays_out_of_e_bs_course_and_k_g_is_followed(tmp_path):
    """E_b does not drift (the gyro's E_b k_g is left out of its course, said so), k_g
    steps at the third day (:func:`_gyro_history`)."""
    store = _gyro_history(tmp_path / "h.sqlite3")
    records = store.calibrations("amr")
    assert [c.relative_to_gyro for c in records] == [False] * 4 + [True] * 2
    assert [c.k_g for c in records] == [0.98, 0.98, 0.995, 0.995, None, None]
    verdict = store.drift("amr")
    assert verdict is not None
    assert verdict.startswith("drift: robot k_g stepped from 0.980000 to 0.995000")
    assert "robot E_b 1.020000 ± " in verdict  # steady: the relative ones left out
    assert "over 4 calibrations (1 to 4)" in verdict
    assert "E_b of calibrations 5, 6 relative to the gyro (E_b k_g) left out" in verdict


@pytest.mark.slow
def test_the_history_command_shows_k_g_and_marks_e_b_relative_to_the_gyro(tmp_path):
    _gyro_history(tmp_path / "h.sqlite3")
    shown = run_cli("history", "amr", "--history", str(tmp_path / "h.sqlite3")).stdout
    assert "gyro k_g" in shown
    assert "0.999600 (k_g)" in shown  # E_b k_g, marked
    assert "0.99500" in shown  # k_g

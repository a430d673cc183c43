"""A simulated fleet (``umbmark simulate --fleet``: robots driving ordinary missions in a
warehouse with wheels, a laser and an IMU, no squares) watched by ``umbmark fleet``: every
robot calibrated by its gyro and its laser together, the truth in ``truth.json``
recovered (the gyro's scale too), the changed wheel, the knocked laser and robot05's
changed gyro flagged as steps at the day they happened, the wearing tyres as a trend of
about their true rate, and the steady robot not flagged; a recording of wheels and an
IMU alone calibrated by the gyro, its E_b relative to the gyro kept apart."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="the fleet's extra: pip install '.[fleet]'")

from fleet_page_view import plot_of, rows_as_seen
from helpers import run_cli

ROBOTS, DAYS = 5, 6


@pytest.fixture(scope="module")
def fleet(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("sim") / "fleet"
    proc = run_cli("simulate", "--fleet", str(ROBOTS), "--days", str(DAYS), "--minutes", "1.5",
                   "--out", str(folder), timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "robot02: right wheel changed on day 4" in proc.stdout
    return folder


@pytest.fixture(scope="module")
def watched(fleet: Path, tmp_path_factory) -> tuple[dict, Path]:  # type: ignore[type-arg]
    """What ``umbmark fleet --json`` says of the simulated fleet, and its page."""
    folder = tmp_path_factory.mktemp("watched")
    page = folder / "fleet.html"
    proc = run_cli("fleet", str(fleet), "--robot-from", "{robot}/{date}/*",
                   "--history", str(folder / "h.sqlite3"), "--workers", "2", "--json",
                   "--report", str(page), timeout=900)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data: dict = json.loads(proc.stdout)  # type: ignore[type-arg]
    return data, page


@pytest.mark.slow
def test_the_simulated_fleet_is_watched(
    fleet: Path,
    watched: tuple[dict, Path],  # type: ignore[type-arg]
    tmp_path: Path,
):
    truth = json.loads((fleet / "truth.json").read_text())
    assert len(truth["recordings"]) == ROBOTS * DAYS
    data, page = watched
    assert data["recordings_done"] == ROBOTS * DAYS
    assert all(r["recordings"] == DAYS for r in data["robots"])
    assert data["drifted"] == ["robot02", "robot03", "robot04", "robot05"]
    by = {r["robot"]: r for r in data["robots"]}
    assert all(r["latest"]["method"] == "gyro" for r in data["robots"])
    assert all(f["change"] == "steady" for f in by["robot01"]["figures"].values())
    wheel, laser = by["robot02"]["figures"]["E_d"], by["robot03"]["figures"]["laser_yaw"]
    gyro = by["robot05"]["figures"]["k_g"]
    for step in (wheel, laser, gyro):
        assert step["change"] == "step"
        assert "2026-11-05" in step["since"]  # day 4 of 6, from 2026-11-02
    assert wheel["size"] == pytest.approx(-0.006, abs=5 * wheel["size_standard_error"])
    assert laser["size"] == pytest.approx(0.05236, abs=5 * laser["size_standard_error"])
    assert gyro["size"] == pytest.approx(0.015, abs=5 * gyro["size_standard_error"])
    assert by["robot05"]["flags"] == [next(f for f in by["robot05"]["flags"] if "k_g" in f)]
    assert truth["events"]["robot05"] == "gyro scale changed on day 4: k_g +0.015"
    wear = by["robot04"]["figures"]["E_s"]
    assert wear["change"] == "trend"
    assert wear["size"] == pytest.approx(-0.0008 * 7, abs=4 * wear["size_standard_error"])
    last = {r["robot"]: r for r in truth["recordings"] if r["day"] == "2026-11-07"}
    # The knocked laser's mounting to declare is its true one, and is said to be wrong.
    knocked = by["robot03"]["mounting"]
    true_x, true_y, true_yaw = last["robot03"]["laser"]
    assert knocked["xyz"][:2] == pytest.approx([true_x, true_y], abs=1.5e-3)
    assert knocked["rpy"][2] == pytest.approx(true_yaw, abs=1e-3)
    assert "correct the stated mounting" in knocked["verdict"]
    assert "nothing to change" in by["robot01"]["mounting"]["verdict"]
    # What to apply is the present state's overlay, keyed by the controller.
    assert "ros__parameters" in by["robot02"]["apply"]["overlay"]
    _check_the_page(page, tmp_path)


def _check_the_page(page: Path, tmp_path: Path) -> None:
    """The fleet's page as a person sees it (``fleet_page_view``): every robot one row in
    view at a desk's and a phone's width; every plot from the first day (2026-11-02) to the
    last (2026-11-07); the wheel's and the laser's steps marked at day 4 (2026-11-05),
    nothing else marked but the steps (the tyres' trend has no day)."""
    from test_report_command import Chromium

    browser = Chromium(tmp_path / "profile")
    try:
        seen = rows_as_seen(browser, page)
    finally:
        browser.close()
    for width, rows in seen.items():
        assert [r["robot"] for r in rows] == [f"robot{k:02d}" for k in range(1, ROBOTS + 1)]
        by = {r["robot"]: r for r in rows}
        assert by["robot01"]["flags"] == []
        for row in rows:
            assert len(row["plots"]) == 8, width  # the wheels', the laser's, the gyro's
            for plot in row["plots"]:
                assert plot["days"] == ["2026-11-02", "2026-11-07"], (width, plot)
        for robot, label in (("robot02", "E_d"), ("robot03", "laser yaw"), ("robot05", "k_g")):
            plot = plot_of(by[robot], label)
            assert plot["since"] == ["2026-11-05"], (width, robot)
            assert plot["since_x"][0] == pytest.approx(plot["points_x"][3], abs=0.2)
        marked = sum(bool(p["since"]) for r in rows for p in r["plots"])
        assert marked == 4, width  # robot02's E_d, robot03's laser forward and yaw, robot05's k_g


#: How much wider than its 95 % interval a figure may miss the truth by: to its 99.9 %
#: interval (3.29 instead of 1.96 standard errors), so that of the 20 figures checked
#: (5 robots x E_d, E_b, E_s, k_g), all of them independent, any one misses by chance in
#: at most 20 x 0.1 % = 2 % of fleets (Bonferroni), where the 95 % intervals themselves
#: would let two in three fleets fail (1 - 0.95^20 = 64 %).
WIDER = 3.29 / 1.96
#: The widest 95 % half-interval accepted [1], so that an interval cannot hold the truth
#: by being wide: one recording of 1.5 min gives E_d to about 8e-5 and E_b, E_s to about
#: 5.5e-4 (a standard error, as each day's calibration here states it); the fewest
#: recordings a latest state pools, three (a step's), give 1.96 x 8e-5 / sqrt(3) = 9e-5
#: for E_d and 1.96 x 5.5e-4 / sqrt(3) = 6.2e-4 for E_b and E_s. The bounds are about
#: twice those (room for scatter carried into an interval, and a trend's end, known less
#: well than its middle).
#: k_g: a recording's about 3e-4 (the laser's heading changes against the gyro's), a
#: step's three 1.96 x 3e-4 / sqrt(3) = 3.4e-4, bounded likewise at about twice.
WIDEST = {"E_d": 2e-4, "E_b": 1.5e-3, "E_s": 1.5e-3, "k_g": 8e-4}


@pytest.mark.slow
def test_the_latest_figures_are_each_robots_truth_within_their_intervals(
    fleet: Path,
    watched: tuple[dict, Path],  # type: ignore[type-arg]
):
    """E_d, E_b, E_s and the gyro's k_g of every robot, on its latest state: the steady
    figures pooled over all six days, robot02's E_d since its wheel was changed (day 4:
    pooled over all days it would be 0.003 off, some 60 standard errors), robot05's k_g
    since its gyro changed, robot04's E_s at the end of its wear (the mean of its days is
    2.5 days of wear, 0.002, higher) against the truth of the last day in
    ``truth.json``."""
    truth = json.loads((fleet / "truth.json").read_text())
    last = {r["robot"]: r for r in truth["recordings"] if r["day"] == "2026-11-07"}
    for day in last.values():
        day["k_g"] = day["imu"]["k_g"]
    assert sorted(last) == [f"robot{k:02d}" for k in range(1, ROBOTS + 1)]
    missed = []
    for robot in watched[0]["robots"]:
        for name in ("E_d", "E_b", "E_s", "k_g"):
            figure = robot["figures"][name]
            low, high = figure["interval_95"]
            half = 0.5 * (high - low)
            centre = 0.5 * (high + low)
            assert 0.0 < half <= WIDEST[name], (robot["robot"], name, half)
            assert figure["value"] == pytest.approx(centre, abs=1e-12)
            miss = abs(figure["value"] - last[robot["robot"]][name])
            if miss > WIDER * half:
                missed.append((robot["robot"], name, figure["value"], miss / half))
    assert missed == [], missed


@pytest.mark.slow
def test_a_recording_that_failed_and_then_was_calibrated_counts_once(fleet: Path, tmp_path: Path):
    """A recording that cannot be read (random bytes at its path) fails, and the page and
    the summary line say so; once its real bytes are there the next run calibrates it, and
    its robot has one recording, none failed."""
    import shutil

    folder = tmp_path / "fleet"
    recording = folder / "robot09" / "2026-11-08" / "drive.mcap"
    recording.parent.mkdir(parents=True)
    recording.write_bytes(bytes(range(256)) * 16)
    args = ["fleet", str(folder), "--robot-from", "{robot}/{date}/*", "--history",
            str(tmp_path / "h.sqlite3"), "--workers", "1", "--json", "--report",
            str(tmp_path / "fleet.html"), "--force"]  # fmt: skip
    first = run_cli(*args, timeout=600)
    assert first.returncode == 0, first.stderr
    data = json.loads(first.stdout)
    assert data["summary"] == (
        "1 robot: 0 changed beyond their intervals, 1 with no usable recording; 1 recording: "
        "0 calibrated, 1 failed"
    )
    page = (tmp_path / "fleet.html").read_text(encoding="utf-8")
    assert "Failed recordings (1)" in page
    assert f"{recording}: cannot read" in page
    shutil.copy(fleet / "robot01" / "2026-11-07" / "drive" / "drive.mcap", recording)
    again = run_cli(*args, timeout=600)
    assert again.returncode == 0, again.stderr
    data = json.loads(again.stdout)
    (robot,) = data["robots"]
    assert (robot["recordings"], robot["failed"], robot["usable"]) == (1, [], True)
    assert data["summary"].startswith(
        "1 robot: 0 changed beyond their intervals, 0 with no usable recording; 1 recording: "
        "1 calibrated; worst E_max,syst"
    )
    assert "Failed recordings" not in (tmp_path / "fleet.html").read_text(encoding="utf-8")


@pytest.mark.slow
def test_the_morning_after_a_change_and_the_morning_it_is_confirmed(fleet: Path, tmp_path: Path):
    """The fleet watched night by night: the morning after the wheel was changed and the
    laser knocked (day 4 of the recordings, 2026-11-05) both are flagged as changes in the
    latest recording, to be confirmed, and the robots' figures, E_max,syst and what to
    apply are that recording's alone; the next morning they are steps, confirmed by two."""
    import math

    from umbmark.core.conventions import Direction
    from umbmark.model.square import square_run_end

    truth = json.loads((fleet / "truth.json").read_text())
    history = tmp_path / "h.sqlite3"

    def night(last_day: int) -> dict:  # type: ignore[type-arg]
        proc = run_cli("fleet", f"{fleet}/*/2026-11-0[2-{last_day}]/*", "--robot-from",
                       "{robot}/{date}/*", "--history", str(history), "--workers", "2",
                       "--json", timeout=900)  # fmt: skip
        assert proc.returncode == 0, proc.stderr
        return json.loads(proc.stdout)  # type: ignore[no-any-return]

    morning = night(5)
    by = {r["robot"]: r for r in morning["robots"]}
    assert {"robot02", "robot03"} <= set(morning["unconfirmed"])
    assert "robot01" not in morning["drifted"]
    assert "in their latest recording, to be confirmed" in morning["summary"]
    wheel = by["robot02"]
    e_d = wheel["figures"]["E_d"]
    assert e_d["change"] == "latest"
    assert "2026-11-05" in e_d["since"]
    day4 = {r["robot"]: r for r in truth["recordings"] if r["day"] == "2026-11-05"}
    low, high = e_d["interval_95"]
    assert low <= day4["robot02"]["E_d"] <= high  # that recording's, never pooled
    assert e_d["value"] == e_d["values"][-1]
    assert e_d["size"] == pytest.approx(-0.006, abs=5 * e_d["size_standard_error"])
    # E_max,syst and what to apply are of the same present state (the square's end in
    # closed form, model.square, with the figures the report shows).
    present = {n: wheel["figures"][n]["value"] for n in ("E_d", "E_b", "E_s")}
    e_max = max(
        math.hypot(
            *square_run_end(present["E_d"], present["E_b"], present["E_s"], 4.0, 0.34, d)[:2]
        )
        for d in (Direction.CW, Direction.CCW)
    )
    assert wheel["e_max_syst"] == pytest.approx(e_max, rel=1e-9)
    apply = wheel["apply"]
    ratio = apply["right_wheel_radius_multiplier"] / apply["left_wheel_radius_multiplier"]
    assert ratio == pytest.approx(present["E_d"], rel=1e-9)
    assert apply["verdict"] == "care"
    assert any("latest recording alone" in r for r in apply["reasons"])
    assert by["robot03"]["figures"]["laser_yaw"]["change"] == "latest"
    # The next morning: both confirmed, as steps since 2026-11-05.
    confirmed = night(6)
    by = {r["robot"]: r for r in confirmed["robots"]}
    for robot, figure in (("robot02", "E_d"), ("robot03", "laser_yaw")):
        step = by[robot]["figures"][figure]
        assert step["change"] == "step", (robot, step["change"])
        assert "2026-11-05" in step["since"]
        assert step["confirmed_by"] == 2
    assert confirmed["recordings_skipped"] == ROBOTS * 4
    assert not any("latest recording alone" in r for r in by["robot02"]["apply"]["reasons"])


@pytest.mark.slow
def test_wheels_and_an_imu_alone_are_calibrated_by_the_gyro_apart_from_the_lasers(
    fleet: Path, tmp_path: Path
):
    """robot01's recordings as another robot's whose laser and motion capture were off
    after the first day (``/scan`` and ``/mocap/robot/pose`` left out of the bag): each
    day without them calibrated by the gyro alone, not left out, its E_d within its
    interval of the truth and its E_b relative to the gyro (E_b k_g) followed as a figure
    of its own, never in one course with the first day's E_b from the laser; the E_b
    offered is the laser's."""
    import shutil

    from robot_bags import without_topics

    truth = json.loads((fleet / "truth.json").read_text())
    days = sorted(p.name for p in (fleet / "robot01").iterdir())[:3]
    lab = tmp_path / "lab" / "robot06"
    for k, day in enumerate(days):
        (lab / day).mkdir(parents=True)
        source = fleet / "robot01" / day / "drive"
        if k == 0:
            shutil.copytree(source, lab / day / "drive")
        else:
            without_topics(source, lab / day / "drive", ["/scan", "/mocap/robot/pose"])
    proc = run_cli("fleet", str(tmp_path / "lab"), "--robot-from", "{robot}/{date}/*",
                   "--history", str(tmp_path / "h.sqlite3"), "--workers", "1", "--json",
                   timeout=600)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    (robot,) = data["robots"]
    figures = robot["figures"]
    assert robot["recordings"] == 3
    assert robot["left_out"] == []
    assert len(figures["E_b"]["values"]) == 1  # the laser's day alone
    assert len(figures["E_b_gyro"]["values"]) == 2  # the gyro's days
    assert len(figures["E_d"]["values"]) == 3
    assert len(figures["k_g"]["values"]) == 1
    true = {r["day"]: r for r in truth["recordings"] if r["robot"] == "robot01"}
    for day, value, se in zip(
        figures["E_d"]["paths"],
        figures["E_d"]["values"],
        figures["E_d"]["standard_errors"],
        strict=True,
    ):
        when = Path(day).parent.name
        assert abs(value - true[when]["E_d"]) < 3.29 * se, (day, value, se)
    # E_b relative to the gyro is the true E_b times the gyro's true k_g (E_s near 1)
    for value, se, day in zip(
        figures["E_b_gyro"]["values"],
        figures["E_b_gyro"]["standard_errors"],
        figures["E_b_gyro"]["paths"],
        strict=True,
    ):
        t = true[Path(day).parent.name]
        expected = t["E_b"] * t["imu"]["k_g"] / t["E_s"]
        assert abs(value - expected) < 3.29 * se + 2e-4, (value, expected, se)
    assert robot["apply"]["wheel_separation_multiplier"] == pytest.approx(
        figures["E_b"]["value"], rel=1e-12
    )
    assert all("E_b" not in flag.split(" ")[0] for flag in robot["flags"])

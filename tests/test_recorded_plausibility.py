"""Recorded sources (run logs, OptiOdom sessions) get the plausibility checks of runs tables:
wheels that never turn, ground truth that never moves, wheel jumps, runs without motion,
values that overflow and return errors larger than the side refuse with one clean line."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.model.kinematics import WheelParams
from umbmark.runs.load import LoadOptions, load_runs
from umbmark.sim.robot import SimRobot

from helpers import OPTIODOM, api_error, cli_error, session_log, simulated_session

SQUARE = OPTIODOM / "square" / "230620202042"  # the shared copy, or the bundled one
needs_data = pytest.mark.skipif(not SQUARE.is_dir(), reason="no OptiOdom data")


@pytest.fixture(scope="module")
def session():  # type: ignore[no-untyped-def]
    odo = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
    robot = SimRobot.with_errors(odo, E_d=1.004, E_b=1.02)
    return simulated_session(robot, ["cw", "cw", "ccw", "ccw"], side=1.0, rest=2.0)


def _load(folder: Path, **options: object) -> object:
    return load_runs(folder, "auto", LoadOptions(**options))  # type: ignore[arg-type]


def _optiodom(tmp_path: Path, name: str) -> Path:
    folder = tmp_path / name
    shutil.copytree(SQUARE, folder)
    return folder


def _rewrite_ticks(path: Path, change) -> None:  # type: ignore[no-untyped-def]
    rows = [line.split(",") for line in path.read_text().splitlines() if line.strip()]
    path.write_text("\n".join(",".join(r[:4] + change(r[4:6])) for r in rows) + "\n")


def test_simulated_log_has_no_new_note(tmp_path: Path, session) -> None:  # type: ignore[no-untyped-def]
    loaded = _load(session_log(tmp_path / "log", session, session[2]))
    assert len(loaded.runs) == 4  # type: ignore[attr-defined]
    assert loaded.notes == []  # type: ignore[attr-defined]


def test_wheels_that_never_turn(tmp_path: Path, session) -> None:  # type: ignore[no-untyped-def]
    times, counts, poses, ends = session
    folder = session_log(tmp_path / "log", (times, counts * 0, poses, ends), poses)
    assert api_error(_load, folder) == (
        f"{folder / 'session.csv'}: the wheels never turn (every wheel angle is constant): no "
        "motion to calibrate from; check the wheel columns or topic"
    )


def test_ground_truth_that_never_moves(tmp_path: Path, session) -> None:  # type: ignore[no-untyped-def]
    folder = session_log(tmp_path / "log", session, session[2] * 0 + 1.0)
    assert api_error(_load, folder) == (
        f"{folder / 'session.csv'}: the ground truth never moves (every pose is the same): "
        "check the ground-truth columns or topic"
    )


def test_a_wheel_jump_names_its_time(tmp_path: Path, session) -> None:  # type: ignore[no-untyped-def]
    times, counts, poses, ends = session
    jumped = counts + np.where(np.arange(times.size)[:, None] >= 300, [200000, 0], 0)
    folder = session_log(tmp_path / "log", (times, jumped, poses, ends), poses)
    assert api_error(_load, folder) == (
        f"{folder / 'session.csv'}: the left wheel jumps by 31.44 rad in one sample at 3.00 s "
        "(more than 10 rad): a corrupt sample or wrong encoder units"
    )


@pytest.mark.slow
def test_ticks_times_1e300_give_one_line(tmp_path: Path, session) -> None:  # type: ignore[no-untyped-def]
    times, counts, poses, ends = session
    folder = session_log(tmp_path / "log", (times, counts * 1e300, poses, ends), poses)
    message = cli_error("calibrate", str(folder))
    start = f"umbmark: error: {folder / 'session.csv'}: the left wheel jumps by "
    assert message.startswith(start)
    assert "rad in one sample at " in message
    assert "inf" not in message
    assert "nan" not in message


def test_a_run_without_motion(tmp_path: Path, session) -> None:  # type: ignore[no-untyped-def]
    folder = session_log(tmp_path / "log", session, session[2])
    message = api_error(_load, folder, split="windows", windows=[(0.0, 1.5), (2.0, 30.0)])
    assert message == (
        f"{folder / 'session.csv'} run 1: the wheels never turn (every wheel angle is "
        "constant): no motion to calibrate from; check the wheel columns or topic"
    )


@pytest.mark.slow
def test_return_error_larger_than_the_side_of_logged_runs(tmp_path: Path, session) -> None:  # type: ignore[no-untyped-def]
    # a wrong wheelbase in the metadata (0.25 m for 0.34 m): the odometry turns a third
    # too far and ends over a side from the truth
    folder = session_log(tmp_path / "log", session, session[2], wheelbase=0.25, side=1.0)
    message = api_error(umbmark.calibrate, folder, method="paper")
    match = re.fullmatch(
        rf"{re.escape(str(folder))}: the return error of session.csv run 2 \((\d\.\d+) m\) is "
        r"larger than the square's side \(1 m\), beyond the paper's small-angle formulas: "
        r"use method exact or endpose \(the exact geometry\)",
        message,
    )
    assert match is not None, message
    assert float(match[1]) > 1.0
    # a side of 0.3 m for these 1 m squares: the ground truth's legs refuse it first
    folder = session_log(tmp_path / "short", session, session[2], wheelbase=0.12, side=0.3)
    message = api_error(umbmark.calibrate, folder, method="paper")
    assert "side_length in " in message
    assert "0.3 m, but the reference's legs measure 1.00 m (median of 16 legs" in message


@needs_data
def test_optiodom_zero_ticks(tmp_path: Path) -> None:
    folder = _optiodom(tmp_path, "zero")
    _rewrite_ticks(folder / "230620202042_run-03.csv", lambda ticks: ["0", "0"])
    expected = (
        f"{folder / '230620202042_run-03.csv'}: the wheels never turn (every wheel angle is "
        "constant): no motion to calibrate from; check the wheel columns or topic"
    )
    assert api_error(umbmark.calibrate, folder) == expected
    assert cli_error("calibrate", str(folder)) == f"umbmark: error: {expected}\n"


@needs_data
def test_optiodom_tiny_encoder_resolution(tmp_path: Path) -> None:
    # The metadata's encRes gets the bounds of umbmark simulate --encoder-resolution.
    folder = _optiodom(tmp_path, "enc")
    meta = folder / "230620202042_metadata.csv"
    meta.write_text(meta.read_text().replace("encRes,64", "encRes,1e-300"))
    assert api_error(_load, folder) == f"{meta}: encRes must be 1 to 1e+07, got 1e-300"


@needs_data
def test_optiodom_overflowing_wheel_angles(tmp_path: Path) -> None:
    folder = _optiodom(tmp_path, "overflow")
    _rewrite_ticks(
        folder / "230620202042_run-01.csv", lambda ticks: [str(float(t) * 1e306) for t in ticks]
    )
    message = api_error(_load, folder)
    assert message.startswith(f"{folder / '230620202042_run-01.csv'}: wheel angles overflow: ")
    assert message.endswith("are not finite numbers")


@pytest.mark.slow
@needs_data
def test_real_sessions_calibrate_without_new_warnings() -> None:
    for folder in sorted(p for p in OPTIODOM.glob("*/*") if p.is_dir()):
        loaded = _load(folder)
        assert loaded.notes == [], folder  # type: ignore[attr-defined]
    report = umbmark.calibrate(SQUARE)
    assert not any("jump" in w or "never" in w for w in (*report.warnings, *report.notes))

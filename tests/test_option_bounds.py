"""Every option bounded (issue 10, item 2): the work an option asks for has a documented
upper bound, refused in the library with a line naming the option (as a keyword to a
Python caller, as the command spells it on the command line) and the range; the
command's --help states the bound; huge and tiny values of the parameter options give
that line and nothing else (no numpy warning first)."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import click
import pytest

import umbmark
from umbmark.jobs import info as info_job
from umbmark.jobs import simulate, study
from umbmark.jobs.calibrate import calibrate
from umbmark.jobs.validate import validate
from umbmark.options import reproduce
from umbmark.options import spec as read_options
from umbmark.sim import setup

from helpers import api_error, cli_error, run_cli

SEED_TOP = 2**63 - 1
RUNS = "runs must be 2 to 1000, got "
SEEDS = f"seed must be 0 to {SEED_TOP}, got "
FACTOR = "is not a plausible factor: it must be within"


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Run logs of a virtual robot: 2 + 2 runs on a 2 m square, b = 0.34 m."""
    path = tmp_path_factory.mktemp("bounds") / "logs"
    umbmark.simulate(E_d=1.004, E_b=1.02, runs=2, side_length=2, dt=0.02, logs=path)
    return path


# --- the library refuses, naming the option and its range -----------------------------


@pytest.mark.parametrize(
    ("call", "kwargs", "message"),
    [
        (umbmark.demo, {"runs": 1_000_000}, RUNS + "1000000"),
        (umbmark.demo, {"runs": 2**63}, RUNS + "9223372036854775808"),
        (umbmark.demo, {"runs": 10**400}, RUNS + "a number of 401 digits"),
        (umbmark.demo, {"runs": 2.5}, "runs must be a whole number, not '2.5'"),
        (umbmark.demo, {"seed": -1}, SEEDS + "-1"),
        (umbmark.study, {"seed": -1, "trials": 1}, SEEDS + "-1"),
        (umbmark.study, {"trials": 50_000, "side_length": [2.0, 3.0, 4.0]},
         "trials=50000 in 3 grid cells are 150000 robots: at most 100000 in all"),
        (umbmark.study, {"slip": [0.0] * 21}, "slip must list 1 to 20 values, got 21"),
        (umbmark.study, {"wheelbase": []}, "wheelbase must list 1 to 20 values, got 0"),
        (umbmark.study, {"workers": 0}, "workers must be 1 to 64, got 0"),
        (umbmark.study, {"E_d_spread": math.nan}, "E_d_spread must be a finite number, got nan"),
        (umbmark.study, {"slip": ["abc"]}, "slip must be a number, not 'abc'"),
        (umbmark.reproduce_table1, {"seeds": 1_000_000}, "seeds must be 1 to 1000, got 1000000"),
        (umbmark.reproduce_table1, {"seed": -1}, f"seed must be 0 to {SEED_TOP}"),
        (umbmark.reproduce_table1, {"tape_thickness": 0.5e-3},
         "tape_thickness=0.0005 m: give more than 0 and at most 0.3 mm"),
        (umbmark.reproduce_fig4, {"leg_bend": "x"}, "leg_bend must be a number, not 'x'"),
    ],
)  # fmt: skip
def test_work_options_are_refused_beyond_their_bound(
    call: Any, kwargs: dict[str, Any], message: str
) -> None:
    assert message in api_error(call, **kwargs)


def test_info_sampling_is_bounded(logs: Path) -> None:
    assert info_job.MAX_MESSAGES == 1_000_000
    line = api_error(umbmark.info, logs, max_messages=1_000_001)
    assert "max_messages=1000001: must be at least 1 and at most 1000000" in line
    assert umbmark.info(logs, max_messages=1_000_000).format == "log"  # the bound itself


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("max_gap", 61.0, "max_gap must be at most 60 s, got 61 s"),
        ("max_gap", 1e308, "max_gap must be at most 60 s, got 1e+308 s"),
        ("min_rest", 601.0, "min_rest must be at most 600 s, got 601 s"),
    ],
)
def test_reading_options_are_refused_beyond_their_bound(
    logs: Path, option: str, value: float, message: str
) -> None:
    assert message in api_error(umbmark.calibrate, logs, **{option: value})


def test_reading_options_at_their_bound_are_taken(logs: Path) -> None:
    report = umbmark.calibrate(
        logs, max_gap=read_options.LONGEST_GAP, min_rest=read_options.LONGEST_REST
    )
    assert len(report.runs) == 4


@pytest.mark.slow
def test_seeds_at_their_bound_are_taken() -> None:
    assert umbmark.study(trials=1, methods=["exact"], seed=SEED_TOP, workers=64).seed == SEED_TOP


# --- the simulator's work and memory ----------------------------------------------------

# A square of side L: 4 L of legs at --speed, and 4 quarter turns on the spot, each wheel
# on an arc of (pi / 2)(b / 2) at 0.2 m/s: (4 L / v + 2 pi (b / 2) / 0.2) / dt periods.


def _periods(side: float, speed: float, dt: float, b: float = 0.34) -> float:
    return (4 * side / speed + 2 * math.pi * (b / 2) / 0.2) / dt


def test_a_run_longer_than_two_million_periods_is_refused() -> None:
    expected = _periods(100, 0.01, 1e-4)  # 4.0005e8
    line = api_error(umbmark.simulate, side_length=100, speed=0.01, dt=1e-4)
    assert f"takes about {expected:.3g} sampling periods: at most 2e+06" in line
    assert "raise speed or dt" in line


def test_all_runs_together_are_bounded() -> None:
    per_run = _periods(4, 0.2, 1e-4)  # 8.53e5: allowed for one run, not for 2000
    assert per_run < setup.MAX_SAMPLES_PER_RUN
    line = api_error(umbmark.simulate, runs=1000, dt=1e-4)
    assert f"2000 runs of about {per_run:.3g} sampling periods each are more than 1e+09" in line


def test_recording_is_bounded_by_memory(tmp_path: Path) -> None:
    per_run = _periods(4, 0.2, 0.01)  # 8534
    line = api_error(umbmark.simulate, runs=1000, logs=tmp_path / "logs")
    assert f"keeping the time series of 2000 runs of about {per_run:.3g} samples" in line
    assert f"needs {2000 * per_run * 130 / 1e9:.1f} GB" in line
    assert not (tmp_path / "logs").exists()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        # 1 pulse x 0.001: a count per thousand wheel revolutions.
        ({"encoder_resolution": 1, "gear_ratio": 0.001},
         "is 0.001 encoder counts per wheel revolution: at least 16"),
        # One count: pi 0.15 m / 40000 = 0.01178 mm; a 0.01 deg turn moves each wheel
        # (0.01 pi / 180)(0.17 m) = 0.02967 mm: 2.52 counts.
        ({"path": "turn", "turn_angle": math.radians(0.01)},
         "turn_angle=0.000174533 rad is 2.52 encoder counts of wheel travel: at least 20"),
        # 20 counts per revolution: a count is pi 0.15 / 20 = 23.6 mm; 0.4 m is 17 counts.
        ({"encoder_resolution": 1, "gear_ratio": 20, "side_length": 0.4},
         "side_length=0.4 m is 17 encoder counts of wheel travel: at least 20 (one count "
         "is 23.6 mm)"),
    ],
)  # fmt: skip
def test_encoders_too_coarse_for_the_path_are_refused(kwargs: dict[str, Any], message: str) -> None:
    assert message in api_error(umbmark.simulate, speed=1.0, dt=0.05, runs=2, **kwargs)


# --- the command line: one line, the bound in --help -------------------------------------


def _help(*path: str) -> str:
    proc = run_cli(*path, "--help")
    assert proc.returncode == 0, proc.stderr
    return " ".join(proc.stdout.split())


@pytest.mark.slow
def test_help_states_the_bounds() -> None:
    assert f"(2 to {simulate.MAX_RUNS})" in _help("demo")
    assert f"(1 to {simulate.MAX_RUNS};" in _help("simulate")
    text = _help("study")
    assert f"(1 to {study.MAX_TRIALS}, and {study.MAX_ROBOTS} in all cells)" in text
    assert f"at most {study.MAX_GRID_VALUES} each" in text
    text = _help("reproduce", "table1")
    assert f"1 to {reproduce.MAX_SEEDS}" in text
    assert f"at most {reproduce.MAX_TAPE_THICKNESS * 1000:g})" in text
    text = _help("calibrate")
    assert f"at most {read_options.LONGEST_GAP:g}." in text
    assert f"at most {read_options.LONGEST_REST:g}." in text


def test_info_max_messages_range_is_the_librarys() -> None:
    from umbmark.cli.info import info as info_command

    (param,) = [p for p in info_command.params if p.name == "max_messages"]
    assert isinstance(param.type, click.IntRange)
    assert param.type.max == info_job.MAX_MESSAGES


def test_a_click_range_error_is_one_line_naming_the_flag(logs: Path) -> None:
    line = cli_error("info", str(logs), "--max-messages", "2000000")
    assert "'--max-messages'" in line
    assert "1<=x<=1000000" in line


def test_a_huge_value_is_not_echoed_whole() -> None:
    line = cli_error("study", "--trials", "7" * 100_000)
    assert len(line) < 1100
    assert "characters left out" in line
    assert "'--trials'" in line


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--current-separation-multiplier", "1e308", FACTOR),
        ("--current-c-l", "1e-308", FACTOR),
        ("--current-c-r", "-1e308", FACTOR),
        ("--wheel-diameter", "1e308", "m is implausibly large"),
        ("--wheelbase", "5e-324", "m is implausibly small"),
        ("--side-length", "1e308", "m is implausibly large"),
    ],
)  # fmt: skip
def test_huge_and_tiny_parameters_give_one_line_and_no_warning(
    tmp_path: Path, option: str, value: str, message: str
) -> None:
    table = tmp_path / "runs.csv"
    umbmark.example(table)
    env = {**os.environ, "PYTHONWARNINGS": "error"}  # a numpy RuntimeWarning would fail
    args = ["calibrate", str(table), "-L", "4", "-b", "0.34", "--unit", "mm", option, value]
    proc = run_cli(*args, env=env)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith(f"umbmark: error: {option} ")
    assert message in proc.stderr


# --- --override-verdict reaches the validation of --method auto ----------------------------------


@pytest.fixture(scope="module")
def other_result(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The result of another robot: nominal wheelbase 0.5 m, wheel diameter 0.2 m."""
    folder = tmp_path_factory.mktemp("other")
    umbmark.simulate(wheelbase=0.5, wheel_diameter=0.2, runs=2, side_length=2, dt=0.02,
                     logs=folder / "logs")  # fmt: skip
    umbmark.calibrate(folder / "logs", output=folder / "result.json")
    return folder / "result.json"


@pytest.mark.slow
def test_override_reaches_the_validation_of_method_auto(logs: Path, other_result: Path) -> None:
    # Without --override-verdict: the other robot's result is refused, by auto as by any
    # method.
    for method in ("exact", "auto"):
        line = api_error(calibrate, logs, method=method, current_params=other_result)
        assert "nominal wheelbase of 0.5 m" in line
        assert "give --override-verdict" in line
    # With it, auto validates on the runs as read with it, and calibrates as the method
    # it chose does with it.
    report = calibrate(logs, method="auto", current_params=other_result, override_verdict=True)
    checked = validate(logs, current_params=other_result, override_verdict=True)
    chosen = checked.recommended or "exact"
    assert report.estimate.method == chosen
    same = calibrate(logs, method=chosen, current_params=other_result, override_verdict=True)
    assert report.estimate.E_d == same.estimate.E_d
    assert report.estimate.E_b == same.estimate.E_b
    assert any(note.startswith(f"method auto: {chosen}") for note in report.notes)


@pytest.mark.slow
def test_validate_takes_the_override_too(logs: Path, other_result: Path) -> None:
    line = cli_error("validate", str(logs), "--current-params", str(other_result))
    assert "give --override-verdict" in line
    args = ("validate", str(logs), "--current-params", str(other_result))
    proc = run_cli(*args, "--override-verdict")
    assert proc.returncode == 0, proc.stderr

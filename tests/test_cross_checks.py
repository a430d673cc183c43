"""Cross-checks of the options against each other and against the sources (issue 10):
implausible parameters, a square smaller than the robot, results of another robot."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import umbmark

from helpers import api_error, cli_error, cli_json, session_log, simulated_session


@pytest.fixture(scope="module")
def runs_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("table") / "runs.csv"
    umbmark.example(path)
    return path


TABLE = {"side_length": 4.0, "wheelbase": 0.34, "unit": "mm"}


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("current_c_l", 1e300, "current_c_l=1e+300 is not a plausible factor"),
        ("current_c_r", 0.01, "current_c_r=0.01 is not a plausible factor"),
        ("current_separation_multiplier", 1e308, "current_separation_multiplier=1e+308"),
        ("wheel_diameter", 1e-300, "wheel_diameter=1e-300 m is implausibly small"),
        ("wheel_diameter", 150.0, "wheel_diameter=150 m is implausibly large"),
        ("wheelbase", 1e-300, "wheelbase=1e-300 m is implausibly small"),
    ],
)
def test_implausible_parameters_are_refused_with_the_range(
    runs_csv: Path, option: str, value: float, expected: str
) -> None:
    message = api_error(umbmark.calibrate, runs_csv, **{**TABLE, option: value})
    assert expected in message
    assert ("0.2 to 5" if option.startswith("current") else "0.001 to 10 m") in message


def test_a_nan_parameter_is_refused_as_no_finite_number(runs_csv: Path) -> None:
    options = {**TABLE, "current_separation_multiplier": math.nan}
    message = api_error(umbmark.calibrate, runs_csv, **options)
    assert message == "current_separation_multiplier must be a finite number, got nan"


@pytest.mark.slow
def test_cli_refuses_huge_multiplier_without_numpy_warnings(runs_csv: Path) -> None:
    line = cli_error(
        "calibrate", str(runs_csv), "-L", "4", "-b", "0.34", "--unit", "mm",
        "--current-separation-multiplier", "1e308",
    )  # fmt: skip
    assert "0.2 to 5" in line
    assert "RuntimeWarning" not in line
    line = cli_error("calibrate", str(runs_csv), "-L", "4", "-b", "1e-300", "--unit", "mm")
    assert "implausibly small" in line


def test_wheelbase_not_smaller_than_the_square_is_refused(runs_csv: Path) -> None:
    line = cli_error("calibrate", str(runs_csv), "-L", "0.5", "-b", "3")
    assert "--wheelbase 3 m is not smaller than the square" in line
    assert "b < 0.25 m" in line
    message = api_error(umbmark.calibrate, runs_csv, side_length=1.0, wheelbase=0.5, unit="mm")
    assert "not smaller than the square" in message


def test_reported_factors_are_positive_and_finite(runs_csv: Path) -> None:
    result = cli_json("calibrate", str(runs_csv), "-L", "4", "-b", "0.34", "--unit", "mm")
    new = result["new"]
    for key in ("c_L", "c_R", "wheelbase", "wheel_separation_multiplier"):
        assert math.isfinite(new[key]), (key, new[key])
        assert new[key] > 0, (key, new[key])


def test_negative_factors_are_refused_not_reported(tmp_path: Path) -> None:
    """Runs whose return errors ask for a negative wheel (E_d <= 0) are refused."""
    from umbmark.calibration.compose import Calibration, check_calibration
    from umbmark.estimators.base import ErrorEstimate
    from umbmark.model.active import ActiveParams

    estimate = ErrorEstimate("exact", 0.0, 0.0, -2.3, 1.0)
    calibration = Calibration(estimate, ActiveParams(wheelbase=0.34))
    message = api_error(check_calibration, calibration)
    assert "E_d = -2.3" in message
    assert "check --side-length, --wheelbase and the runs' units" in message
    # Where no square was driven (scan matching, a trajectory fit) its side is not named.
    for method in ("scan-matching", "trajectory"):
        driven = Calibration(ErrorEstimate(method, 0.0, 0.0, -2.3, 1.0), calibration.active)
        message = api_error(check_calibration, driven)
        assert message.startswith("the recording gives E_d = -2.3, which no robot can have")
        assert "side" not in message
        assert "check --wheelbase, --wheel-diameter and the wheels' readings" in message
    # Parameters a run log's metadata gave are named by field and file, not as options.
    from umbmark.core.bounds import Origin

    meta = str(tmp_path / "metadata.yaml")
    origins = {"wheelbase": Origin("wheelbase", meta), "side_length": Origin("side_length", meta)}
    message = api_error(check_calibration, calibration, origins)
    assert f"check side_length in {meta}, wheelbase in {meta} and the runs' units" in message
    assert "--" not in message


# --- results of another robot ----------------------------------------------------------


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Two run logs of one simulated session: with the robot's nominal wheelbase (0.34 m)
    and as if another robot's (0.5 m); and a result computed on the first."""
    from umbmark.model.kinematics import WheelParams
    from umbmark.sim.robot import SimRobot

    base = tmp_path_factory.mktemp("logs")
    odo = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
    robot = SimRobot.with_errors(odo, E_d=1.004, E_b=1.02)
    session = simulated_session(robot, ["cw", "cw", "ccw", "ccw"], side=1.0, rest=2.0)
    ours = session_log(base / "ours", session, session[2], wheelbase=0.34)
    other = session_log(base / "other", session, session[2], wheelbase=0.5)
    result = base / "result.json"
    umbmark.calibrate(ours, output=result)
    return {"ours": ours, "other": other, "result": result}


def test_result_matches_its_own_source(logs: dict[str, Path]) -> None:
    data = json.loads(logs["result"].read_text())
    assert data["active"]["wheelbase"] == pytest.approx(0.34)
    report = umbmark.replay(logs["ours"], logs["result"])
    assert "calibrated" in report.parameter_sets


@pytest.mark.slow
def test_replay_refuses_result_of_another_robot(logs: dict[str, Path]) -> None:
    message = api_error(umbmark.replay, logs["other"], logs["result"])
    assert "0.34 m" in message
    assert "0.5 m" in message
    assert "override_verdict=True" in message
    line = cli_error("replay", str(logs["other"]), "--params", str(logs["result"]))
    assert "nominal wheelbase of 0.34 m" in line
    assert "has 0.5 m" in line
    assert "give --override-verdict" in line
    # --force replaces files; it does not lift the check (issue 21: one meaning each).
    assert "has 0.5 m" in api_error(umbmark.replay, logs["other"], logs["result"], force=True)
    forced = ("replay", str(logs["other"]), "--params", str(logs["result"]), "--force")
    assert "give --override-verdict" in cli_error(*forced)
    report = umbmark.replay(logs["other"], logs["result"], override_verdict=True)
    assert "calibrated" in report.parameter_sets
    args = ("replay", str(logs["other"]), "--params", str(logs["result"]), "--override-verdict")
    assert cli_json(*args)


@pytest.mark.slow
def test_calibrate_refuses_current_params_of_another_robot(logs: dict[str, Path]) -> None:
    message = api_error(umbmark.calibrate, logs["other"], current_params=logs["result"])
    assert "0.34 m" in message
    assert "0.5 m" in message
    line = cli_error("calibrate", str(logs["other"]), "--current-params", str(logs["result"]))
    assert "more than 1 % apart" in line
    assert line.endswith("give --override-verdict to use it anyway\n")
    # --force replaces files; it does not take another robot's parameters.
    args = ("calibrate", str(logs["other"]), "--current-params", str(logs["result"]))
    assert cli_error(*args, "--force") == line
    forced = api_error(umbmark.calibrate, logs["other"], current_params=logs["result"], force=True)
    assert forced.endswith("give override_verdict=True to use it anyway")
    report = umbmark.calibrate(logs["other"], current_params=logs["result"], override_verdict=True)
    assert report.calibration.new_c_left > 0
    # the result's own source is fine
    assert umbmark.calibrate(logs["ours"], current_params=logs["result"]).runs


def test_wheel_diameter_of_another_robot_is_refused(logs: dict[str, Path], tmp_path: Path) -> None:
    data = json.loads(logs["result"].read_text())
    data["active"]["wheel_diameter"] = 0.2
    other = tmp_path / "bigger_wheels.json"
    other.write_text(json.dumps(data))
    message = api_error(umbmark.replay, logs["ours"], other)
    assert "wheel diameter of 0.2 m" in message
    assert "0.15 m" in message
    # within 1 %: the same robot
    data["active"]["wheel_diameter"] = 0.1505
    other.write_text(json.dumps(data))
    assert umbmark.replay(logs["ours"], other).parameter_sets

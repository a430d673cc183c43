"""A wheel diameter a power of ten off (issue 35, item 5).

- Scan matching measures the wheels' diameter against the laser: a diameter given ten or
  a hundred times off comes out as ``E_s`` of 0.1 or 10 (true over given), a unit or
  decimal-point slip, "do not apply" (exit status 4) naming the ``--wheel-diameter`` meant.
  A diameter ten times too large used to start every match from ten times the motion, and
  the calibration then failed with "check --side-length" where no square was driven.
- A square test does not observe the wheels' mean diameter: a diameter ten times off used
  to print wheels of 1.5 m with "apply". It warns now, naming the option, and the verdict
  is "apply with care" (the multipliers, from the return errors, do not depend on it).
- Recorded runs read with a diameter ten times too small used to be refused as turning
  errors beyond the square test; the refusal names the diameter first.

The expected figures are derived by hand from the simulated truth (the virtual robot's
wheels: 0.15 m, or ``scan_sim``'s), not from the code under test.
"""

from __future__ import annotations

import json
import math
import re
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.calibration.verdict import Evidence, judge
from umbmark.core.conventions import Direction
from umbmark.estimators.base import ErrorEstimate, SquareTest
from umbmark.estimators.scale import observed_scale
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog
from umbmark.model.run import EndPose, Run

from helpers import api_error, cli_error, run_cli

#: The virtual robot's wheels (``umbmark simulate``'s, with E_s = 1): 0.15 m, on 0.34 m.
DIAMETER, WHEELBASE = 0.15, 0.34
SQUARE = {"side_length": 2.0, "runs": 3, "dt": 0.02, "E_d": 1.004, "E_b": 0.98}


# --- the verdict: E_s a power of ten is a unit slip --------------------------------------


@pytest.mark.parametrize(
    ("E_s", "given", "meant", "said"),
    [
        (0.1, 1.5, 0.15, "the wheel diameter given, 1.5 m, is 10 times the wheels'"),
        (10.0, 0.015, 0.15, "the wheel diameter given, 0.015 m, is a tenth of the wheels'"),
        (100.0, 0.0015, 0.15, "is a hundredth of the wheels'"),
        (0.01, 6.6, 0.066, "is 100 times the wheels' (E_s = 0.0100"),  # 6.6 cm as metres
    ],
)
def test_a_scale_of_a_power_of_ten_is_a_unit_slip_not_to_apply(E_s, given, meant, said):
    estimate = ErrorEstimate("scan-matching", 0.0, 0.0, 1.0, 1.0, E_s=E_s)
    verdict = judge(estimate, SquareTest(1.0, WHEELBASE), Evidence(wheel_diameter=given))
    assert verdict.level == "do-not-apply"
    assert said in verdict.reasons[0]
    if E_s == 0.01:
        assert "a diameter in centimetres, not metres" in verdict.reasons[0]
    assert (
        verdict.instead
        == f"calibrate again with --wheel-diameter {meant:g}, the diameter in metres"
    )
    assert "side" not in verdict.line()


@pytest.mark.parametrize("E_s", [1.12, 1.3, 0.7, 2.0])
def test_a_scale_no_power_of_ten_explains_is_applied_with_care(E_s):
    # tyres (12 %), a scale 30 % off (no factor of ten within 15 %), a radius (2): care
    estimate = ErrorEstimate("scan-matching", 0.0, 0.0, 1.0, 1.0, E_s=E_s)
    verdict = judge(estimate, SquareTest(1.0, WHEELBASE), Evidence(wheel_diameter=0.15))
    assert verdict.level == "care"
    assert "unit or decimal-point slip" not in verdict.line()


# --- the scale a ground truth shows -------------------------------------------------------


def _straight(given: float, jitter: float = 0.0) -> Run:
    """A straight run by hand: 10 s at 0.2 m/s on wheels of 0.15 m (each turning
    0.2 / 0.075 rad/s), 50 Hz, the ground truth along x with ``jitter`` [m] of noise."""
    time = np.arange(0.0, 10.0 + 1e-9, 0.02)
    angle = 0.2 * time / 0.075
    truth = np.column_stack([0.2 * time, np.zeros_like(time), np.zeros_like(time)])
    truth[1:, :2] += np.random.default_rng(5).normal(0.0, jitter, (len(time) - 1, 2))
    log = RunLog(time=time, wheel_angles=np.column_stack([angle, angle]), truth=truth)
    end = EndPose(2.0, 0.0, 0.0)
    return Run(Direction.CCW, end, EndPose(2.0 * given / 0.15, 0.0, 0.0), "straight", log=log)


@pytest.mark.parametrize(("given", "scale"), [(1.5, 0.1), (0.015, 10.0), (0.15, 1.0)])
def test_the_ground_truths_path_against_the_odometrys_is_the_scale(given, scale):
    # odometry: given / 2 x 0.2 t / 0.075 = (given / 0.15) x 0.2 t; truth 0.2 t
    params = WheelParams(wheelbase=WHEELBASE, wheel_diameter=given)
    assert observed_scale([_straight(given)], params) == pytest.approx(scale, rel=1e-9)
    # 2 mm of jitter at 50 Hz would add about 14 % to a path summed sample by sample;
    # sampled every 0.5 s (0.1 m), at most 0.04 x 2 mm^2 ... under 1 %
    noisy = observed_scale([_straight(given, jitter=0.002)], params)
    assert noisy == pytest.approx(scale, rel=0.01)
    # a truth known at fewer than half the samples (at the stops only) says nothing
    sparse = _straight(given)
    assert sparse.log is not None
    sparse.log.truth[1:-1:3] = np.nan  # one in three unknown: still two in three known
    assert observed_scale([sparse], params) == pytest.approx(scale, rel=1e-9)
    sparse.log.truth[1:-1] = np.nan  # the ends only
    assert observed_scale([sparse], params) is None


# --- square tests: a runs table ------------------------------------------------------------


#: The bundled table (``umbmark example``): 5 + 5 runs of a LabMate on a 4 m square, mm.
EXAMPLE = str(resources.files("umbmark.data").joinpath("labmate_runs_mm.csv"))


def test_a_tables_diameter_ten_times_off_warns_and_is_not_plainly_applied():
    path = EXAMPLE
    given = {"side_length": 4, "wheelbase": WHEELBASE, "unit": "mm"}
    good = umbmark.calibrate(path, **given, wheel_diameter=DIAMETER)
    assert good.verdict.level == "apply"
    assert good.warnings == ()
    for wrong, ratio, side in ((1.5, "4.41", "large"), (0.015, "0.0441", "small")):
        report = umbmark.calibrate(path, **given, wheel_diameter=wrong)
        (warning,) = report.warnings
        # 1.5 / 0.34 = 4.41; 0.015 / 0.34 = 0.0441; 0.15 / 0.34 = 0.44, typical
        assert warning.startswith(
            f"the wheel diameter {wrong:g} m (--wheel-diameter) is implausible"
        )
        assert f"no differential drive has wheels {ratio} times its wheelbase (0.34 m" in warning
        assert f"too {side} by about a power of ten" in warning
        assert "(--wheel-diameter 0.15 would be 0.44 times it)" in warning
        assert "does not observe the wheels' mean diameter (E_s)" in warning
        assert report.verdict.level == "care"
        # what it does not change: the multipliers, from the return errors alone
        cal = report.calibration
        assert cal.new_c_left == good.calibration.new_c_left
        assert cal.new_c_right == good.calibration.new_c_right
        assert cal.new_separation_multiplier == good.calibration.new_separation_multiplier
        # what it does: the wheels printed, c_L D
        assert cal.wheel_diameter_left == pytest.approx(cal.new_c_left * wrong, rel=1e-12)


@pytest.mark.slow
def test_the_command_warns_naming_the_option_and_its_file(tmp_path):
    path = EXAMPLE
    proc = run_cli("calibrate", path, "-L", "4", "-b", "0.34", "--unit", "mm",
                   "--wheel-diameter", "1.5")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "umbmark: warning: the wheel diameter 1.5 m (--wheel-diameter) is implausible" in (
        proc.stderr
    )
    assert "Verdict: apply with care" in proc.stdout
    # the same diameter from a parameter file: its wheel_radius named
    params = tmp_path / "controllers.yaml"
    params.write_text(
        "diff_drive_controller:\n  ros__parameters:\n    wheel_separation: 0.34\n"
        "    wheel_radius: 0.75\n"
    )
    proc = run_cli("calibrate", path, "-L", "4", "--unit", "mm", "--current-params",
                   str(params))  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert f"the wheel diameter 1.5 m (twice wheel_radius in {params}) is implausible" in (
        proc.stderr
    )


# --- square tests: recorded runs -------------------------------------------------------------


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Run logs of the virtual robot (wheels 0.15 m): 3 + 3 runs on a 2 m square."""
    path = tmp_path_factory.mktemp("diameter") / "logs"
    umbmark.simulate(**SQUARE, wheel_diameter=DIAMETER, logs=path)  # type: ignore[arg-type]
    return path


@pytest.mark.slow
def test_recorded_runs_with_a_diameter_ten_times_too_large_name_the_one_meant(logs):
    # The ground truth moves 0.15 / 1.5 = 0.1 times as far as the odometry integrated
    # with 1.5 m wheels says: the wheels are 0.15 m.
    report = umbmark.calibrate(logs, wheel_diameter=1.5)
    (warning,) = report.warnings
    assert "the ground truth moved 0.1 times as far as the odometry integrated with it" in warning
    assert "the wheels are 0.15 m (--wheel-diameter 0.15)" in warning
    assert "and the odometry the runs were integrated with" in warning
    assert report.verdict.level == "care"
    assert umbmark.calibrate(logs, wheel_diameter=DIAMETER).warnings == ()


@pytest.mark.slow
def test_recorded_runs_with_a_diameter_ten_times_too_small_are_refused_naming_it(logs):
    # Read with 0.015 m, every 90 degree turn is 9 degrees in the odometry: no square. The
    # refusal says so first, before the turning errors it would otherwise name.
    line = api_error(umbmark.calibrate, logs, wheel_diameter=0.015)
    cause = line.index("the wheel diameter given, 0.015 m, is a tenth of the wheels'")
    assert "(read with 10 times that, the runs are squares a robot drives" in line
    assert "pass wheel_diameter=0.15, the diameter in metres" in line  # the library's keyword
    assert cause < line.index("Calibrate the turning coarsely first")
    command = cli_error("calibrate", str(logs), "--wheel-diameter", "0.015")
    assert "pass --wheel-diameter 0.15, the diameter in metres" in command


@pytest.mark.slow
def test_a_trajectory_fit_that_stays_at_its_start_is_no_reading(logs):
    # Read with twice the diameter (0.3 m), the trajectory fit fails; it was retried with
    # twice that again (0.6 m), where the fit stays at its start (E_s = 1, metres off the
    # ground truth) and was taken for the right reading: "pass --wheel-diameter 0.6".
    line = api_error(umbmark.calibrate, logs, wheel_diameter=0.3, method="trajectory")
    assert "looks like twice the wheels' diameter" in line
    assert "pass wheel_diameter=0.15, half of it" in line


# --- scan matching --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def room(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """docs/scan-matching.md's bag: 2 + 2 runs of a 1 m square in a room, /scan at 10 Hz,
    the robot's wheels 0.15 m (E_s = 1) in its robot description."""
    pytest.importorskip("rosbags")
    bag = tmp_path_factory.mktemp("room") / "room.bag"
    made = run_cli("simulate", "--E-d", "1.002", "--E-b", "1.01", "-L", "1", "--runs", "2",
                   "--seed", "3", "--dt", "0.02", "--bag", str(bag), "--scan")  # fmt: skip
    assert made.returncode == 0, made.stderr
    return bag


@pytest.mark.slow
@pytest.mark.parametrize(("given", "E_s"), [(1.5, 0.1), (0.015, 10.0), (0.0015, 100.0)])
def test_scan_matching_with_a_diameter_a_power_of_ten_off_is_not_applied(room, given, E_s):
    # E_s is the wheels' mean diameter over the one given: 0.15 / given.
    args = ("calibrate", str(room), "--scan-topic", "/scan", "--wheel-diameter", f"{given:g}")
    proc = run_cli(*args)
    assert proc.returncode == 4, proc.stderr  # a result, not to apply
    verdict = next(line for line in proc.stdout.splitlines() if line.startswith("Verdict: "))
    assert verdict.startswith(f"Verdict: do not apply: the wheel diameter given, {given:g} m,")
    assert verdict.endswith(
        "Instead: calibrate again with --wheel-diameter 0.15, the diameter in metres."
    )
    assert "side-length" not in proc.stdout + proc.stderr
    data = json.loads(run_cli(*args, "--json").stdout)
    se = data["standard_errors"]
    assert abs(data["E_s"] - E_s) < 4 * se["E_s"], (data["E_s"], se["E_s"])
    # the wheels measured are the robot's, 0.15 m x 2 / (1 + E_d) and E_d times that
    left = 2 * DIAMETER / (1 + 1.002)
    assert abs(data["wheel_diameter_left"] - left) < 4 * se["wheel_diameter_left"]
    assert data["verdict"]["level"] == "do-not-apply"


@pytest.mark.slow
def test_scan_matching_from_ten_times_the_motion_matches_from_the_sweeps_alone(room):
    # With 1.5 m wheels every match started from ten times the motion: most failed, and
    # the calibration was refused ("c_L = -0.78 ... check --side-length"). The guess is
    # given up, said in a warning, and the sweeps alone give the motion.
    report = umbmark.calibrate(room, scan_topic="/scan", wheel_diameter=1.5)
    (gave_up,) = [w for w in report.warnings if "matched from the sweeps alone" in w]
    # the laser moves 0.15 / 1.5 = 0.1 times as far per wheel turn as 1.5 m wheels say
    found = re.search(r"the laser moves ([0-9.]+) times as far per wheel rotation", gave_up)
    assert found is not None, gave_up
    assert float(found[1]) == pytest.approx(0.1, rel=0.01)
    assert report.verdict.level == "do-not-apply"
    right = umbmark.calibrate(room, scan_topic="/scan", wheel_diameter=DIAMETER)
    assert right.verdict.level == "apply"
    assert not [w for w in right.warnings if "sweeps alone" in w]
    assert math.isclose(report.estimate.E_d, right.estimate.E_d, abs_tol=1e-3)

"""A recording's wheels calibrated with its gyro: the result, its verdict and its JSON.

The recordings are the tests' own closed-form robot with a gyro (``tests/gyro_sim.py``);
the expected figures are its truth.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace

import numpy as np
import pytest

from gyro_sim import Truth, heading_reference, mixed_program, record, scan_reference
from umbmark.calibration.gyro import calibrate_gyro, gyro_lines
from umbmark.core.errors import InputError
from umbmark.model.gyro_series import GyroSeries
from umbmark.runs.read_options import ReadOptions
from umbmark.scans.gyro_intervals import HeadingReference

from helpers import cli_error

TRUTH = Truth()
OPTIONS = ReadOptions(wheel_diameter=TRUTH.nominal_diameter)


@pytest.fixture(scope="module")
def recording():
    return record(mixed_program(6.0), TRUTH, seed=11)


def test_without_a_reference_the_wheelbase_is_the_gyros_and_applied_with_care(recording):
    done = calibrate_gyro(recording.wheels, recording.gyro, OPTIONS, wheelbase=0.34)
    result, verdict = done.result, done.verdict
    assert verdict.level == "care"
    assert result.estimate.E_d == pytest.approx(TRUTH.E_d, abs=2e-4)
    # the overlay's multiplier makes the turns agree with the gyro's: E_b k_g
    assert result.calibration.new_separation_multiplier == pytest.approx(
        TRUTH.E_b * TRUTH.k_z / TRUTH.E_s, rel=1e-4
    )
    assert any("E_b is relative to the gyro" in w for w in result.warnings)
    lines = gyro_lines(done.gyro)
    assert lines[0] == "Gyro (imu_link), against the wheels alone:"
    said = next(line for line in lines if line.startswith("bias = "))
    value, error = (float(x) for x in re.findall(r"[-\d.]+(?= deg/s| ±)", said)[:2])
    true_mean = math.degrees(float(np.mean(recording.bias)))
    assert value == pytest.approx(true_mean, abs=0.01)
    assert 0.0 < error < 0.01
    assert not any(line.startswith("scale k_g") for line in lines)
    assert "k_g not determined" in " ".join(lines) or any("E_b k_g = " in x for x in lines)
    data = json.loads(json.dumps(done.to_dict()))
    assert data["method"] == "gyro"
    assert data["gyro_calibration"]["relative_to_gyro"] == ["E_b"]
    assert data["gyro_calibration"]["mounting"]["differs_from_stated"] is True


def test_with_motion_capture_the_gyro_is_calibrated_too(recording):
    start, end, yaw = heading_reference(recording, noise=math.radians(0.1))
    done = calibrate_gyro(
        recording.wheels, recording.gyro, OPTIONS, wheelbase=0.34,
        reference=HeadingReference(start, end, yaw, source="mocap"),
    )  # fmt: skip
    k_g = done.gyro.values["k_g"]
    assert k_g == pytest.approx(TRUTH.k_z, rel=1e-3)
    assert done.result.estimate.components["gyro_scale"] == k_g
    assert any(line.startswith(f"scale k_g = {k_g:.5f}") for line in gyro_lines(done.gyro))
    assert not any("relative to the gyro" in w for w in done.result.warnings)


def test_with_scan_matching_the_laser_is_in_the_result(recording):
    done = calibrate_gyro(
        recording.wheels, recording.gyro, OPTIONS, wheelbase=0.34,
        reference=scan_reference(recording),
    )  # fmt: skip
    data = done.to_dict()
    assert data["laser_pose"] == pytest.approx([0.12, -0.03, 0.05], abs=2e-3)
    assert data["E_s"] == pytest.approx(TRUTH.E_s, abs=3 * data["standard_errors"]["E_s"])


def test_an_imu_upside_down_is_never_applied(recording):
    upside = record(mixed_program(3.0), replace(TRUTH, tilt=(math.pi, 0.0)), seed=12)
    done = calibrate_gyro(upside.wheels, upside.gyro, OPTIONS, wheelbase=0.34)
    assert done.verdict.level == "do-not-apply"
    assert "reads the turns backwards" in done.verdict.reasons[0]
    assert done.result.overlay_withheld


def test_a_saturating_gyro_is_refused_in_one_line_saying_how_fast_it_turned():
    fast = record(mixed_program(3.0), TRUTH, seed=13)
    g = fast.gyro
    rate = g.rate.copy()
    top = 0.9 * float(np.abs(rate[:, 2]).max())  # a full scale below the fastest turn
    rate[:, 2] = np.clip(rate[:, 2], -top, top)
    gyro = GyroSeries(g.time, rate, None, source="drive.bag /imu")
    with pytest.raises(InputError) as caught:
        calibrate_gyro(fast.wheels, gyro, OPTIONS, wheelbase=0.34)
    line = caught.value.command_line()
    peak = math.degrees(top)
    assert line.startswith(
        f"drive.bag /imu: the gyro saturates: an axis held at its extreme reading ({peak:.1f} "
        "deg/s) in "
    )
    assert line.endswith(
        f"record again turning slower than {0.8 * peak:.0f} deg/s, or set the gyro's range higher"
    )
    assert "\n" not in line


def test_without_the_nominal_geometry_one_line_names_the_options(recording):
    with pytest.raises(InputError) as caught:
        calibrate_gyro(recording.wheels, recording.gyro, ReadOptions(), source="drive.bag")
    assert caught.value.command_line() == (
        "drive.bag: the gyro calibration needs the odometry's nominal geometry: give "
        "--wheelbase and --wheel-diameter (or --current-params)"
    )


def test_a_runs_table_is_not_for_the_gyro(tmp_path, table):
    path = table([["cw", 0.01, 0.02, 0.0, 0.0]] * 3 + [["ccw", -0.01, 0.02, 0.0, 0.0]] * 3)
    line = cli_error("calibrate", str(path), "-b", "0.34", "-L", "4", "--method", "gyro")
    assert "the gyro method needs a recording's wheels and its gyro" in line
    assert "--imu-topic" in line


def test_a_tilt_the_stated_transform_misses_is_said_as_the_imu_frames_urdf_origin(recording):
    """The closed-form IMU rolled and pitched 0.7 deg each (TRUTH.tilt), stated level:
    the origin found is that roll and pitch (the yaw as stated), within three of the
    tilt's standard errors, and the line says where to put it."""
    done = calibrate_gyro(
        recording.wheels, recording.gyro, OPTIONS, wheelbase=0.34, stated=np.eye(3)
    )
    apply = done.gyro.to_apply()
    assert apply["mounting_differs"] is True
    assert apply["origin_rpy_stated"] == [0.0, 0.0, 0.0]
    roll, pitch, yaw = apply["origin_rpy_found"]
    error = done.gyro.mounting.tilt_error
    assert error is not None
    assert roll == pytest.approx(TRUTH.tilt[0], abs=3 * error + 1e-4)
    assert pitch == pytest.approx(TRUTH.tilt[1], abs=3 * error + 1e-4)
    assert yaw == pytest.approx(0.0, abs=1e-12)
    assert apply["rotation_offset"] == pytest.approx([roll, pitch, yaw], abs=1e-12)
    said = [line for line in gyro_lines(done.gyro) if "URDF joint origin" in line]
    assert said == [
        f'imu_link\'s URDF joint origin: rpy="{roll:.5f} {pitch:.5f} 0.00000" (stated: '
        '"0.00000 0.00000 0.00000"; its yaw as stated, which the turns do not show) [rad]; '
        "or, keeping the stated transform, imu_sensor_broadcaster's rotation_offset roll, "
        f"pitch, yaw = {roll:.5f} {pitch:.5f} 0.00000 [rad]"
    ]
    data = json.loads(json.dumps(done.to_dict()))
    assert data["gyro_calibration"]["apply"]["origin_rpy_found"] == pytest.approx(
        [roll, pitch, yaw]
    )
    assert data["new"]["gyro_bias"] == done.gyro.values["bias"]

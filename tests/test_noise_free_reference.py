"""A noise-free reference that follows the wheels with other geometry than the odometry's
is the calibration itself, not circular truth (issue 30, item 8).

The wheels of a simulated 1 m square (3 runs each way), and as the reference the wheels
integrated with the true geometry of a robot with known errors, no slip and no noise:
radii 74.925 / 75.075 mm and a wheelbase of 343.4 mm, where the odometry uses 75 / 340.
Written as ROS 1, ROS 2 sqlite3 and MCAP bags with rosbags, it is accepted in each, with a
note, and calibrates to that geometry; the same wheels integrated with the odometry's own
geometry are still refused as circular.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.model.kinematics import integrate_odometry
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import read_recording
from umbmark.sources.bag.writer import bag_target, write_bag

from helpers import api_error

pytest.importorskip("rosbags")

#: The odometry's geometry [m], and the robot's.
WHEELBASE, DIAMETER = 0.34, 0.15
R_LEFT, R_RIGHT, TRUE_WHEELBASE = 0.074925, 0.075075, 0.3434
JOINTS = {"left_joint": "left_wheel_joint", "right_joint": "right_wheel_joint"}
READ = {"wheelbase": WHEELBASE, "wheel_diameter": DIAMETER, "side_length": 1.0, **JOINTS}


@pytest.fixture(scope="module")
def wheels(tmp_path_factory: pytest.TempPathFactory) -> WheelSeries:
    """The wheel angles of a noise-free simulated square, as its bag holds them."""
    folder = tmp_path_factory.mktemp("sim")
    umbmark.simulate(side_length=1.0, runs=3, seed=1, noise_free=True, bag=folder / "sim.bag")
    options = BagOptions(truth_topic="/mocap/robot/pose", **JOINTS)
    read = read_recording(folder / "sim.bag", options).wheels
    return WheelSeries(time=read.time - read.time[0], angles=read.angles)  # the writer's clock


def _poses(wheels: WheelSeries, r_left: float, r_right: float, b: float) -> PoseSeries:
    steps = np.diff(wheels.angles, axis=0)
    poses = integrate_odometry(r_left * steps[:, 0], r_right * steps[:, 1], b)
    return PoseSeries(time=wheels.time, poses=poses)


@pytest.mark.slow
@pytest.mark.parametrize("storage", [None, "sqlite3", "mcap"])
def test_a_noise_free_reference_of_other_geometry_is_accepted(
    tmp_path: Path, wheels: WheelSeries, storage: str | None
) -> None:
    odometry = _poses(wheels, 0.5 * DIAMETER, 0.5 * DIAMETER, WHEELBASE)
    truth = _poses(wheels, R_LEFT, R_RIGHT, TRUE_WHEELBASE)
    bag = write_bag(
        bag_target(tmp_path / ("quiet" if storage else "quiet.bag"), storage),
        wheels, odometry, truth,
    )  # fmt: skip
    report = umbmark.calibrate(bag, truth_topic="/mocap/robot/pose", method="exact", **READ)
    # the truth is 1e-3 (E_d) and 1e-2 (E_b) from the nominal 1: the exact estimator on
    # noise-free runs gives it to 1e-6
    assert report.estimate.E_d == pytest.approx(R_RIGHT / R_LEFT, abs=2e-6)
    assert report.estimate.E_b == pytest.approx(TRUE_WHEELBASE / WHEELBASE, abs=2e-6)
    (note,) = [n for n in report.notes if "without noise" in n]
    assert "the ground truth /mocap/robot/pose follows the wheels without noise" in note
    assert "wheel radii 74.925 and 75.075 mm and a wheelbase of 343.40 mm" in note


@pytest.mark.slow
def test_a_reference_of_the_odometrys_own_geometry_is_still_refused(
    tmp_path: Path, wheels: WheelSeries
) -> None:
    odometry = _poses(wheels, 0.5 * DIAMETER, 0.5 * DIAMETER, WHEELBASE)
    bag = write_bag(bag_target(tmp_path / "own.bag", None), wheels, odometry, odometry)
    message = api_error(umbmark.calibrate, bag, truth_topic="/mocap/robot/pose", **READ)
    assert "the ground truth /mocap/robot/pose reproduces the wheels' own odometry" in message
    assert "75.000 and 75.000 mm and a wheelbase of 340.00 mm" in message
    # and so with the active multipliers the odometry integrated with
    active = _poses(wheels, 0.5 * DIAMETER * 1.002, 0.5 * DIAMETER * 0.998, WHEELBASE * 1.01)
    bag = write_bag(bag_target(tmp_path / "active.bag", None), wheels, active, active)
    message = api_error(
        umbmark.calibrate, bag, truth_topic="/mocap/robot/pose", current_c_l=1.002,
        current_c_r=0.998, current_separation_multiplier=1.01, **READ,
    )  # fmt: skip
    assert "reproduces the wheels' own odometry" in message

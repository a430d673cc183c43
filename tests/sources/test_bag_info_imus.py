"""``umbmark info`` finds a bag's IMUs (``sources/bag/info/imus.py``): each
``sensor_msgs/Imu`` topic with its rate and mounting, ``--imu-topic`` suggested for the
one with a gyro and a mounting, and why not for the others."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

import umbmark
from robot_bags import IMU, JS, TF, BagWriter
from umbmark.sim.imu import ImuSetup

from helpers import run_cli

DEG = math.pi / 180.0
WHEELS = "--left-joint left_wheel_joint --right-joint right_wheel_joint"


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``simulate --bag --imu``: a 50 Hz IMU tilted 1 degree and turned 90 about z."""
    path = tmp_path_factory.mktemp("info") / "imu"
    setup = ImuSetup(imu_rate=50.0, imu_roll=1.0 * DEG, imu_yaw=90.0 * DEG)
    umbmark.simulate(runs=2, side_length=1.0, speed=0.4, dt=0.02, bag=path, bag_storage="mcap",
                     imu=setup)  # fmt: skip
    return path


@pytest.mark.slow
def test_a_simulated_imu_is_found_with_its_mounting_and_suggested(simulated: Path):
    report = umbmark.info(simulated)
    (imu,) = report.bag.imus
    assert (imu.topic, imu.frame, imu.gyro, imu.problem) == ("/imu", "imu_link", True, None)
    assert imu.rate == pytest.approx(50.0, rel=0.01)
    assert imu.mounting.base == "base_link"
    assert imu.mounting.source == "/tf_static"
    np.testing.assert_allclose(imu.mounting.rpy, [DEG, 0.0, 90.0 * DEG], atol=1e-9)
    assert report.suggested_options == f"--truth-topic /mocap/robot/pose {WHEELS} --imu-topic /imu"
    data = report.to_dict()
    assert data["imus"][0]["mounting"]["source"] == "/tf_static"
    assert data["suggested_options"].endswith("--imu-topic /imu")
    done = run_cli("info", str(simulated))
    assert done.returncode == 0, done.stderr
    assert (
        "  /imu, 50.0 Hz, imu_link in base_link (/tf_static): roll 1.00, pitch 0.00, yaw 90.00 "
        "deg   --imu-topic /imu"
    ) in done.stdout


def _imu(bag: BagWriter, t: float, frame: str, rate: float, cov: float):
    covariance = np.zeros(9)
    covariance[0] = cov
    return bag.T(IMU)(
        header=bag.header(t, frame),
        orientation=bag.quaternion((0.0, 0.0, 0.0, 1.0)),
        orientation_covariance=np.zeros(9),
        angular_velocity=bag.vector(z=rate),
        angular_velocity_covariance=covariance,
        linear_acceleration=bag.vector(z=9.81),
        linear_acceleration_covariance=np.zeros(9),
    )


@pytest.fixture(scope="module")
def two_imus(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Wheels, an orientation-only IMU mounted on ``/tf_static`` and a gyro whose frame no
    transform names."""
    bag = BagWriter("ros1")
    rng = np.random.default_rng(1)
    for k in range(300):
        t = 0.01 * k
        names, angles = ["left_wheel_joint", "right_wheel_joint"], [2.0 * t, 2.1 * t]
        bag.add("/joint_states", JS, t, bag.joint_state(t, names, angles))
        # an orientation-only IMU (robot_localization's input, say) ...
        bag.add("/imu/data", IMU, t, _imu(bag, t, "imu_link", 0.0, -1.0))
        # ... and a gyro whose frame is in no transform
        bag.add("/gyro", IMU, t, _imu(bag, t, "gyro_link", float(rng.normal()), 0.0))
    still = bag.transform(0.0, "base_link", "imu_link", (0.0, 0.0, 0.1), (0.0, 0.0, 0.0, 1.0))
    bag.add("/tf_static", TF, 0.0, bag.tf([still]))
    return bag.write(tmp_path_factory.mktemp("imus") / "b")


def test_imus_without_a_gyro_or_a_mounting_say_why_and_are_not_suggested(two_imus: Path):
    report = umbmark.info(two_imus)
    by_topic = {imu.topic: imu for imu in report.bag.imus}
    assert set(by_topic) == {"/imu/data", "/gyro"}
    assert by_topic["/imu/data"].problem == (
        "its messages give no angular velocity (angular_velocity_covariance[0] = -1, or exactly "
        "0): no gyro"
    )
    assert by_topic["/imu/data"].mounting is not None
    assert by_topic["/gyro"].problem.startswith(
        "the IMU's frame gyro_link has no transform to base_link or base_footprint"
    )
    assert report.suggested_options == WHEELS


@pytest.mark.slow
def test_the_command_says_why_not(two_imus: Path):
    done = run_cli("info", str(two_imus))
    assert "IMU:\n  /gyro, 100.0 Hz, frame 'gyro_link'\n" in done.stdout
    assert "\n  /imu/data, 100.0 Hz, imu_link in base_link (/tf_static): roll 0.00" in done.stdout
    assert "    not suggested: the IMU's frame gyro_link has no transform" in done.stdout

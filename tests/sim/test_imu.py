"""The virtual robot's IMU (``sim/imu.py``): its readings against closed forms, and the
bag ``simulate --bag --imu`` writes read back (``sources/bag/imu.py``) against the
simulated motion: each run's heading change from the true poses, the gyro's scale and
bias applied by hand, the mounting's rotation by scipy's."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import umbmark
from umbmark.model.recording import PoseSeries
from umbmark.sim.imu import ACCEL_NOISE, GRAVITY, IMU_TRANSLATION, ImuSetup, simulate_imu
from umbmark.sim.session import REST, continuous_session

from helpers import api_error

DEG = math.pi / 180.0


def _spin(omega: float, seconds: float = 20.0, dt: float = 0.01) -> PoseSeries:
    """The true poses of a robot turning on the spot at ``omega`` [rad/s]."""
    time = np.arange(0.0, seconds + dt / 2, dt)
    return PoseSeries(
        time, np.column_stack([np.zeros(time.size), np.zeros(time.size), omega * time])
    )


def test_a_spin_reads_its_rate_over_the_scale_plus_the_bias_and_the_lever_arms_force():
    setup = ImuSetup(imu_rate=100.0, gyro_scale=1.03, gyro_bias=0.4 * DEG, gyro_noise=0.0,
                     gyro_bias_walk=0.0)  # fmt: skip
    imu = simulate_imu(_spin(1.2), setup, np.random.default_rng(1))
    track = imu.track
    assert track.time.size == 2000
    np.testing.assert_allclose(track.time[[0, -1]], [0.01, 20.0])
    np.testing.assert_allclose(track.rate[:, 2], 1.2 / 1.03 + 0.4 * DEG, atol=1e-12)
    np.testing.assert_allclose(track.rate[:, :2], np.tile(imu.bias_start[:2], (2000, 1)))
    assert np.all(np.abs(imu.bias_start[:2]) <= 0.4 * DEG)
    assert imu.bias_start[2] == 0.4 * DEG
    # a spin at omega: the point r feels -omega^2 (rx, ry) and gravity's reaction
    rx, ry, _ = IMU_TRANSLATION
    force = np.array([-(1.2**2) * rx, -(1.2**2) * ry, GRAVITY])
    assert np.abs(track.accel[10:] - force).max() < 6 * ACCEL_NOISE * 10.0
    truth = imu.truth()
    assert truth["k_g"] == 1.03
    assert truth["yaw_bias"] == pytest.approx(0.4 * DEG)


def test_the_mounting_rotates_the_readings_into_the_imus_frame():
    roll, pitch, yaw = 180.0, 1.0, 90.0
    setup = ImuSetup(gyro_noise=0.0, gyro_bias=0.0, gyro_bias_walk=0.0, imu_roll=roll * DEG,
                     imu_pitch=pitch * DEG, imu_yaw=yaw * DEG)  # fmt: skip
    imu = simulate_imu(_spin(-0.7), setup, np.random.default_rng(2))
    mounted = Rotation.from_euler("xyz", [roll, pitch, yaw], degrees=True)
    want = mounted.inv().apply([0.0, 0.0, -0.7 / setup.gyro_scale])
    np.testing.assert_allclose(imu.track.rate, np.tile(want, (imu.track.time.size, 1)), atol=1e-12)
    stated = Rotation.from_quat(imu.track.rotation)
    assert (stated.inv() * mounted).magnitude() < 1e-12


def test_the_noise_and_the_bias_walk_have_their_densities():
    setup = ImuSetup(imu_rate=400.0, gyro_noise=0.01 * DEG, gyro_bias_walk=0.0, gyro_bias=0.0)
    rates = simulate_imu(_spin(0.0, 50.0), setup, np.random.default_rng(3)).track.rate
    # white noise of density N: std N sqrt(rate) per reading (20 000 readings: 1 % of it)
    assert np.std(rates, axis=0) == pytest.approx(np.full(3, 0.01 * DEG * 20.0), rel=0.03)
    walked = ImuSetup(imu_rate=50.0, gyro_noise=0.0, gyro_bias_walk=0.01 * DEG, gyro_bias=0.0)
    ends = np.array([
        simulate_imu(_spin(0.0, 25.0, 0.05), walked, np.random.default_rng(s)).bias_end
        for s in range(200)
    ])  # fmt: skip
    # a random walk of K over T: std K sqrt(T) (600 values: within 10 %)
    assert np.std(ends) == pytest.approx(0.01 * DEG * 5.0, rel=0.1)


def test_a_turn_beyond_the_full_scale_is_clipped():
    setup = ImuSetup(gyro_range=100.0 * DEG, gyro_noise=0.0, gyro_bias=0.0, gyro_bias_walk=0.0)
    imu = simulate_imu(_spin(3.0, 5.0), setup, np.random.default_rng(4))
    assert imu.clipped == imu.track.time.size
    np.testing.assert_allclose(imu.track.rate[:, 2], 100.0 * DEG)


@pytest.mark.parametrize(
    ("keyword", "value", "message"),
    [
        ("imu_rate", 5000.0, "--imu-rate must be 10 to 1000 Hz, got 5000 Hz"),
        ("gyro_scale", 2.0, "--gyro-scale must be 0.8 to 1.25, got 2"),
        ("gyro_bias", 20 * DEG, "--gyro-bias must be -10 to 10 deg/s, got 20 deg/s"),
        ("imu_pitch", 100 * DEG, "--imu-pitch must be -90 to 90 deg, got 100 deg"),
        ("gyro_noise", "x", "--gyro-noise must be a number, not 'x'"),
    ],
)
def test_the_setup_is_bounded(keyword, value, message):
    assert message in api_error(ImuSetup, **{keyword: value})


# --- simulate --bag --imu, read back against the simulated motion -------------------------

pytest.importorskip("rosbags")

from umbmark.sources.bag.bag_options import BagOptions  # noqa: E402
from umbmark.sources.bag.imu import read_imu  # noqa: E402
from umbmark.sources.bag.writer import START_EPOCH  # noqa: E402

CASES = {
    "tilted 1 deg, ros1, 200 Hz": ("x.bag", None, (1.0, -0.5, 0.0), 200.0),
    "90 deg about z, sqlite3, 50 Hz": ("x", "sqlite3", (0.0, 0.0, 90.0), 50.0),
    "upside down, mcap, 50 Hz": ("x", "mcap", (180.0, 0.0, 0.0), 50.0),
    "upside down and turned, ros1, 1 kHz": ("x.bag", None, (180.0, 1.0, -90.0), 1000.0),
    "tilted, mcap, 1 kHz": ("x", "mcap", (1.0, 1.0, 30.0), 1000.0),
}


@pytest.mark.slow  # a second each at 50 Hz, three at 1 kHz
@pytest.mark.parametrize("case", list(CASES))
def test_the_recorded_gyro_gives_each_runs_true_heading_change(tmp_path: Path, case: str):
    name, storage, (roll, pitch, yaw), rate = CASES[case]
    setup = ImuSetup(imu_rate=rate, gyro_scale=0.975, gyro_bias=0.35 * DEG, imu_roll=roll * DEG,
                     imu_pitch=pitch * DEG, imu_yaw=yaw * DEG)  # fmt: skip
    report = umbmark.simulate(runs=2, side_length=1.0, speed=0.4, dt=0.02, seed=5,
                              bag=tmp_path / name, bag_storage=storage, imu=setup)  # fmt: skip
    read = read_imu(tmp_path / name, BagOptions(imu_topic="/imu"))
    assert read.notes == ()
    session = continuous_session(report.result, report.robot.odometry.radians_per_pulse)
    heading = session.truth.poses[:, 2]
    truth = report.to_dict()["imu"]
    mounted = Rotation.from_euler("xyz", [roll, pitch, yaw], degrees=True)
    yaw_bias = mounted.apply(truth["bias"])[2]  # the walk is small: the start's bias
    assert truth["yaw_bias"] == pytest.approx(yaw_bias, abs=1e-15)
    # each run from the rest before it to the rest after it (the robot still at both)
    start = session.windows[:, 0] - 0.5 * REST
    end = session.windows[:, 1] + 0.5 * REST
    turned = np.interp(end, session.truth.time, heading) - np.interp(
        start, session.truth.time, heading
    )
    read_turn = read.gyro.yaw_change(start + START_EPOCH, end + START_EPOCH)
    expected = turned / 0.975 + yaw_bias * (end - start)
    assert np.all(np.abs(turned) > 6.0)  # a square: four quarter turns each
    # the noise over a run (about 15 s) and the bias's walk: well under 2e-3 rad
    np.testing.assert_allclose(read_turn, expected, atol=2e-3)
    # without the scale and the bias the runs' turns are off by ten times the tolerance
    assert np.all(np.abs(read_turn - turned) > 0.02)
    # at rest, the accelerometer in the base frame points up, whatever the mounting
    rest = read.gyro.time < read.gyro.time[0] + 1.0
    assert read.gyro.accel is not None
    np.testing.assert_allclose(read.gyro.accel[rest].mean(axis=0), [0, 0, GRAVITY], atol=0.01)


def test_the_imu_read_as_the_motion_goes_on_is_the_one_read_at_once():
    """:class:`ImuStream` given the motion a sample at a time, read in pieces, gives the
    readings :func:`simulate_imu` gives of the whole (without noise and walk, exactly: the
    same model; the draws of a stream come in other pieces)."""
    from umbmark.sim.imu import ImuStream, _travel

    t = np.arange(0.0, 12.0 + 1e-9, 0.02)
    poses = np.column_stack([0.3 * np.sin(0.5 * t), 0.2 * t, 0.8 * np.sin(0.7 * t)])
    setup = ImuSetup(gyro_noise=0.0, gyro_bias_walk=0.0, imu_rate=100.0, imu_roll=2.0 * DEG)
    whole = simulate_imu(PoseSeries(t, poses), setup, np.random.default_rng(9))
    stream = ImuStream(setup, np.random.default_rng(9), float(t[0]))
    travel = _travel(poses)
    pieces = []
    for k in range(t.size):
        stream.add(float(t[k]), float(poses[k, 2]), float(travel[k]))
        if k % 37 == 0 or k == t.size - 1:
            pieces.append(stream.read())
    time = np.concatenate([p.time for p in pieces])
    rate = np.concatenate([p.rate for p in pieces])
    np.testing.assert_allclose(time, whole.track.time, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rate, whole.track.rate, rtol=0, atol=1e-12)
    assert stream.pending < 10  # only what the next readings look back to is kept

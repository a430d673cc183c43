"""An IMU's gyro read from a bag (``sources/bag/imu.py``, its mounting by
``sources/bag/imu_frames.py``): bags written by hand with rosbags, in every format, with
readings whose base-frame rates are derived here by an independent rotation (scipy's),
and each bad input's one line.

The simulated robot's IMU read back against the simulated motion is in
``tests/sim/test_imu.py``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

from scipy.spatial.transform import Rotation

from robot_bags import FORMATS, IMU, STRING, T0, TF, BagWriter
from umbmark.model.recording import WheelSeries
from umbmark.sources.bag import imu as imu_reader
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.imu import check_against_wheels, read_gyro, read_imu, read_imu_windows
from umbmark.sources.bag.reader import time_windows

from helpers import api_error

OPTIONS = BagOptions(imu_topic="/imu")
#: Every format; the quick loop reads MCAP, the slow one the others too.
EVERY_FORMAT = [f if f == "mcap" else pytest.param(f, marks=pytest.mark.slow) for f in FORMATS]
RATE = 100.0  # Hz


def _rates(n: int, seed: int = 1) -> np.ndarray:
    """Readings in the IMU's frame, shape (n, 3): a slow turn with a gyro's noise (every
    reading differs, as a real gyro's)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    base = np.column_stack([0.05 * np.sin(t), -0.03 * np.cos(0.5 * t), 0.4 * np.sin(0.2 * t)])
    return base + rng.normal(0.0, 1e-3, (n, 3))


def _imu_message(
    bag: BagWriter, stamp: float, frame: str, rate, *, cov: float = 0.0, accel=(0.0, 0.0, 9.81)
):
    covariance = np.zeros(9)
    covariance[0] = cov
    no_orientation = np.zeros(9)
    no_orientation[0] = -1.0
    return bag.T(IMU)(
        header=bag.header(stamp, frame),
        orientation=bag.quaternion((0.0, 0.0, 0.0, 1.0)),
        orientation_covariance=no_orientation,
        angular_velocity=bag.vector(*(float(v) for v in rate)),
        angular_velocity_covariance=covariance,
        linear_acceleration=bag.vector(*accel),
        linear_acceleration_covariance=np.zeros(9),
    )


def imu_bag(
    path: Path,
    fmt: str,
    rates: np.ndarray,
    *,
    frame: str = "imu_link",
    stamps: np.ndarray | None = None,
    received: np.ndarray | None = None,
    covariance: np.ndarray | None = None,
    static: tuple = (("base_link", "imu_link", (0.0, 0.0, 0.0, 1.0)),),
    dynamic: tuple = (),
    description: str | None = None,
) -> Path:
    """A bag with ``/imu`` (``rates`` in ``frame``, received at ``received`` [s from T0],
    default at ``RATE`` from 1 s, stamped ``stamps``, default the receive times),
    ``/tf_static`` with ``static`` ``(parent, child, quaternion xyzw)``, ``/tf`` with
    ``dynamic`` (each repeated at 10 Hz for 2 s) and a ``/robot_description``."""
    bag = BagWriter(fmt)
    received = np.arange(len(rates)) / RATE + 1.0 if received is None else received
    stamps = received if stamps is None else stamps
    for k, rate in enumerate(rates):
        cov = 0.0 if covariance is None else float(covariance[k])
        msg = _imu_message(bag, float(stamps[k]), frame, rate, cov=cov)
        bag.add("/imu", IMU, float(received[k]), msg)
    if static:
        transforms = [bag.transform(0.0, p, c, (0.1, 0.0, 0.2), q) for p, c, q in static]
        bag.add("/tf_static", TF, 0.0, bag.tf(transforms))
    for k in range(20 if dynamic else 0):
        transforms = [bag.transform(0.1 * k, p, c, (0.0, 0.0, 0.1), q) for p, c, q in dynamic]
        bag.add("/tf", TF, 0.1 * k, bag.tf(transforms))
    if description is not None:
        bag.add("/robot_description", STRING, 0.0, bag.T(STRING)(data=description))
    return bag.write(path)


def _quat(rotation: Rotation) -> tuple[float, float, float, float]:
    x, y, z, w = rotation.as_quat()
    return (float(x), float(y), float(z), float(w))


# --- the mounting: the readings in the base frame -----------------------------------------


MOUNTINGS = {
    "tilted 1 deg": Rotation.from_euler("xyz", [1.0, -0.7, 0.0], degrees=True),
    "90 deg about z": Rotation.from_euler("z", 90.0, degrees=True),
    "upside down": Rotation.from_euler("xyz", [180.0, 0.0, 30.0], degrees=True),
}


@pytest.mark.parametrize("fmt", EVERY_FORMAT)
@pytest.mark.parametrize("mounted", list(MOUNTINGS))
def test_the_readings_come_out_in_the_base_frame(tmp_path, fmt, mounted):
    rotation = MOUNTINGS[mounted]
    rates = _rates(300)
    path = imu_bag(tmp_path / "b", fmt, rates, static=(("base_link", "imu_link", _quat(rotation)),))
    read = read_imu(path, OPTIONS)
    assert read.notes == ()
    assert read.mounting.base == "base_link"
    assert read.mounting.source == "/tf_static"
    np.testing.assert_allclose(read.gyro.rate, rotation.apply(rates), atol=1e-12)
    np.testing.assert_allclose(read.gyro.accel, rotation.apply(np.tile([0, 0, 9.81], (300, 1))))
    np.testing.assert_allclose(read.gyro.time, T0 + 1.0 + np.arange(300) / RATE, atol=1e-6)
    assert read.mounting.upside_down == (mounted == "upside down")
    stated = Rotation.from_euler("xyz", read.mounting.rpy)
    assert (stated.inv() * rotation).magnitude() < 1e-9
    assert len(read_gyro(path, OPTIONS)) == 300


def test_a_chain_through_another_link_and_walked_backwards(tmp_path):
    """``chassis -> base_link`` and ``chassis -> imu_link``: the IMU in the base frame is
    ``R_chassis_base^T R_chassis_imu``."""
    chassis_base = Rotation.from_euler("xyz", [0.0, 2.0, 90.0], degrees=True)
    chassis_imu = Rotation.from_euler("xyz", [180.0, 0.0, -45.0], degrees=True)
    static = (("chassis", "base_link", _quat(chassis_base)),
              ("chassis", "imu_link", _quat(chassis_imu)))  # fmt: skip
    rates = _rates(200)
    read = read_imu(imu_bag(tmp_path / "b", "mcap", rates, static=static), OPTIONS)
    want = (chassis_base.inv() * chassis_imu).apply(rates)
    np.testing.assert_allclose(read.gyro.rate, want, atol=1e-12)


def test_a_mounting_only_on_tf_and_through_several_links(tmp_path):
    up = Rotation.from_euler("x", 180.0, degrees=True)
    turn = Rotation.from_euler("z", -90.0, degrees=True)
    dynamic = (("base_link", "plate", _quat(turn)), ("plate", "imu_link", _quat(up)))
    rates = _rates(200)
    read = read_imu(imu_bag(tmp_path / "b", "ros1", rates, static=(), dynamic=dynamic), OPTIONS)
    assert read.mounting.source == "/tf"
    np.testing.assert_allclose(read.gyro.rate, (turn * up).apply(rates), atol=1e-12)


URDF = """<?xml version="1.0"?>
<robot name="r"><link name="base_footprint"/><link name="base_link"/><link name="chassis"/>
<link name="imu_link"/>
<joint name="a" type="fixed"><parent link="base_footprint"/><child link="base_link"/>
<origin xyz="0 0 0.05" rpy="0 0 0"/></joint>
<joint name="b" type="fixed"><parent link="base_link"/><child link="chassis"/>
<origin xyz="0.1 0 0.1" rpy="0 0 1.5707963267948966"/></joint>
<joint name="c" type="fixed"><parent link="chassis"/><child link="imu_link"/>
<origin xyz="0 0 0.02" rpy="3.141592653589793 0.017453292519943295 0"/></joint>
</robot>
"""


@pytest.mark.parametrize("fmt", EVERY_FORMAT)
def test_a_mounting_only_in_the_robot_description(tmp_path, fmt):
    rates = _rates(200)
    path = imu_bag(tmp_path / "b", fmt, rates, static=(), description=URDF)
    read = read_imu(path, OPTIONS)
    assert read.mounting.source == "/robot_description"
    assert read.mounting.base == "base_link"
    chain = Rotation.from_euler("z", 90.0, degrees=True) * Rotation.from_euler(
        "xyz", [180.0, 1.0, 0.0], degrees=True
    )
    np.testing.assert_allclose(read.gyro.rate, chain.apply(rates), atol=1e-12)


def test_the_tf_static_mounting_wins_over_the_description(tmp_path):
    turn = Rotation.from_euler("z", 45.0, degrees=True)
    rates = _rates(100)
    path = imu_bag(
        tmp_path / "b", "mcap", rates, static=(("base_link", "imu_link", _quat(turn)),),
        description=URDF,
    )  # fmt: skip
    np.testing.assert_allclose(read_imu(path, OPTIONS).gyro.rate, turn.apply(rates), atol=1e-12)


def test_an_imu_in_the_base_frame_itself(tmp_path):
    rates = _rates(100)
    path = imu_bag(tmp_path / "b", "sqlite3", rates, frame="base_link", static=())
    read = read_imu(path, OPTIONS)
    np.testing.assert_array_equal(read.gyro.rate, rates)
    assert read.mounting.source == "the IMU's own frame"


@pytest.mark.parametrize("fmt", EVERY_FORMAT)
def test_a_frame_without_a_transform_is_one_line(tmp_path, fmt):
    static = (("base_link", "laser", (0.0, 0.0, 0.0, 1.0)), ("odom", "base_link", (0, 0, 0, 1)))
    path = imu_bag(tmp_path / "b", fmt, _rates(50), static=static)
    line = api_error(read_imu, path, OPTIONS)
    assert line.startswith(f"{path}: /imu: the IMU's frame imu_link has no transform to base_link")
    assert "frames in the bag: base_link, laser, odom" in line


def test_a_frame_never_named_is_one_line(tmp_path):
    path = imu_bag(tmp_path / "b", "mcap", _rates(50), frame="")
    line = api_error(read_imu, path, OPTIONS)
    assert "/imu: the IMU's messages name no frame (header.frame_id is empty)" in line
    assert "frames in the bag: base_link, imu_link" in line


# --- what is left out, each in one line ---------------------------------------------------


def test_no_angular_velocity_in_any_message_is_refused(tmp_path):
    rates = _rates(50)
    path = imu_bag(tmp_path / "b", "mcap", rates, covariance=np.full(50, -1.0))
    line = api_error(read_imu, path, OPTIONS)
    assert line == (
        f"{path}: /imu: every message says it has no angular velocity "
        "(angular_velocity_covariance[0] = -1): this IMU gives accelerations, no gyro readings"
    )


def test_messages_without_angular_velocity_are_left_out_and_counted(tmp_path):
    covariance = np.zeros(100)
    covariance[[3, 40, 41, 77]] = -1.0
    rates = _rates(100)
    read = read_imu(imu_bag(tmp_path / "b", "ros1", rates, covariance=covariance), OPTIONS)
    assert len(read.gyro) == 96
    assert read.dropped["no_gyro"] == 4
    (note,) = read.notes
    assert "/imu: 4 of 100 messages say they have no angular velocity" in note
    np.testing.assert_allclose(read.gyro.rate, np.delete(rates, [3, 40, 41, 77], axis=0))


def test_readings_that_are_not_numbers_are_left_out_and_counted(tmp_path):
    rates = _rates(100)
    rates[[10, 11, 50], 1] = np.nan
    rates[60, 2] = np.inf
    read = read_imu(imu_bag(tmp_path / "b", "sqlite3", rates), OPTIONS)
    assert len(read.gyro) == 96
    (note,) = read.notes
    assert note == (
        f"{tmp_path / 'b'}: /imu: 4 of 100 messages have angular velocities that are not finite "
        "numbers (NaN): left out"
    )


def test_repeated_and_out_of_order_stamps(tmp_path):
    rates = _rates(100)
    stamps = np.arange(100) / RATE + 1.0
    stamps[[20, 21, 22]] = stamps[19]  # three repeat the one before
    stamps[60], stamps[61] = stamps[61], stamps[60]  # two swapped
    read = read_imu(imu_bag(tmp_path / "b", "mcap", rates, stamps=stamps), OPTIONS)
    assert len(read.gyro) == 97
    assert read.dropped["repeated"] == 3
    assert read.dropped["reordered"] == 1
    notes = " | ".join(read.notes)
    assert "3 of 100 messages repeat an earlier message's stamp: dropped" in notes
    assert "1 of 100 messages arrive out of order" in notes
    assert np.all(np.diff(read.gyro.time) > 0)
    np.testing.assert_allclose(read.gyro.rate[19], rates[19])  # the first of a stamp kept
    np.testing.assert_allclose(read.gyro.rate[57:59], rates[[61, 60]])


def test_a_gap_is_named_and_no_interval_across_it_is_usable(tmp_path):
    rates = _rates(300)
    keep = np.r_[0:100, 250:300]  # 1.5 s without readings
    received = (np.arange(300) / RATE + 1.0)[keep]
    path = imu_bag(tmp_path / "b", "mcap", rates[keep], stamps=received)
    read = read_imu(path, OPTIONS)
    (note,) = read.notes
    assert "/imu: 1 gap(s) without readings (longest 1.51 s;" in note
    assert "the gyro's heading change across them is not measured" in note
    np.testing.assert_allclose(read.gaps, [[T0 + 1.99, T0 + 3.5]], atol=1e-6)
    start = T0 + np.array([1.1, 1.5, 3.6, 1.0])
    end = T0 + np.array([1.9, 3.7, 3.9, 1.0])
    assert read.usable(start, end).tolist() == [True, False, True, True]


def _frozen(rates: np.ndarray, a: int, b: int) -> np.ndarray:
    out = rates.copy()
    out[a:b] = out[a]
    return out


def test_a_frozen_imu_is_said_and_named_against_turning_wheels(tmp_path):
    rates = _frozen(_rates(600), 200, 450)  # 2.5 s of one reading
    read = read_imu(imu_bag(tmp_path / "b", "mcap", rates), OPTIONS)
    (note,) = read.notes
    assert "/imu: the IMU repeats exactly the same rates for 1 s or more" in note
    np.testing.assert_allclose(read.frozen, [[T0 + 3.0, T0 + 5.49]], atol=1e-6)
    assert not read.usable(np.array([T0 + 3.5]), np.array([T0 + 4.0]))[0]
    time = T0 + np.arange(0.0, 8.0, 0.02)
    turning = WheelSeries(time, np.column_stack([2.0 * (time - T0), 1.5 * (time - T0)]))
    (line,) = check_against_wheels(read, turning)
    assert "the IMU reads the same rates for 2.5 s while the wheels turn (285 deg" in line
    resting = WheelSeries(time, np.zeros((time.size, 2)))
    assert check_against_wheels(read, resting) == ()


def test_an_imu_frozen_from_first_to_last_is_refused(tmp_path):
    rates = _frozen(_rates(300), 0, 300)
    line = api_error(read_imu, imu_bag(tmp_path / "b", "sqlite3", rates), OPTIONS)
    assert "/imu: every reading is the same" in line
    assert "a frozen IMU" in line


def test_a_saturating_gyro_is_named_with_its_stretch(tmp_path):
    rates = _rates(500)
    full_scale = math.radians(250.0)
    rates[200:240, 2] = np.linspace(3.0, 6.0, 40)  # a fast turn ...
    rates[210:240, 2] = full_scale  # ... clipped at 250 deg/s for 0.3 s
    read = read_imu(imu_bag(tmp_path / "b", "ros1", rates), OPTIONS)
    (note,) = read.notes
    assert (
        "/imu: the gyro saturates: an axis held at its extreme reading (up to 250.0 deg/s)" in note
    )
    assert "(3.10 to 3.39 s of the recording)" in note
    np.testing.assert_allclose(read.saturated, [[T0 + 3.1, T0 + 3.39]], atol=1e-6)
    assert read.usable(np.array([T0 + 2.0, T0 + 3.0]), np.array([T0 + 3.0, T0 + 3.2])).tolist() == [
        True,
        False,
    ]


def test_a_fast_turn_that_stays_within_the_full_scale_is_not_saturated(tmp_path):
    rates = _rates(500)
    rates[200:240, 2] = 3.0 + np.abs(np.random.default_rng(2).normal(0.0, 0.01, 40))
    assert read_imu(imu_bag(tmp_path / "b", "mcap", rates), OPTIONS).notes == ()


def test_an_accelerometer_only_stream_is_refused(tmp_path):
    line = api_error(read_imu, imu_bag(tmp_path / "b", "mcap", np.zeros((80, 3))), OPTIONS)
    assert line == (
        f"{tmp_path / 'b'}: /imu: the angular velocity is exactly 0 in every message: an "
        "accelerometer-only stream, no gyro readings"
    )


def test_no_topic_the_wrong_type_no_option(tmp_path):
    path = imu_bag(tmp_path / "b", "mcap", _rates(20))
    assert "no topic /gyro (an IMU's readings) in the bag; topics present: /imu" in api_error(
        read_imu, path, BagOptions(imu_topic="/gyro")
    )
    assert "topic /tf_static has messages of type tf2_msgs/msg/TFMessage; an IMU's readings" in (
        api_error(read_imu, path, BagOptions(imu_topic="/tf_static"))
    )
    assert "reading a gyro needs --imu-topic: a sensor_msgs/Imu topic" in api_error(
        read_imu, path, BagOptions()
    )


def test_one_read_is_bounded(tmp_path, monkeypatch):
    path = imu_bag(tmp_path / "b", "mcap", _rates(50))
    monkeypatch.setattr(imu_reader, "MAX_SAMPLES", 40)
    line = api_error(read_imu, path, OPTIONS)
    assert "/imu: more than 40 readings in one read: read the recording in windows" in line


@pytest.mark.parametrize("fmt", EVERY_FORMAT)
def test_windows_read_the_whole_reads_readings(tmp_path, fmt):
    rates = _rates(1000)
    path = imu_bag(tmp_path / "b", fmt, rates)
    whole = read_imu(path, OPTIONS).gyro
    windows = time_windows(path, str(path), 3.0)
    assert len(windows) == 4
    parts = [read_imu(path, OPTIONS, window=w).gyro for w in windows]
    np.testing.assert_array_equal(np.concatenate([p.time for p in parts]), whole.time)
    np.testing.assert_array_equal(np.concatenate([p.rate for p in parts]), whole.rate)
    # the same windows from the bag opened once, each holding one window's readings
    once = [read.gyro for read in read_imu_windows(path, OPTIONS, 3.0)]
    assert [len(p) for p in once] == [len(p) for p in parts]
    assert max(len(p) for p in once) <= 3.0 * RATE
    np.testing.assert_array_equal(np.concatenate([p.rate for p in once]), whole.rate)


def test_a_window_without_readings_is_a_pause_passed_over(tmp_path):
    rates = _rates(600)
    keep = np.r_[0:200, 500:600]  # no readings from 3 s to 6 s
    times = (np.arange(600) / RATE + 1.0)[keep]
    path = imu_bag(tmp_path / "b", "mcap", rates[keep], received=times)
    reads = list(read_imu_windows(path, OPTIONS, 1.0))
    # 0-1 s holds only /tf_static, 3-6 s nothing: passed over
    assert [len(r.gyro) for r in reads] == [100, 100, 100]

"""The reading options checked once (``runs/read_options.py``), and what the sources
hold deciding how they are read (``runs/read.py``): ``imu_topic`` reads a bag's IMU."""

from __future__ import annotations

import umbmark
from umbmark.runs.read import holds_gyro, is_bag
from umbmark.runs.read_options import ReadOptions

from helpers import api_error


def test_the_imu_topic_reads_a_bags_imu_not_a_runs_table(tmp_path, table):
    path = table([["cw", 0.01, 0.02, 0.0, 0.0]] * 3 + [["ccw", -0.01, 0.02, 0.0, 0.0]] * 3)
    line = api_error(umbmark.calibrate, path, imu_topic="/imu", wheelbase=0.34, side_length=4)
    assert line == f"imu_topic reads a bag's IMU: {path} is not a bag"
    options = ReadOptions(imu_topic="/imu")
    assert not is_bag(path, options)
    assert not holds_gyro(path, options)
    bag = tmp_path / "drive.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n")
    assert is_bag(bag, options)
    assert holds_gyro(bag, options)
    assert not holds_gyro(bag, ReadOptions())

"""The reading options checked once (``runs/read_options.py``): an option the calibrations
do not use yet is refused, not ignored."""

from __future__ import annotations

import umbmark

from helpers import api_error


def test_the_imu_topic_is_refused_until_the_calibrations_use_the_gyro(tmp_path):
    line = api_error(umbmark.calibrate, tmp_path / "x.bag", imu_topic="/imu")
    assert line == (
        "imu_topic is not used by the calibrations yet: umbmark info shows the IMU, "
        "umbmark.sources.bag.imu.read_imu reads its gyro"
    )
    assert "imu_topic is not used" in api_error(umbmark.replay, tmp_path / "x.bag", imu_topic="/i")

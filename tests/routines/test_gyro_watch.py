"""An IMU that fell silent or froze while a routine drove, found from its readings: a
100 Hz gyro of white noise over 0 to 10 s, cut or held where the test says (the times in
the line are those it was built with)."""

from __future__ import annotations

import numpy as np
import pytest

from umbmark.model.gyro_series import GyroSeries
from umbmark.routines.gyro_watch import SILENT, gyro_trouble


def _gyro(time: np.ndarray, frozen: tuple[float, float] | None = None) -> GyroSeries:
    rate = np.random.default_rng(5).normal(0.0, 1e-3, (time.size, 3))
    if frozen is not None:
        held = (time >= frozen[0]) & (time <= frozen[1])
        rate[held] = rate[np.argmax(held)]
    return GyroSeries(time=time, rate=rate)


TIME = np.arange(0.0, 10.001, 0.01)


def test_a_gyro_that_read_throughout_is_no_trouble() -> None:
    assert gyro_trouble(_gyro(TIME), 0.0, 10.0, "/imu") is None
    # its last readings a little late (a subscriber's delay) are no trouble either
    assert gyro_trouble(_gyro(TIME[TIME < 10.0 - 0.9 * SILENT]), 0.0, 10.0, "/imu") is None


@pytest.mark.parametrize(
    ("gyro", "said"),
    [
        (None, "the IMU on /imu gave no readings over the 10.0 s the robot drove"),
        (_gyro(TIME[TIME <= 4.0]), "the IMU on /imu fell silent 4.0 s into the 10.0 s"),
        (_gyro(TIME[TIME >= 3.0]), "the IMU on /imu gave no readings for the first 3.0 s of"),
        (
            _gyro(TIME[(TIME <= 4.0) | (TIME >= 6.5)]),
            "the IMU on /imu was silent from 4.0 to 6.5 s of the 10.0 s the robot drove",
        ),
        (_gyro(TIME, frozen=(5.0, 7.0)), "the IMU on /imu froze from 5.0 to 7.0 s of the 10.0 s"),
    ],
    ids=["none", "silent-at-the-end", "late", "silent-within", "frozen"],
)
def test_the_trouble_in_one_line(gyro: GyroSeries | None, said: str) -> None:
    line = gyro_trouble(gyro, 0.0, 10.0, "/imu")
    assert line is not None
    assert said in line
    assert "\n" not in line


def test_a_short_gap_or_hold_is_left_to_the_calibration() -> None:
    """A gap under SILENT (0.5 s) and the same rates for under a second (the bag
    reader's frozen stretch is 1 s) are not trouble: the intervals across them are left
    out by the calibration."""
    short = _gyro(TIME[(TIME <= 4.0) | (TIME >= 4.5)])
    assert gyro_trouble(short, 0.0, 10.0, "/imu") is None
    assert gyro_trouble(_gyro(TIME, frozen=(5.0, 5.5)), 0.0, 10.0, "/imu") is None

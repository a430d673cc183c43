"""MotionIntervals: picking rows keeps each interval whole, in its order."""

import numpy as np

from umbmark.model.motion_intervals import MotionIntervals


def _intervals(n: int, *, with_extras: bool) -> MotionIntervals:
    k = np.arange(n, dtype=np.float64)
    return MotionIntervals(
        duration=0.1 + k,
        phi_left=10.0 + k,
        phi_right=20.0 + k,
        sensor_motion=np.column_stack([30.0 + k, 40.0 + k, 50.0 + k]),
        sensor_covariance=np.stack([np.eye(3) * (1.0 + i) for i in range(n)])
        if with_extras
        else None,
        start_time=100.0 + k if with_extras else None,
        source="a.bag",
    )


def test_rows_keep_each_picked_interval_whole_and_in_order():
    picked = _intervals(5, with_extras=True).rows(np.array([True, False, True, False, True]))
    assert len(picked) == 3
    assert picked.duration.tolist() == [0.1, 2.1, 4.1]
    assert picked.phi_left.tolist() == [10.0, 12.0, 14.0]
    assert picked.phi_right.tolist() == [20.0, 22.0, 24.0]
    assert picked.sensor_motion[:, 2].tolist() == [50.0, 52.0, 54.0]
    assert picked.sensor_covariance is not None
    assert picked.sensor_covariance[:, 0, 0].tolist() == [1.0, 3.0, 5.0]
    assert picked.start_time is not None
    assert picked.start_time.tolist() == [100.0, 102.0, 104.0]
    assert picked.source == "a.bag"


def test_rows_without_covariance_or_times_stay_without():
    picked = _intervals(3, with_extras=False).rows(np.array([False, True, True]))
    assert picked.sensor_covariance is None
    assert picked.start_time is None
    assert picked.phi_left.tolist() == [11.0, 12.0]

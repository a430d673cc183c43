"""A stretch's chunks joined: every field of the gyro's intervals and reference kept (the
gyro's rate changes its delay is fitted from, the wheels' rotation that pairs each scan
interval with the gyro)."""

from __future__ import annotations

import numpy as np

from umbmark.monitor.chunks import join_gyro, join_reference
from umbmark.scans.gyro_intervals import GyroIntervals, GyroReference


def _intervals(t0: float, change: float) -> GyroIntervals:
    start = np.array([t0, t0 + 1.0])
    return GyroIntervals(start=start, end=start + 1.0, phi_left=np.ones(2),
                         phi_right=np.ones(2), yaw=np.zeros(2), rotation=np.zeros((2, 3)),
                         rest=np.zeros(2, dtype=bool), left_out={"gap": 1},
                         rate_change=np.array([change, -change]))  # fmt: skip


def _reference(t0: float, phi: float) -> GyroReference:
    start = np.array([t0])
    return GyroReference(start=start, end=start + 1.0, yaw=np.array([0.1]),
                         variance=np.array([1e-6]), gyro_yaw=np.array([0.1]),
                         phi_left=np.array([phi]), phi_right=np.array([phi + 1.0]),
                         rate_change=np.array([0.5]))  # fmt: skip


def test_the_gyro_intervals_keep_their_rate_changes() -> None:
    joined = join_gyro([_intervals(0.0, 0.3), _intervals(10.0, 0.7)])
    assert joined is not None
    assert joined.rate_changes.tolist() == [0.3, -0.3, 0.7, -0.7]
    assert joined.left_out == {"gap": 2}


def test_the_reference_keeps_its_wheels_and_rate_changes() -> None:
    joined = join_reference([_reference(0.0, 2.0), _reference(10.0, 3.0)])
    assert joined is not None
    assert joined.paired.tolist() == [True, True]  # the pairs of the joint fit
    assert joined.phi_right is not None
    assert joined.phi_right.tolist() == [3.0, 4.0]
    assert joined.rate_changes.tolist() == [0.5, 0.5]

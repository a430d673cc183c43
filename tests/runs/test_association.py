"""Time association of wheel data and ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.runs.association import associate, summarize


def _wheels(t):
    t = np.asarray(t, dtype=float)
    return WheelSeries(time=t, angles=np.column_stack([t, 2 * t]))


def test_linear_motion_is_interpolated_exactly():
    # Ground truth at 10 Hz of x = 0.5 t, y = -t, theta = 0.1 t; wheels at 30 Hz, offset.
    gt_t = np.arange(0.0, 2.01, 0.1)
    truth = PoseSeries(gt_t, np.column_stack([0.5 * gt_t, -gt_t, 0.1 * gt_t]))
    wt = np.arange(0.013, 1.99, 1 / 30)
    poses, assoc = associate(_wheels(wt), truth)
    np.testing.assert_allclose(poses, np.column_stack([0.5 * wt, -wt, 0.1 * wt]), atol=1e-12)
    assert assoc.matched == assoc.total == wt.size
    assert assoc.largest_gap == pytest.approx(0.1)


def test_heading_is_unwrapped_across_pi():
    gt_t = np.array([0.0, 1.0, 2.0])
    theta = np.array([3.0, math.pi + 0.14 - 2 * math.pi, 3.28 - 2 * math.pi])  # wraps
    truth = PoseSeries(gt_t, np.column_stack([np.zeros(3), np.zeros(3), theta]))
    poses, _ = associate(_wheels([0.5, 1.5]), truth, max_gap=2.0)
    # Unwrapped: 3.0, pi + 0.14, 3.28; halfway between them.
    np.testing.assert_allclose(
        poses[:, 2], [(3.0 + math.pi + 0.14) / 2, (math.pi + 0.14 + 3.28) / 2], atol=1e-12
    )


def test_gaps_and_samples_outside_give_no_ground_truth():
    gt_t = np.array([1.0, 1.1, 1.2, 2.0, 2.1])
    truth = PoseSeries(gt_t, np.column_stack([gt_t, gt_t, gt_t]))
    wt = np.array([0.5, 1.05, 1.5, 2.05, 3.0])
    poses, assoc = associate(_wheels(wt), truth, max_gap=0.25)
    known = np.all(np.isfinite(poses), axis=1)
    assert known.tolist() == [False, True, False, True, False]
    assert assoc.matched == 2
    assert assoc.largest_gap == pytest.approx(0.8)
    assert "2 of 5 wheel samples matched ground truth (40.0 %)" in assoc.describe()


def test_no_overlap_is_refused_with_both_time_spans():
    truth = PoseSeries(np.array([100.0, 101.0]), np.zeros((2, 3)))
    with pytest.raises(
        InputError,
        match=r"rec.bag: wheel data \(0.000 to 1.000 s\) and ground "
        r"truth \(100.000 to 101.000 s\) do not overlap in time",
    ):
        associate(_wheels([0.0, 1.0]), truth, source="rec.bag")


def test_summary_lines():
    truth = PoseSeries(np.array([0.0, 1.0]), np.zeros((2, 3)))
    _, full = associate(_wheels([0.2, 0.8]), truth, max_gap=2.0)
    _, part = associate(_wheels([0.5, 2.0]), truth, max_gap=2.0)
    lines = summarize([("a", full), ("b", full), ("c", part)])
    assert lines[0].startswith("2 recordings: all 4 wheel samples matched")
    assert lines[1].startswith("c: 1 of 2 wheel samples matched")

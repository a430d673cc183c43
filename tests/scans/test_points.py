"""A sweep's points: scipy's KD-tree is imported by the matching alone."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from umbmark.scans.points import prepare


def test_the_self_calibration_starts_without_scipy():
    # The self-calibration's modules import the scan matching; a command that refuses an
    # option (or drives a square) never builds a KD-tree: scipy.spatial cost 0.4 s of
    # every `umbmark selfcal` start.
    code = "import sys, umbmark.jobs.selfcal; print(sorted(m for m in sys.modules if 'scipy' in m))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_line_of_points_gets_its_tree():
    # Ten points 0.1 m apart along x: a line, every normal along y.
    points = np.column_stack([np.linspace(0.0, 0.9, 10), np.full(10, 2.0)])
    prepared = prepare(points)
    assert prepared.line_points.shape == (10, 2)
    np.testing.assert_allclose(np.abs(prepared.normals[:, 1]), 1.0, atol=1e-12)
    assert prepared.tree is not None
    distance, index = prepared.tree.query([0.42, 2.0])
    assert index == 4
    assert abs(distance - 0.02) < 1e-12

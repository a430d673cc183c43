"""umbmark: measure and correct the systematic odometry errors of differential-drive robots.

Implements Borenstein & Feng (1996), *Measurement and Correction of Systematic Odometry
Errors in Mobile Robots* (UMBmark), and goes past it. The public names below are imported
on first use, so that ``import umbmark`` (and ``umbmark --help``) stay fast.

Conventions (frame, signs, units) are in :mod:`umbmark.conventions`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__version__ = "0.1.0"

_EXPORTS = {
    "ActiveParams": "umbmark.calibration",
    "Benchmark": "umbmark.benchmark",
    "Calibration": "umbmark.calibration",
    "Direction": "umbmark.conventions",
    "EndPose": "umbmark.runs",
    "ErrorEstimate": "umbmark.estimators",
    "Run": "umbmark.runs",
    "SquareTest": "umbmark.estimators",
    "WheelParams": "umbmark.kinematics",
    "estimate_errors": "umbmark.estimators",
    "integrate_odometry": "umbmark.kinematics",
    "read_runs_table": "umbmark.io.runs_table",
    "umbmark_benchmark": "umbmark.benchmark",
}

__all__ = [
    "ActiveParams",
    "Benchmark",
    "Calibration",
    "Direction",
    "EndPose",
    "ErrorEstimate",
    "Run",
    "SquareTest",
    "WheelParams",
    "__version__",
    "estimate_errors",
    "integrate_odometry",
    "read_runs_table",
    "umbmark_benchmark",
]

if TYPE_CHECKING:
    from .benchmark import Benchmark, umbmark_benchmark
    from .calibration import ActiveParams, Calibration
    from .conventions import Direction
    from .estimators import ErrorEstimate, SquareTest, estimate_errors
    from .io.runs_table import read_runs_table
    from .kinematics import WheelParams, integrate_odometry
    from .runs import EndPose, Run


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'umbmark' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)

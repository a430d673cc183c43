"""What a simulation shows, as JSON-ready facts."""

from __future__ import annotations

import numpy as np

from ..benchmark import umbmark_benchmark
from .engine import SimResult
from .robot import VirtualRobot

__all__ = ["describe_simulation"]


def describe_simulation(
    robot: VirtualRobot, result: SimResult, path_name: str, kind: str
) -> dict[str, object]:
    """JSON-ready facts of a simulation: the truth, every run's end poses, and per path
    kind what a user measures: E_max,syst (square), true over odometry distance
    (straight line: the scale error E_s), true over odometry rotation and the centre's
    sideways shift (on-the-spot turn, Sec. 2.3)."""
    odo = robot.odometry
    out: dict[str, object] = {
        "path": path_name,
        "true_E_d": robot.E_d,
        "true_E_b": robot.wheelbase / odo.wheelbase,
        "true_E_s": robot.E_s,
        "true_wheelbase": robot.wheelbase,
        "true_wheel_diameter_left": robot.diameter_left,
        "true_wheel_diameter_right": robot.diameter_right,
        "runs": [
            {
                "direction": d.value,
                "true_end": [float(v) for v in result.true_end[i]],
                "odometry_end": [float(v) for v in result.odometry_end[i]],
            }
            for i, d in enumerate(result.directions)
        ],
    }
    if kind == "square":
        runs = result.runs()
        if len({r.direction for r in runs}) == 2 and len(runs) >= 4:
            out["e_max_syst"] = umbmark_benchmark(runs).e_max_syst
    elif kind == "straight":
        true_d = np.hypot(result.true_end[:, 0], result.true_end[:, 1])
        odo_d = np.hypot(result.odometry_end[:, 0], result.odometry_end[:, 1])
        if np.all(odo_d > 0):  # a robot that never moved has no ratio (not NaN)
            out["distance_ratio"] = float(np.mean(true_d / odo_d))
    else:
        if np.all(result.odometry_end[:, 2] != 0):
            ratio = result.true_end[:, 2] / result.odometry_end[:, 2]
            out["rotation_ratio"] = float(np.mean(ratio))
        out["centre_shift"] = float(np.mean(np.hypot(result.true_end[:, 0], result.true_end[:, 1])))
    return out

"""What a simulation shows, as JSON-ready facts."""

from __future__ import annotations

import numpy as np

from umbmark.returns.clusters import umbmark_benchmark
from umbmark.sim.result import SimResult
from umbmark.sim.robot import SimRobot

__all__ = ["describe_simulation", "odometry_errors", "true_errors"]


def true_errors(robot: SimRobot, nominal_wheelbase: float) -> dict[str, float]:
    """The robot's errors relative to the nominal wheels (``D_n``, ``b``): its truth.

    ``E_d = D_R / D_L``, ``E_b = b_actual / b`` and ``E_s = D_avg / D_n`` (Eqs. 2.3,
    2.4, Sec. 2.2), whatever parameters its odometry uses: what ``simulate`` was given.
    """
    return {
        "E_d": robot.E_d,
        "E_b": robot.wheelbase / nominal_wheelbase,
        "E_s": robot.E_s,
    }


def odometry_errors(robot: SimRobot) -> dict[str, float]:
    """The robot's errors relative to the parameters its odometry uses (``c_L D_n``,
    ``c_R D_n``, its wheelbase): what a calibration of its runs measures, with those
    parameters active. Without corrections (``c_L = c_R = 1``, the nominal wheelbase)
    they are :func:`true_errors`."""
    odo = robot.odometry
    return {
        "E_d": robot.E_d * odo.c_left / odo.c_right,
        "E_b": robot.wheelbase / odo.wheelbase,
        "E_s": robot.E_s * 2.0 / (odo.c_left + odo.c_right),
    }


def describe_simulation(
    robot: SimRobot, result: SimResult, path_name: str, kind: str, nominal_wheelbase: float
) -> dict[str, object]:
    """JSON-ready facts of a simulation: the truth (:func:`true_errors`, relative to the
    nominal wheels; ``odometry_E_*``: :func:`odometry_errors`, relative to the parameters
    the odometry used), every run's end poses, and per path kind what a user measures:
    E_max,syst (square), true over odometry distance (straight line: the scale error
    E_s), true over odometry rotation and the centre's sideways shift (on-the-spot turn,
    Sec. 2.3)."""
    truth, odometry = true_errors(robot, nominal_wheelbase), odometry_errors(robot)
    out: dict[str, object] = {
        "path": path_name,
        **{f"true_{k}": v for k, v in truth.items()},
        **{f"odometry_{k}": v for k, v in odometry.items()},
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

"""The parts of a calibration's JSON (:meth:`umbmark.calibration.result.CalibrationResult.to_dict`)
that are each one thing's: a cluster of return errors, a run, a calibration from motion
intervals (metres, radians)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from umbmark.estimators.scan_matching import ScanCalibration
    from umbmark.model.run import Run
    from umbmark.returns.clusters import Cluster

__all__ = ["cluster_dict", "run_dict", "sensor_dict"]


def sensor_dict(sensor: ScanCalibration) -> dict[str, Any]:
    """What a calibration from motion intervals adds to the JSON (metres, radians)."""
    se = sensor.standard_errors
    return {
        "laser_pose": list(sensor.laser_pose),
        "laser_pose_standard_errors": [se["laser_x"], se["laser_y"], se["laser_yaw"]],
        "wheel_diameter_left_standard_error": se["wheel_diameter_left"],
        "wheel_diameter_right_standard_error": se["wheel_diameter_right"],
        "wheelbase_standard_error": se["wheelbase"],
        "motion_intervals": {
            "n": int(sensor.kept.shape[0]),
            "used": sensor.n_used,
            "outliers": int(sensor.kept.shape[0] - sensor.n_used),
            "noise": list(sensor.noise),
            "condition": sensor.excitation.condition,
            "turns_on_the_spot": sensor.excitation.n_spot,
            "straights": sensor.excitation.n_straight,
            "arcs": sensor.excitation.n_arc,
            "turning_left": sensor.excitation.n_left,
            "turning_right": sensor.excitation.n_right,
        },
        "uncertainty": "Cramer-Rao bound, sensor noise from the residuals",
    }


def cluster_dict(cluster: Cluster) -> dict[str, Any]:
    d = cluster.direction.value
    std = cluster.std_xy
    return {
        f"cg_{d}": [float(cluster.cg[0]), float(cluster.cg[1])],
        f"r_cg_{d}": cluster.r_cg,
        f"std_{d}": [float(std[0]), float(std[1])],
        f"sigma_{d}": cluster.sigma,
        f"sem_{d}": cluster.sem,
    }


def run_dict(run: Run) -> dict[str, Any]:
    """A run's figures; a logged run's also its start and end time on the recording's own
    clock [s] (a bag's stamps, a run log's time column)."""
    eps_x, eps_y = run.return_error
    out: dict[str, Any] = {
        "label": run.label,
        "kind": run.kind,
        "direction": run.direction.value,
        "eps_x": eps_x,
        "eps_y": eps_y,
        "eps_theta": run.heading_error,
    }
    if run.log is not None:
        out["start_time"] = run.log.start
        out["end_time"] = run.log.start + float(run.log.time[-1])
    return out

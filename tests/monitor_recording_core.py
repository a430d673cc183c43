"""A recording :class:`~umbmark.monitor.status.MonitorCore` for developing the ROS nodes
before the real core is there: it counts what it is fed, says OK with nothing determined,
integrates nothing (its corrected odometry is the controller's pose as it came), and asks
for an apply when told to. Not the monitor: the real tests run the real core."""

from __future__ import annotations

import numpy as np

from umbmark.monitor.status import FIGURES, CorrectedOdometry, Figure, MonitorStatus
from umbmark.robot.base import ApplyResult, DriveParams, Pose2D, ScanSweep


class RecordingCore:
    def __init__(self, robot: str = "robot", apply: DriveParams | None = None) -> None:
        self.robot = robot
        self.counts = {"wheels": 0, "odometry": 0, "scan": 0, "imu": 0}
        self.last: tuple[float, Pose2D] | None = None
        self.to_apply = apply
        self.results: list[ApplyResult] = []

    def wheels(self, time: float, left: float, right: float) -> None:
        self.counts["wheels"] += 1

    def odometry(self, time: float, pose: Pose2D) -> None:
        self.counts["odometry"] += 1
        self.last = (time, pose)

    def scan(self, sweep: ScanSweep) -> None:
        self.counts["scan"] += 1

    def gyro(self, time: float, yaw_rate: float) -> None:
        self.counts["imu"] += 1

    def status(self, now: float) -> MonitorStatus:
        figures = tuple(Figure(n, None, None, u, "recording core") for n, u in FIGURES)
        said = ", ".join(f"{k} {v}" for k, v in self.counts.items())
        return MonitorStatus(now, self.robot, "OK", f"fed {said}", figures, 0.0, 0.0, 0.0,
                             0.0, None)  # fmt: skip

    def corrected(self) -> CorrectedOdometry | None:
        if self.last is None:
            return None
        cov = np.diag([1e-3, 1e-3, 0.0, 0.0, 0.0, 1e-2])
        return CorrectedOdometry(self.last[0], self.last[1], 0.0, 0.0, cov, cov)

    def apply_due(self, now: float) -> DriveParams | None:
        params, self.to_apply = self.to_apply, None
        return params

    def applied(self, now: float, result: ApplyResult) -> None:
        self.results.append(result)

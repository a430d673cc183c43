"""A virtual robot whose IMU's driver fails (for the tests of a gyro that falls silent or
freezes mid-routine): the simulation's own readings, cut or held from a time on."""

from __future__ import annotations

import dataclasses

import numpy as np

from umbmark.model.gyro_series import GyroSeries
from umbmark.robot.virtual import VirtualRobot


class FaultyImu(VirtualRobot):
    """The virtual robot, its IMU's driver failing ``after`` seconds into the robot's
    time: ``silent``, no reading after then; ``frozen``, the last rates before then in
    every later reading (the stamps going on)."""

    def __init__(self, fault: str, after: float, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.fault, self.after = fault, after
        self.held: np.ndarray | None = None

    def gyro(self, since: float) -> GyroSeries | None:
        read = super().gyro(since)
        if read is None:
            return None
        if self.fault == "silent":
            keep = read.time < self.after
            return dataclasses.replace(read, time=read.time[keep], rate=read.rate[keep], accel=None)
        later = read.time >= self.after
        if not later.any():
            return read
        if self.held is None:  # the last reading before the fault, held from then on
            self.held = read.rate[max(int(np.argmax(later)) - 1, 0)].copy()
        rate = read.rate.copy()
        rate[later] = self.held
        return dataclasses.replace(read, rate=rate)

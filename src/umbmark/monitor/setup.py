"""What a monitor is asked to do: :class:`MonitorSetup`, checked once by the option specs
of :mod:`umbmark.options.monitor` (the command line's and the ROS parameters' defaults
and bounds)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Literal

from umbmark.core.errors import InputError, option
from umbmark.options.monitor import MONITOR
from umbmark.robot.base import DriveParams, Pose2D

__all__ = ["INPUTS", "Input", "MonitorSetup"]

#: The monitor's inputs, as :attr:`MonitorSetup.inputs` names them.
Input = Literal["wheels", "odometry", "scan", "imu"]
INPUTS: tuple[Input, ...] = ("wheels", "odometry", "scan", "imu")


def _default(name: str) -> float:
    return float(MONITOR[name].default)


@dataclass(frozen=True)
class MonitorSetup:
    """The monitor's configuration (the options of :mod:`umbmark.options.monitor`).

    Attributes
    ----------
    robot : str
        The robot's name (the diagnostic's hardware id, its name in the history).
    params : DriveParams
        What the controller runs with (its nominal geometry and multipliers).
    laser : Pose2D or None
        The laser's stated mounting in the base frame [m, m, rad]; None: each sweep's own
        (:attr:`~umbmark.robot.base.ScanSweep.mount`, from TF).
    window_metres, window_radians : float
        The estimate's window in driving: at least this far driven [m] and turned each
        way [rad].
    stretch_metres : float
        A stretch: this much wheel travel [m] (both wheels' mean distance rolled).
    scan_period : float
        One sweep matched per this time [s]: the motion intervals' length.
    stale_after : float
        An expected input silent this long [s] is stale.
    tolerance : float
        The navigation tolerance (:data:`umbmark.options.monitor.MONITOR` ``tolerance``).
    apply : {"never", "at-rest"}
    rest_time : float
        With ``apply="at-rest"``: how long the wheels must stand still [s].
    history : path or None
        The history file the stretches go to and the course is taken up from; None: none.
    inputs : tuple of str
        The inputs the node feeds (``wheels`` or ``odometry``, ``scan``, ``imu``): the
        ones whose silence makes the status STALE.
    judge_silence : bool
        Whether the core says its inputs' silence itself (STALE after ``stale_after`` of
        the robot's clock, naming the inputs): the simulated robot's and the library's
        core. A ROS node judges its topics' silence on the wall clock and names the topics
        (:class:`umbmark.monitor.node_loop.MonitorLoop`): its core does not
        (:func:`umbmark.monitor.core.make_monitor`), so that sim time running faster than
        the wall clock makes no STALE of its own.
    """

    robot: str
    params: DriveParams
    laser: Pose2D | None = None
    window_metres: float = _default("window_metres")
    window_radians: float = _default("window_radians")
    stretch_metres: float = _default("stretch_metres")
    scan_period: float = _default("scan_period")
    stale_after: float = _default("stale_after")
    tolerance: float = _default("tolerance")
    apply: Literal["never", "at-rest"] = "never"
    rest_time: float = _default("rest_time")
    history: str | os.PathLike[str] | None = None
    inputs: tuple[Input, ...] = ("wheels", "scan")
    judge_silence: bool = True

    def __post_init__(self) -> None:
        if not self.robot.strip():
            raise InputError(f"the monitor needs a robot name ({option('robot')})")
        for name in ("window_metres", "window_radians", "stretch_metres", "scan_period",
                     "stale_after", "tolerance", "rest_time"):  # fmt: skip
            MONITOR[name].check(getattr(self, name))
        MONITOR["apply"].check(self.apply)
        p = self.params
        values = (p.wheel_separation, p.wheel_radius, p.wheel_separation_multiplier,
                  p.left_wheel_radius_multiplier, p.right_wheel_radius_multiplier)  # fmt: skip
        if not all(math.isfinite(v) and v > 0.0 for v in values):
            raise InputError(f"the controller's parameters must be positive: {p}")
        unknown = [i for i in self.inputs if i not in INPUTS]
        if unknown or not self.inputs:
            raise InputError(f"the monitor's inputs are {', '.join(INPUTS)}, got {self.inputs}")

    @property
    def wheel_radii(self) -> tuple[float, float]:
        """The effective wheel radii the controller's odometry uses [m]."""
        p = self.params
        return (
            p.wheel_radius * p.left_wheel_radius_multiplier,
            p.wheel_radius * p.right_wheel_radius_multiplier,
        )

"""The monitor job: ``umbmark monitor --sim``, the monitor's core
(:class:`umbmark.monitor.core.Monitor`) fed by a simulated warehouse robot
(:mod:`umbmark.monitor.simulated`) driving ordinary missions, its right wheel changed
after some minutes (and its laser knocked, where asked), at a speed-up; what it said as it
changed, and the truth beside it at the end. The ROS nodes (``--ros1``, ``--ros2``) feed
the same core.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

from umbmark.core.jsontext import JsonText
from umbmark.monitor.status import MonitorStatus

__all__ = ["KNOCK", "MonitorSimReport", "monitor_sim"]

#: The knocked laser: forward [m], yaw [rad] (the fleet simulation's).
KNOCK = (0.01, math.radians(3.0))


def _gist(status: MonitorStatus) -> tuple[object, ...]:
    """What a status says, without the figures' last digits and the metres since."""
    changes = tuple((c.figure, c.confirmed, c.beyond_tolerance) for c in status.changes)
    return (status.level, changes, status.stale, status.outliers, status.applied)


def _status_dict(status: MonitorStatus) -> dict[str, Any]:
    return {
        "time": status.time,
        "level": status.level,
        "message": status.message,
        "key_values": dict(status.key_values()),
    }


@dataclass(frozen=True)
class MonitorSimReport(JsonText):
    """What the monitor said on the simulated robot.

    Attributes
    ----------
    robot : str
    said : tuple of MonitorStatus
        Each status that differed from the one before in what it says (:func:`_gist`: the
        level, the changes found and whether confirmed, the stale topics), in time order.
    last : MonitorStatus
        The status at the end.
    truth : dict of str to float
        The robot's true figures at the end (``E_d``, ``E_b``, ``E_s``, ``laser_x``,
        ``laser_y``, ``laser_yaw``, ``k_g``, ``gyro_bias``), and the change's time
        (``changed_at`` [s]) and odometer (``changed_at_metres`` [m]).
    seconds : float
        Robot time simulated [s].
    cpu : float
        CPU seconds the monitor's core spent [s].
    """

    robot: str
    said: tuple[MonitorStatus, ...]
    last: MonitorStatus
    truth: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0
    cpu: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {
            "robot": self.robot,
            "said": [_status_dict(s) for s in self.said],
            "last": _status_dict(self.last),
            # a change that never came (the run ended before it) has no time or odometer
            "truth": {k: v if math.isfinite(v) else None for k, v in self.truth.items()},
            "seconds": self.seconds,
            "cpu_seconds": self.cpu,
        }


def monitor_sim(
    *,
    robot: str = "robot",
    minutes: float = 20.0,
    change_after: float = 8.0,
    wheel_change: float = -0.006,
    knock: bool = False,
    speedup: float = 0.0,
    seed: int = 1,
    history: str | os.PathLike[str] | None = None,
    on_status: Callable[[MonitorStatus], None] | None = None,
    window_metres: float = 50.0,
    window_radians: float = 4.0 * math.pi,
    stretch_metres: float = 20.0,
    scan_period: float = 1.0,
    stale_after: float = 2.0,
    tolerance: float = 0.02,
    apply: Literal["never", "at-rest"] = "never",
    rest_time: float = 5.0,
) -> MonitorSimReport:
    """Run the monitor on the simulated robot (the module's notes).

    Parameters
    ----------
    robot : str
        The robot's name.
    minutes : float
        Robot time to simulate [min].
    change_after : float
        When the right wheel is changed [min].
    wheel_change : float
        The new right wheel's diameter over the old one, less 1.
    knock : bool
        Knock the laser at the same time (:data:`KNOCK`).
    speedup : float
        Robot time per wall time; 0: as fast as the computer allows.
    seed : int
    history : path, optional
        The history file the stretches go to (none by default).
    on_status : callable, optional
        Called with each status that differs from the one before in what it says.
    window_metres, window_radians, stretch_metres, scan_period, stale_after, tolerance,
    apply, rest_time
        The monitor's options (:data:`umbmark.options.monitor.MONITOR`, whose defaults
        these are: :class:`umbmark.monitor.setup.MonitorSetup` checks them).

    Raises
    ------
    InputError
        An option out of its bounds.
    """
    from umbmark.monitor.core import Monitor
    from umbmark.monitor.setup import MonitorSetup
    from umbmark.monitor.simulated import NOMINAL, SimChange, SimRobotSetup, feed, messages
    from umbmark.options.monitor import MONITOR_SIM
    from umbmark.robot.base import DriveParams, Pose2D

    for name, value in (("minutes", minutes), ("change_after", change_after),
                        ("wheel_change", wheel_change), ("speedup", speedup),
                        ("seed", seed)):  # fmt: skip
        MONITOR_SIM[name].check(value)
    base = SimRobotSetup(seed=seed)
    e_d, e_b, e_s = base.errors
    right = 1.0 + wheel_change  # the right wheel's diameter: E_d and E_s follow
    errors = (e_d * right, e_b, e_s * (1.0 + e_d * right) / (1.0 + e_d))
    laser = (base.laser[0] + KNOCK[0], base.laser[1], base.laser[2] + KNOCK[1]) if knock else None
    change = SimChange(60.0 * change_after, errors=errors, laser=laser)
    sim = SimRobotSetup(seed=seed, changes=(change,))
    setup = MonitorSetup(
        robot, DriveParams(NOMINAL[0], 0.5 * NOMINAL[1]), Pose2D(*base.stated),
        window_metres=window_metres, window_radians=window_radians,
        stretch_metres=stretch_metres, scan_period=scan_period, stale_after=stale_after,
        tolerance=tolerance, apply=apply, rest_time=rest_time, history=history,
        inputs=("wheels", "scan", "imu"),
    )  # fmt: skip
    core = Monitor(setup)
    said: list[MonitorStatus] = []
    last: MonitorStatus | None = None
    next_status, cpu = 0.0, 0.0
    wall0, seconds = time.monotonic(), 60.0 * minutes
    changed_metres = math.nan
    for message, _ in messages(sim, seconds):
        if message.time > seconds:
            break
        start = time.process_time()
        feed(core, message)
        if message.time >= next_status:
            next_status = math.floor(message.time) + 1.0
            status = core.status(message.time)
            if last is None or _gist(status) != _gist(last):
                said.append(status)
                if on_status is not None:
                    on_status(status)
            last = status
        cpu += time.process_time() - start
        if math.isnan(changed_metres) and message.time >= change.at:
            changed_metres = core.odometer
        if speedup > 0:
            ahead = message.time / speedup - (time.monotonic() - wall0)
            if ahead > 0.01:
                time.sleep(ahead)
    final = core.status(seconds)
    true_errors, true_laser = sim.state_at(seconds)
    truth = dict(zip(("E_d", "E_b", "E_s"), true_errors, strict=True))
    truth.update(zip(("laser_x", "laser_y", "laser_yaw"), true_laser, strict=True))
    truth.update(k_g=sim.gyro_scale, gyro_bias=sim.gyro_bias, changed_at=change.at,
                 changed_at_metres=changed_metres)  # fmt: skip
    return MonitorSimReport(robot, tuple(said), final, truth, seconds, cpu)

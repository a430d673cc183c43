"""What arrives, when: the last arrival of each input, messages out of order dropped and
counted, the clock going back, and the wheels' angles kept continuous across a
controller's restart.

- A message older than (or as old as) the last of its kind is dropped and counted
  (:attr:`Arrivals.dropped`); one older by more than :data:`CLOCK_BACK` is the clock going
  back (a simulation reset): :meth:`Arrivals.arrive` says so and the monitor restarts its
  window.
- :class:`WheelAngles` takes the wheels' angles as the joint states give them, or the
  controller's odometry turned back into wheel rotation
  (:func:`umbmark.model.kinematics.wheel_travel_from_poses`, the inverse of the arc step
  :func:`umbmark.sources.bag.wheels.odometry.wheels_from_odometry` applies to a whole
  recording, here one message after the other, with the controller's effective radii and
  separation). A step no wheel can make (faster than :data:`MAX_WHEEL_RATE`, or odometry
  moving faster than :data:`MAX_SPEED` or turning faster than :data:`MAX_TURN_RATE`) is a
  restart of the controller or the driver (its counts or its pose reset): the angles go
  on from where they were (no jump), and :attr:`WheelAngles.breaks` counts it.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from umbmark.model.kinematics import wheel_travel_from_poses
from umbmark.monitor.setup import Input
from umbmark.robot.base import Pose2D

__all__ = ["CLOCK_BACK", "MAX_SPEED", "MAX_TURN_RATE", "MAX_WHEEL_RATE", "Arrivals", "WheelAngles"]

#: A message this much older than the last of its kind [s] is the clock going back.
CLOCK_BACK = 3.0
#: Fastest wheel rotation taken as driving [rad/s] (a 0.15 m wheel at 7.5 m/s).
MAX_WHEEL_RATE = 100.0
#: Fastest odometry taken as driving [m/s] and turning [rad/s].
MAX_SPEED = 5.0
MAX_TURN_RATE = 10.0
#: The slack of those bounds over a step [m, rad]: a message late by a cycle or two.
_SLACK = (0.05, 0.1)
#: The slack of the wheels' bound over a step [rad].
_WHEEL_SLACK = 1.0


class Arrivals:
    """The last arrival of each input on the robot's clock, and what was dropped."""

    def __init__(self) -> None:
        self.last: dict[Input, float] = {}
        self.dropped: Counter[str] = Counter()
        #: The first arrival since the start (or since the clock went back).
        self.first: float | None = None

    def arrive(self, kind: Input, time: float) -> str:
        """``"ok"`` for a message to use, ``"drop"`` for one out of order (counted),
        ``"back"`` where the clock went back (the caller restarts; the time is taken as
        this input's last)."""
        if not math.isfinite(time):
            self.dropped[f"{kind}: time not finite"] += 1
            return "drop"
        last = self.last.get(kind)
        if last is not None and time <= last:
            if time < last - CLOCK_BACK:
                self.last, self.first = {kind: time}, time
                return "back"
            self.dropped[f"{kind}: out of order"] += 1
            return "drop"
        self.last[kind] = time
        if self.first is None:
            self.first = time
        return "ok"

    def silent(self, now: float, expected: tuple[Input, ...], after: float) -> tuple[str, ...]:
        """The expected inputs silent for more than ``after`` [s] at ``now``: the wheels
        (joint states or odometry, either) from the first input heard on, a laser or a
        gyro (which a robot may not have) once it has spoken, as the nodes judge."""
        first = now if self.first is None else self.first
        wheels = [self.last[k] for k in ("wheels", "odometry") if k in self.last]
        out = []
        for kind in expected:
            if kind in ("wheels", "odometry"):
                last = max(wheels, default=first)
                if now - last > after and "wheels" not in out:
                    out.append("wheels")
            elif kind in self.last and now - self.last[kind] > after:
                out.append(kind)
        return tuple(out)


class WheelAngles:
    """The wheels' cumulative angles [rad], continuous across restarts (module notes).

    Parameters
    ----------
    radii : (float, float)
        The controller's effective wheel radii [m] (odometry to wheel rotation).
    separation : float
        Its effective wheel separation [m].
    """

    def __init__(self, radii: tuple[float, float], separation: float) -> None:
        self.radii = radii
        self.separation = separation
        self.time: float | None = None
        self.angles = (0.0, 0.0)
        self.breaks = 0
        self._raw: tuple[float, float] | None = None
        self._pose: Pose2D | None = None

    def reset(self) -> None:
        """Forget the last reading (the clock went back): the next one continues."""
        self.time, self._raw, self._pose = None, None, None

    def from_wheels(self, time: float, left: float, right: float) -> bool:
        """Take a joint-states reading; whether it continued the angles (False: the first
        reading, or a restart)."""
        raw = (float(left), float(right))
        last, was = self.time, self._raw
        self.time, self._raw = time, raw
        if last is None or was is None:
            return False
        d = (raw[0] - was[0], raw[1] - was[1])
        if not all(math.isfinite(v) for v in d) or max(map(abs, d)) > (
            MAX_WHEEL_RATE * (time - last) + _WHEEL_SLACK
        ):
            self.breaks += 1
            return False
        self.angles = (self.angles[0] + d[0], self.angles[1] + d[1])
        return True

    def from_odometry(self, time: float, pose: Pose2D) -> bool:
        """Take the controller's odometry pose; whether it continued the angles."""
        last, was = self.time, self._pose
        self.time, self._pose = time, pose
        if last is None or was is None:
            return False
        dt = time - last
        dtheta = math.remainder(pose.theta - was.theta, math.tau)
        moved = math.hypot(pose.x - was.x, pose.y - was.y)
        if moved > MAX_SPEED * dt + _SLACK[0] or abs(dtheta) > MAX_TURN_RATE * dt + _SLACK[1]:
            self.breaks += 1
            return False
        poses = np.array([[was.x, was.y, was.theta], [pose.x, pose.y, was.theta + dtheta]])
        d_left, d_right, _ = wheel_travel_from_poses(poses, self.separation)
        self.angles = (
            self.angles[0] + float(d_left[0]) / self.radii[0],
            self.angles[1] + float(d_right[0]) / self.radii[1],
        )
        return True

"""A simulated robot's messages for the monitor: a warehouse robot driving ordinary missions
(:func:`umbmark.sim.missions.mission`: corridors, turns at shelves, whole turns now and
then) with its wheels at 50 Hz, its laser in the warehouse (:mod:`umbmark.robot.warehouse`)
and a MEMS gyro (:func:`umbmark.sim.imu.simulate_imu`), its errors changed at given times
(a wheel changed, a laser knocked, a payload), pushed now and then: what
``umbmark monitor --sim``, the monitor's tests and its benchmark feed it.

The robot drives one mission after the other by its odometry, each simulated by the batch
engine (:func:`umbmark.sim.engine.simulate`, with its wheel slip) and laid end to end on
one clock (:func:`umbmark.sim.session.continuous_session`: a rest before and after); it
navigates back to its aisle's crossing before each (a turn, a straight and a turn from
where its true pose ended), as a localized robot does, so that it stays on the aisles
whatever its errors. A push moves the true pose (not the wheels) sideways while it drives.
Every message is in time order on the robot's clock, truth beside it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.model.recording import PoseSeries
from umbmark.model.scans import ScanSeries
from umbmark.robot.base import Pose2D, ScanSweep
from umbmark.sim.paths import Path, Segment

if TYPE_CHECKING:
    from umbmark.monitor.status import MonitorCore
    from umbmark.sources.bag.imu_writer import ImuTrack

__all__ = ["Message", "Push", "SimChange", "SimRobotSetup", "feed", "messages"]

#: The nominal geometry [m]: wheelbase, wheel diameter (the fleet simulation's).
NOMINAL = (0.34, 0.15)
#: Cruise speed [m/s].
SPEED = 0.5
#: Each mission's driving [s].
MISSION_SECONDS = 60.0


@dataclass(frozen=True)
class SimChange:
    """A change of the robot at ``at`` [s of robot time]: its errors ``E_d, E_b, E_s``
    and its laser's true mounting ``x, y, yaw`` [m, m, rad] from then on (None: as
    before)."""

    at: float
    errors: tuple[float, float, float] | None = None
    laser: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class Push:
    """The robot pushed sideways while it drives: ``metres`` over ``seconds`` from the
    first mission starting after ``at`` [s]."""

    at: float
    metres: float = 0.3
    seconds: float = 3.0


@dataclass(frozen=True)
class SimRobotSetup:
    """The simulated robot.

    Attributes
    ----------
    errors : (float, float, float)
        ``E_d, E_b, E_s`` at the start.
    laser : (float, float, float)
        The laser's true mounting [m, m, rad] at the start; the stated one is
        :attr:`stated`.
    stated : (float, float, float)
    changes : tuple of SimChange
    pushes : tuple of Push
    scan_rate, imu_rate : float
        [Hz] (the wheels come at the engine's 50 Hz); ``imu_rate`` 0: no gyro.
    gyro_scale, gyro_bias : float
        The gyro's ``k_g`` and bias [rad/s] (the bias at the start).
    gyro_bias_walk : float
        The bias's random walk [rad/s/sqrt(s)], carried from one mission to the next (0:
        a steady bias).
    slip : float
        The wheels' random slip [m^0.5].
    seed : int
    """

    errors: tuple[float, float, float] = (1.002, 1.01, 0.998)
    laser: tuple[float, float, float] = (0.1, 0.0, 0.0)
    stated: tuple[float, float, float] = (0.1, 0.0, 0.0)
    changes: tuple[SimChange, ...] = ()
    pushes: tuple[Push, ...] = ()
    scan_rate: float = 10.0
    imu_rate: float = 200.0
    gyro_scale: float = 1.01
    gyro_bias: float = 0.002
    gyro_bias_walk: float = 0.0
    slip: float = 0.0002
    seed: int = 1

    def state_at(self, t: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """The errors and the laser's true mounting at robot time ``t``."""
        errors, laser = self.errors, self.laser
        for change in sorted(self.changes, key=lambda c: c.at):
            if change.at <= t:
                errors = change.errors or errors
                laser = change.laser or laser
        return errors, laser


@dataclass(frozen=True)
class Message:
    """One message: ``kind`` ``wheels`` (``values`` = left, right [rad]), ``gyro``
    (``values`` = yaw rate [rad/s]), ``scan`` (``sweep``), with the true pose."""

    kind: Literal["wheels", "imu", "scan"]
    time: float
    values: tuple[float, ...] = ()
    sweep: ScanSweep | None = None


def _plan_end(start: tuple[float, float, float], path: Path) -> tuple[float, float, float]:
    """Where a mission's plan ends (a crossing and a heading)."""
    x, y, heading = start
    for seg in path.segments:
        if seg.kind == "turn":
            heading += seg.amount
        else:
            x += seg.amount * math.cos(heading)
            y += seg.amount * math.sin(heading)
    return round(x, 6), round(y, 6), math.remainder(heading, math.tau)


def _back_to(truth: FloatArray, crossing: tuple[float, float, float]) -> list[Segment]:
    """The segments from the true pose to the crossing and its heading."""
    x, y, th = (float(v) for v in truth)
    dx, dy = crossing[0] - x, crossing[1] - y
    out: list[Segment] = []
    if math.hypot(dx, dy) > 0.02:
        way = math.atan2(dy, dx)
        out.append(Segment("turn", math.remainder(way - th, math.tau)))
        th = way
        out.append(Segment("straight", math.hypot(dx, dy)))
    last = math.remainder(crossing[2] - th, math.tau)
    if abs(last) > 1e-3:
        out.append(Segment("turn", last))
    return out


def messages(setup: SimRobotSetup, seconds: float) -> Iterator[tuple[Message, Pose2D]]:
    """The robot's messages over ``seconds`` of robot time, in time order, each with the
    true pose then (the module's notes)."""
    from umbmark.core.conventions import Direction
    from umbmark.model.kinematics import WheelParams
    from umbmark.robot.warehouse import warehouse_world
    from umbmark.robot.world import sweeps_along
    from umbmark.sim.engine import simulate
    from umbmark.sim.imu import ImuSetup, simulate_imu
    from umbmark.sim.missions import Warehouse, mission
    from umbmark.sim.robot import ControlConfig, NoiseModel, SimRobot
    from umbmark.sim.session import continuous_session

    rng = np.random.default_rng(setup.seed)
    wheels = WheelParams(wheelbase=NOMINAL[0], wheel_diameter=NOMINAL[1],
                         encoder_resolution=2000.0, gear_ratio=20.0)  # fmt: skip
    house = Warehouse()
    crossing = house.start(0)
    truth_at = np.array(crossing, dtype=np.float64)
    clock, angles_at = 0.0, np.zeros(2)
    pushes = sorted(setup.pushes, key=lambda p: p.at)
    stated = Pose2D(*setup.stated)
    bias = setup.gyro_bias
    while clock < seconds:
        errors, laser = setup.state_at(clock)
        robot = SimRobot.with_errors(wheels, *errors, noise=NoiseModel(slip=setup.slip))
        plan = mission(house, crossing, rng, MISSION_SECONDS, SPEED)
        back = _back_to(truth_at, crossing)
        route = Path(plan.name, (*back, *plan.segments))
        crossing = _plan_end(crossing, plan)
        result = simulate(robot, route, [Direction.CCW], ControlConfig(dt=0.02, speed=SPEED),
                          rng, record=True)  # fmt: skip
        start = (float(truth_at[0]), float(truth_at[1]), float(truth_at[2]))
        session = continuous_session(result, wheels.radians_per_pulse, start=start)
        truth = session.truth
        if pushes and pushes[0].at <= clock:
            truth = _pushed(truth, pushes.pop(0))
        world = warehouse_world(house, Pose2D(*laser))
        sweeps = sweeps_along(world, truth, setup.scan_rate, rng)
        times = session.wheels.time + clock
        angles = session.wheels.angles + angles_at
        gyro = None
        if setup.imu_rate > 0:
            imu = ImuSetup(imu_rate=setup.imu_rate, gyro_scale=setup.gyro_scale,
                           gyro_bias=bias, gyro_bias_walk=setup.gyro_bias_walk)  # fmt: skip
            read = simulate_imu(truth, imu, rng)
            gyro, bias = read.track, float(read.bias_end[2])  # the IMU's axes are the base's
        yield from _merged(times, angles, sweeps, gyro, clock, truth, stated)
        truth_at = truth.poses[-1].copy()
        clock = float(times[-1]) + 0.02
        angles_at = angles[-1]


def _pushed(truth: PoseSeries, push: Push) -> PoseSeries:
    """``truth`` moved sideways by the push from the middle of its driving on."""
    t, poses = truth.time, truth.poses.copy()
    a = float(t[0] + 0.5 * (t[-1] - t[0]))
    ramp = np.clip((t - a) / push.seconds, 0.0, 1.0)
    poses[:, 0] += -np.sin(poses[:, 2]) * push.metres * ramp
    poses[:, 1] += np.cos(poses[:, 2]) * push.metres * ramp
    return PoseSeries(time=t, poses=poses)


def _merged(
    times: FloatArray,
    angles: FloatArray,
    sweeps: ScanSeries,
    gyro: ImuTrack | None,
    clock: float,
    truth: PoseSeries,
    stated: Pose2D,
) -> Iterator[tuple[Message, Pose2D]]:
    """One mission's messages in time order."""
    s = sweeps
    items: list[tuple[float, int, Message]] = []
    for t, left, right in zip(times.tolist(), angles[:, 0].tolist(), angles[:, 1].tolist(),
                              strict=True):  # fmt: skip
        items.append((t, 0, Message("wheels", t, (left, right))))
    for k, t in enumerate((s.times + clock).tolist()):
        sweep = ScanSweep(t, s.angle_min, s.angle_increment, s.ranges[k], s.range_min,
                          s.range_max, stated, frame="laser", base="base_link")  # fmt: skip
        items.append((t, 1, Message("scan", t, sweep=sweep)))
    if gyro is not None:
        for t, w in zip((gyro.time + clock).tolist(), gyro.rate[:, 2].tolist(), strict=True):
            items.append((t, 2, Message("imu", t, (w,))))
    items.sort(key=lambda i: (i[0], i[1]))
    tt = truth.time + clock
    poses = truth.poses
    for t, _, message in items:
        k = min(int(np.searchsorted(tt, t)), len(tt) - 1)
        yield message, Pose2D(float(poses[k, 0]), float(poses[k, 1]), float(poses[k, 2]))


def feed(core: MonitorCore, message: Message) -> None:
    """Hand one message to the monitor's core."""
    if message.kind == "wheels":
        core.wheels(message.time, message.values[0], message.values[1])
    elif message.kind == "imu":
        core.gyro(message.time, message.values[0])
    elif message.sweep is not None:
        core.scan(message.sweep)

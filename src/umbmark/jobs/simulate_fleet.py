"""A fleet to try ``umbmark fleet`` on: ``umbmark simulate --fleet N --days D``.

:func:`simulate_fleet` writes the recordings of ``N`` virtual robots over ``D`` days, one a
day each, as a fleet records them: ``FOLDER/ROBOT/DATE/drive`` (ROS 2 MCAP, or ROS 1
``drive.bag``), each with the wheels (``/joint_states``), the odometry, a 2D laser
(``/scan``, its stated mounting on ``/tf_static`` and in ``/robot_description``), an IMU
(``/imu`` at :data:`IMU_RATE`, a MEMS gyro of the robot's own scale, bias and tilt,
mounted likewise: :mod:`umbmark.sim.imu`) and the motion capture's truth, driving
ordinary missions in a warehouse (:func:`umbmark.sim.missions.mission`: corridors,
quarter turns at shelves, whole turns now and then; not squares). Each robot has errors
of its own; some change:

- robot 2's right wheel is changed halfway (``E_d`` steps by :data:`WHEEL_STEP`);
- robot 3's laser is knocked the same day (:data:`KNOCK`: 10 mm forward, 3 degrees);
- robot 4's tyres wear (``E_s`` falls by :data:`WEAR_PER_DAY` a day);
- robot 5's gyro changes its scale the same day (``k_g`` steps by :data:`GYRO_STEP`: a
  replaced IMU, or one set to another range);
- the others stay as they are.

``FOLDER/truth.json`` holds every robot's true errors, laser mounting and gyro
(:meth:`umbmark.sim.imu.SimulatedImu.truth`) per day, and the events, beside the
recordings. The recordings' clocks start on their days, so the
day is in each recording as well as in its path.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import json
import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.core.jsontext import JsonText

if TYPE_CHECKING:
    from umbmark.sim.imu import ImuSetup

__all__ = ["GYRO_STEP", "IMU_RATE", "KNOCK", "WEAR_PER_DAY", "WHEEL_STEP", "FleetDay"]
__all__ += ["FleetSimulation", "simulate_fleet"]

#: The changed wheel's step in ``E_d``.
WHEEL_STEP = -0.006
#: The knocked laser: forward [m], yaw [rad].
KNOCK = (0.01, math.radians(3.0))
#: The wearing robot's loss of ``E_s`` a day.
WEAR_PER_DAY = 0.0008
#: The changed gyro's step in ``k_g``.
GYRO_STEP = 0.015
#: The robots' IMU rate [Hz].
IMU_RATE = 100.0
#: The truth's file in the fleet's folder.
TRUTH = "truth.json"
#: A robot's folder (:func:`robot_name`).
_ROBOT = re.compile(r"robot\d{2,}")
#: The fleet's nominal wheels: wheelbase, diameter [m].
NOMINAL = (0.34, 0.15)
#: The missions' speed [m/s] and the simulation's period [s].
SPEED, DT = 0.4, 0.02


@dataclass(frozen=True)
class FleetDay:
    """One robot's recording of one day, and its truth.

    Attributes
    ----------
    robot : str
    day : str
        ``YYYY-MM-DD``.
    path : str
        The recording.
    E_d, E_b, E_s : float
        The robot's true errors that day.
    laser : (float, float, float)
        The laser's true mounting ``x, y, yaw`` [m, m, rad] (stated: 0.1, 0, 0).
    imu : dict or None
        The IMU's truth that day (:meth:`umbmark.sim.imu.SimulatedImu.truth`: ``k_g``,
        the bias at the start and the end, its walk, the noise, the mounting; SI units).
    """

    robot: str
    day: str
    path: str
    E_d: float
    E_b: float
    E_s: float
    laser: tuple[float, float, float]
    imu: dict[str, Any] | None = None


@dataclass(frozen=True)
class FleetSimulation(JsonText):
    """What :func:`simulate_fleet` wrote.

    Attributes
    ----------
    folder : str
    recordings : tuple of FleetDay
    events : dict of str to str
        Each robot's change, in words (none: steady).
    """

    folder: str
    recordings: tuple[FleetDay, ...]
    events: dict[str, str]

    def to_dict(self) -> dict[str, Any]:
        """What ``truth.json`` holds (metres, radians)."""
        return {
            "folder": self.folder,
            "events": self.events,
            "recordings": [
                {
                    "robot": r.robot,
                    "day": r.day,
                    "path": r.path,
                    "E_d": r.E_d,
                    "E_b": r.E_b,
                    "E_s": r.E_s,
                    "laser": list(r.laser),
                    "imu": r.imu,
                }
                for r in self.recordings
            ],
        }


def _truths(
    robots: int, days: int, rng: np.random.Generator
) -> tuple[list[list[tuple[float, float, float, tuple[float, float, float]]]], dict[str, str]]:
    """Every robot's true ``E_d``, ``E_b``, ``E_s`` and laser per day, and the events."""
    out, events = [], {}
    half = days // 2
    for k in range(robots):
        name = robot_name(k)
        e_d = 1.0 + float(rng.normal(0.0, 0.002))
        e_b = 1.0 + float(rng.normal(0.0, 0.01))
        e_s = 1.0 + float(rng.normal(0.0, 0.003))
        laser = (0.1, 0.0, 0.0)
        mine = []
        for d in range(days):
            day_e_d, day_e_s, day_laser = e_d, e_s, laser
            if k == 1 and d >= half:
                day_e_d = e_d + WHEEL_STEP
            if k == 2 and d >= half:
                day_laser = (laser[0] + KNOCK[0], laser[1], laser[2] + KNOCK[1])
            if k == 3:
                day_e_s = e_s - WEAR_PER_DAY * d
            mine.append((day_e_d, e_b, day_e_s, day_laser))
        out.append(mine)
        events[name] = {
            1: f"right wheel changed on day {half + 1}: E_d {WHEEL_STEP:+g}",
            2: f"laser knocked on day {half + 1}: {KNOCK[0] * 1000:g} mm forward, "
            f"{math.degrees(KNOCK[1]):g} deg",
            3: f"tyres wearing: E_s {-WEAR_PER_DAY * 7:+g} a week",
            4: f"gyro scale changed on day {half + 1}: k_g {GYRO_STEP:+g}",
        }.get(k, "steady")
    return out, events


def _gyros(robots: int, days: int, rng: np.random.Generator) -> list[list[ImuSetup]]:
    """Every robot's gyro per day: a MEMS part's scale (``k_g`` within 3 %), bias (up to
    0.5 deg/s), tilt (up to 1 degree each way), the default noise and bias walk; robot
    5's scale steps by :data:`GYRO_STEP` halfway."""
    from umbmark.sim.imu import ImuSetup

    out = []
    for k in range(robots):
        k_g = 1.0 + float(rng.uniform(-0.03, 0.03))
        bias = math.radians(float(rng.uniform(-0.5, 0.5)))
        roll, pitch = (math.radians(float(rng.uniform(-1.0, 1.0))) for _ in range(2))
        made = [
            ImuSetup(imu_rate=IMU_RATE, gyro_scale=k_g + (GYRO_STEP if k == 4 and d >= days // 2
                     else 0.0), gyro_bias=bias, imu_roll=roll, imu_pitch=pitch)
            for d in range(days)
        ]  # fmt: skip
        out.append(made)
    return out


def simulate_fleet(
    out: str | os.PathLike[str] = "umbmark-fleet",
    *,
    fleet: int = 6,
    days: int = 8,
    minutes: float = 2.0,
    seed: int = 1,
    first_day: str = "2026-11-02",
    bag_storage: str = "mcap",
    force: bool = False,
    progress: Callable[[float], None] | None = None,
) -> FleetSimulation:
    """Write a simulated fleet's recordings and their truth into ``folder``.

    Parameters
    ----------
    out : path
        The folder to write: new or empty (``force``: one holding an earlier simulated fleet,
        and nothing else, is replaced whole). It is written whole or not at all: built in
        a hidden folder beside it and renamed onto it at the end, so a run that fails or
        is interrupted leaves nothing (and an earlier fleet as it was).
    fleet, days : int
        How many robots, and days of one recording each.
    minutes : float
        Each recording's driving [min].
    seed : int
    first_day : str
        ``YYYY-MM-DD`` of the first day.
    bag_storage : {"mcap", "sqlite3", "ros1"}
        ROS 2 bags (a folder each) or ROS 1 ``.bag`` files.
    force : bool
    progress : callable, optional
        Called with the fraction done (0 to 1).

    Raises
    ------
    InputError
        For counts out of range, a bad day or storage, a folder that holds files (without
        ``force``; with it, files that are not a simulated fleet's), or a recording that
        cannot be written.
    """
    from umbmark.core.atomic import atomic_tree, atomic_write_text
    from umbmark.options.fleet import FLEET_SIMULATION
    from umbmark.outputs.files import check_folder_output

    if fleet is None:
        raise InputError(f"{option('fleet')}: give how many robots")
    for name, value in (("fleet", fleet), ("days", days), ("minutes", minutes)):
        FLEET_SIMULATION[name].check(value)
    robots, days = int(fleet), int(days)
    if bag_storage not in ("mcap", "sqlite3", "ros1"):
        raise InputError(f"{option('bag_storage', repr(bag_storage))}: use mcap, sqlite3 or ros1")
    try:
        start = dt.date.fromisoformat(first_day)
    except ValueError:
        raise InputError(f"{option('first_day', repr(first_day))}: give YYYY-MM-DD") from None
    target = Path(out)
    check_folder_output(target)
    _check_replaceable(target, force)
    rng = np.random.default_rng(seed)
    truths, events = _truths(robots, days, rng)
    gyros = _gyros(robots, days, np.random.default_rng([seed, 3]))
    made = _make_parents(target)
    try:
        with atomic_tree(target) as fresh:  # whole or not at all: renamed in at the end
            fresh.mkdir()
            written = _recordings(fresh, target, truths, gyros, start, bag_storage, minutes,
                                  seed, progress)  # fmt: skip
            result = FleetSimulation(str(target), written, events)
            atomic_write_text(fresh / TRUTH, json.dumps(result.to_dict(), indent=1) + "\n")
    except BaseException:
        _remove_made(made)
        raise
    return result


def _recordings(
    fresh: Path,
    target: Path,
    truths: list[list[tuple[float, float, float, tuple[float, float, float]]]],
    gyros: list[list[ImuSetup]],
    start: dt.date,
    storage: str,
    minutes: float,
    seed: int,
    progress: Callable[[float], None] | None,
) -> tuple[FleetDay, ...]:
    """Every robot's recording of every day written into ``fresh`` (the folder being
    built), each named by where it will be (in ``target``)."""
    written: list[FleetDay] = []
    total = sum(len(days) for days in truths)
    for k, days in enumerate(truths):
        name = robot_name(k)
        for d, (e_d, e_b, e_s, laser) in enumerate(days):
            day = start + dt.timedelta(days=d)
            where = Path(name, day.isoformat(), "drive.bag" if storage == "ros1" else "drive")
            (fresh / where).parent.mkdir(parents=True)
            seeded = seed * 10007 + k * 389 + d
            gyro = _record(fresh / where, storage, k, day, (e_d, e_b, e_s), laser, gyros[k][d],
                           minutes, seeded)  # fmt: skip
            written.append(FleetDay(name, day.isoformat(), str(target / where), e_d, e_b, e_s,
                                    laser, gyro))  # fmt: skip
            if progress is not None:
                progress(len(written) / total)
    return tuple(written)


def robot_name(k: int) -> str:
    """The name of the fleet's robot ``k`` (from 0): ``robot01``, ``robot02``, ..."""
    return f"robot{k + 1:02d}"


def _check_replaceable(target: Path, force: bool) -> None:
    """Refuse a folder that holds anything (without ``force``), or anything but an earlier
    simulated fleet (with ``force``: its ``truth.json`` and robot folders, which are
    replaced whole; never a user's other files)."""
    if not target.is_dir():
        return
    held = sorted(p.name for p in target.iterdir())
    if not held:
        return
    if not force:
        raise InputError(
            f"is not empty; choose a new or empty folder, or pass {option('force')} to replace "
            "the simulated fleet it holds",
            source=target,
        )
    others = [n for n in held if n != TRUTH and not _ROBOT.fullmatch(n)]
    if TRUTH not in held or others:
        shown = others[0] if others else f"no {TRUTH}"
        raise InputError(
            f"holds {shown}: not a simulated fleet's, which {option('force')} replaces whole; "
            "choose a new or empty folder",
            source=target,
        )


def _make_parents(target: Path) -> list[Path]:
    """Make ``target``'s missing parent folders; those made, deepest first."""
    made = []
    parent = target.resolve().parent
    while not parent.exists():
        made.append(parent)
        parent = parent.parent
    for folder in reversed(made):
        try:
            folder.mkdir()
        except OSError as exc:
            _remove_made(made)
            raise InputError(f"cannot be made ({exc.strerror or exc})", source=folder) from None
    return made


def _remove_made(made: list[Path]) -> None:
    """Remove the parent folders :func:`_make_parents` made (deepest first), where empty."""
    for folder in made:
        with contextlib.suppress(OSError):
            folder.rmdir()


def _record(
    path: Path,
    storage: str,
    k: int,
    day: dt.date,
    errors: tuple[float, float, float],
    laser: tuple[float, float, float],
    gyro: ImuSetup,
    minutes: float,
    seed: int,
) -> dict[str, Any]:
    """One robot's recording of one day, at ``path`` (new); its IMU's truth."""
    from umbmark.core.conventions import Direction
    from umbmark.model.kinematics import WheelParams
    from umbmark.robot.base import Pose2D
    from umbmark.robot.warehouse import FLEET_LIDAR, warehouse_world
    from umbmark.robot.world import sweeps_along
    from umbmark.sim.engine import simulate as run_simulation
    from umbmark.sim.imu import IMU_TRANSLATION, simulate_imu
    from umbmark.sim.missions import Warehouse, mission
    from umbmark.sim.robot import ControlConfig, NoiseModel, SimRobot
    from umbmark.sim.session import continuous_session
    from umbmark.sources.bag.urdf import robot_urdf
    from umbmark.sources.bag.writer import bag_target, write_bag

    rng = np.random.default_rng(seed)
    odometry = WheelParams(  # 2000-count encoders on a 20:1 gear, as simulate's robot
        wheelbase=NOMINAL[0], wheel_diameter=NOMINAL[1], encoder_resolution=2000.0,
        gear_ratio=20.0,
    )  # fmt: skip
    robot = SimRobot.with_errors(odometry, *errors, noise=NoiseModel(slip=0.0002))
    warehouse = Warehouse()
    start = warehouse.start(k)
    route = mission(warehouse, start, rng, 60.0 * minutes, SPEED)
    result = run_simulation(
        robot, route, [Direction.CCW], ControlConfig(dt=DT, speed=SPEED), rng, record=True
    )
    session = continuous_session(result, odometry.radians_per_pulse, start=start)
    world = warehouse_world(warehouse, Pose2D(*laser))
    sweeps = sweeps_along(world, session.truth, 5.0, rng)
    stated = (FLEET_LIDAR.mount.x, FLEET_LIDAR.mount.y, FLEET_LIDAR.mount.theta)
    imu = simulate_imu(session.truth, gyro, np.random.default_rng([seed, 2]))
    mounted = (IMU_TRANSLATION, (gyro.imu_roll, gyro.imu_pitch, gyro.imu_yaw))
    epoch = dt.datetime(day.year, day.month, day.day, 8, tzinfo=dt.timezone.utc).timestamp()
    write_bag(
        bag_target(path, None if storage == "ros1" else storage),
        session.wheels, session.odometry, session.truth, scans=sweeps, laser_pose=stated,
        description=robot_urdf(NOMINAL[0], NOMINAL[1], stated, name=robot_name(k),
                               imu=mounted),
        start_epoch=epoch + 60.0 * k, imu=imu.track,
    )  # fmt: skip
    return imu.truth()

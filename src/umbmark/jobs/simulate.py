"""The simulation job: drive a virtual robot with known errors, keep what it measured.

:func:`simulate` is what ``umbmark simulate`` does. The robot's controller follows the
path in its **odometry** frame; its wheels move it by their true diameters; its encoders
quantize the rotation (see ``docs/simulator.md``). The report holds the runs (end points,
and with ``record``, ``logs`` or ``bag`` the time series) and writes the runs table, the
run logs and the ROS bag that ``calibrate`` reads.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.calibration.result import Calibrated, calibrated_params
from umbmark.core.errors import InputError, option, python_api, unexpected_keyword
from umbmark.core.jsontext import JsonText
from umbmark.core.version import __version__
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog
from umbmark.model.run import Run
from umbmark.outputs.files import OutputPlan
from umbmark.sim.imu import ImuSetup, SimulatedImu
from umbmark.sim.result import SimResult
from umbmark.sim.robot import SimRobot
from umbmark.sim.setup import DIRECTIONS, MAX_RUNS, PATHS, SEED_RANGE, SimSetup

if TYPE_CHECKING:
    from umbmark.sources.bag.writer import BagTarget

__all__ = [
    "DIRECTIONS",
    "MAX_RUNS",
    "PATHS",
    "SEED_RANGE",
    "SimSetup",
    "SimulationReport",
    "simulate",
]

#: Sweeps a second of the laser ``scan`` writes into a bag [Hz].
SCAN_RATE = 10.0
#: Share of the work done by the simulation when a bag is written (the rest is writing it).
SIMULATION_SHARE = 0.2


@dataclass(frozen=True, repr=False)
class SimulationReport(JsonText):
    """What a simulation drove and measured.

    Attributes
    ----------
    robot : SimRobot
        The robot: its true geometry, its odometry parameters, its noise.
    path : {"square", "straight", "turn"}
        The kind of path.
    path_name : str
        The path, for people (``"4 x 4 m square"``).
    side_length : float
        Side of the square, or length of the straight line [m].
    seed : int
        Seed of the non-systematic errors.
    result : SimResult
        End poses and, when recorded, the time series of every run.
    runs : tuple of Run
        Every run; with its time series (``run.log``) when recorded.
    configured_wheelbase : float or None
        The odometry's configured wheelbase [m] before a calibration's
        ``wheel_separation_multiplier``, recorded with the active parameters in the files.
    imu : SimulatedImu or None
        The IMU the bag records (``simulate(imu=...)``), with its truth.
    """

    robot: SimRobot
    path: str
    path_name: str
    side_length: float
    seed: int
    result: SimResult
    runs: tuple[Run, ...]
    configured_wheelbase: float | None = None
    imu: SimulatedImu | None = None

    def __repr__(self) -> str:
        truth = self.true_errors
        return (
            f"SimulationReport(path={self.path_name!r}, runs={len(self.runs)}, "
            f"E_d={truth['E_d']:.6f}, E_b={truth['E_b']:.6f}, E_s={truth['E_s']:.6f}, "
            f"seed={self.seed}, recorded={self.result.trace is not None})"
        )

    @property
    def nominal_wheelbase(self) -> float:
        """The nominal wheelbase ``b`` [m] the errors are relative to."""
        return self.configured_wheelbase or self.robot.odometry.wheelbase

    @property
    def true_errors(self) -> dict[str, float]:
        """``E_d``, ``E_b``, ``E_s`` of the robot relative to the nominal wheels (``D_n``,
        ``b``): what was asked for (:func:`umbmark.sim.summary.true_errors`)."""
        from umbmark.sim.summary import true_errors

        return true_errors(self.robot, self.nominal_wheelbase)

    @property
    def odometry_errors(self) -> dict[str, float]:
        """``E_d``, ``E_b``, ``E_s`` relative to the parameters the odometry used (with
        ``params``: the calibration's), what a calibration of these runs measures
        (:func:`umbmark.sim.summary.odometry_errors`)."""
        from umbmark.sim.summary import odometry_errors

        return odometry_errors(self.robot)

    @property
    def provenance(self) -> str:
        """Comment lines for the files written: where these runs came from."""
        robot, o = self.robot, self.robot.odometry
        return (
            f"Simulated by umbmark {__version__}: {self.path_name}, seed {self.seed}.\n"
            f"True robot: D_L = {robot.diameter_left:.6f} m, D_R = {robot.diameter_right:.6f} m, "
            f"b = {robot.wheelbase:.6f} m (E_d = {robot.E_d:.6f}, E_s = {robot.E_s:.6f}).\n"
            f"Odometry: D_n = {o.wheel_diameter:g} m, b = {o.wheelbase:.6f} m, "
            f"c_L = {o.c_left:.6f}, c_R = {o.c_right:.6f}, "
            f"{o.encoder_resolution:g} pulses x {o.gear_ratio:g}.\n"
            f"Noise: {robot.noise}"
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres, radians): what ``simulate --json`` prints."""
        from umbmark.sim.summary import describe_simulation

        out = describe_simulation(
            self.robot, self.result, self.path_name, self.path, self.nominal_wheelbase
        )
        out["seed"] = self.seed
        if self.imu is not None:
            out["imu"] = self.imu.truth()
        return out

    @python_api
    def write(
        self,
        *,
        output: str | os.PathLike[str] | None = None,
        logs: str | os.PathLike[str] | None = None,
        force: bool = False,
        bag: str | os.PathLike[str] | None = None,
        bag_storage: str | None = None,
        progress: Callable[[float], None] | None = None,
        scan: bool = False,
    ) -> list[Path]:
        """Write the runs table (``output``), the run logs (``logs``, a folder) and the
        runs as one recording in a ROS bag (``bag``: ``NAME.bag`` for ROS 1, a folder for
        ROS 2 with ``bag_storage`` sqlite3 or mcap; with ``scan``, a 2D laser's ``/scan``
        in a room around the runs, its mounting on ``/tf_static`` and in a
        ``/robot_description``; with the report's ``imu``, its ``/imu`` likewise).

        Without ``force`` no file is replaced: ``output`` and ``bag`` must be new paths,
        ``logs`` a new or empty folder. With ``force`` they are replaced, and the run log in
        ``logs`` (``metadata.yaml``, ``run-NN.csv``) is replaced whole: its older runs are
        removed, never mixed with the new ones (a folder holding another ``.csv`` is
        refused all the same). ``progress`` is called with the fraction of the bag written.

        Raises
        ------
        InputError
            If a file cannot be written, the runs have no time series for ``logs`` or
            ``bag``, an output exists or ``logs`` holds files (without ``force``), or
            ``logs`` holds a ``.csv`` that is not one of its run log's.
        """
        from umbmark.sources.runlog.writer import clear_run_log

        plan, target = _plan(self.path, output, logs, bag, bag_storage, force)
        if (plan.logs is not None or target is not None) and self.result.trace is None:
            raise InputError(
                f"{option('logs' if plan.logs is not None else 'bag')} needs the time series: "
                "simulate with record=True"
            )
        if plan.logs is not None:
            clear_run_log(plan.logs, remove=True)  # the new run log replaces the old whole
        written: list[Path] = []
        if plan.output is not None:
            from umbmark.sources.runs_table.writer import active_of, write_runs_table

            active = active_of(self.robot.odometry, self.configured_wheelbase)
            write_runs_table(plan.output, self.runs, comment=self.provenance, active=active)
            written.append(plan.output)
        if plan.logs is not None:
            written += self._write_logs(plan.logs)
        if target is not None:
            written.append(self._write_bag(target, progress, scan))
        return written

    def _write_bag(
        self, target: BagTarget, progress: Callable[[float], None] | None, scan: bool
    ) -> Path:
        from umbmark.sim.session import continuous_session
        from umbmark.sources.bag.writer import write_bag

        session = continuous_session(self.result, self.robot.odometry.radians_per_pulse)
        if not scan and self.imu is None:
            return write_bag(
                target, session.wheels, session.odometry, session.truth, progress=progress
            )
        from umbmark.robot.world import SCAN_LIDAR, room_around, sweeps_along
        from umbmark.sim.imu import IMU_TRANSLATION
        from umbmark.sources.bag.urdf import robot_urdf

        sweeps, pose = None, None
        if scan:
            room = room_around(session.truth.poses[:, :2])
            rng = np.random.default_rng([self.seed, 1])
            sweeps = sweeps_along(room, session.truth, SCAN_RATE, rng)
            pose = (SCAN_LIDAR.mount.x, SCAN_LIDAR.mount.y, SCAN_LIDAR.mount.theta)
        imu = None if self.imu is None else self.imu.track
        mounted = None
        if self.imu is not None:
            setup = self.imu.setup
            mounted = (IMU_TRANSLATION, (setup.imu_roll, setup.imu_pitch, setup.imu_yaw))
        odometry = self.robot.odometry
        description = robot_urdf(self.nominal_wheelbase, odometry.wheel_diameter, pose, imu=mounted)
        return write_bag(
            target, session.wheels, session.odometry, session.truth, progress=progress,
            scans=sweeps, laser_pose=pose or (0.0, 0.0, 0.0), description=description, imu=imu,
        )  # fmt: skip

    def _write_logs(self, folder: Path) -> list[Path]:
        from umbmark.sources.runlog.reader import LogMetadata
        from umbmark.sources.runlog.writer import run_file_name, write_log_csv, write_metadata
        from umbmark.sources.runs_table.writer import active_of

        trace = self.result.trace
        assert trace is not None
        robot, odo = self.robot, self.robot.odometry
        active = active_of(odo, self.configured_wheelbase)
        metadata = LogMetadata(
            wheel_diameter=odo.wheel_diameter,
            wheelbase=active.wheelbase,
            separation_multiplier=active.separation_multiplier,
            wheel_data="counts",
            encoder_resolution=odo.encoder_resolution,
            gear_ratio=odo.gear_ratio,
            side_length=self.side_length,
            c_left=odo.c_left,
            c_right=odo.c_right,
            extra={
                "truth": {
                    "wheel_diameter_left": robot.diameter_left,
                    "wheel_diameter_right": robot.diameter_right,
                    "wheelbase": robot.wheelbase,
                }
            },
        )
        written = [write_metadata(folder, metadata)]
        for i in range(len(self.result.directions)):
            end = int(self.result.samples_used[i])
            path = folder / run_file_name(i + 1)
            write_log_csv(
                path,
                trace.time[: end + 1],
                trace.true_pose[i, : end + 1],
                trace.counts[i, : end + 1],
                comment=self.provenance,
            )
            written.append(path)
        return written


def simulate(
    setup: SimSetup | None = None,
    *,
    params: Calibrated | None = None,
    record: bool = False,
    output: str | os.PathLike[str] | None = None,
    logs: str | os.PathLike[str] | None = None,
    force: bool = False,
    bag: str | os.PathLike[str] | None = None,
    bag_storage: str | None = None,
    progress: Callable[[float], None] | None = None,
    scan: bool = False,
    imu: bool | ImuSetup = False,
    **changes: float | str | bool,
) -> SimulationReport:
    """Drive a virtual robot with known errors around a path, steering by its own odometry.

    What ``umbmark simulate`` does, with the same options as keywords (SI units: the
    command's ``--turn-angle`` in degrees is ``turn_angle`` in radians here).

    Parameters
    ----------
    setup : SimSetup, optional
        The robot, path and noise (:class:`umbmark.sim.setup.SimSetup`: its fields and
        defaults).
    params : path, CalibrationReport or CalibratedParams, optional
        A calibration (result file or report) whose ``c_L``, ``c_R`` and wheelbase the
        robot's odometry uses; the truth stays relative to the nominal values.
    record : bool
        Keep every run's time series (``run.log``); implied by ``logs`` and ``bag``.
    output, logs : path, optional
        Write the runs table (CSV, metres, radians) and the run logs (a folder).
    force : bool
        Replace ``output`` and ``bag`` if they exist, and the run log in ``logs`` whole
        (its older runs removed; see :meth:`SimulationReport.write`).
    bag : path, optional
        Write the runs as one recording in a ROS bag, as a robot with motion capture
        records them (:mod:`umbmark.sources.bag.writer`): ``NAME.bag`` is ROS 1, another
        name a ROS 2 bag folder.
    bag_storage : {"sqlite3", "mcap"}, optional
        Storage of a ROS 2 bag; sqlite3 (rosbags' default) when not given.
    progress : callable, optional
        Called with the fraction done (0 to 1); with ``bag``, the simulation is the first
        :data:`SIMULATION_SHARE` of it, writing the bag the rest.
    scan : bool
        With ``bag``: a 2D laser in a room around the runs too (``/scan`` at
        :data:`SCAN_RATE`, 360 beams, 1 cm noise; its mounting 0.1 m ahead of the axle on
        ``/tf_static`` and, with the nominal wheels, in ``/robot_description``), for
        ``calibrate BAG --scan-topic /scan``.
    imu : bool or ImuSetup
        With ``bag``: an IMU too (``/imu``, ``sensor_msgs/Imu`` in ``imu_link``, its
        mounting on ``/tf_static`` and in ``/robot_description``): True for a MEMS part's
        defaults, or an :class:`umbmark.sim.imu.ImuSetup` (its rate, the gyro's scale,
        bias, bias walk, noise, full scale, the mounting); its truth goes into the report
        (``report.imu``, ``to_dict()["imu"]``).
    **changes
        Fields of ``setup`` to change, or of the default one (``E_d=1.01, runs=10``).

    Raises
    ------
    InputError
        For an option out of range.
    """
    chosen = _setup(setup, changes)
    for flag, what in ((scan, "a laser"), (imu, "an IMU")):
        if flag is not False and bag is None:
            name = "scan" if what == "a laser" else "imu"
            raise InputError(
                f"{option(name)} writes {what} into {option('bag')}: give {option('bag')} too"
            )
    imu_setup = _imu_setup(imu)
    inputs = [params] if isinstance(params, (str, os.PathLike)) else []
    _plan(chosen.path, output, logs, bag, bag_storage, force, inputs)

    from umbmark.sim.engine import simulate as run_simulation

    odometry = chosen.odometry
    robot = SimRobot.with_errors(
        odometry, E_d=chosen.E_d, E_b=chosen.E_b, E_s=chosen.E_s, noise=chosen.noise
    )
    if params is not None:
        applied = calibrated_params(params).applied_to(odometry)
        robot = robot.calibrated(applied.c_left, applied.c_right, applied.wheelbase)
    route, directions = chosen.route()
    recorded = record or logs is not None or bag is not None
    simulated, written = _split_progress(progress, bag is not None)
    chosen.check_work(route, len(directions), recorded)
    result = run_simulation(
        robot,
        route,
        directions,
        chosen.control,
        np.random.default_rng(chosen.seed),
        record=recorded,
        progress=simulated,
    )
    report = SimulationReport(
        robot=robot,
        path=chosen.path,
        path_name=route.name,
        side_length=chosen.side_length,
        seed=chosen.seed,
        result=result,
        runs=tuple(_runs_with_logs(result, odometry) if recorded else result.runs()),
        configured_wheelbase=chosen.wheelbase,
        imu=None if imu_setup is None else _read_imu(result, robot, imu_setup, chosen.seed),
    )
    report.write(
        output=output, logs=logs, force=force, bag=bag, bag_storage=bag_storage,
        progress=written, scan=scan,
    )  # fmt: skip
    return report


simulate.__keyword_fields__ = SimSetup  # type: ignore[attr-defined]  # its **changes


def _imu_setup(imu: object) -> ImuSetup | None:
    """The IMU asked for: None (False), the defaults (True), or the setup given."""
    if imu is False:
        return None
    if imu is True:
        return ImuSetup()
    if isinstance(imu, ImuSetup):
        return imu
    raise InputError(f"{option('imu', repr(imu)[:40])}: give True, False or an ImuSetup")


def _read_imu(result: SimResult, robot: SimRobot, setup: ImuSetup, seed: int) -> SimulatedImu:
    """The IMU read along the runs as one recording (its own random numbers)."""
    from umbmark.sim.imu import simulate_imu
    from umbmark.sim.session import continuous_session

    session = continuous_session(result, robot.odometry.radians_per_pulse)
    return simulate_imu(session.truth, setup, np.random.default_rng([seed, 2]))


def _setup(setup: SimSetup | None, changes: Mapping[str, float | str | bool]) -> SimSetup:
    """``setup`` (or the default) with ``changes``, refusing a keyword it has no field of."""
    known = [f.name for f in fields(SimSetup)]
    for name in changes:
        if name not in known:
            raise unexpected_keyword("simulate", name, known)
    return replace(setup or SimSetup(), **changes)  # type: ignore[arg-type]


def _plan(
    path: str,
    output: str | os.PathLike[str] | None,
    logs: str | os.PathLike[str] | None,
    bag: str | os.PathLike[str] | None,
    bag_storage: str | None,
    force: bool,
    inputs: Sequence[str | os.PathLike[str]] = (),
) -> tuple[OutputPlan, BagTarget | None]:
    """The outputs and the bag, checked before anything is simulated or written: none
    replaces a file without ``force``; ``logs`` is new or empty, or (``force``) one whose
    run log the new one replaces whole (:func:`~umbmark.sources.runlog.writer.clear_run_log`)."""
    from umbmark.sources.bag.writer import bag_target
    from umbmark.sources.runlog.writer import clear_run_log

    _check_square_outputs(path, output, bag)
    plan = OutputPlan.of(force=force, inputs=inputs, output=output, logs=logs, bag=bag)
    if bag_storage is not None and plan.bag is None:
        raise InputError(
            f"{option('bag_storage')} says how to store {option('bag')}: give {option('bag')} too"
        )
    target = None if plan.bag is None else bag_target(plan.bag, bag_storage, force=force)
    if plan.logs is not None:
        clear_run_log(plan.logs, remove=False)
    return plan, target


def _check_square_outputs(path: str, output: object, bag: object) -> None:
    """Refuse a runs table or a bag of runs that are not squares."""
    if path == "square":
        return
    if output is not None:
        raise InputError(
            f"{option('output')} writes a runs table of square runs: use {option('path', 'square')}"
        )
    if bag is not None:
        raise InputError(
            f"{option('bag')} writes square runs (one recording, split where the robot rests "
            f"near the start): use {option('path', 'square')}"
        )


def _split_progress(
    progress: Callable[[float], None] | None, bag: bool
) -> tuple[Callable[[float], None] | None, Callable[[float], None] | None]:
    """The progress callbacks of the simulation and of writing the bag: the simulation's
    fraction is all of it without a bag, the first :data:`SIMULATION_SHARE` with one."""
    if progress is None or not bag:
        return progress, None
    report = progress
    return (
        lambda fraction: report(SIMULATION_SHARE * fraction),
        lambda fraction: report(SIMULATION_SHARE + (1.0 - SIMULATION_SHARE) * fraction),
    )


def _runs_with_logs(result: SimResult, odometry: WheelParams) -> list[Run]:
    """The runs with their time series: wheel angles from the counts, truth as driven."""
    trace = result.trace
    assert trace is not None
    out = []
    for i, run in enumerate(result.runs()):
        end = int(result.samples_used[i]) + 1
        counts = trace.counts[i, :end]
        log = RunLog(
            time=trace.time[:end].copy(),
            wheel_angles=(counts - counts[0]) * odometry.radians_per_pulse,
            truth=trace.true_pose[i, :end].copy(),
            source=run.label,
        )
        out.append(replace(run, log=log))
    return out

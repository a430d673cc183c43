"""The simulation job: drive a virtual robot with known errors, keep what it measured.

:func:`simulate` is what ``umbmark simulate`` does. The robot's controller follows the
path in its **odometry** frame; its wheels move it by their true diameters; its encoders
quantize the rotation (see ``docs/simulator.md``). The report holds the runs (end points,
and with ``record``, ``logs`` or ``bag`` the time series) and writes the runs table, the
run logs and the ROS bag that ``calibrate`` reads.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from umbmark.calibration.report import Calibrated, calibrated_params
from umbmark.core.bounds import (
    ENCODER_RESOLUTION_RANGE,
    GEAR_RATIO_RANGE,
    MAX_SIDE_LENGTH,
    MAX_WHEELBASE,
    check_length,
    check_positive_option,
    check_range,
    option_float,
)
from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, python_api
from umbmark.core.jsontext import JsonText
from umbmark.core.version import __version__
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog
from umbmark.model.runs import Run
from umbmark.outputs.files import OutputPlan
from umbmark.sim.result import SimResult
from umbmark.sim.robot import ControlConfig, NoiseModel, VirtualRobot

if TYPE_CHECKING:
    from umbmark.sim.paths import Path as SimPath
    from umbmark.sources.bag.writer import BagTarget

__all__ = ["PATHS", "SimulationReport", "simulate"]

PathKind = Literal["square", "straight", "turn"]
PATHS: tuple[PathKind, ...] = ("square", "straight", "turn")
DirectionChoice = Literal["both", "cw", "ccw"]
DIRECTIONS: tuple[DirectionChoice, ...] = ("both", "cw", "ccw")
#: Largest on-the-spot turn [rad]: ten turns.
MAX_TURN = 20.0 * math.pi
#: Bounds of the options that set how much work a simulation is (and of plausibility).
MAX_RUNS = 1000
SEED_RANGE = (0, 2**63 - 1)
DT_RANGE = (1e-4, 0.1)  # s
SPEED_RANGE = (0.01, 5.0)  # m/s
MAX_SLIP = 0.1  # standard deviation of the relative wheel slip
MAX_BUMP_SIZE = 0.05  # m
MAX_BUMP_RATE = 100.0  # per metre
#: Most sampling periods one run may take (path length / --speed / --dt and the turns):
#: the simulation's time grows with it (about 15 us a period on one core).
MAX_SAMPLES_PER_RUN = 2_000_000
#: Most sampling periods of all runs together (the work of the vectorized runs) ...
MAX_SAMPLES = 1_000_000_000
#: ... and when the time series are kept (--logs, --bag, ``record``): about 130 bytes each.
MAX_RECORDED_SAMPLES = 5_000_000
#: Share of the work done by the simulation when a bag is written (the rest is writing it).
SIMULATION_SHARE = 0.2
#: Fewest encoder counts per wheel revolution (--encoder-resolution x --gear-ratio) ...
MIN_COUNTS_PER_REVOLUTION = 16
#: ... and per path: fewer, and the robot stops before it starts (it stops within two
#: counts of its goal), so that its runs would measure nothing.
MIN_COUNTS_PER_PATH = 20


@dataclass(frozen=True, repr=False)
class SimulationReport(JsonText):
    """What a simulation drove and measured.

    Attributes
    ----------
    robot : VirtualRobot
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
    """

    robot: VirtualRobot
    path: str
    path_name: str
    side_length: float
    seed: int
    result: SimResult
    runs: tuple[Run, ...]
    configured_wheelbase: float | None = None

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
    ) -> list[Path]:
        """Write the runs table (``output``), the run logs (``logs``, a folder) and the
        runs as one recording in a ROS bag (``bag``: ``NAME.bag`` for ROS 1, a folder for
        ROS 2 with ``bag_storage`` sqlite3 or mcap).

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
                f"{'--logs' if plan.logs is not None else '--bag'} needs the time series: "
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
            written.append(self._write_bag(target, progress))
        return written

    def _write_bag(self, target: BagTarget, progress: Callable[[float], None] | None) -> Path:
        from umbmark.sim.session import continuous_session
        from umbmark.sources.bag.writer import write_bag

        session = continuous_session(self.result, self.robot.odometry.radians_per_pulse)
        return write_bag(target, session.wheels, session.odometry, session.truth, progress=progress)

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
    *,
    E_d: float = 1.0,
    E_b: float = 1.0,
    E_s: float = 1.0,
    side_length: float = 4.0,
    wheelbase: float = 0.34,
    wheel_diameter: float = 0.15,
    encoder_resolution: float = 2000.0,
    gear_ratio: float = 20.0,
    runs: int = 5,
    direction: DirectionChoice = "both",
    path: PathKind = "square",
    turn_angle: float = 2.0 * math.pi,
    noise_free: bool = False,
    slip: float = 0.0004,
    bump_rate: float = 0.0,
    bump_size: float = 0.002,
    params: Calibrated | None = None,
    dt: float = 0.01,
    speed: float = 0.2,
    seed: int = 1,
    record: bool = False,
    output: str | os.PathLike[str] | None = None,
    logs: str | os.PathLike[str] | None = None,
    force: bool = False,
    bag: str | os.PathLike[str] | None = None,
    bag_storage: str | None = None,
    progress: Callable[[float], None] | None = None,
) -> SimulationReport:
    """Drive a virtual robot with known errors around a path, steering by its own odometry.

    What ``umbmark simulate`` does, with the same options as keywords (SI units: the
    command's ``--turn-angle`` in degrees is ``turn_angle`` in radians here).

    Parameters
    ----------
    E_d, E_b, E_s : float
        True ``D_R / D_L`` (Eq. 2.3), ``b_actual / b`` (Eq. 2.4), ``D_avg / D_n``.
    side_length : float
        Side of the square, or length of the straight line [m].
    wheelbase, wheel_diameter : float
        Nominal ``b`` and ``D_n`` [m], what the robot's odometry uses.
    encoder_resolution, gear_ratio : float
        Encoder pulses per motor revolution; motor revolutions per wheel revolution.
    runs : int
        Runs in each direction.
    direction : {"both", "cw", "ccw"}
        Both (UMBmark), or one direction only (the uni-directional test).
    path : {"square", "straight", "turn"}
        A square (UMBmark), a straight leg of ``side_length`` (shows ``E_s``) or an
        on-the-spot turn by ``turn_angle`` [rad], ccw positive (shows Sec. 2.3).
    noise_free : bool
        No slip and no bumps (only quantization).
    slip, bump_rate, bump_size : float
        Wheel slip [m^0.5], floor bumps per metre of wheel travel, extra wheel rotation
        per bump as a length [m].
    params : path, CalibrationReport or CalibratedParams, optional
        A calibration (result file or report) whose ``c_L``, ``c_R`` and wheelbase the
        robot's odometry uses; the truth stays relative to the nominal values.
    dt, speed : float
        Sampling period [s], speed on the legs [m/s].
    seed : int
        Seed of the non-systematic errors.
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

    Raises
    ------
    InputError
        For an option out of range.
    """
    E_d, E_b, E_s = (
        option_float(n, v) for n, v in (("--E-d", E_d), ("--E-b", E_b), ("--E-s", E_s))
    )
    slip, bump_rate, bump_size = (
        option_float(n, v)
        for n, v in (("--slip", slip), ("--bump-rate", bump_rate), ("--bump-size", bump_size))
    )
    turn_angle = option_float("--turn-angle", turn_angle)
    for name, value in (("--E-d", E_d), ("--E-b", E_b), ("--E-s", E_s)):
        check_positive_option(name, value)
        if not 0.5 < value < 2.0:
            raise InputError(f"{name} {value:g} is not a plausible ratio (0.5 to 2)")
    check_length("--side-length", side_length, MAX_SIDE_LENGTH)
    check_length("--wheelbase", wheelbase, MAX_WHEELBASE)
    check_length("--wheel-diameter", wheel_diameter, MAX_WHEELBASE)
    for name, value in (
        ("--encoder-resolution", encoder_resolution),
        ("--gear-ratio", gear_ratio),
        ("--dt", dt),
        ("--speed", speed),
    ):
        check_positive_option(name, value)
    for name, value, bounds in (
        ("--dt", dt, DT_RANGE),
        ("--speed", speed, SPEED_RANGE),
        ("--encoder-resolution", encoder_resolution, ENCODER_RESOLUTION_RANGE),
        ("--gear-ratio", gear_ratio, GEAR_RATIO_RANGE),
        ("--slip", slip, (0.0, MAX_SLIP)),
        ("--bump-size", bump_size, (0.0, MAX_BUMP_SIZE)),
        ("--bump-rate", bump_rate, (0.0, MAX_BUMP_RATE)),
    ):
        check_range(name, value, bounds)
    if isinstance(seed, bool) or not SEED_RANGE[0] <= seed <= SEED_RANGE[1]:
        raise InputError(f"--seed {seed} is outside {SEED_RANGE[0]} to {SEED_RANGE[1]}")
    if runs > MAX_RUNS:
        raise InputError(f"--runs {runs} is more than {MAX_RUNS}")
    if not math.isfinite(turn_angle):
        raise InputError(f"--turn-angle {turn_angle!r} is not a finite number")
    if direction not in DIRECTIONS:
        raise InputError(f"--direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
    if path not in PATHS:
        raise InputError(f"--path {path!r}: use one of {', '.join(PATHS)}")
    if runs < 1:
        raise InputError(f"--runs must be at least 1, got {runs}")
    if path == "square" and direction == "both" and runs < 2:
        raise InputError("--runs must be at least 2 for UMBmark (the paper uses 5)")
    for name, value in (("--slip", slip), ("--bump-rate", bump_rate), ("--bump-size", bump_size)):
        if not (math.isfinite(value) and value >= 0):
            raise InputError(f"{name} must be >= 0, got {value:g}")
    if path == "turn" and not (0 < abs(turn_angle) <= MAX_TURN):
        raise InputError(
            f"--turn-angle {math.degrees(turn_angle):g} deg: give a turn of up to "
            f"{math.degrees(MAX_TURN):g} deg either way, not zero"
        )
    inputs = [params] if isinstance(params, (str, os.PathLike)) else []
    _plan(path, output, logs, bag, bag_storage, force, inputs)

    from umbmark.sim import paths
    from umbmark.sim.engine import simulate as run_simulation

    odometry = WheelParams(
        wheelbase=wheelbase,
        wheel_diameter=wheel_diameter,
        encoder_resolution=encoder_resolution,
        gear_ratio=gear_ratio,
    )
    noise = NoiseModel() if noise_free else NoiseModel(slip, bump_rate, bump_size)
    robot = VirtualRobot.with_errors(odometry, E_d=E_d, E_b=E_b, E_s=E_s, noise=noise)
    if params is not None:
        applied = calibrated_params(params).applied_to(odometry)
        robot = robot.calibrated(applied.c_left, applied.c_right, applied.wheelbase)

    if path == "square":
        chosen = paths.square(side_length)
        directions = {
            "both": [Direction.CW] * runs + [Direction.CCW] * runs,
            "cw": [Direction.CW] * runs,
            "ccw": [Direction.CCW] * runs,
        }[direction]
    elif path == "straight":
        chosen = paths.straight_line(side_length)
        directions = [Direction.CCW] * runs
    else:
        chosen = paths.spot_turn(turn_angle)
        directions = [Direction.CCW] * runs

    recorded = record or logs is not None or bag is not None
    simulated, written = _split_progress(progress, bag is not None)
    _check_resolution(chosen, odometry)
    _check_work(chosen, len(directions), wheelbase, ControlConfig(dt=dt, speed=speed), recorded)
    result = run_simulation(
        robot,
        chosen,
        directions,
        ControlConfig(dt=dt, speed=speed),
        np.random.default_rng(seed),
        record=recorded,
        progress=simulated,
    )
    report = SimulationReport(
        robot=robot,
        path=path,
        path_name=chosen.name,
        side_length=side_length,
        seed=seed,
        result=result,
        runs=tuple(_runs_with_logs(result, odometry) if recorded else result.runs()),
        configured_wheelbase=wheelbase,
    )
    report.write(
        output=output, logs=logs, force=force, bag=bag, bag_storage=bag_storage, progress=written
    )
    return report


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
        raise InputError("--bag-storage says how to store --bag: give --bag too")
    target = None if plan.bag is None else bag_target(plan.bag, bag_storage, force=force)
    if plan.logs is not None:
        clear_run_log(plan.logs, remove=False)
    return plan, target


def _check_square_outputs(path: str, output: object, bag: object) -> None:
    """Refuse a runs table or a bag of runs that are not squares."""
    if path == "square":
        return
    if output is not None:
        raise InputError("-o writes a runs table of square runs: use --path square")
    if bag is not None:
        raise InputError(
            "--bag writes square runs (one recording, split where the robot rests near the "
            "start): use --path square"
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


def _check_resolution(path: SimPath, odometry: WheelParams) -> None:
    """Refuse encoders too coarse for the robot to drive the path by them.

    A wheel count is ``pi D_n / (resolution x gear ratio)`` of wheel travel; a leg needs
    :data:`MIN_COUNTS_PER_PATH` counts of it, an on-the-spot turn as many counts of each
    wheel's arc (``|angle| b / 2``).
    """
    per_revolution = odometry.encoder_resolution * odometry.gear_ratio
    if per_revolution < MIN_COUNTS_PER_REVOLUTION:
        raise InputError(
            f"--encoder-resolution {odometry.encoder_resolution:g} x --gear-ratio "
            f"{odometry.gear_ratio:g} is {per_revolution:.3g} encoder counts per wheel "
            f"revolution: at least {MIN_COUNTS_PER_REVOLUTION}"
        )
    count = math.pi * odometry.wheel_diameter / per_revolution  # m of wheel travel
    for segment in path.segments:
        travel = segment.amount if segment.kind == "straight" else 0.5 * odometry.wheelbase
        if segment.kind == "turn":
            travel *= abs(segment.amount)
        if travel < MIN_COUNTS_PER_PATH * count:
            what = (
                f"--side-length {segment.amount:g} m"
                if segment.kind == "straight"
                else f"--turn-angle {math.degrees(segment.amount):g} deg"
            )
            raise InputError(
                f"{what} is {travel / count:.3g} encoder counts of wheel travel: at least "
                f"{MIN_COUNTS_PER_PATH} (one count is {count * 1000:.3g} mm); the robot "
                "would stop before it moves"
            )


def _check_work(
    path: SimPath, runs: int, wheelbase: float, control: ControlConfig, recorded: bool
) -> None:
    """Refuse a simulation whose work or memory exceeds the documented bounds.

    A run takes about (legs / speed + turns / turning rate) / dt sampling periods; the
    limits are :data:`MAX_SAMPLES_PER_RUN`, :data:`MAX_SAMPLES` for all runs and
    :data:`MAX_RECORDED_SAMPLES` when the time series are kept.
    """
    turning = sum(abs(s.amount) for s in path.segments if s.kind == "turn")
    seconds = path.length / control.speed + turning * 0.5 * wheelbase / control.turn_wheel_speed
    per_run = seconds / control.dt
    if per_run > MAX_SAMPLES_PER_RUN:
        raise InputError(
            f"a run of the {path.name} path at --speed {control.speed:g} m/s and --dt "
            f"{control.dt:g} s takes about {per_run:.3g} sampling periods: at most "
            f"{MAX_SAMPLES_PER_RUN:.3g}; raise --speed or --dt, or shorten the path"
        )
    if per_run * runs > MAX_SAMPLES:
        raise InputError(
            f"{runs} runs of about {per_run:.3g} sampling periods each are more than "
            f"{MAX_SAMPLES:.3g} in all; give fewer --runs, or raise --speed or --dt"
        )
    if recorded and per_run * runs > MAX_RECORDED_SAMPLES:
        raise InputError(
            f"keeping the time series of {runs} runs of about {per_run:.3g} samples each "
            f"needs {per_run * runs * 130 / 1e9:.1f} GB: at most {MAX_RECORDED_SAMPLES:.3g} "
            "samples in all; give fewer --runs, a larger --dt, or no --logs or --bag"
        )


def _runs_with_logs(result: SimResult, odometry: WheelParams) -> list[Run]:
    """The runs with their time series: wheel angles from the counts, truth as driven."""
    from dataclasses import replace

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

"""What a simulation drives: the virtual robot's errors and geometry, the path, the
noise, the controller's period and speed, and the seed, checked once (:class:`SimSetup`).

``umbmark simulate`` and :func:`umbmark.simulate` take these as keywords (the command's
``--turn-angle`` in degrees is ``turn_angle`` in radians here); messages name the
command's flags (the library shows its keywords). Also here: the bounds of the work one
simulation may be.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

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
from umbmark.core.errors import InputError, option
from umbmark.model.kinematics import WheelParams
from umbmark.sim.paths import Path, spot_turn, square, straight_line
from umbmark.sim.robot import ControlConfig, NoiseModel

__all__ = [
    "DIRECTIONS",
    "MAX_RUNS",
    "PATHS",
    "SEED_RANGE",
    "DirectionChoice",
    "PathKind",
    "SimSetup",
]

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
#: Fewest encoder counts per wheel revolution (--encoder-resolution x --gear-ratio) ...
MIN_COUNTS_PER_REVOLUTION = 16
#: ... and per path: fewer, and the robot stops before it starts (it stops within two
#: counts of its goal), so that its runs would measure nothing.
MIN_COUNTS_PER_PATH = 20


@dataclass(frozen=True)
class SimSetup:
    """A simulation's robot, path and noise, checked when made.

    Attributes
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
    turn_angle : float
        The turn of ``path="turn"`` [rad].
    noise_free : bool
        No slip and no bumps (only quantization).
    slip, bump_rate, bump_size : float
        Wheel slip [m^0.5], floor bumps per metre of wheel travel, extra wheel rotation
        per bump as a length [m].
    dt, speed : float
        Sampling period [s], speed on the legs [m/s].
    seed : int
        Seed of the non-systematic errors.

    Raises
    ------
    InputError
        For a value out of its range, naming the option.
    """

    E_d: float = 1.0
    E_b: float = 1.0
    E_s: float = 1.0
    side_length: float = 4.0
    wheelbase: float = 0.34
    wheel_diameter: float = 0.15
    encoder_resolution: float = 2000.0
    gear_ratio: float = 20.0
    runs: int = 5
    direction: DirectionChoice = "both"
    path: PathKind = "square"
    turn_angle: float = 2.0 * math.pi
    noise_free: bool = False
    slip: float = 0.0004
    bump_rate: float = 0.0
    bump_size: float = 0.002
    dt: float = 0.01
    speed: float = 0.2
    seed: int = field(default=1)

    def __post_init__(self) -> None:
        for name, flag in (
            ("E_d", "--E-d"),
            ("E_b", "--E-b"),
            ("E_s", "--E-s"),
            ("slip", "--slip"),
            ("bump_rate", "--bump-rate"),
            ("bump_size", "--bump-size"),
            ("turn_angle", "--turn-angle"),
        ):
            object.__setattr__(self, name, option_float(flag, getattr(self, name)))
        self._check_errors()
        self._check_robot()
        self._check_runs()

    def _check_errors(self) -> None:
        for name, value in (("--E-d", self.E_d), ("--E-b", self.E_b), ("--E-s", self.E_s)):
            check_positive_option(name, value)
            if not 0.5 < value < 2.0:
                raise InputError(f"{name} {value:g} is not a plausible ratio (0.5 to 2)")

    def _check_robot(self) -> None:
        check_length(option("side_length"), self.side_length, MAX_SIDE_LENGTH)
        check_length(option("wheelbase"), self.wheelbase, MAX_WHEELBASE)
        check_length(option("wheel_diameter"), self.wheel_diameter, MAX_WHEELBASE)
        for name, value in (
            ("--encoder-resolution", self.encoder_resolution),
            ("--gear-ratio", self.gear_ratio),
            ("--dt", self.dt),
            ("--speed", self.speed),
        ):
            check_positive_option(name, value)
        for name, value, bounds in (
            ("--dt", self.dt, DT_RANGE),
            ("--speed", self.speed, SPEED_RANGE),
            ("--encoder-resolution", self.encoder_resolution, ENCODER_RESOLUTION_RANGE),
            ("--gear-ratio", self.gear_ratio, GEAR_RATIO_RANGE),
            ("--slip", self.slip, (0.0, MAX_SLIP)),
            ("--bump-size", self.bump_size, (0.0, MAX_BUMP_SIZE)),
            ("--bump-rate", self.bump_rate, (0.0, MAX_BUMP_RATE)),
        ):
            check_range(name, value, bounds)

    def _check_runs(self) -> None:
        seed, runs, direction, path = self.seed, self.runs, self.direction, self.path
        if isinstance(seed, bool) or not SEED_RANGE[0] <= seed <= SEED_RANGE[1]:
            raise InputError(f"--seed {seed} is outside {SEED_RANGE[0]} to {SEED_RANGE[1]}")
        if runs > MAX_RUNS:
            raise InputError(f"--runs {runs} is more than {MAX_RUNS}")
        if not math.isfinite(self.turn_angle):
            raise InputError(f"--turn-angle {self.turn_angle!r} is not a finite number")
        if direction not in DIRECTIONS:
            raise InputError(f"--direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
        if path not in PATHS:
            raise InputError(f"--path {path!r}: use one of {', '.join(PATHS)}")
        if runs < 1:
            raise InputError(f"--runs must be at least 1, got {runs}")
        if path == "square" and direction == "both" and runs < 2:
            raise InputError("--runs must be at least 2 for UMBmark (the paper uses 5)")
        for name, value in (
            ("--slip", self.slip),
            ("--bump-rate", self.bump_rate),
            ("--bump-size", self.bump_size),
        ):
            if not (math.isfinite(value) and value >= 0):
                raise InputError(f"{name} must be >= 0, got {value:g}")
        if path == "turn" and not (0 < abs(self.turn_angle) <= MAX_TURN):
            raise InputError(
                f"--turn-angle {math.degrees(self.turn_angle):g} deg: give a turn of up to "
                f"{math.degrees(MAX_TURN):g} deg either way, not zero"
            )

    @property
    def odometry(self) -> WheelParams:
        """The nominal parameters, what the robot's odometry uses."""
        return WheelParams(
            wheelbase=self.wheelbase,
            wheel_diameter=self.wheel_diameter,
            encoder_resolution=self.encoder_resolution,
            gear_ratio=self.gear_ratio,
        )

    @property
    def noise(self) -> NoiseModel:
        return (
            NoiseModel()
            if self.noise_free
            else NoiseModel(self.slip, self.bump_rate, self.bump_size)
        )

    @property
    def control(self) -> ControlConfig:
        return ControlConfig(dt=self.dt, speed=self.speed)

    def route(self) -> tuple[Path, list[Direction]]:
        """The path and the direction of each run."""
        runs = self.runs
        if self.path == "square":
            directions = {
                "both": [Direction.CW] * runs + [Direction.CCW] * runs,
                "cw": [Direction.CW] * runs,
                "ccw": [Direction.CCW] * runs,
            }[self.direction]
            return square(self.side_length), directions
        if self.path == "straight":
            return straight_line(self.side_length), [Direction.CCW] * runs
        return spot_turn(self.turn_angle), [Direction.CCW] * runs

    def check_work(self, path: Path, runs: int, recorded: bool) -> None:
        """Refuse encoders too coarse to drive ``path`` by, and a simulation whose work or
        memory exceeds the documented bounds (:func:`check_resolution`, :func:`check_work`)."""
        check_resolution(path, self.odometry)
        check_work(path, runs, self.wheelbase, self.control, recorded)


def check_resolution(path: Path, odometry: WheelParams) -> None:
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


def check_work(
    path: Path, runs: int, wheelbase: float, control: ControlConfig, recorded: bool
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

"""What a simulation drives: the virtual robot's errors and geometry, the path, the
noise, the controller's period and speed, and the seed, checked once (:class:`SimSetup`).

``umbmark simulate`` and :func:`umbmark.simulate` take these as keywords (the command's
``--turn-angle`` in degrees is ``turn_angle`` in radians here); each is an option of
:mod:`umbmark.options.simulate` (its default and bound are there), and messages name it
by its keyword (the command shows its flag). Also here: the checks of the work one
simulation may be (its bounds are the options module's too).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from umbmark.core.bounds import option_float
from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, option
from umbmark.model.kinematics import WheelParams
from umbmark.options.simulate import (
    DIRECTIONS,
    MAX_RECORDED_SAMPLES,
    MAX_RUNS,
    MAX_SAMPLES,
    MAX_SAMPLES_PER_RUN,
    MAX_TURN,
    PATHS,
    SEED_RANGE,
    SIMULATE,
    SIMULATE_OPTIONS,
    DirectionChoice,
    PathKind,
)
from umbmark.sim.paths import Path, spot_turn, square, straight_line
from umbmark.sim.robot import ControlConfig, NoiseModel

__all__ = [
    "DIRECTIONS",
    "MAX_RECORDED_SAMPLES",
    "MAX_RUNS",
    "MAX_SAMPLES",
    "MAX_SAMPLES_PER_RUN",
    "PATHS",
    "SEED_RANGE",
    "DirectionChoice",
    "PathKind",
    "SimSetup",
]

#: The fields that are numbers, made floats when the setup is made.
_FLOATS = ("E_d", "E_b", "E_s", "slip", "bump_rate", "bump_size", "turn_angle")
#: The options that are fields of :class:`SimSetup` (``params`` is the job's).
_FIELDS = tuple(spec for spec in SIMULATE_OPTIONS if spec.name != "params")
#: Fewest encoder counts per wheel revolution (encoder resolution x gear ratio) ...
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

    E_d: float = SIMULATE["E_d"].default
    E_b: float = SIMULATE["E_b"].default
    E_s: float = SIMULATE["E_s"].default
    side_length: float = SIMULATE["side_length"].default
    wheelbase: float = SIMULATE["wheelbase"].default
    wheel_diameter: float = SIMULATE["wheel_diameter"].default
    encoder_resolution: float = SIMULATE["encoder_resolution"].default
    gear_ratio: float = SIMULATE["gear_ratio"].default
    runs: int = SIMULATE["runs"].default
    direction: DirectionChoice = SIMULATE["direction"].default
    path: PathKind = SIMULATE["path"].default
    turn_angle: float = math.radians(SIMULATE["turn_angle"].default)
    noise_free: bool = SIMULATE["noise_free"].default
    slip: float = SIMULATE["slip"].default
    bump_rate: float = SIMULATE["bump_rate"].default
    bump_size: float = SIMULATE["bump_size"].default
    dt: float = SIMULATE["dt"].default
    speed: float = SIMULATE["speed"].default
    seed: int = field(default=SIMULATE["seed"].default)

    def __post_init__(self) -> None:
        for name in _FLOATS:
            object.__setattr__(self, name, option_float(option(name), getattr(self, name)))
        if not math.isfinite(self.turn_angle):
            raise InputError(f"{option('turn_angle', self.turn_angle)} is not a finite number")
        for spec in _FIELDS:
            spec.check(getattr(self, spec.name))
        if self.path == "square" and self.direction == "both" and self.runs < 2:
            raise InputError(f"{option('runs')} must be at least 2 for UMBmark (the paper uses 5)")
        if self.path == "turn" and not (0 < abs(self.turn_angle) <= MAX_TURN):
            raise InputError(
                f"{option('turn_angle', math.degrees(self.turn_angle), 'deg')}: give a turn of "
                f"up to {math.degrees(MAX_TURN):g} deg either way, not zero"
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
            f"{option('encoder_resolution', odometry.encoder_resolution)} x "
            f"{option('gear_ratio', odometry.gear_ratio)} is {per_revolution:.3g} encoder "
            f"counts per wheel revolution: at least {MIN_COUNTS_PER_REVOLUTION}"
        )
    count = math.pi * odometry.wheel_diameter / per_revolution  # m of wheel travel
    for segment in path.segments:
        travel = segment.amount if segment.kind == "straight" else 0.5 * odometry.wheelbase
        if segment.kind == "turn":
            travel *= abs(segment.amount)
        if travel < MIN_COUNTS_PER_PATH * count:
            what = (
                option("side_length", segment.amount, "m")
                if segment.kind == "straight"
                else option("turn_angle", math.degrees(segment.amount), "deg")
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
            f"a run of the {path.name} path at {option('speed', control.speed, 'm/s')} and "
            f"{option('dt', control.dt, 's')} takes about {per_run:.3g} sampling periods: at "
            f"most {MAX_SAMPLES_PER_RUN:.3g}; raise {option('speed')} or {option('dt')}, or "
            "shorten the path"
        )
    if per_run * runs > MAX_SAMPLES:
        raise InputError(
            f"{runs} runs of about {per_run:.3g} sampling periods each are more than "
            f"{MAX_SAMPLES:.3g} in all; give fewer {option('runs')}, or raise {option('speed')} "
            f"or {option('dt')}"
        )
    if recorded and per_run * runs > MAX_RECORDED_SAMPLES:
        raise InputError(
            f"keeping the time series of {runs} runs of about {per_run:.3g} samples each "
            f"needs {per_run * runs * 130 / 1e9:.1f} GB: at most {MAX_RECORDED_SAMPLES:.3g} "
            f"samples in all; give fewer {option('runs')}, a larger {option('dt')}, or no "
            f"{option('logs')} or {option('bag')}"
        )

"""The options of ``umbmark simulate``, ``umbmark study`` and the seed and runs of ``umbmark
demo``, written once (:class:`~umbmark.options.spec.Spec`): name, flags, section of
``--help``, help, kind, default, unit and bound.

From these entries come the click options (:func:`umbmark.cli.click_options.spec_option`),
the defaults of :class:`umbmark.sim.setup.SimSetup`, :func:`umbmark.study` and
:func:`umbmark.demo`, and their checks (:meth:`Spec.check`). The bounds of the work a
simulation may be are here too. ``--turn-angle`` is in degrees on the command line, in
radians in the library (``turn_angle``).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal

from umbmark.core.bounds import (
    ENCODER_RESOLUTION_RANGE,
    GEAR_RATIO_RANGE,
    GYRO_BIAS_RANGE,
    GYRO_BIAS_WALK_RANGE,
    GYRO_FULL_SCALE_RANGE,
    GYRO_NOISE_RANGE,
    GYRO_SCALE_RANGE,
    IMU_RATE_RANGE,
    MAX_SIDE_LENGTH,
    MAX_WHEELBASE,
)
from umbmark.options.spec import Bound, Spec

__all__ = [
    "DEMO_RUNS",
    "DIRECTIONS",
    "DRIVE",
    "DT_RANGE",
    "GRID",
    "IMU",
    "IMU_OPTIONS",
    "IMU_SECTION",
    "MAX_BUMP_RATE",
    "MAX_BUMP_SIZE",
    "MAX_GRID_VALUES",
    "MAX_RECORDED_SAMPLES",
    "MAX_ROBOTS",
    "MAX_RUNS",
    "MAX_SAMPLES",
    "MAX_SAMPLES_PER_RUN",
    "MAX_SLIP",
    "MAX_TRIALS",
    "MAX_TURN",
    "NOISE",
    "PATHS",
    "RATIO_RANGE",
    "ROBOT",
    "ROBOTS",
    "SEED",
    "SEED_RANGE",
    "SIMULATE",
    "SIMULATE_OPTIONS",
    "SPEED_RANGE",
    "STUDY",
    "STUDY_OPTIONS",
    "DirectionChoice",
    "PathKind",
]

# --- the sections of --help -----------------------------------------------------------

ROBOT = "The robot"
DRIVE = "What it drives"
NOISE = "Non-systematic errors"
ROBOTS = "The robots"
IMU_SECTION = "The IMU (with --bag --imu)"
OTHER = "Other options"

# --- bounds -----------------------------------------------------------------------------

PathKind = Literal["square", "straight", "turn"]
PATHS: tuple[PathKind, ...] = ("square", "straight", "turn")
DirectionChoice = Literal["both", "cw", "ccw"]
DIRECTIONS: tuple[DirectionChoice, ...] = ("both", "cw", "ccw")
#: Largest on-the-spot turn [rad]: ten turns.
MAX_TURN = 20.0 * math.pi
#: Most runs in each direction of a simulation (and of ``demo``).
MAX_RUNS = 1000
#: The seeds of the random errors.
SEED_RANGE = (0, 2**63 - 1)
#: Most sampling periods one run may take (path length / speed / dt and the turns):
#: the simulation's time grows with it (about 15 us a period on one core).
MAX_SAMPLES_PER_RUN = 2_000_000
#: Most sampling periods of all runs together (the work of the vectorized runs) ...
MAX_SAMPLES = 1_000_000_000
#: ... and when the time series are kept (``logs``, ``bag``, ``record``): about 130 bytes each.
MAX_RECORDED_SAMPLES = 5_000_000
DT_RANGE = (1e-4, 0.1)  # s
SPEED_RANGE = (0.01, 5.0)  # m/s
MAX_SLIP = 0.1  # standard deviation of the relative wheel slip [m^0.5]
MAX_BUMP_SIZE = 0.05  # m
MAX_BUMP_RATE = 100.0  # per metre
#: The true-over-nominal ratios E_d, E_b, E_s a virtual robot may have (both excluded).
RATIO_RANGE = (0.5, 2.0)
#: Most trials a study runs per cell ...
MAX_TRIALS = 100_000
#: ... and in all, over every cell of the grid (each robot costs about 0.05 s per method).
MAX_ROBOTS = 100_000
#: Most values of one grid option (--slip, --side-length, --runs, --wheelbase).
MAX_GRID_VALUES = 20
GRID = f"The grid (comma-separated values, at most {MAX_GRID_VALUES} each)"
#: Largest wheel slip of a study's grid [m^0.5].
MAX_GRID_SLIP = 0.01
#: Runs per direction of a study's grid.
GRID_RUNS = (2, 100)
#: Largest spread of a study's E_d and E_b about 1.
MAX_SPREAD = 0.2
#: Most worker processes of a study.
MAX_WORKERS = 64

_RATIO = Bound("ratio", low=RATIO_RANGE[0], high=RATIO_RANGE[1])
_SEEDS = Bound("range", low=SEED_RANGE[0], high=SEED_RANGE[1])

#: ``--seed`` of ``simulate``, ``study`` and ``demo`` (each says what it seeds).
SEED = Spec(
    "seed",
    ("--seed",),
    NOISE,
    "Seed of the random errors (0 to 2^63-1).",
    kind="integer",
    default=1,
    bound=_SEEDS,
)

# --- simulate ---------------------------------------------------------------------------

#: The options of ``umbmark simulate`` that say what it simulates (the fields of
#: :class:`umbmark.sim.setup.SimSetup`, and ``--params``), in the order ``--help`` lists them.
SIMULATE_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "E_d",
        ("--E-d",),
        ROBOT,
        "True wheel-diameter ratio D_R / D_L (Eq. 2.3), with the wheels of nominal diameter "
        "D_n (without --params' c_L, c_R).",
        kind="number",
        default=1.0,
        bound=_RATIO,
    ),
    Spec(
        "E_b",
        ("--E-b",),
        ROBOT,
        "True wheelbase over nominal, b_actual / b (Eq. 2.4), with b of --wheelbase (without "
        "--params' correction).",
        kind="number",
        default=1.0,
        bound=_RATIO,
    ),
    Spec(
        "E_s",
        ("--E-s",),
        ROBOT,
        "True average wheel diameter over nominal, D_avg / D_n.",
        kind="number",
        default=1.0,
        bound=_RATIO,
    ),
    Spec(
        "wheelbase",
        ("--wheelbase", "-b"),
        ROBOT,
        "Nominal wheelbase b [m].",
        kind="number",
        default=0.34,
        unit="m",
        bound=Bound("length", MAX_WHEELBASE),
    ),
    Spec(
        "wheel_diameter",
        ("--wheel-diameter",),
        ROBOT,
        "Nominal wheel diameter D_n [m].",
        kind="number",
        default=0.15,
        unit="m",
        bound=Bound("length", MAX_WHEELBASE),
    ),
    Spec(
        "encoder_resolution",
        ("--encoder-resolution",),
        ROBOT,
        "Encoder pulses per motor revolution.",
        kind="number",
        default=2000.0,
        bound=Bound("range", low=ENCODER_RESOLUTION_RANGE[0], high=ENCODER_RESOLUTION_RANGE[1]),
    ),
    Spec(
        "gear_ratio",
        ("--gear-ratio",),
        ROBOT,
        "Motor revolutions per wheel revolution.",
        kind="number",
        default=20.0,
        bound=Bound("range", low=GEAR_RATIO_RANGE[0], high=GEAR_RATIO_RANGE[1]),
    ),
    Spec(
        "params",
        ("--params",),
        ROBOT,
        "Calibration result (calibrate -o) whose c_L, c_R and wheelbase the robot's odometry "
        "uses; --E-d, --E-b, --E-s stay the truth relative to the nominal values (printed "
        "so), the errors left to the odometry are printed too.",
        kind="file",
    ),
    Spec(
        "path",
        ("--path",),
        DRIVE,
        "square (UMBmark), straight (a leg of --side-length, to measure E_s) or turn (on the "
        "spot, by --turn-angle).",
        kind="choice",
        default="square",
        choices=PATHS,
    ),
    Spec(
        "side_length",
        ("--side-length", "-L"),
        DRIVE,
        "Side of the square [m].",
        kind="number",
        default=4.0,
        unit="m",
        bound=Bound("length", MAX_SIDE_LENGTH),
    ),
    Spec(
        "runs",
        ("--runs", "-n"),
        DRIVE,
        f"Runs in each direction (1 to {MAX_RUNS}; a run may take at most "
        f"{MAX_SAMPLES_PER_RUN / 1e6:g} million sampling periods, all runs "
        f"1e{round(math.log10(MAX_SAMPLES))}, with --logs {MAX_RECORDED_SAMPLES / 1e6:g} million).",
        kind="integer",
        default=5,
        bound=Bound("range", low=1, high=MAX_RUNS),
    ),
    Spec(
        "direction",
        ("--direction",),
        DRIVE,
        "both (UMBmark), or cw / ccw only (uni-directional).",
        kind="choice",
        default="both",
        choices=DIRECTIONS,
    ),
    Spec(
        "turn_angle",
        ("--turn-angle",),
        DRIVE,
        "Angle of --path turn [deg], ccw positive.",
        kind="number",
        default=360.0,
        unit="deg",
    ),
    Spec(
        "dt",
        ("--dt",),
        DRIVE,
        "Sampling period [s].",
        kind="number",
        default=0.01,
        unit="s",
        bound=Bound("range", low=DT_RANGE[0], high=DT_RANGE[1]),
    ),
    Spec(
        "speed",
        ("--speed",),
        DRIVE,
        "Speed on the legs [m/s].",
        kind="number",
        default=0.2,
        unit="m/s",
        bound=Bound("range", low=SPEED_RANGE[0], high=SPEED_RANGE[1]),
    ),
    Spec(
        "noise_free",
        ("--noise-free",),
        NOISE,
        "No slip and no bumps (only quantization).",
        kind="flag",
        default=False,
    ),
    Spec(
        "slip",
        ("--slip",),
        NOISE,
        "Wheel slip [m^0.5]: each wheel's floor travel errs by slip x sqrt(travel). The "
        "default gives the paper's ~25 mm spread on a 4 m square.",
        kind="number",
        default=0.0004,
        bound=Bound("range", low=0.0, high=MAX_SLIP),
    ),
    Spec(
        "bump_rate",
        ("--bump-rate",),
        NOISE,
        "Floor bumps per metre of wheel travel.",
        kind="number",
        default=0.0,
        bound=Bound("range", low=0.0, high=MAX_BUMP_RATE),
    ),
    Spec(
        "bump_size",
        ("--bump-size",),
        NOISE,
        "Extra wheel rotation per bump, as a length [m].",
        kind="number",
        default=0.002,
        bound=Bound("range", low=0.0, high=MAX_BUMP_SIZE),
    ),
    SEED,
)

#: The options of ``simulate`` by keyword.
SIMULATE: dict[str, Spec] = {spec.name: spec for spec in SIMULATE_OPTIONS}

# --- the IMU of simulate --bag --imu ------------------------------------------------


def _range(low_high: tuple[float, float]) -> Bound:
    return Bound("range", low=low_high[0], high=low_high[1])


#: The IMU a simulated bag records (:class:`umbmark.sim.imu.ImuSetup`, which holds them in
#: SI units: rad, rad/s), in the order ``--help`` lists them; the defaults are a MEMS
#: part's (MPU-6050, BMI088 class: docs/simulator.md#the-imu).
IMU_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "imu_rate",
        ("--imu-rate",),
        IMU_SECTION,
        "Readings a second [Hz].",
        kind="number",
        default=200.0,
        unit="Hz",
        bound=_range(IMU_RATE_RANGE),
    ),
    Spec(
        "gyro_scale",
        ("--gyro-scale",),
        IMU_SECTION,
        "The factor k_g that corrects the gyro, omega_true = k_g (omega_read - bias): 1.02 "
        "is a gyro that reads 2 % low.",
        kind="number",
        default=1.02,
        bound=_range(GYRO_SCALE_RANGE),
    ),
    Spec(
        "gyro_bias",
        ("--gyro-bias",),
        IMU_SECTION,
        "The gyro's bias about its z axis at the start [deg/s] (its x and y axes get one "
        "of up to that size, drawn).",
        kind="number",
        default=0.3,
        unit="deg/s",
        bound=_range(GYRO_BIAS_RANGE),
    ),
    Spec(
        "gyro_bias_walk",
        ("--gyro-bias-walk",),
        IMU_SECTION,
        "The bias's random walk [deg/s/sqrt(s)] (2e-4: a bias instability of about 7 deg/h).",
        kind="number",
        default=2e-4,
        unit="deg/s/sqrt(s)",
        bound=_range(GYRO_BIAS_WALK_RANGE),
    ),
    Spec(
        "gyro_noise",
        ("--gyro-noise",),
        IMU_SECTION,
        "The gyro's white-noise density [deg/s/sqrt(Hz)].",
        kind="number",
        default=0.005,
        unit="deg/s/sqrt(Hz)",
        bound=_range(GYRO_NOISE_RANGE),
    ),
    Spec(
        "gyro_range",
        ("--gyro-range",),
        IMU_SECTION,
        "The gyro's full scale [deg/s]: faster rates read as it (saturated).",
        kind="number",
        default=2000.0,
        unit="deg/s",
        bound=_range(GYRO_FULL_SCALE_RANGE),
    ),
    Spec(
        "imu_roll",
        ("--imu-roll",),
        IMU_SECTION,
        "The IMU's mounting in base_link: roll [deg] (180: upside down); stated on "
        "/tf_static and in /robot_description.",
        kind="number",
        default=0.0,
        unit="deg",
        bound=_range((-180.0, 180.0)),
    ),
    Spec(
        "imu_pitch",
        ("--imu-pitch",),
        IMU_SECTION,
        "... pitch [deg].",
        kind="number",
        default=0.0,
        unit="deg",
        bound=_range((-90.0, 90.0)),
    ),
    Spec(
        "imu_yaw",
        ("--imu-yaw",),
        IMU_SECTION,
        "... and yaw [deg] (90: its x axis points left).",
        kind="number",
        default=0.0,
        unit="deg",
        bound=_range((-180.0, 180.0)),
    ),
)

#: The IMU's options by keyword.
IMU: dict[str, Spec] = {spec.name: spec for spec in IMU_OPTIONS}

# --- study ------------------------------------------------------------------------------


def _grid(spec: Spec) -> Spec:
    """``spec`` as a grid option: a list of at most :data:`MAX_GRID_VALUES`."""
    return replace(spec, section=GRID, most=MAX_GRID_VALUES, default=(spec.default,))


#: The options of ``umbmark study`` (of :func:`umbmark.study`), in the order ``--help``
#: lists them; ``--methods`` names estimators (:mod:`umbmark.estimators.registry`), checked
#: by the job.
STUDY_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "trials",
        ("--trials",),
        ROBOTS,
        f"Robots per grid cell (1 to {MAX_TRIALS}, and {MAX_ROBOTS} in all cells).",
        kind="integer",
        default=200,
        bound=Bound("range", low=1, high=MAX_TRIALS),
    ),
    Spec(
        "E_d_spread",
        ("--E-d-spread",),
        ROBOTS,
        "E_d drawn uniformly from 1 +- this.",
        kind="number",
        default=0.02,
        bound=Bound("range", low=0.0, high=MAX_SPREAD),
    ),
    Spec(
        "E_b_spread",
        ("--E-b-spread",),
        ROBOTS,
        "E_b drawn uniformly from 1 +- this.",
        kind="number",
        default=0.05,
        bound=Bound("range", low=0.0, high=MAX_SPREAD),
    ),
    _grid(
        Spec(
            "slip",
            ("--slip",),
            GRID,
            "Wheel slip [m^0.5] (0.0004: the paper's ~25 mm on a 4 m square).",
            kind="number",
            default=0.0004,
            bound=Bound("range", low=0.0, high=MAX_GRID_SLIP),
        )
    ),
    _grid(
        Spec(
            "side_length",
            ("--side-length", "-L"),
            GRID,
            "Square sides [m].",
            kind="number",
            default=4.0,
            unit="m",
            bound=Bound("length", MAX_SIDE_LENGTH),
        )
    ),
    _grid(
        Spec(
            "runs",
            ("--runs", "-n"),
            GRID,
            "Runs per direction.",
            kind="integer",
            default=5,
            bound=Bound("range", low=GRID_RUNS[0], high=GRID_RUNS[1]),
        )
    ),
    _grid(
        Spec(
            "wheelbase",
            ("--wheelbase", "-b"),
            GRID,
            "Nominal wheelbases [m] (wheel diameter alike).",
            kind="number",
            default=0.34,
            unit="m",
            bound=Bound("length", MAX_WHEELBASE),
        )
    ),
    replace(SEED, section=OTHER, help="Seed of the whole study (0 to 2^63-1)."),
    Spec(
        "workers",
        ("--workers",),
        OTHER,
        f"Processes, 1 to {MAX_WORKERS} [default: the machine's cores].",
        kind="integer",
        bound=Bound("range", low=1, high=MAX_WORKERS),
    ),
)

#: The options of ``study`` by keyword.
STUDY: dict[str, Spec] = {spec.name: spec for spec in STUDY_OPTIONS}

#: ``--runs`` of ``demo``: runs in each direction.
DEMO_RUNS = Spec(
    "runs",
    ("--runs", "-n"),
    "Options",
    f"Runs in each direction (2 to {MAX_RUNS}).",
    kind="integer",
    default=5,
    bound=Bound("range", low=2, high=MAX_RUNS),
)

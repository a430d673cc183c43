"""The options of ``umbmark selfcal`` that the option spec holds (:class:`Spec`, each
written once, with its check): which routine, the square test's side, runs, passes, how
the fixes are taken and the corrections applied, where the corner stands, and the
obstacle stop's margin with its bounds. :class:`umbmark.routines.setup.SelfcalSetup`
takes its defaults from these and checks its values by them; ``umbmark selfcal``'s
options are made from them."""

from __future__ import annotations

from dataclasses import replace

from umbmark.options.simulate import IMU_OPTIONS
from umbmark.options.spec import TEST, Bound, Spec

__all__ = [
    "APPLY",
    "CORNER_SIDE",
    "DRIVING",
    "MAX_PASSES",
    "MAX_SELFCAL_PASSES",
    "MAX_SELFCAL_RUNS",
    "MEASURE",
    "OBSTACLE_MARGIN",
    "OBSTACLE_MARGIN_RANGE",
    "ROBOT_WIDTH",
    "ROBOT_WIDTH_RANGE",
    "ROUTINE",
    "ROUTINE_SECTION",
    "RUNS",
    "SIM_IMU_OPTIONS",
    "SIM_SECTION",
    "SQUARE_SIDE",
    "SQUARE_SIDE_RANGE",
    "STOP_LATENCY",
    "TAPE_MARKS",
]

#: The section of ``umbmark selfcal --help`` listing which routine the robot drives (the
#: squares' options are "The square test"; the anywhere pattern has none of its own).
ROUTINE_SECTION = "The routine"

#: ``--routine`` of ``selfcal`` (``routine=`` of :func:`umbmark.selfcal`): what the robot
#: drives to calibrate itself.
ROUTINE = Spec(
    "routine",
    ("--routine",),
    ROUTINE_SECTION,
    "umbmark: the paper's squares, measured at an L-shaped corner (needs 4 x 4 m and the "
    "corner); anywhere: a short pattern of turns, straights and arcs on about 2 x 2 m, "
    "calibrated against the laser's own motion (needs a laser and walls or furniture in "
    "view; also gives E_s and the laser's mounting).",
    kind="choice",
    default="umbmark",
    choices=("umbmark", "anywhere"),
)

#: The section of ``umbmark selfcal --help`` listing how the robot drives.
DRIVING = "Driving"

#: The values ``--obstacle-margin`` may take [m] (checked by
#: :class:`umbmark.routines.drive.DriveLimits`).
OBSTACLE_MARGIN_RANGE = (0.05, 2.0)
#: The stop latency of the obstacle stop [s] (``DriveLimits.stop_latency``'s default).
STOP_LATENCY = 0.4
#: ``--obstacle-margin`` of ``selfcal`` (``DriveLimits.obstacle_margin``).
OBSTACLE_MARGIN = Spec(
    "obstacle_margin",
    ("--obstacle-margin",),
    DRIVING,
    f"Room left before an obstacle seen ahead [m] ({OBSTACLE_MARGIN_RANGE[0]:g} to "
    f"{OBSTACLE_MARGIN_RANGE[1]:g}): the robot is stopped when one is nearer than "
    "v^2/(2 a) + v t + this, v the speed, a the acceleration limit, t the stop latency "
    f"({STOP_LATENCY:g} s); measured from the robot's centre.",
    kind="number",
    default=0.3,
    unit="m",
)
#: The values ``--robot-width`` may take [m].
ROBOT_WIDTH_RANGE = (0.1, 2.0)
#: ``--robot-width`` of ``selfcal``: the footprint where the robot's description gives none.
ROBOT_WIDTH = Spec(
    "robot_width",
    ("--robot-width",),
    DRIVING,
    f"The robot's width [m] ({ROBOT_WIDTH_RANGE[0]:g} to {ROBOT_WIDTH_RANGE[1]:g}; its "
    "footprint taken as a square this wide around the axle centre): the band its path "
    "sweeps, which the laser watches and the check before moving keeps free. Default: "
    "the base link's collision (else visual) box or cylinder in the robot's description, "
    "else 0.4 m.",
    kind="number",
    default=None,
    unit="m",
    bound=Bound("range", ROBOT_WIDTH_RANGE[1], ROBOT_WIDTH_RANGE[0]),
)
#: ``--corner-side`` of ``selfcal``: where the L-shaped corner stands, seen from the start.
CORNER_SIDE = Spec(
    "corner_side",
    ("--corner-side",),
    TEST,
    "Where the L-shaped corner stands, seen from the robot at its start: behind it and to "
    "its right, or to its left (the wall beside the start on that side); auto: found by "
    "the first fix (lidar, ranges), the right taken for a tape.",
    kind="choice",
    default="auto",
    choices=("auto", "right", "left"),
)

#: The sides of a square the self-calibration drives [m].
SQUARE_SIDE_RANGE = (0.5, 20.0)
#: Most runs per direction in a pass.
MAX_SELFCAL_RUNS = 20
#: Most UMBmark passes one self-calibration drives (verification not counted).
MAX_SELFCAL_PASSES = 5

#: ``--side-length`` of ``selfcal``: the side of the squares it drives.
SQUARE_SIDE = Spec(
    "side_length",
    ("--side-length", "-L"),
    TEST,
    f"Side of the square [m] ({SQUARE_SIDE_RANGE[0]:g} to {SQUARE_SIDE_RANGE[1]:g}).",
    kind="number",
    default=4.0,
    unit="m",
    bound=Bound("range", SQUARE_SIDE_RANGE[1], SQUARE_SIDE_RANGE[0]),
)
#: ``--runs`` of ``selfcal``: runs in each direction of a pass.
RUNS = Spec(
    "runs",
    ("--runs", "-n"),
    TEST,
    f"Runs in each direction (2 to {MAX_SELFCAL_RUNS}).",
    kind="integer",
    default=5,
    bound=Bound("range", MAX_SELFCAL_RUNS, 2),
)
#: ``--measure`` of ``selfcal``: how the fixes at the corner are taken.
MEASURE = Spec(
    "measure",
    ("--measure",),
    TEST,
    "How the robot's pose in the corner is measured at each stop: the laser, three range "
    "sensors, motion capture, or a person with a tape (prompted).",
    kind="choice",
    default="lidar",
    choices=("lidar", "ranges", "truth", "tape"),
)
#: ``--tape-marks`` of ``selfcal`` (checked with the robot's own marks, by
#: :func:`umbmark.routines.measure.marks_for`).
TAPE_MARKS = Spec(
    "tape_marks",
    ("--tape-marks",),
    TEST,
    "With --measure tape: the three points on the robot (its base frame, metres) the "
    "distances are measured from; the first two to the wall behind the start, the third "
    "to the side wall [default: the virtual robot's].",
    metavar="X1,Y1,X2,Y2,X3,Y3",
)
#: ``--apply`` of ``selfcal`` (the library takes True for ``reconfigure``, False for
#: ``none`` too).
APPLY = Spec(
    "apply",
    ("--apply",),
    TEST,
    "How corrections reach the controller (none: one pass, nothing applied).",
    kind="choice",
    default="reconfigure",
    choices=("reconfigure", "yaml", "none"),
)
#: ``--max-passes`` of ``selfcal``.
MAX_PASSES = Spec(
    "max_passes",
    ("--max-passes",),
    TEST,
    f"Most UMBmark passes before the verification (1 to {MAX_SELFCAL_PASSES}).",
    kind="integer",
    default=3,
    bound=Bound("range", MAX_SELFCAL_PASSES, 1),
)

#: The section of ``umbmark selfcal --help`` listing the robot: ``--sim`` and its options.
SIM_SECTION = "The robot"

#: The virtual robot's IMU (``selfcal --sim``): the options of ``simulate --imu``
#: (:data:`umbmark.options.simulate.IMU_OPTIONS`: their defaults, units and bounds) as
#: ``--sim-gyro-scale``, ``--sim-imu-rate``, ..., keywords ``sim_gyro_scale``, ...
SIM_IMU_OPTIONS: tuple[Spec, ...] = tuple(
    replace(
        spec,
        name=f"sim_{spec.name}",
        flags=(f"--sim-{spec.flags[0].removeprefix('--')}",),
        section=SIM_SECTION,
        help="With --sim: the virtual robot's IMU: "
        + f"{spec.help[0].lower()}{spec.help[1:]}".replace(
            "; stated on /tf_static and in /robot_description", ""
        ),
    )
    for spec in IMU_OPTIONS
)

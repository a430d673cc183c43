"""The options of ``umbmark fleet`` (of :func:`umbmark.fleet`) written once
(:class:`~umbmark.options.spec.Spec`); the reading options it shares with ``calibrate``
are the spec's own, and ``--history`` is :data:`~umbmark.options.spec.HISTORY`.
"""

from __future__ import annotations

from umbmark.options.spec import OUTPUTS, Bound, Spec

__all__ = [
    "A_FLEET",
    "ENGINE",
    "FLEET",
    "FLEET_OPTIONS",
    "FLEET_SIMULATION",
    "FLEET_SIMULATION_OPTIONS",
    "MAX_WORKERS",
    "RECORDINGS",
]

#: The ``--help`` section of what the fleet reads.
RECORDINGS = "The recordings"
#: The ``--help`` section of the engine.
ENGINE = "The engine (Dask distributed)"
#: Most local workers.
MAX_WORKERS = 64

#: The options of ``umbmark fleet``, in the order ``--help`` lists them.
FLEET_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "robot_from",
        ("--robot-from",),
        RECORDINGS,
        "A pattern of the recordings' paths naming the robot and the day: {robot} and "
        "{date} (YYYY-MM-DD or YYYYMMDD) stand for a path component or part of one, * for "
        "any part of one, ** for any components ('{robot}/{date}/*.mcap') [default: the "
        "robot from the recording's namespace, the day from its clock].",
        metavar="PATTERN",
    ),
    Spec(
        "robot_options",
        ("--robot-options",),
        RECORDINGS,
        "A YAML file of reading options per robot (robot: {truth_topic: ..., wheelbase: "
        "...}), over the ones given here for every robot.",
        kind="file",
    ),
    Spec(
        "scheduler",
        ("--scheduler",),
        ENGINE,
        "An existing Dask scheduler to run on (tcp://host:8786), whose workers have "
        "umbmark installed and see the files [default: $DASK_SCHEDULER_ADDRESS, else a "
        "local cluster on this machine's cores].",
        metavar="ADDRESS",
    ),
    Spec(
        "workers",
        ("--workers",),
        ENGINE,
        "Workers of the local cluster [default: this machine's cores].",
        kind="integer",
        bound=Bound("range", MAX_WORKERS, 1),
    ),
    Spec(
        "report",
        ("--report",),
        OUTPUTS,
        "Write the fleet's page (.html): every robot's latest figures, their course over "
        "time and its flags, what to apply, the failed recordings and the robots with no "
        "usable recording.",
        kind="file",
    ),
    Spec(
        "output",
        ("--output", "-o"),
        OUTPUTS,
        "Write the JSON (what --json prints; metres, radians, seconds).",
        kind="file",
    ),
)

#: The options by keyword.
FLEET: dict[str, Spec] = {spec.name: spec for spec in FLEET_OPTIONS}

#: The ``--help`` section of ``umbmark simulate``'s fleet.
A_FLEET = "A fleet (umbmark fleet's input)"

#: ``umbmark simulate``'s options for a simulated fleet (:func:`umbmark.simulate_fleet`).
FLEET_SIMULATION_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "fleet",
        ("--fleet",),
        A_FLEET,
        "Write the recordings of this many virtual robots driving ordinary missions in a "
        "warehouse (corridors, turns at shelves, whole turns now and then), wheels, a laser "
        "and an IMU, one a day each, into --out ROBOT/DATE/drive; one wheel changed, one "
        "laser knocked, one robot's tyres wearing, one gyro's scale changed; truth.json "
        "beside them.",
        kind="integer",
        bound=Bound("range", 200, 1),
    ),
    Spec(
        "days",
        ("--days",),
        A_FLEET,
        "With --fleet: days of recordings.",
        kind="integer",
        default=8,
        bound=Bound("range", 365, 1),
    ),
    Spec(
        "minutes",
        ("--minutes",),
        A_FLEET,
        "With --fleet: each recording's driving [min].",
        kind="number",
        default=2.0,
        unit="min",
        bound=Bound("range", 60.0, 0.2),
    ),
    Spec(
        "out",
        ("--out",),
        A_FLEET,
        "With --fleet: the folder to write the fleet into (new or empty, or --force).",
        kind="folder",
        default="umbmark-fleet",
    ),
)

#: The fleet simulation's options by keyword.
FLEET_SIMULATION: dict[str, Spec] = {spec.name: spec for spec in FLEET_SIMULATION_OPTIONS}

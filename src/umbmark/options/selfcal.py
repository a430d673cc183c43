"""The options of ``umbmark selfcal`` that the option spec holds (:class:`Spec`, each
written once): which routine, where the corner stands, and the obstacle stop's margin
with its bounds."""

from __future__ import annotations

from umbmark.options.spec import TEST, Spec

__all__ = [
    "CORNER_SIDE",
    "DRIVING",
    "OBSTACLE_MARGIN",
    "OBSTACLE_MARGIN_RANGE",
    "ROUTINE",
    "STOP_LATENCY",
]

#: ``--routine`` of ``selfcal`` (``routine=`` of :func:`umbmark.selfcal`): what the robot
#: drives to calibrate itself.
ROUTINE = Spec(
    "routine",
    ("--routine",),
    TEST,
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
#: ``--corner-side`` of ``selfcal``: where the L-shaped corner stands, seen from the start.
CORNER_SIDE = Spec(
    "corner_side",
    ("--corner-side",),
    TEST,
    "Where the L-shaped corner stands, seen from the robot at its start: behind it and to "
    "its right, or to its left (the wall beside the start on that side).",
    kind="choice",
    default="right",
    choices=("right", "left"),
)

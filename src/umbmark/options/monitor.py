"""The options of ``umbmark monitor`` written once (:class:`~umbmark.options.spec.Spec`):
the monitor's own (its window in driving, its stretches, the scan decimation, the stale
time, the navigation tolerance, the apply policy), shared by the command line and the ROS
nodes' parameters (``--ros-args -p window_metres:=80``: each parameter is the option's
keyword), and those of its simulated robot (``--sim``). ``--history`` is
:data:`~umbmark.options.spec.HISTORY`.

:class:`umbmark.monitor.setup.MonitorSetup` takes its defaults from these and checks its
values by them. Lengths in metres, angles in radians, times in seconds.
"""

from __future__ import annotations

import math

from umbmark.options.spec import Bound, Spec

__all__ = [
    "APPLY_POLICIES",
    "MONITOR",
    "MONITOR_OPTIONS",
    "MONITOR_SECTION",
    "MONITOR_SIM",
    "MONITOR_SIM_OPTIONS",
    "SIM_SECTION",
]

#: The ``--help`` section of the monitor's own options.
MONITOR_SECTION = "The monitor"
#: The ``--help`` section of the simulated robot (``--sim``).
SIM_SECTION = "The simulated robot (--sim)"
#: ``--apply``'s policies: never apply; apply a confirmed change at rest.
APPLY_POLICIES = ("never", "at-rest")

#: The monitor's options, in the order ``--help`` lists them.
MONITOR_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "robot",
        ("--robot",),
        MONITOR_SECTION,
        "The robot's name: the diagnostic's hardware id and its name in the history.",
        default="robot",
    ),
    Spec(
        "window_metres",
        ("--window-metres",),
        MONITOR_SECTION,
        "The estimate's window: at least this much driving [m] (and --window-radians "
        "turned each way), the newest motion since the last change.",
        kind="number",
        default=50.0,
        unit="m",
        bound=Bound("range", 5000.0, 5.0),
    ),
    Spec(
        "window_radians",
        ("--window-radians",),
        MONITOR_SECTION,
        "The estimate's window: at least this much turning each way [rad] (left and "
        "right), with --window-metres.",
        kind="number",
        default=4.0 * math.pi,
        unit="rad",
        bound=Bound("range", 1000.0, 0.5),
    ),
    Spec(
        "stretch_metres",
        ("--stretch-metres",),
        MONITOR_SECTION,
        "A stretch of driving, the unit of the robot's course: this much wheel travel "
        "[m] (the mean of both wheels' distance rolled, turns on the spot included), "
        "calibrated on its own and followed by the change model.",
        kind="number",
        default=20.0,
        unit="m",
        bound=Bound("range", 1000.0, 2.0),
    ),
    Spec(
        "scan_period",
        ("--scan-period",),
        MONITOR_SECTION,
        "Scan decimation: one sweep matched per this time [s], the motion intervals' "
        "length (a 10 Hz laser is matched at 1 Hz by default).",
        kind="number",
        default=1.0,
        unit="s",
        bound=Bound("range", 10.0, 0.05),
    ),
    Spec(
        "stale_after",
        ("--stale-after",),
        MONITOR_SECTION,
        "A topic silent this long [s] is stale (the diagnostic's level STALE).",
        kind="number",
        default=2.0,
        unit="s",
        bound=Bound("range", 600.0, 0.1),
    ),
    Spec(
        "tolerance",
        ("--tolerance",),
        MONITOR_SECTION,
        "What the robot's navigation tolerates of a change (ERROR beyond it): the "
        "odometry's error per metre driven or radian turned it makes (E_s, E_b: their "
        "change; E_d: its heading drift per metre, the change over the wheelbase [rad/m]; "
        "the laser's x, y [m], yaw [rad]; k_g: its change).",
        kind="number",
        default=0.02,
        bound=Bound("range", 1.0, 1e-4),
    ),
    Spec(
        "apply",
        ("--apply",),
        MONITOR_SECTION,
        "never: only say; at-rest: apply a confirmed change whose verdict lets it be "
        "applied, once the robot has rested --rest-time, never while it moves.",
        kind="choice",
        default="never",
        choices=APPLY_POLICIES,
    ),
    Spec(
        "rest_time",
        ("--rest-time",),
        MONITOR_SECTION,
        "With --apply at-rest: how long the wheels must have stood still [s].",
        kind="number",
        default=5.0,
        unit="s",
        bound=Bound("range", 3600.0, 0.5),
    ),
)

#: The monitor's options by keyword.
MONITOR: dict[str, Spec] = {spec.name: spec for spec in MONITOR_OPTIONS}

#: The simulated robot's options (``umbmark monitor --sim``).
MONITOR_SIM_OPTIONS: tuple[Spec, ...] = (
    Spec(
        "minutes",
        ("--minutes",),
        SIM_SECTION,
        "Robot time to simulate [min].",
        kind="number",
        default=20.0,
        unit="min",
        bound=Bound("range", 24 * 60.0, 1.0),
    ),
    Spec(
        "change_after",
        ("--change-after",),
        SIM_SECTION,
        "The right wheel is changed (its diameter) after this much robot time [min].",
        kind="number",
        default=8.0,
        unit="min",
        bound=Bound("range", 24 * 60.0, 0.0),
    ),
    Spec(
        "wheel_change",
        ("--wheel-change",),
        SIM_SECTION,
        "The changed right wheel's diameter over the old one, less 1 (-0.006: 0.6 % "
        "smaller; 0: no change).",
        kind="number",
        default=-0.006,
        bound=Bound("range", 0.05, -0.05),
    ),
    Spec(
        "knock",
        ("--knock",),
        SIM_SECTION,
        "Knock the laser at the same time: 10 mm forward and 3 degrees.",
        kind="flag",
        default=False,
    ),
    Spec(
        "speedup",
        ("--speedup",),
        SIM_SECTION,
        "Robot time per wall time (0: as fast as the computer allows).",
        kind="number",
        default=0.0,
        bound=Bound("range", 10000.0, 0.0),
    ),
    Spec(
        "seed",
        ("--seed",),
        SIM_SECTION,
        "Seeds the missions and the sensors' noise.",
        kind="integer",
        default=1,
        bound=Bound("range", 2**31 - 1, 0),
    ),
)

#: The simulated robot's options by keyword.
MONITOR_SIM: dict[str, Spec] = {spec.name: spec for spec in MONITOR_SIM_OPTIONS}

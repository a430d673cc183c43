"""What a self-calibration is asked to do, checked once (:class:`SelfcalSetup`): the
square test (side, runs, passes, how the fixes are taken, where the corner stands), how
the corrections reach the controller, and where the results go.

:func:`umbmark.selfcal` takes one (``setup=``), or its fields as keywords
(``side_length=2, runs=3``), as :func:`umbmark.simulate` takes
:class:`umbmark.sim.setup.SimSetup`. The defaults and checks of the options the command
line shares are those of their spec entries (:mod:`umbmark.options.selfcal`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace
from typing import Literal

from umbmark.options.selfcal import (
    APPLY,
    CORNER_SIDE,
    MAX_PASSES,
    MEASURE,
    ROBOT_WIDTH,
    RUNS,
    SQUARE_SIDE,
)
from umbmark.options.spec import READ
from umbmark.robot.base import ApplyMethod, Robot
from umbmark.routines.clearance import robot_footprint
from umbmark.routines.drive import DriveLimits
from umbmark.routines.measure import CornerChoice, MeasureMethod

__all__ = ["SQUARE_ONLY", "Routine", "SelfcalSetup"]

#: What the robot drives: the paper's squares at a corner, or the pattern anywhere.
Routine = Literal["umbmark", "anywhere"]

#: The square routine's own fields: ``routine="anywhere"`` refuses them given.
SQUARE_ONLY = (
    "side_length", "runs", "measure", "max_passes", "report", "resume", "tape_marks",
    "corner_side",
)  # fmt: skip


@dataclass(frozen=True)
class SelfcalSetup:
    """A self-calibration's settings, checked when made.

    Attributes
    ----------
    side_length : float
        The square's side [m] (0.5 to 20).
    runs : int
        Runs per direction (5 in the paper; 2 to 20).
    measure : {"lidar", "ranges", "truth", "tape"}
        How the fixes are taken (``tape``: a person answers :func:`umbmark.selfcal`'s
        ``ask`` at each stop).
    apply : bool or {"reconfigure", "yaml", "none"}
        How corrections reach the controller: ``True`` is ``reconfigure`` (at once, as
        dynamic_reconfigure does), ``yaml`` writes the controller's parameter file,
        ``False`` or ``none`` applies nothing (one pass).
    verify : bool
        Drive a verification pass on the final parameters.
    max_passes : int
        Most UMBmark passes before the verification (1 to 5).
    robot_name, history : optional
        Record every pass in the robot's history (SQLite) and mark the applied ones.
    out : path, optional
        Folder for the passes' run logs, the report and the overlay: new, empty, or
        (``force``) an earlier self-calibration's, replaced whole. Without it nothing is
        written (run logs in a temporary folder) [``umbmark selfcal``:
        :func:`umbmark.jobs.selfcal.default_folder`].
    report : path, optional
        The HTML page of all passes [default: ``report.html`` in ``out``; none without
        ``out``].
    limits : DriveLimits, optional
        Speeds, accelerations and safety limits.
    robot_width : float, optional
        The robot's width [m] (0.1 to 2): its footprint taken as a square this wide around
        the axle centre, the band the watch and the check before moving keep clear
        [default: ``limits.footprint`` where given, else the robot's own (its description's
        base link, ``robot.footprint()``), else 0.4 m: :meth:`drive_limits`].
    tape_marks : six floats, optional
        For ``tape``: ``x1, y1, x2, y2, x3, y3`` [m] on the robot, measured from (two to
        the wall behind, one to the side wall) [default: the robot's ``tape_marks()``].
    coarse : bool
        Check first that the robot turns as its odometry believes (lidar or truth; with
        an IMU, ranges too: the gyro measures the turns).
    force : bool
        Replace an earlier self-calibration in ``out`` and a ``report`` file that exists.
    resume : path, optional
        The folder of a self-calibration stopped for a controller restart: go on with its
        settings (the test's given here are not used), once the controller holds the
        parameters it stopped on (:mod:`umbmark.routines.resume`).
    corner_side : {"auto", "right", "left"}
        Where the corner stands seen from the start: behind it and to its right or left
        (which wall each range sensor or tape mark faces; the first fix must find it
        there, else nothing moves); ``auto``, the default: the side the first fix finds
        it on (a check line says which; a tape fix takes the right).
    controller : str, optional
        The controller the corrections are for, with its namespace
        (``/robot1/diff_cont``): the overlays and the history are keyed by it [default:
        a ROS robot's own (``--controller``), else ``diff_drive_controller``, said so].
    command : str, optional
        The command line that runs it (``umbmark selfcal ...``), shown on the page
        (None: "made from Python").
    gyro_scale_tolerance : float
        How far the gyro's scale may be off, a fraction (0 to 0.2; MEMS datasheets: 0.03):
        the coarse check's ratio by the gyro is known to it, and without a laser the
        anywhere routine's ``E_b`` interval is widened by it.

    Raises
    ------
    InputError
        For a value out of its range, naming the option.
    """

    side_length: float = SQUARE_SIDE.default
    runs: int = RUNS.default
    measure: MeasureMethod = MEASURE.default
    apply: bool | ApplyMethod = True
    verify: bool = True
    max_passes: int = MAX_PASSES.default
    robot_name: str | None = None
    history: str | os.PathLike[str] | None = None
    out: str | os.PathLike[str] | None = None
    report: str | os.PathLike[str] | None = None
    limits: DriveLimits | None = None
    robot_width: float | None = ROBOT_WIDTH.default
    tape_marks: Sequence[float] | None = None
    coarse: bool = True
    force: bool = False
    resume: str | os.PathLike[str] | None = None
    corner_side: CornerChoice = CORNER_SIDE.default
    controller: str | None = None
    command: str | None = None
    gyro_scale_tolerance: float = READ["gyro_scale_tolerance"].default

    def __post_init__(self) -> None:
        for spec in (SQUARE_SIDE, RUNS, MAX_PASSES, MEASURE, ROBOT_WIDTH):
            spec.check(getattr(self, spec.name))
        READ["gyro_scale_tolerance"].check(self.gyro_scale_tolerance)
        if not isinstance(self.apply, bool):
            APPLY.check(self.apply)
        CORNER_SIDE.check(self.corner_side)

    @property
    def apply_method(self) -> ApplyMethod:
        """``apply`` as a method: True is ``reconfigure``, False is ``none``."""
        if isinstance(self.apply, bool):
            return "reconfigure" if self.apply else "none"
        return self.apply

    def drive_limits(self, robot: Robot) -> DriveLimits:
        """``limits`` with the footprint the routine keeps clear: ``robot_width``'s square
        where given, else the footprint ``limits`` give, else the robot's own, else the
        default (:func:`umbmark.routines.clearance.robot_footprint`)."""
        limits = self.limits or DriveLimits()
        if self.robot_width is None and limits.footprint is not None:
            return limits
        return replace(limits, footprint=robot_footprint(robot, self.robot_width))

    @classmethod
    def square_options(
        cls, setup: SelfcalSetup | None, changes: Mapping[str, object]
    ) -> dict[str, bool]:
        """For each of :data:`SQUARE_ONLY`, whether ``setup`` or ``changes`` give it other
        than its default (what ``routine="anywhere"`` refuses)."""
        defaults = {f.name: f.default for f in fields(cls)}
        given = {name: getattr(setup, name) for name in SQUARE_ONLY} if setup else {}
        given.update({k: v for k, v in changes.items() if k in SQUARE_ONLY})
        return {name: given.get(name, defaults[name]) != defaults[name] for name in SQUARE_ONLY}

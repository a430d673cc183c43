"""Taking a fix at a stop: the robot's pose in the corner frame from what the robot
offers (laser scans, range sensors, motion capture) or from a person with a tape.

The robot stands still while readings are taken; several are averaged
(:data:`READINGS`), spaced by the sensor's period so that they are independent.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Literal

from umbmark.core.errors import InputError, option
from umbmark.robot.base import Pose2D, RangeReading, Robot, ScanSweep, StampedPose
from umbmark.routines.corner import CornerFix, CornerNotFoundError
from umbmark.routines.corner_lidar import LidarCorner, fix_from_scans
from umbmark.routines.corner_sensors import (
    PAPER_FACES,
    TapeMarks,
    Wall,
    ask_tape,
    fix_from_ground_truth,
    fix_from_ranges,
    fix_from_tape,
)

__all__ = [
    "CORNER_SIDES",
    "MEASURE_METHODS",
    "READINGS",
    "CornerChoice",
    "CornerSide",
    "Measure",
    "MeasureMethod",
    "check_side",
    "first_fix",
    "marks_for",
    "take_fix",
]

MeasureMethod = Literal["lidar", "ranges", "truth", "tape"]
MEASURE_METHODS: tuple[MeasureMethod, ...] = ("lidar", "ranges", "truth", "tape")

#: Where the L-shaped corner stands seen from the start: behind it, to its right or left.
CornerSide = Literal["right", "left"]
CORNER_SIDES: tuple[CornerSide, ...] = ("right", "left")
#: The side asked for: one of them, or ``auto`` (found by the first fix, :func:`first_fix`).
CornerChoice = Literal["auto", "right", "left"]
#: The wall each range sensor (tape mark) faces, by the corner's side: the first two the
#: wall behind the start, the third the side wall. The corner frame is right-handed with
#: the robot inside, so the wall behind is the y wall with the corner on the right and
#: the x wall with it on the left (:mod:`umbmark.routines.corner`).
FACES: dict[CornerSide, tuple[Wall, ...]] = {"right": PAPER_FACES, "left": ("x", "x", "y")}
#: The robot's heading in the corner frame when placed square in the corner [rad].
SQUARE: dict[CornerSide, float] = {"right": 0.0, "left": 0.5 * math.pi}

#: Readings averaged at a stop (scans, range readings, motion-capture poses).
READINGS = 5
#: Time between readings [s]: a 10 Hz laser's period.
READING_PERIOD = 0.1


@dataclass(frozen=True)
class Measure:
    """How fixes are taken.

    Attributes
    ----------
    method : {"lidar", "ranges", "truth", "tape"}
    readings : int
        Readings averaged per fix.
    ask : callable, optional
        For ``tape``: shows a prompt, returns the person's answer (``input``).
    marks : TapeMarks, optional
        For ``tape``: the marks on the robot the person measures from.
    side : {"auto", "right", "left"}
        Where the corner stands seen from the start (behind it, to that side): which wall
        each range sensor or tape mark faces (:data:`FACES`), and the side the first fix
        must find it on (:func:`check_side`); ``auto``: the side the first fix finds
        (:func:`first_fix`).
    """

    method: MeasureMethod = "lidar"
    readings: int = READINGS
    ask: Callable[[str], str] | None = None
    marks: TapeMarks | None = None
    side: CornerChoice = "right"

    def __post_init__(self) -> None:
        if self.side not in ("auto", *CORNER_SIDES):
            raise InputError(f"{option('corner_side', repr(self.side))}: use auto, right or left")

    @property
    def sided(self) -> CornerSide:
        """The side the fixes take: ``auto`` not yet found is the right."""
        return "left" if self.side == "left" else "right"


def _collect(robot: Robot, read: Callable[[], object], what: str, count: int) -> list[object]:
    out: list[object] = []
    last: float | None = None
    for _ in range(50 * count):
        value = read()
        time = getattr(value, "time", None)
        if value is not None and time != last:
            out.append(value)
            last = time
            if len(out) == count:
                return out
        robot.wait(READING_PERIOD)
    raise CornerNotFoundError("missing_echo", f"the robot gives no {what} (asked for {count})")


def take_fix(
    robot: Robot,
    how: Measure,
    prior: Pose2D | None = None,
    gate: tuple[float, float] = (0.5, math.radians(20.0)),
) -> CornerFix:
    """A fix of the robot where it stands.

    Parameters
    ----------
    robot : Robot
        Standing still.
    how : Measure
    prior : Pose2D, optional
        Where the robot should be in the corner frame (from the last fix and the odometry):
        gates the corner found.
    gate : (float, float)
        How far [m] and how much turned [rad] from ``prior`` the fix may be (after a run,
        the return error's size).

    Raises
    ------
    CornerNotFoundError
        No fix, with the cause.
    """
    n = how.readings
    if how.method == "lidar":
        scans = _collect(robot, robot.scan, "laser scan", n)
        config = LidarCorner(prior_distance=gate[0], prior_angle=gate[1])
        return fix_from_scans([s for s in scans if isinstance(s, ScanSweep)], prior, config)
    if how.method == "ranges":
        readings = _collect(robot, robot.ranges, "range-sensor reading", n)
        return fix_from_ranges(
            [r for r in readings if isinstance(r, RangeReading)],
            FACES[how.sided],
            prior=prior,
            prior_distance=gate[0],
            prior_angle=gate[1],
        )
    if how.method == "truth":
        poses = _collect(robot, robot.ground_truth, "ground-truth pose", n)
        return fix_from_ground_truth([p for p in poses if isinstance(p, StampedPose)])
    if how.ask is None or how.marks is None:
        raise CornerNotFoundError("missing_echo", "a tape fix needs a person to ask and marks")
    marks = replace(how.marks, faces=FACES[how.sided])
    distances = ask_tape(how.ask, marks)
    return fix_from_tape(distances, marks, prior=prior, time=robot.now(), square=SQUARE[how.sided])


def _found_side(fix: CornerFix) -> tuple[Pose2D, CornerSide]:
    """The corner's vertex in the robot's frame, and the side it is on (y > 0: left)."""
    vertex = Pose2D().relative_to(fix.pose)
    return vertex, "left" if vertex.y > 0.0 else "right"


def check_side(fix: CornerFix, side: CornerChoice) -> CornerSide:
    """Refuse a first fix whose corner is not behind the robot on ``side`` (the corner's
    vertex seen from the robot: behind it, y < 0 on the right, y > 0 on the left; with
    ``auto``, behind it on either side); the side it was found on.

    Raises
    ------
    InputError
        Naming where the corner was found and the option to give.
    """
    vertex, found = _found_side(fix)
    if side in (found, "auto") and vertex.x < 0.0:
        return found
    where = "behind" if vertex.x < 0.0 else "ahead of"
    said = (
        ""
        if side == "auto"
        else f", not behind it and to its {side} as {option('corner_side', side)} says"
    )
    give = "" if side == "auto" else f"give {option('corner_side', found)}, or "
    raise InputError(
        f"the corner was found {where} the robot and to its {found} (its vertex at x = "
        f"{vertex.x:.2f} m, y = {vertex.y:.2f} m of the robot){said}: {give}place the "
        "robot with the corner behind it"
    )


def first_fix(robot: Robot, how: Measure) -> tuple[CornerFix, Measure, str | None]:
    """The first fix, checked to find the corner behind the robot on the side asked
    (:func:`check_side`; not for motion capture, whose frame is not the corner's), and
    how the fixes are taken from then on: on the side found for ``auto``, with the line
    that says so. A laser scan sees both walls whatever the side; range sensors are
    tried as on the right, then as on the left (the side whose echoes put the corner
    there); a tape fix cannot tell, and takes the right (the line says so).

    Raises
    ------
    InputError, CornerNotFoundError
        No corner, or one elsewhere (naming where).
    """
    if how.method == "truth" or how.side != "auto":
        fix = take_fix(robot, how)
        if how.method != "truth":
            check_side(fix, how.side)
        return fix, how, None
    if how.method == "tape":
        line = (
            "the corner taken behind the robot and to its right (corner side auto: a tape "
            "cannot tell; corner side left for one on its left)"
        )
        fix = take_fix(robot, replace(how, side="right"))
        check_side(fix, "right")
        return fix, replace(how, side="right"), line
    tried: list[CornerSide] = ["right"] if how.method == "lidar" else ["right", "left"]
    failed: CornerNotFoundError | None = None
    for side in tried:
        try:
            fix = take_fix(robot, replace(how, side=side))
        except CornerNotFoundError as exc:
            failed = failed or exc
            continue
        found = check_side(fix, "auto")
        if how.method == "lidar" or found == side:
            line = f"the corner found behind the robot and to its {found} (corner side auto)"
            return fix, replace(how, side=found), line
    if failed is not None:
        raise failed
    raise InputError(
        "the range sensors' echoes put the corner on neither side of the robot (read as "
        f"on its right, it is on its left, and the other way round): give "
        f"{option('corner_side', 'right')} or {option('corner_side', 'left')}"
    )


def marks_for(robot: Robot, given: Sequence[float] | None) -> TapeMarks:
    """The marks a person measures from: the given ones (``--tape-marks``), else the
    robot's own (``tape_marks()``, as the virtual robot has); refused when neither."""
    if given is not None:
        values = [float(v) for v in given]
        if len(values) != 6 or not all(math.isfinite(v) and abs(v) <= 2.0 for v in values):
            raise InputError(
                f"{option('tape_marks', ','.join(f'{v:g}' for v in values))}: give "
                "X1,Y1,X2,Y2,X3,Y3, "
                "three points on the robot in its base frame, in metres (within 2 m)"
            )
        marks = ((values[0], values[1]), (values[2], values[3]), (values[4], values[5]))
        if math.dist(marks[0], marks[1]) < 0.05:
            raise InputError(
                f"{option('tape_marks')}: the first two marks (measured to the same wall) must "
                "be at least 50 mm apart, or the heading cannot be told"
            )
        return TapeMarks(marks=marks)
    own = getattr(robot, "tape_marks", None)
    if callable(own):
        return TapeMarks(marks=tuple((float(x), float(y)) for x, y in own()))
    raise InputError(
        f"{option('measure', 'tape')} needs {option('tape_marks')}: the three points on the "
        "robot the distances "
        "are measured from (X1,Y1,X2,Y2,X3,Y3 in its base frame, metres; the first two to "
        "the wall behind the start, the third to the side wall)"
    )

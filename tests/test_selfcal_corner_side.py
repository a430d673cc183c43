"""The corner behind the start on either side (issue 22, item 2): ``corner_side`` /
``--corner-side``, on the virtual robot in the standard world and in its mirror image."""

from __future__ import annotations

import math

import pytest

from umbmark.core.errors import InputError
from umbmark.jobs.selfcal import selfcal
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import corner_world
from umbmark.routines.measure import Measure, take_fix

from helpers import run_cli

#: The paper's kind of errors (Sec. 5): unequal wheels and a wrong wheelbase.
E_D, E_B = 1.004, 0.97


@pytest.mark.slow
@pytest.mark.parametrize("side", ["right", "left"])
def test_the_corner_on_either_side_recovers_the_robots_truth(side, tmp_path):
    """The virtual robot's truth: the separation multiplier is E_b, the ratio of the
    radius multipliers E_d; the same tolerances on both sides."""
    robot = VirtualRobot(E_d=E_D, E_b=E_B, slip=0.0004, seed=3, world=corner_world(side=side))
    report = selfcal(
        robot, side_length=2.0, runs=3, max_passes=2, corner_side=side, out=tmp_path / "out"
    )
    before, after = report.e_max_syst_before, report.e_max_syst_after
    assert before is not None
    assert after is not None
    assert before / after >= 10.0
    final = report.final
    assert final.wheel_separation_multiplier == pytest.approx(E_B, abs=0.002)
    ratio = final.right_wheel_radius_multiplier / final.left_wheel_radius_multiplier
    assert ratio == pytest.approx(E_D, abs=5e-4)
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.002  # m rms, against the truth in the (mirrored) corner frame


@pytest.mark.slow
def test_range_sensors_face_the_walls_of_a_corner_on_the_left(tmp_path):
    """The sensors mirrored with the corner: the first two face the wall behind (the x
    wall of a corner on the left), the third the side wall."""
    robot = VirtualRobot(E_d=1.001, E_b=0.995, slip=0.0004, seed=1, world=corner_world(side="left"))
    report = selfcal(
        robot, measure="ranges", side_length=2.0, runs=3, corner_side="left", out=tmp_path / "o"
    )
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.003  # m rms
    assert math.degrees(errors[1]) <= 0.4  # deg rms
    final = report.final
    assert final.wheel_separation_multiplier == pytest.approx(0.995, abs=0.001)
    ratio = final.right_wheel_radius_multiplier / final.left_wheel_radius_multiplier
    assert ratio == pytest.approx(1.001, abs=0.0002)


@pytest.mark.parametrize(
    ("side", "answers", "expected"),
    [
        # marks at x = -0.35 m; the wall behind at x = -1.6 m: 1.25 m; the side wall
        # 1.3 m to that side, the third mark 0.25 m towards it: 1.05 m
        ("right", ("1250", "1250", "1050"), (1.6, 1.3, 0.0)),
        ("left", ("1250", "1250", "1050"), (1.3, 1.6, 90.0)),
    ],
)
def test_a_tape_fix_in_a_corner_on_either_side(side, answers, expected):
    """At the start, the distances a person reads give the pose in the corner frame by
    hand: right-handed with the robot inside (on the left: x along the wall behind)."""
    robot = VirtualRobot(seed=1, world=corner_world(side=side))
    marks = iter(answers)
    from umbmark.routines.corner_sensors import TapeMarks

    how = Measure(
        "tape", ask=lambda prompt: next(marks), marks=TapeMarks(robot.tape_marks()), side=side
    )
    fix = take_fix(robot, how)
    x, y, degrees = expected
    assert fix.pose.x == pytest.approx(x, abs=1e-9)
    assert fix.pose.y == pytest.approx(y, abs=1e-9)
    assert math.degrees(fix.pose.theta) == pytest.approx(degrees, abs=1e-7)
    truth = robot.corner_truth()
    assert truth is not None
    assert (truth.x, truth.y) == pytest.approx((x, y), abs=1e-12)


@pytest.mark.parametrize(("world", "forced"), [("left", "right"), ("right", "left")])
def test_a_side_given_is_forced_and_the_other_refused_before_moving(world, forced, tmp_path):
    robot = VirtualRobot(seed=1, world=corner_world(side=world))
    y = r"1\.30" if world == "left" else r"-1\.30"
    with pytest.raises(InputError, match=rf"found behind the robot and to its {world} .*y = {y} m"):
        selfcal(robot, side_length=1.0, runs=2, corner_side=forced, out=tmp_path / "out")
    assert all((v, w) == (0.0, 0.0) for _, v, w in robot.commands)
    assert robot.true_pose.x == 0.0


@pytest.mark.parametrize(
    ("side", "measure"),
    [
        ("left", "lidar"),  # the quick loop's; the others are the same routine mirrored
        pytest.param("right", "lidar", marks=pytest.mark.slow),
        pytest.param("left", "ranges", marks=pytest.mark.slow),
        pytest.param("right", "ranges", marks=pytest.mark.slow),
    ],
)
def test_the_corner_is_found_on_its_side_by_default(side, measure, tmp_path):
    """No side given (``auto``): the first fix finds the corner behind the robot on the
    left (or right), the check lines say so, and the routine completes there."""
    robot = VirtualRobot(E_d=1.002, E_b=0.99, seed=2, world=corner_world(side=side))
    lines: list[str] = []
    report = selfcal(
        robot, side_length=1.0, runs=2, max_passes=1, verify=False, coarse=False,
        measure=measure, out=tmp_path / "out", notify=lines.append,
    )  # fmt: skip
    found = f"the corner found behind the robot and to its {side} (corner side auto)"
    assert [c for c in report.checks if c.startswith("the corner found")] == [found]
    assert found in lines
    assert len(report.passes) == 1
    assert len(report.passes[0].report.runs) == 4
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.003  # m rms: the fixes in the corner frame of that side


def test_the_option_takes_auto_right_or_left():
    from umbmark.options.selfcal import CORNER_SIDE

    assert CORNER_SIDE.default == "auto"
    assert CORNER_SIDE.choices == ("auto", "right", "left")


def test_the_option_takes_right_or_left():
    proc = run_cli("selfcal", "--sim", "--corner-side", "behind")
    assert proc.returncode == 2
    assert "--corner-side" in proc.stderr


@pytest.mark.slow
def test_a_person_with_a_tape_in_a_corner_on_the_left(tmp_path):
    """The person simulated by geometry, as in tests/test_selfcal.py: the distance from
    the named mark to the named wall (the y wall along x = 0, the x wall along y = 0 of
    the corner frame), read off the true pose and rounded to the millimetre."""
    import re

    from umbmark.robot.base import Pose2D

    robot = VirtualRobot(E_d=1.001, E_b=0.995, slip=0.0004, seed=3, world=corner_world(side="left"))
    walls: list[str] = []

    def person(prompt: str) -> str:
        found = re.search(
            r"mark \d \(x (-?\d+) mm, y (-?\d+) mm on the robot\) to the (x|y) wall", prompt
        )
        assert found, prompt
        walls.append(found[3])
        where = robot.corner_truth()
        assert where is not None
        at = where.compose(Pose2D(float(found[1]) / 1000, float(found[2]) / 1000, 0.0))
        return f"{round((at.x if found[3] == 'y' else at.y) * 1000)}"

    report = selfcal(
        robot, measure="tape", ask=person, side_length=1.0, runs=2, max_passes=1, verify=False,
        corner_side="left", out=tmp_path / "out",
    )  # fmt: skip
    assert walls[:3] == ["x", "x", "y"]  # the wall behind is the x wall on the left
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.002  # m rms: millimetre readings
    assert math.degrees(errors[1]) <= 0.4  # deg rms


def test_a_tape_cannot_tell_the_side_and_takes_the_right_saying_so():
    """The person's three distances fit a corner on either side: ``auto`` takes the right
    (the pose by hand as in the tape test above) and the check line says so."""
    from umbmark.routines.corner_sensors import TapeMarks
    from umbmark.routines.measure import first_fix

    robot = VirtualRobot(seed=1, world=corner_world(side="right"))
    answers = iter(("1250", "1250", "1050"))
    how = Measure(
        "tape", ask=lambda prompt: next(answers), marks=TapeMarks(robot.tape_marks()), side="auto"
    )
    fix, taken, line = first_fix(robot, how)
    assert taken.side == "right"
    assert (fix.pose.x, fix.pose.y) == pytest.approx((1.6, 1.3), abs=1e-9)
    assert line is not None
    assert line.startswith("the corner taken behind the robot and to its right")
    assert "corner side left" in line
    from umbmark.core.errors import option_names

    assert option_names(line) == []  # a line for people, no option markers

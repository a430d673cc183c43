"""The robot's pose in the corner from three range sensors (the paper's "sonar
calibrator"), a tape measure and motion capture, against the simulated world's truth.

Expected poses are the world's truth (``LCorner.in_corner`` of the true pose); the tape
distances are measured from the true pose by hand geometry.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.robot.base import Pose2D, RangeReading, StampedPose
from umbmark.robot.world import LCorner, MotionCapture, RangeSensors, World, corner_world
from umbmark.routines.corner import CornerNotFoundError
from umbmark.routines.corner_sensors import (
    TapeMarks,
    ask_tape,
    fix_from_ground_truth,
    fix_from_ranges,
    fix_from_tape,
)

READINGS = 5  # range readings the routine averages while the robot stands still

# The paper's layout: the robot well inside the corner, two sensors 0.5 m apart at the
# back facing the wall behind, one on the right side square to the side wall.
PAPER = World.build(
    corner=LCorner(vertex=(-0.6, -0.5), heading=0.0, x_length=1.5, y_length=2.0),
    lidar=None,
    sonars=RangeSensors(
        (
            Pose2D(-0.25, 0.25, math.pi),
            Pose2D(-0.25, -0.25, math.pi),
            Pose2D(0.0, -0.2, -math.pi / 2),
        )
    ),
)


def _readings(world: World, pose: Pose2D, rng: np.random.Generator, n: int) -> list[RangeReading]:
    out = []
    for k in range(n):
        reading = world.ranges(pose, 0.1 * k, rng)
        assert reading is not None
        out.append(reading)
    return out


def _range_errors(world: World, seed: int, trials: int, n: int, radius: float = 0.15):
    assert world.corner is not None
    rng = np.random.default_rng(seed)
    errors, z = [], []
    for _ in range(trials):
        pose = Pose2D(*rng.uniform(-radius, radius, 2), math.radians(rng.uniform(-5, 5)))
        truth = world.corner.in_corner(pose)
        fix = fix_from_ranges(_readings(world, pose, rng, n))
        e = np.array([fix.pose.x - truth.x, fix.pose.y - truth.y, fix.pose.theta - truth.theta])
        errors.append(e)
        z.append(e / np.array(fix.std))
    return np.array(errors), np.array(z)


# --- range sensors ------------------------------------------------------------------------


def test_noise_free_ranges_give_the_true_pose_exactly():
    for world in (PAPER, corner_world()):
        assert world.corner is not None
        assert world.sonars is not None
        exact = replace(world, sonars=replace(world.sonars, sigma=0.0))
        for pose in (Pose2D(), Pose2D(0.1, -0.05, 0.08), Pose2D(-0.1, 0.1, -0.06)):
            fix = fix_from_ranges(_readings(exact, pose, np.random.default_rng(0), 1))
            truth = world.corner.in_corner(pose)
            assert (fix.pose.x, fix.pose.y, fix.pose.theta) == pytest.approx(
                (truth.x, truth.y, truth.theta), abs=1e-9
            )


@pytest.mark.parametrize("world", [PAPER, corner_world()], ids=["paper layout", "standard world"])
def test_three_sensors_meet_the_papers_2_mm_and_0_4_deg(world):
    # 2 mm sensor noise, 5 readings averaged, 200 poses within 0.15 m and 5 deg
    errors, z = _range_errors(world, seed=31, trials=200, n=READINGS)
    rms = np.sqrt(np.mean(errors**2, axis=0))
    assert rms[0] <= 0.002
    assert rms[1] <= 0.002
    assert math.degrees(rms[2]) <= 0.4
    spread = np.sqrt(np.mean(z**2, axis=0))
    assert np.all((spread > 0.8) & (spread < 1.2)), spread


def test_a_single_reading_is_as_uncertain_as_stated():
    # one reading of 2 mm sensors: the heading from two ranges 0.5 m apart, sqrt(2) 2 mm
    # / 0.5 m = 0.32 deg; the side distance from one range, 2 mm
    errors, z = _range_errors(PAPER, seed=32, trials=300, n=1)
    rms = np.sqrt(np.mean(errors**2, axis=0))
    assert math.degrees(rms[2]) == pytest.approx(math.degrees(math.sqrt(2) * 0.002 / 0.5), rel=0.15)
    assert rms[1] == pytest.approx(0.002, rel=0.15)
    assert np.all(np.abs(np.sqrt(np.mean(z**2, axis=0)) - 1.0) < 0.15)


def test_ranges_refuse_a_missing_echo():
    # 1.2 m forward the side sensor looks past the end of the side wall
    error = _refuse_ranges(corner_world(), Pose2D(1.2, 0.0, 0.0))
    assert error.cause == "missing_echo"
    assert "sensor 3" in str(error)


def test_ranges_refuse_readings_that_disagree():
    world = corner_world()
    rng = np.random.default_rng(1)
    moved = _readings(world, Pose2D(), rng, 3) + _readings(world, Pose2D(0.05, 0.0, 0.0), rng, 2)
    with pytest.raises(CornerNotFoundError, match="readings disagree") as caught:
        fix_from_ranges(moved)
    assert caught.value.cause == "implausible"


def test_ranges_refuse_walls_named_the_wrong_way_round():
    world = corner_world()
    readings = _readings(world, Pose2D(), np.random.default_rng(2), 1)
    with pytest.raises(CornerNotFoundError, match="implausible geometry") as caught:
        fix_from_ranges(readings, faces=("x", "x", "y"))
    assert caught.value.cause == "implausible"


def test_ranges_refuse_beams_far_off_square():
    # turned 15 deg, every beam meets its wall 15 deg off square: more than 10 allowed
    error = _refuse_ranges(PAPER, Pose2D(0.0, 0.0, math.radians(15.0)), max_incidence=0.175)
    assert error.cause == "implausible"
    assert "sensor 1 meets the y wall 15 deg off square" in str(error)


def test_three_ranges_cannot_tell_echoes_from_the_wrong_wall_but_the_prior_can():
    # turned 50 deg in the paper's tight corner, a rear sensor's beam meets the side wall:
    # three ranges fit some other pose exactly, and only the prior tells
    world, pose = PAPER, Pose2D(0.0, 0.0, math.radians(50.0))
    assert world.corner is not None
    readings = _readings(world, pose, np.random.default_rng(4), READINGS)
    wrong = fix_from_ranges(readings)
    assert abs(math.degrees(wrong.pose.theta) - 50.0) > 10.0
    with pytest.raises(CornerNotFoundError, match="not where expected"):
        fix_from_ranges(readings, prior=world.corner.in_corner(pose))


def test_ranges_refuse_a_pose_far_from_the_prior():
    error = _refuse_ranges(corner_world(), Pose2D(), prior=Pose2D(1.0, 0.0, 0.0))
    assert error.cause == "not_where_expected"


def _refuse_ranges(world: World, pose: Pose2D, **kw: object) -> CornerNotFoundError:
    readings = _readings(world, pose, np.random.default_rng(3), READINGS)
    with pytest.raises(CornerNotFoundError) as caught:
        fix_from_ranges(readings, **kw)  # type: ignore[arg-type]
    assert isinstance(caught.value, InputError)
    assert "\n" not in str(caught.value)
    return caught.value


# --- tape measure ---------------------------------------------------------------------------

MARKS = TapeMarks(((-0.25, 0.25), (-0.25, -0.25), (0.1, -0.2)))


def _tape(truth: Pose2D) -> list[float]:
    """What a person measures: each mark's distance square to its wall, from the truth."""
    marks = [truth.compose(Pose2D(a, b)) for a, b in MARKS.marks]
    return [marks[0].x, marks[1].x, marks[2].y]  # the y wall is x = 0, the x wall y = 0


@pytest.mark.parametrize(
    "truth", [Pose2D(0.6, 0.5, 0.0), Pose2D(0.7, 0.4, 0.1), Pose2D(0.55, 0.6, -0.2)]
)
def test_exact_tape_distances_give_the_true_pose(truth):
    fix = fix_from_tape(_tape(truth), MARKS)
    assert (fix.pose.x, fix.pose.y, fix.pose.theta) == pytest.approx(
        (truth.x, truth.y, truth.theta), abs=1e-12
    )


def test_the_prior_chooses_between_the_two_headings_a_tape_allows():
    # turned round (heading near pi), the same two distances to the back wall fit too
    truth = Pose2D(0.6, 0.5, math.pi - 0.1)
    fix = fix_from_tape(_tape(truth), MARKS, prior=Pose2D(0.6, 0.5, math.pi))
    assert (fix.pose.x, fix.pose.y) == pytest.approx((truth.x, truth.y), abs=1e-12)
    assert math.remainder(fix.pose.theta - truth.theta, 2 * math.pi) == pytest.approx(
        0.0, abs=1e-12
    )


def test_tape_uncertainty_is_as_stated():
    rng = np.random.default_rng(5)
    z = []
    for _ in range(400):
        truth = Pose2D(rng.uniform(0.5, 0.7), rng.uniform(0.4, 0.6), rng.uniform(-0.1, 0.1))
        d = np.array(_tape(truth)) + rng.normal(0.0, 0.001, 3)
        fix = fix_from_tape(d.tolist(), MARKS, sigma=0.001)
        e = np.array([fix.pose.x - truth.x, fix.pose.y - truth.y, fix.pose.theta - truth.theta])
        z.append(e / np.array(fix.std))
    assert np.all(np.abs(np.sqrt(np.mean(np.square(z), axis=0)) - 1.0) < 0.12)


def test_tape_refuses_distances_the_marks_cannot_have():
    # marks 1 and 2 are 0.5 m apart: their distances to one wall differ by at most that
    with pytest.raises(CornerNotFoundError, match="implausible distances"):
        fix_from_tape([0.3, 0.9, 0.5], MARKS)
    with pytest.raises(InputError, match="three positive distances"):
        fix_from_tape([0.3, -0.2, 0.5], MARKS)


def test_ask_tape_prompts_for_each_mark_and_asks_again_on_nonsense():
    answers = iter(["", "abc", "600", "-3", "612.5", "480"])
    prompts: list[str] = []

    def ask(prompt: str) -> str:
        prompts.append(prompt)
        return next(answers)

    got = ask_tape(ask, MARKS)
    assert got == pytest.approx([0.6, 0.6125, 0.48])
    assert len(prompts) == 6
    assert prompts[0].startswith("distance from mark 1 ")
    assert prompts[0].endswith("to the y wall, square to the wall [mm]: ")
    assert prompts[-1].startswith("distance from mark 3 ")
    assert "x wall" in prompts[-1]
    with pytest.raises(InputError, match="mark 1: no distance in 3 answers"):
        ask_tape(lambda _: "n/a", MARKS)


# --- motion capture -------------------------------------------------------------------------


def test_ground_truth_in_the_corner_frame():
    world = replace(corner_world(), mocap=MotionCapture(sigma_xy=0.0, sigma_theta=0.0))
    assert world.corner is not None
    pose = Pose2D(0.3, -0.2, 0.4)
    stamped = world.truth(pose, 12.0, np.random.default_rng(0))
    assert stamped is not None
    fix = fix_from_ground_truth(stamped, corner=world.corner.frame, sigma_xy=0.001)
    truth = world.corner.in_corner(pose)
    assert (fix.pose.x, fix.pose.y, fix.pose.theta) == pytest.approx((1.9, 1.1, 0.4))
    assert (fix.pose.x, fix.pose.y) == pytest.approx((truth.x, truth.y))
    assert fix.std[0] == pytest.approx(0.001)
    assert fix.time == 12.0


def test_ground_truth_averages_poses_across_the_heading_seam():
    poses = [
        StampedPose(1.0, Pose2D(1.0, 2.0, math.pi - 0.01)),
        StampedPose(2.0, Pose2D(1.2, 2.2, -math.pi + 0.03)),
    ]
    fix = fix_from_ground_truth(poses)
    assert (fix.pose.x, fix.pose.y) == pytest.approx((1.1, 2.1))
    assert math.remainder(fix.pose.theta - (math.pi + 0.01), 2 * math.pi) == pytest.approx(0.0)
    assert fix.readings == 2
    assert fix.time == 2.0

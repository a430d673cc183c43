"""Clearance as the robot's path (issue 29, items 1 and 8), on the virtual robot braking
at a bounded deceleration as a real base does: a tight corner the plan keeps clear of
stops nothing; a box on a leg, behind a backward leg or on an arc stops the robot before
it, each stop bounded from ``v^2 / (2 a) + v t + m``; a site too tight is refused before
moving with what to change; the footprint from a URDF's base link."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, SafetyError
from umbmark.jobs.selfcal import selfcal
from umbmark.robot.base import Pose2D
from umbmark.robot.urdf import urdf_footprint
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import DEFAULT_LIDAR, LCorner, MotionCapture, World, box
from umbmark.routines.clearance import Footprint, robot_footprint
from umbmark.routines.drive import DriveLimits, Driver, drive_square

from helpers import run_cli

#: The laser's noise (1 cm) on the nearest of many beams: a wall seen up to this early [m].
NOISE = 0.03


def _corner(behind: float, beside: float, side: float = 1.0, extra: object = ()) -> World:
    """An L-shaped corner alone: its back wall ``behind`` [m] behind the start (across
    the whole room), its side wall ``beside`` [m] to the right of the cw square's far leg
    (``y = -side - beside``), plus ``extra`` segments."""
    corner = LCorner(
        vertex=(-behind, -(side + beside)), heading=0.0, x_length=side + 2.0,
        y_length=2.0 * side + beside + 1.0,
    )  # fmt: skip
    walls = np.asarray(extra, dtype=np.float64).reshape(-1, 4)
    return World.build(walls, (), corner, lidar=DEFAULT_LIDAR, mocap=MotionCapture())


def _come_to_rest(robot: VirtualRobot) -> Pose2D:
    """Let the robot brake after the zero velocity; where it stands at rest."""
    assert robot.commands[-1][1:] == (0.0, 0.0)
    robot.wait(5.0)
    return robot.true_pose


# --- (a) a tight corner the plan keeps clear of --------------------------------------------


def test_a_tight_corner_passes_and_every_run_is_driven_without_a_stop():
    """The issue's corner: walls 0.45 m behind the start and 0.4 m beside the cw
    square's far leg, a 1 m square, a robot of 168 mm (E_b 0.97). The ccw run's third
    leg ends 0.45 m before the back wall: its stop margin is 0.3 m, so the wall is
    beyond where the robot stops and does not stop it (before: "an obstacle 0.42 m ahead
    (stop distance 0.44 m)" on the first ccw run)."""
    world = _corner(0.45, 0.4)
    for direction in (Direction.CW, Direction.CCW):
        robot = VirtualRobot(E_d=1.004, E_b=0.97, seed=1, world=world, acceleration=0.3)
        run = drive_square(robot, 1.0, direction)
        assert run.end_error[0] < 0.005


@pytest.mark.slow
def test_the_whole_selfcal_completes_in_the_tight_corner(tmp_path):
    """Preflight, five runs each way, passes until verified: no safety stop, and the
    verification's error small (pass 1 found the robot's E_b of 0.97)."""
    robot = VirtualRobot(
        E_d=1.004, E_b=0.97, slip=0.0004, seed=4, world=_corner(0.45, 0.4), acceleration=0.3
    )
    said: list[str] = []
    selfcal(robot, side_length=1.0, out=tmp_path / "out", notify=said.append)
    assert said[2].startswith("the squares' path is clear as far as the laser sees")
    first = next(line for line in said if line.startswith("pass 1: E_max,syst"))
    found = re.search(r"E_b (\d\.\d+)", first)
    assert found is not None, first
    assert float(found[1]) == pytest.approx(0.97, abs=0.002), first
    verified = next(line for line in reversed(said) if line.startswith("verification:"))
    last = re.match(r"verification: E_max,syst (\d+\.\d) mm", verified)
    assert last is not None, verified
    assert float(last[1]) < 5.0, verified


# --- (b) a box on a leg ---------------------------------------------------------------------


@pytest.mark.parametrize(("speed", "at"), [(0.01, 0.8), (1.0, 6.0)])
def test_a_box_on_a_leg_stops_the_robot_with_its_margin_at_the_slowest_and_fastest(speed, at):
    """The box's face at ``at`` [m] on the first leg; the robot braking at the
    acceleration limit a = 0.3 m/s^2. It decides to stop when the box is nearer than
    d = v^2/(2 a) + v t + m (t = 0.4 s, m = 0.3 m), looking every 0.24 s, then brakes
    v^2/(2 a) and half a period at v: at rest it is at least m from the box (less the
    1 cm of the laser's noise) and at most m + v t + the noise, where it would be had
    it decided just then."""
    limits = DriveLimits(speed=speed, acceleration=0.3)
    world = _corner(1.6, 0.8, 8.0, box(at + 0.15, 0.0, 0.3, 0.4))
    robot = VirtualRobot(world=world, seed=1, acceleration=0.3)
    with pytest.raises(SafetyError, match=r"an obstacle \d\.\d\d m ahead on the robot's path"):
        drive_square(robot, 8.0, Direction.CCW, limits)
    rest = _come_to_rest(robot)
    gap = at - rest.x
    assert 0.3 - 0.01 <= gap <= 0.3 + speed * 0.4 + NOISE, gap


# --- (c) the backward watch, an obstacle on an arc -----------------------------------------


def _driver(robot: VirtualRobot, limits: DriveLimits) -> Driver:
    driver = Driver(robot, 0.0, Direction.CCW, limits)
    driver.radius = math.inf
    driver.origin = driver.settle().pose
    return driver


def test_a_box_behind_a_backward_leg_stops_the_robot():
    """Driving 3 m backward (as the anywhere pattern does) towards a box 1.5 m behind:
    at rest between m and m + v t + the noise from it, as ahead."""
    limits = DriveLimits(speed=0.2, acceleration=0.3)
    robot = VirtualRobot(world=_corner(4.0, 2.0, 1.0, box(-1.65, 0.0, 0.3, 0.4)), seed=2,
                         acceleration=0.3)  # fmt: skip
    driver = _driver(robot, limits)
    with pytest.raises(SafetyError, match=r"an obstacle \d\.\d\d m behind on the robot's path"):
        driver.leg(Pose2D(), 3.0, backward=True)
    gap = _come_to_rest(robot).x - (-1.5)
    assert 0.3 - 0.01 <= gap <= 0.3 + 0.2 * 0.4 + NOISE, gap


@pytest.mark.parametrize("backward", [False, True])
def test_a_box_on_an_arc_stops_the_robot(backward):
    """An arc of 162 degrees, 1 m radius, to the left (forward: centre at (0, 1); backward the
    robot swings to (0, ... ) mirrored: centre at (0, -1)), a box on the circle a
    quarter turn on (at (1, 1), or (-1, -1) backward), never straight ahead of the robot
    at the start. The robot stops before it: at rest at least the margin along the arc
    short of the box's near face, at most m + v t + the noise."""
    limits = DriveLimits(speed=0.2, acceleration=0.3)
    sign = -1.0 if backward else 1.0
    # the box's nearest corner in the band, (0.85, 0.85): its angle about the centre
    near = 0.5 * math.pi - math.atan2(0.15, 0.85)
    robot = VirtualRobot(world=_corner(4.0, 3.0, 1.0, box(sign, sign, 0.3, 0.3)), seed=3,
                         acceleration=0.3)  # fmt: skip
    driver = _driver(robot, limits)
    where = "behind" if backward else "ahead"
    with pytest.raises(SafetyError, match=rf"an obstacle \d\.\d\d m {where} on the robot's path"):
        driver.arc(0.9 * math.pi, 1.0, backward=backward)
    rest = _come_to_rest(robot)
    swept = math.atan2(sign * rest.x, 1.0 - sign * rest.y)  # angle about the centre
    gap = near - swept  # [m]: radius 1
    assert 0.3 - 0.01 <= gap <= 0.3 + 0.2 * 0.4 + NOISE, (gap, rest)


def test_a_wall_beside_a_leg_or_beyond_its_end_does_not_stop_it():
    """Walls 0.3 m beside the leg (outside the 0.4 m robot's band of 0.25 m) and 0.35 m
    past its end (beyond the 0.3 m margin): a 2 m leg is driven to its end."""
    walls = [[-0.5, 0.3, 2.35, 0.3], [2.35, 0.3, 2.35, -0.3]]
    robot = VirtualRobot(world=_corner(4.0, 2.0, 1.0, walls), seed=4, acceleration=0.3)
    driver = _driver(robot, DriveLimits())
    driver.leg(Pose2D(), 2.0)
    assert _come_to_rest(robot).x == pytest.approx(2.0, abs=0.01)


# --- (d) a site too tight -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("behind", "beside", "change"),
    [
        # the back wall 0.3 m behind: the 0.4 m robot turning at the start (its reach
        # 0.283 m + 0.03 m, + 1 m sin 2 deg = 0.035 m back from the last leg) needs
        # 0.348 m: 0.10 m forward (0.05 m leaves 0.35 m, less the laser's 1 cm noise); a
        # shorter side does not help (0.5 m: 0.33 m)
        (0.3, 0.8, "move the robot 0.10 m forward"),
        # the side wall 0.28 m beside the cw square's far leg: its corners need 0.348 m:
        # 0.10 m to the left (0.05 m: 0.33 m), or a 0.9 m side (0.38 m from its far leg,
        # needing 0.313 + 0.031 m)
        (0.8, 0.28, "move the robot 0.10 m to the left; or use --side-length 0.9 m"),
    ],
)
def test_a_site_too_tight_is_refused_before_moving_with_what_to_change(
    behind, beside, change, tmp_path
):
    robot = VirtualRobot(world=_corner(behind, beside), seed=5)
    with pytest.raises(InputError, match="something stands on the squares' path") as caught:
        selfcal(robot, side_length=1.0, out=tmp_path / "out")
    assert str(caught.value).endswith(f"): {change}")
    assert robot.true_pose == robot.world.start


# --- (e) the footprint ----------------------------------------------------------------------

_URDF = """<robot name="r">
  <link name="base_link">{geometry}</link>
  <link name="laser"/>
  <joint name="j" type="fixed"><parent link="base_link"/><child link="laser"/></joint>
</robot>"""


@pytest.mark.parametrize(
    ("geometry", "expected"),
    [
        (  # a collision box 0.5 long, 0.36 wide, 5 cm behind the axle (visual ignored)
            '<visual><geometry><box size="0.9 0.9 0.1"/></geometry></visual>'
            '<collision><origin xyz="-0.05 0 0.1" rpy="0 0 0"/>'
            '<geometry><box size="0.5 0.36 0.2"/></geometry></collision>',
            (0.5, 0.36, -0.05),
        ),
        (  # the same box turned 90 degrees: its length across
            '<collision><origin xyz="0 0 0" rpy="0 0 1.5707963267948966"/>'
            '<geometry><box size="0.5 0.36 0.2"/></geometry></collision>',
            (0.36, 0.5, 0.0),
        ),
        (  # a cylinder of radius 0.177 (a TurtleBot 2): 0.354 m across
            '<collision><geometry><cylinder radius="0.177" length="0.1"/></geometry></collision>',
            (0.354, 0.354, 0.0),
        ),
        (  # no collision: the visual
            '<visual><geometry><cylinder radius="0.2" length="0.1"/></geometry></visual>',
            (0.4, 0.4, 0.0),
        ),
        ('<visual><geometry><mesh filename="base.stl"/></geometry></visual>', None),
    ],
)
def test_the_footprint_is_read_from_the_base_links_geometry(geometry, expected):
    found = urdf_footprint(_URDF.format(geometry=geometry))
    if expected is None:
        assert found is None
    else:
        assert found == pytest.approx(expected)


def test_the_footprint_is_the_option_else_the_robots_else_the_default():
    class Described(VirtualRobot):
        def footprint(self) -> tuple[float, float, float]:
            return (0.5, 0.36, -0.05)

    robot = Described(seed=1)
    assert robot_footprint(robot, 0.6) == Footprint(0.6, 0.6)
    assert robot_footprint(robot, None) == Footprint(0.5, 0.36, -0.05)
    assert robot_footprint(VirtualRobot(seed=1), None) == Footprint(0.4, 0.4)
    # the band: half the width + 3 cm; the reach turning: the far corner + 3 cm
    assert Footprint(0.5, 0.36, -0.05).half_width == pytest.approx(0.21)
    assert Footprint(0.5, 0.36, -0.05).reach == pytest.approx(math.hypot(0.3, 0.18) + 0.03)


def test_the_width_option_is_bounded():
    proc = run_cli("selfcal", "--sim", "--robot-width", "3")
    assert proc.returncode == 2
    assert proc.stderr.strip() == "umbmark: error: --robot-width must be 0.1 to 2 m, got 3 m"

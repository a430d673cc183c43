"""The robot's footprint on its whole way, from ``--robot-width`` (or ``robot_width=``)
to the watch and the check before moving (issue 35, item 7).

An obstacle :data:`OFFSET` off the centre line of the robot's path is inside the band a
0.4 m wide robot sweeps (half its width plus 3 cm: 0.23 m) and outside a 0.2 m one's
(0.13 m). So the wide robot is stopped for it, on a leg, on an arc, forward and backward,
and refused before moving when it stands there from the start; the narrow one drives
past it. The default footprint is 0.4 m across: a width dropped anywhere on its way (a
default used instead) stops the narrow robot too, and these tests fail. Everything goes
through :func:`umbmark.selfcal` on the virtual robot, the command's own path from its
setup on; the last test gives the command's option.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

import umbmark
from umbmark.core.errors import InputError, SafetyError
from umbmark.robot.base import Pose2D
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import ROOM_LASER, World, box, corner_world, room_world
from umbmark.routines.clearance import Footprint
from umbmark.routines.drive import DriveLimits

from helpers import run_cli

#: How far the obstacle's nearest point is off the centre line [m]: within a 0.4 m
#: robot's band (0.23 m), outside a 0.2 m robot's (0.13 m; the check before moving
#: widens it by ``a sin 2 deg`` after ``a`` metres: 0.158 m at 0.8 m along a leg).
OFFSET = 0.18
WIDE, NARROW = 0.4, 0.2
#: The stop's margin, the look-ahead latency at 0.2 m/s, the laser's noise [m]
#: (``tests/test_selfcal_clearance.py``): at rest between MARGIN - 0.01 and
#: MARGIN + 0.2 x 0.4 + NOISE short of the obstacle.
MARGIN, LATENCY, NOISE = 0.3, 0.2 * 0.4, 0.03

Progress = Callable[[str, int, object, str], None]


def _stood_still(robot: VirtualRobot) -> None:
    """Nothing but zero velocities was sent, and the robot is where it started."""
    assert all(v == 0.0 and w == 0.0 for _, v, w in robot.commands)
    start = robot.world.start
    assert (robot.true_pose.x, robot.true_pose.y) == (start.x, start.y)


def _at_rest(robot: VirtualRobot) -> Pose2D:
    """Where the robot stands once it has braked after the zero velocity it was sent."""
    assert robot.commands[-1][1:] == (0.0, 0.0)
    robot.wait(5.0)
    return robot.true_pose


# --- the square routine: a box beside the first leg ---------------------------------------


def _corner_robot() -> VirtualRobot:
    """The standard corner without its clutter; braking at 0.3 m/s^2 as a real base does."""
    return VirtualRobot(
        E_d=1.002, E_b=0.998, seed=1, world=corner_world(clutter=False), acceleration=0.3
    )


def _box_beside_the_first_leg(world: World, side: float) -> World:
    """A 0.3 x 0.2 m box from x = 0.5 to 0.8 m (on the first leg of a 1 m square, which
    both directions drive along +x), its near face :data:`OFFSET` to the left (``side``
    1) or right (-1) of the centre line."""
    obstacle = box(0.65, side * (OFFSET + 0.1), 0.3, 0.2)
    return replace(world, segments=np.vstack([world.segments, obstacle]))


def _squares(robot: VirtualRobot, progress: Progress, said: list[str], **options: object) -> None:
    """A 1 m self-calibration (no coarse check), each line it says added to ``said``."""
    umbmark.selfcal(
        robot, side_length=1.0, runs=2, coarse=False, corner_side="right", progress=progress,
        notify=said.append, **options,
    )  # fmt: skip


def _stop_at(what: str) -> Progress:
    """A progress callback interrupting the routine when it reports ``what``."""

    def progress(label: str, k: int, direction: object, now: str) -> None:
        if now == what:
            raise KeyboardInterrupt

    return progress


@pytest.mark.parametrize("side", [1.0, -1.0], ids=["left", "right"])
@pytest.mark.parametrize("width", [WIDE, NARROW])
def test_a_box_beside_a_leg_stops_a_wide_robot_and_not_a_narrow_one(width, side):
    """The box appears once the robot drives its first leg (after the check before
    moving). The 0.4 m robot is stopped for it and comes to rest between the margin and
    margin + v t + noise before its near face (x = 0.5 m); the 0.2 m robot drives the
    whole leg (to x = 1 m) past it."""
    robot = _corner_robot()
    blocked = _box_beside_the_first_leg(robot.world, side)

    def progress(label: str, k: int, direction: object, what: str) -> None:
        if what == "driving, leg 1":
            robot.world = blocked
        elif what == "driving, leg 2":  # the first leg driven, and its turn
            raise KeyboardInterrupt

    if width == WIDE:
        with pytest.raises(SafetyError, match=r"an obstacle \d\.\d\d m ahead on the robot's path"):
            _squares(robot, progress, [], robot_width=width)
        gap = 0.5 - _at_rest(robot).x
        assert MARGIN - 0.01 <= gap <= MARGIN + LATENCY + NOISE, gap
    else:
        with pytest.raises(KeyboardInterrupt):
            _squares(robot, progress, [], robot_width=width)
        assert robot.true_pose.x == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize("width", [WIDE, NARROW])
def test_the_check_before_moving_refuses_a_wide_robot_beside_a_box_and_not_a_narrow_one(width):
    """The box stands there from the start: the 0.4 m robot is refused before it moves,
    the message naming its width; the 0.2 m robot's path is clear."""
    robot = _corner_robot()
    robot.world = _box_beside_the_first_leg(robot.world, 1.0)
    said: list[str] = []
    if width == WIDE:
        with pytest.raises(InputError) as caught:
            _squares(robot, _stop_at("back to the start"), said, robot_width=width)
        assert str(caught.value).startswith("something stands on the squares' path at x = 0.4"), (
            caught.value
        )
        assert "y = 0.18 m of the robot" in str(caught.value)
        assert "in the band a 0.4 m wide robot sweeps on the 1 m squares" in str(caught.value)
        _stood_still(robot)
    else:
        with pytest.raises(KeyboardInterrupt):
            _squares(robot, _stop_at("back to the start"), said, robot_width=width)
        assert any(line.startswith("the squares' path is clear") for line in said), said
        assert any("(0.2 m wide plus room each side)" in line for line in said), said


class _Described(VirtualRobot):
    """A robot whose description gives its footprint (as a ROS robot's URDF base link
    does: :meth:`umbmark.robot.ros2.Ros2Robot.footprint`): 0.2 m square."""

    def footprint(self) -> tuple[float, float, float]:
        return (0.2, 0.2, 0.0)


@pytest.mark.parametrize(
    ("robot_width", "limits", "refused"),
    [
        (None, None, False),  # the robot's own 0.2 m
        (WIDE, None, True),  # the option over the robot's own
        (None, DriveLimits(footprint=Footprint(WIDE, WIDE)), True),  # the limits' over it
        (NARROW, DriveLimits(footprint=Footprint(WIDE, WIDE)), False),  # the option over all
    ],
)
def test_the_footprint_is_the_width_given_else_the_limits_else_the_robots_own(
    robot_width, limits, refused
):
    """From Python as from the command: a robot describing its own footprint is taken at
    it when no width is given (before, ``umbmark.selfcal`` took 0.4 m unless told)."""
    robot = _Described(E_d=1.002, E_b=0.998, seed=1, world=corner_world(clutter=False))
    robot.world = _box_beside_the_first_leg(robot.world, 1.0)
    options = {"robot_width": robot_width, "limits": limits}
    if refused:
        with pytest.raises(InputError, match=r"a 0\.4 m wide robot sweeps"):
            _squares(robot, _stop_at("back to the start"), [], **options)
        _stood_still(robot)
    else:
        with pytest.raises(KeyboardInterrupt):
            _squares(robot, _stop_at("back to the start"), [], **options)


# --- the anywhere routine: legs and arcs, forward and backward ----------------------------

#: The obstacle: a post of this radius [m], its centre this far along the move [m].
POST, ALONG = 0.05, 0.55
#: The pattern's arcs' radius [m] (:data:`umbmark.routines.anywhere.PATTERN`).
RADIUS = 0.4


def _room_robot() -> VirtualRobot:
    """The command's robot of the anywhere routine (its laser off the axle centre)."""
    return VirtualRobot(
        1.002, 0.998, 1.0, slip=0.0004, seed=1, world=room_world(),
        laser_pose=(ROOM_LASER.x, ROOM_LASER.y, ROOM_LASER.theta), acceleration=0.3,
    )  # fmt: skip


def _post(move: str, start: Pose2D, side: float) -> tuple[Pose2D, float]:
    """Where the post stands for ``move`` driven from ``start`` (the robot's true pose):
    its nearest point :data:`OFFSET` to the ``side`` (1 left, -1 right) of the path,
    :data:`ALONG` along it; and how far along the path the band first meets it [m].
    The pattern's arcs all turn about a centre to the robot's left at their start
    (forward to +90 deg, or backward undoing one: ``arc -90 deg ... backward``)."""
    across = side * (OFFSET + POST)
    if move.startswith("straight"):
        sign = -1.0 if move.startswith("straight -") else 1.0
        return start.compose(Pose2D(sign * ALONG, across, 0.0)), ALONG - POST
    rho = RADIUS - across  # from the arc's centre: the left is inside
    phi = ALONG / RADIUS * (-1.0 if move.endswith("backward") else 1.0)
    angle = -0.5 * math.pi + phi
    where = start.compose(Pose2D(rho * math.cos(angle), RADIUS + rho * math.sin(angle), 0.0))
    # the band meets the post where its radius reaches the band's edge: no later than the
    # tangent from the centre, asin(POST / rho) before its centre's angle
    return where, RADIUS * (abs(phi) - math.asin(POST / rho))


@pytest.mark.parametrize("width", [WIDE, NARROW])
@pytest.mark.parametrize(
    ("move", "side"),
    [
        ("straight +0.60 m", 1.0),
        ("straight -0.60 m", -1.0),
        ("arc +90 deg, radius 0.40 m", 1.0),  # inside the arc
        ("arc -90 deg, radius 0.40 m backward", -1.0),  # outside it
    ],
)
def test_a_post_beside_a_move_stops_a_wide_robot_and_not_a_narrow_one(move, side, width):
    """The post appears as the move begins. The 0.4 m robot is stopped for it (ahead, or
    behind where it drives backward) and comes to rest short of where its band meets the
    post by at least the margin less the noise (no more than margin + v t + noise on a
    straight); the 0.2 m robot drives the move to its end past it."""
    robot = _room_robot()
    seen: dict[str, object] = {}

    def progress(label: str, k: int, direction: object, what: str) -> None:
        if "start" in seen:
            raise KeyboardInterrupt  # the move after it: it was driven
        if what == move:
            seen["start"] = start = robot.true_pose
            seen["post"], seen["meets"] = _post(move, start, side)
            post = seen["post"]
            assert isinstance(post, Pose2D)
            circles = np.vstack([robot.world.circles, [[post.x, post.y, POST]]])
            robot.world = replace(robot.world, circles=circles)

    call = {"routine": "anywhere", "robot_width": width, "apply": "none", "progress": progress}
    if width == NARROW:
        with pytest.raises(KeyboardInterrupt):
            umbmark.selfcal(robot, **call)
        start = seen["start"]
        assert isinstance(start, Pose2D)
        moved = robot.true_pose.relative_to(start)
        if move.startswith("straight"):
            assert abs(moved.x) == pytest.approx(0.6, abs=0.01), moved
        else:
            assert abs(moved.theta) == pytest.approx(0.5 * math.pi, abs=0.02), moved
        return
    where = "behind" if move.endswith("backward") or move.startswith("straight -") else "ahead"
    with pytest.raises(SafetyError, match=rf"an obstacle \d\.\d\d m {where} on the robot's path"):
        umbmark.selfcal(robot, **call)
    start, meets = seen["start"], seen["meets"]
    assert isinstance(start, Pose2D)
    assert isinstance(meets, float)
    moved = _at_rest(robot).relative_to(start)
    driven = abs(moved.x) if move.startswith("straight") else RADIUS * abs(moved.theta)
    assert meets - driven >= MARGIN - 0.01, (meets, moved)
    if move.startswith("straight"):
        assert meets - driven <= MARGIN + LATENCY + NOISE, (meets, moved)


@pytest.mark.parametrize("width", [WIDE, NARROW])
def test_the_pattern_floor_refuses_a_wide_robot_near_a_post_and_not_a_narrow_one(width):
    """A post whose nearest point is 1 m to the left of the start: within the pattern's
    reach (0.75 m) plus the 0.4 m robot's turning disc (its corner, hypot(0.2, 0.2), plus
    3 cm: 1.063 m in all), beyond the 0.2 m robot's (0.75 + 0.171 = 0.921 m)."""
    robot = _room_robot()
    post = [[0.0, 1.0 + POST, POST]]
    robot.world = replace(robot.world, circles=np.vstack([robot.world.circles, post]))
    call = {"routine": "anywhere", "robot_width": width, "progress": _stop_at("turn +120 deg")}
    if width == WIDE:
        with pytest.raises(InputError) as caught:
            umbmark.selfcal(robot, **call)
        assert str(caught.value).startswith(
            "something stands within the pattern's floor at x = 0.0"
        ), caught.value
        assert "within 1.06 m of its centre" in str(caught.value)
        _stood_still(robot)
    else:
        with pytest.raises(KeyboardInterrupt):
            umbmark.selfcal(robot, **call)


# --- the command's option -----------------------------------------------------------------


def test_the_commands_width_reaches_the_check_before_moving(tmp_path):
    """``umbmark selfcal --sim`` (4 m squares in the standard corner): the side wall ends
    0.35 m beside the cw square's last leg (x = 0), 2.7 m along it. A 0.6 m robot's band
    there is 0.3 + 0.03 + 2.7 sin 2 deg = 0.424 m: refused before moving, naming its
    width, and nothing written (the 0.4 m default's 0.324 m passes: the command's other
    tests)."""
    proc = run_cli("selfcal", "--sim", "--robot-width", "0.6", "--out", str(tmp_path / "out"))
    assert proc.returncode == 2, proc.stderr
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith(
        "umbmark: error: something stands on the squares' path at x = -0.35 m, y = -1.2"
    ), last
    assert "in the band a 0.6 m wide robot sweeps on the 4 m squares" in last
    assert not (tmp_path / "out").exists()

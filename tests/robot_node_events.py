"""What happens to the simulated robot nodes' robot mid-run (tests/ros1_robot_node.py,
tests/ros2_robot_node.py), and the world it drives in: their options and the truth.

- ``--world warehouse``: the fleet's warehouse (:func:`umbmark.robot.warehouse.warehouse_world`
  of :class:`umbmark.sim.missions.Warehouse`, its aisles 6 m and 3.5 m apart, racks
  between them), the robot at its first crossing (0, 0) heading along +x, its laser the
  fleet's (360 beams, 12 m) at ``--laser-x``; ``corner`` (the default): the corner world
  as before. tests/mission_driver.py drives the warehouse's missions.
- A wheel changed (a tyre changed): the right wheel's true diameter times
  ``1 + --wheel-change`` (so the true ``E_d = D_R / D_L`` times that, ``E_s`` moving by
  half of it), at ``--change-wheel-at T`` [s of simulated time since the start] or when
  ``change_wheel`` comes on ``/sim/control``;
- the laser knocked: its true mounting's yaw turned by ``--knock-yaw`` [deg] (and moved
  ``--knock-x`` [m] forward), at ``--knock-laser-at T`` or on ``knock_laser``; the mounting
  the robot states (``/tf_static``, its URDF) is kept, as a knock leaves it;
- ``mute_scan`` / ``unmute_scan`` on ``/sim/control``: the laser's driver silent, and
  speaking again (the clock and the rest go on);
- ``--joint-states``: ``sensor_msgs/JointState`` on ``/joint_states`` every period, the
  wheels' encoder angles (``left_wheel_joint``, ``right_wheel_joint``), as
  joint_state_broadcaster publishes them (:func:`joint_state_values`).

``--truth FILE`` (JSON, rewritten by a rename at each event): the robot's truth at the
start (``E_d``, ``E_b``, ``E_s``, the laser's true and stated mountings ``x, y, yaw``
[m, m, rad]), ``T0`` (the ROS time of the simulation's start [s]) and every event so far,
each its ``kind`` (``wheel``, ``laser``), its ROS ``time`` [s], the robot's true travel
``metres`` [m, the axle centre's path] and its truth ``before`` and ``after``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
from dataclasses import replace
from pathlib import Path
from typing import Any

from umbmark.robot.base import Pose2D
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import Lidar, World, corner_world

#: The controls of /sim/control that are events, and those that mute the laser.
EVENTS = ("change_wheel", "knock_laser")
SCAN_CONTROLS = ("mute_scan", "unmute_scan")


def event_arguments(parser: argparse.ArgumentParser) -> None:
    """The world's and the events' options."""
    parser.add_argument(
        "--world",
        choices=("corner", "warehouse"),
        default="corner",
        help="corner: the corner world; warehouse: the fleet's warehouse",
    )
    parser.add_argument(
        "--change-wheel-at",
        type=float,
        default=None,
        help="simulated seconds after the start: the right wheel changed",
    )
    parser.add_argument(
        "--wheel-change",
        type=float,
        default=0.006,
        help="the new right wheel's diameter over the old one, less 1",
    )
    parser.add_argument(
        "--knock-laser-at",
        type=float,
        default=None,
        help="simulated seconds after the start: the laser knocked",
    )
    parser.add_argument("--knock-yaw", type=float, default=2.0, help="the knock's turn [deg]")
    parser.add_argument("--knock-x", type=float, default=0.0, help="the knock's shift [m]")
    parser.add_argument("--truth", default=None, help="write the robot's truth here (JSON)")
    parser.add_argument(
        "--joint-states",
        action="store_true",
        help="publish the wheels' angles on /joint_states every period",
    )


def node_world(args: argparse.Namespace, corner: World | None = None) -> tuple[World, Lidar]:
    """The world of ``--world`` (``corner``: ``corner`` or the corner world) and the
    laser at ``--laser-x`` (the world's own beams)."""
    if args.world == "warehouse":
        from umbmark.robot.warehouse import FLEET_LIDAR, warehouse_world
        from umbmark.sim.missions import Warehouse

        warehouse = Warehouse()
        lidar = replace(FLEET_LIDAR, mount=Pose2D(args.laser_x, 0.0, 0.0))
        world = replace(warehouse_world(warehouse), start=Pose2D(*warehouse.start(0)))
        return replace(world, lidar=lidar), lidar
    world = corner or corner_world()
    return world, Lidar(mount=Pose2D(args.laser_x, 0.0, 0.0))


def _errors(robot: VirtualRobot) -> dict[str, float]:
    truth = robot.truth
    b = truth.wheelbase / truth.odometry.wheelbase
    return {"E_d": truth.E_d, "E_b": b, "E_s": truth.E_s}


def _mount(pose: Pose2D) -> dict[str, float]:
    return {"x": pose.x, "y": pose.y, "yaw": pose.theta}


class Events:
    """The events of the options and of /sim/control, made on the node's robot (call
    :meth:`step` after each simulated period, under the node's lock)."""

    def __init__(
        self, args: argparse.Namespace, robot: VirtualRobot, stated: tuple[float, float, float],
        t0: float,
    ) -> None:  # fmt: skip
        self.args, self.robot, self.t0 = args, robot, t0
        self.mute_scan = False
        self._asked: list[str] = []
        self._done: set[str] = set()
        self._travel = 0.0
        self._last = robot.true_pose
        lidar = robot.world.lidar
        self.truth: dict[str, Any] = {
            "T0": t0,
            "start": {
                **_errors(robot),
                "laser": None if lidar is None else _mount(lidar.mount),
                "stated_laser": dict(zip(("x", "y", "yaw"), stated, strict=True)),
            },
            "events": [],
        }
        self._write()

    def control(self, command: str) -> None:
        """A ``/sim/control`` message (others are not these)."""
        if command in SCAN_CONTROLS:
            self.mute_scan = command == "mute_scan"
        elif command in EVENTS:
            self._asked.append(command)

    def step(self) -> None:
        """After a period: the travel counted, the events due made."""
        pose = self.robot.true_pose
        self._travel += math.hypot(pose.x - self._last.x, pose.y - self._last.y)
        self._last = pose
        t = self.robot.now()
        args = self.args
        for kind, at in (("change_wheel", args.change_wheel_at),
                         ("knock_laser", args.knock_laser_at)):  # fmt: skip
            if at is not None and t >= at and kind not in self._done:
                self._asked.append(kind)
                self._done.add(kind)
        while self._asked:
            kind = self._asked.pop(0)
            if kind == "change_wheel":
                self._wheel()
            else:
                self._knock()

    def _wheel(self) -> None:
        robot = self.robot
        before = _errors(robot)
        truth = robot.truth
        robot.truth = replace(
            truth, diameter_right=truth.diameter_right * (1.0 + self.args.wheel_change)
        )
        self._said("wheel", before, _errors(robot))

    def _knock(self) -> None:
        robot = self.robot
        lidar = robot.world.lidar
        if lidar is None:
            return
        m = lidar.mount
        theta = math.radians(self.args.knock_yaw)
        knocked = Pose2D(m.x + self.args.knock_x, m.y, m.theta + theta)
        robot.world = replace(robot.world, lidar=replace(lidar, mount=knocked))
        self._said("laser", _mount(m), _mount(knocked))

    def _said(self, kind: str, before: dict[str, float], after: dict[str, float]) -> None:
        self.truth["events"].append({
            "kind": kind, "time": self.t0 + self.robot.now(), "metres": self._travel,
            "before": before, "after": after,
        })  # fmt: skip
        print(f"event {kind} at {self.robot.now():.2f} s", flush=True)
        self._write()

    def _write(self) -> None:
        path = self.args.truth
        if not path:
            return
        temporary = Path(f"{path}.part")
        temporary.write_text(json.dumps(self.truth), encoding="utf-8")
        os.replace(temporary, path)


def joint_state_values(robot: VirtualRobot) -> tuple[list[str], list[float]]:
    """The joint names and positions [rad] of a ``/joint_states`` message now."""
    _, left, right = robot.wheel_angles()
    return ["left_wheel_joint", "right_wheel_joint"], [left, right]

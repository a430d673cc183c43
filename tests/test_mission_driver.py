"""tests/mission_driver.py's follower without ROS: it drives a virtual robot (E_d 1.004,
E_b 0.97, wheel slip) in the fleet's warehouse on its missions, localised as the driver
is (the odometry carried by the true pose at 10 Hz): ordinary missions, not squares
(straights of several lengths, turns both ways), on the aisles, clear of every rack and
wall."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from mission_driver import Follower, Localised
from umbmark.robot.base import Pose2D
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.warehouse import warehouse_world
from umbmark.sim.missions import Warehouse


def test_the_follower_drives_missions_on_the_aisles() -> None:
    warehouse = Warehouse()
    world = replace(warehouse_world(warehouse), start=Pose2D(*warehouse.start(0)), lidar=None)
    robot = VirtualRobot(E_d=1.004, E_b=0.97, slip=0.0004, seed=1, world=world)
    follower, where = Follower(warehouse, seed=2), Localised()
    path, turns = [], []
    for step in range(int(150.0 / robot.period)):
        where.odometry(robot.odometry().pose)
        if step % 5 == 0:  # the laser's rate: the localisation's
            where.true_pose(robot.true_pose)
            path.append((robot.true_pose.x, robot.true_pose.y))
        pose = where.pose()
        if step % 3 == 0 and pose is not None:
            linear, angular = follower.command(pose, robot.now())
            robot.send_velocity(linear, angular)
            if linear == 0.0 and abs(angular) > 0.3:
                turns.append(math.copysign(1.0, angular))
        robot.wait(robot.period)
    p = np.asarray(path)
    xs, ys = np.asarray(warehouse.aisles_x), np.asarray(warehouse.aisles_y)
    off = np.minimum(np.abs(p[:, :1] - xs).min(axis=1), np.abs(p[:, 1:] - ys).min(axis=1))
    assert off.max() < 0.05  # on an aisle's centre line, whatever the odometry's errors
    assert world.clearance(p) > 0.9  # posts 1.01 m from the centre line, the robot 0.3 m
    assert follower.done >= 10
    assert {1.0, -1.0} <= set(turns)  # turned both ways: not a square
    travelled = float(np.sum(np.hypot(*np.diff(p, axis=0).T)))
    assert travelled > 40.0

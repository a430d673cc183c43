"""A warehouse for a simulated fleet: walls around the aisles of a
:class:`~umbmark.sim.missions.Warehouse`, racks of shelves between the aisles (each an
outline with posts, so that a laser sees structure in every direction), and a pillar
here and there; the robot's laser at its (possibly knocked) mounting.
"""

from __future__ import annotations

import itertools

import numpy as np

from umbmark.robot.base import Pose2D
from umbmark.robot.world import SCAN_LIDAR, Lidar, World, box
from umbmark.sim.missions import Warehouse

__all__ = ["FLEET_LIDAR", "warehouse_world"]

#: The fleet's laser: as the scan bags' (360 beams, 1 cm noise, 12 m), 0.1 m ahead.
FLEET_LIDAR = SCAN_LIDAR
#: Half the free width of an aisle [m]: racks stand this far from its centre line.
AISLE_HALF_WIDTH = 1.1
#: How far the walls stand beyond the outer aisles [m].
WALL_MARGIN = 2.0


def warehouse_world(warehouse: Warehouse, mount: Pose2D | None = None) -> World:
    """The world of ``warehouse``, its laser mounted at ``mount`` [default: the fleet
    laser's mounting, 0.1 m ahead of the axle centre].

    Racks fill each block between two aisles each way, leaving :data:`AISLE_HALF_WIDTH`
    on either side of every aisle's centre line; a block too small for a rack stays empty.
    """
    x0, y0, x1, y1 = warehouse.bounds
    m = WALL_MARGIN
    walls = [
        [x0 - m, y0 - m, x1 + m, y0 - m],
        [x1 + m, y0 - m, x1 + m, y1 + m],
        [x1 + m, y1 + m, x0 - m, y1 + m],
        [x0 - m, y1 + m, x0 - m, y0 - m],
    ]
    parts = [np.asarray(walls, dtype=np.float64)]
    circles = []
    xs, ys = warehouse.aisles_x, warehouse.aisles_y
    for a, b in itertools.pairwise(xs):
        for c, d in itertools.pairwise(ys):
            width, depth = (b - a) - 2 * AISLE_HALF_WIDTH, (d - c) - 2 * AISLE_HALF_WIDTH
            if width <= 0.2 or depth <= 0.2:
                continue
            cx, cy = 0.5 * (a + b), 0.5 * (c + d)
            parts.append(box(cx, cy, width, depth))
            for sx in (-0.5, 0.0, 0.5):  # posts along the rack's long sides
                for sy in (-0.5, 0.5):
                    circles.append((cx + sx * width, cy + sy * (depth + 0.1), 0.04))
    circles.append((x0 - 0.8 * m, y1 + 0.5 * m, 0.25))  # pillars off the corners
    circles.append((x1 + 0.6 * m, y0 - 0.4 * m, 0.2))
    lidar = FLEET_LIDAR if mount is None else _mounted(mount)
    return World.build(np.vstack(parts), np.asarray(circles), lidar=lidar)


def _mounted(mount: Pose2D) -> Lidar:
    from dataclasses import replace

    return replace(FLEET_LIDAR, mount=mount)

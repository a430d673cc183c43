"""One entry to a robot: the virtual one, a ROS 1 robot or a ROS 2 robot."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Literal

from umbmark.core.errors import InputError, option
from umbmark.robot.base import Robot
from umbmark.robot.ros_common import RosOptions

if TYPE_CHECKING:
    from umbmark.sim.imu import ImuSetup

__all__ = ["BACKENDS", "Backend", "connect"]

Backend = Literal["sim", "ros1", "ros2"]
BACKENDS: tuple[Backend, ...] = ("sim", "ros1", "ros2")


def connect(
    backend: Backend,
    *,
    E_d: float = 1.0,
    E_b: float = 1.0,
    E_s: float = 1.0,
    slip: float = 0.0004,
    seed: int | None = None,
    ros: RosOptions | None = None,
    room: bool = False,
    corner_side: Literal["auto", "right", "left"] = "right",
    imu: ImuSetup | None = None,
    laser: bool = True,
) -> Robot:
    """The robot to calibrate.

    ``sim``: a :class:`~umbmark.robot.virtual.VirtualRobot` (LabMate-sized, 4 m squares'
    room, the corner behind the start on ``corner_side``) with errors ``E_d``, ``E_b``,
    ``E_s`` and wheel slip ``slip`` [m^(1/2)], the IMU ``imu`` (None: none) and a laser
    (``laser`` False: none); ``ros1`` / ``ros2``: the robot behind the topics and
    controller of ``ros`` (its IMU: ``ros.imu``). ``room``: the virtual robot stands in an
    ordinary room (:func:`umbmark.robot.world.room_world`) with its laser off its centre
    (:data:`umbmark.robot.world.ROOM_LASER`), for the routine that calibrates anywhere;
    else at the corner of the UMBmark routine.

    Raises
    ------
    InputError
        Bad errors, or a ROS robot that cannot be reached (with the reason).
    """
    if backend == "sim":
        from umbmark.robot.virtual import ERROR_RANGE, MAX_SLIP, VirtualRobot
        from umbmark.robot.world import corner_world

        low, high = ERROR_RANGE
        for name, value in (("E_d", E_d), ("E_b", E_b), ("E_s", E_s)):
            if not (low <= value <= high):
                raise InputError(f"{option(name, repr(value))}: give {low:g} to {high:g}")
        if not (0.0 <= slip <= MAX_SLIP):
            raise InputError(f"{option('slip', repr(slip), 'm^0.5')}: give 0 to {MAX_SLIP:g}")
        if room:
            from umbmark.robot.world import ROOM_LASER, room_world

            world, pose = room_world(), (ROOM_LASER.x, ROOM_LASER.y, ROOM_LASER.theta)
        else:
            world, pose = corner_world(side="left" if corner_side == "left" else "right"), None
        if not laser:
            world, pose = replace(world, lidar=None), None
        return VirtualRobot(E_d, E_b, E_s, slip=slip, seed=seed, world=world, laser_pose=pose,
                            imu=imu)  # fmt: skip
    if backend == "ros1":
        from umbmark.robot.ros1 import Ros1Robot

        return Ros1Robot(ros or RosOptions())
    if backend == "ros2":
        from umbmark.robot.ros2 import Ros2Robot

        return Ros2Robot(ros or RosOptions())
    raise InputError(f"robot {backend!r}: use one of {', '.join(BACKENDS)}")

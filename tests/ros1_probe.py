"""Drives :class:`umbmark.robot.ros1.Ros1Robot` against the simulated node and prints what
it observed as one JSON object (for tests/test_ros1.py, which makes the assertions).

It runs as a subprocess because rospy keeps a node and its threads for the rest of the
process, and its own code warns (``notifyAll``, unclosed sockets) from those threads at
any time: in pytest's process, with warnings as errors, that would break later tests.

Usage: ``python ros1_probe.py CHECK [PARAMS_FILE]`` with ``ROS_MASTER_URI`` set; CHECK is
one of ``read``, ``reconfigure``, ``outside``, ``stale``, ``held``, ``watch``, ``imu``
(:func:`robot_node_imu.imu_probe`; ``imu --no-imu``: the adapter told to use none),
``coarse-fault FAULT`` (the coarse turning check, the IMU failing: :func:`coarse_fault`).
"""

from __future__ import annotations

import json
import sys
import threading
import time
from typing import Any

import numpy as np
import rospy
from geometry_msgs.msg import Pose2D as Pose2DMsg
from geometry_msgs.msg import Twist
from std_msgs.msg import String

from umbmark.core.conventions import Direction
from umbmark.core.errors import SafetyError
from umbmark.robot.base import DriveParams
from umbmark.robot.ros1 import Ros1Robot
from umbmark.robot.ros_common import RosOptions
from umbmark.routines.drive import DriveLimits, drive_square


def _true_pose() -> list[float]:
    msg = rospy.wait_for_message("/sim/true_pose", Pose2DMsg, timeout=10.0)
    return [float(msg.x), float(msg.y), float(msg.theta)]


def _params(p: DriveParams) -> list[float]:
    return [
        p.wheel_separation,
        p.wheel_radius,
        p.wheel_separation_multiplier,
        p.left_wheel_radius_multiplier,
        p.right_wheel_radius_multiplier,
    ]


def read(robot: Ros1Robot) -> dict[str, Any]:
    start = robot.now()
    wall = time.monotonic()
    robot.wait(2.0)
    wall = time.monotonic() - wall
    now = robot.now()
    odom, scan = robot.odometry(), robot.scan()
    assert odom is not None
    assert scan is not None
    true = _true_pose()
    beam = scan.angles() + scan.mount.theta + true[2]  # in the world
    ahead = np.abs(beam) < np.radians(1.0)
    ranges = scan.ranges[ahead]
    return {
        "start": start,
        "now": now,
        "wall": wall,
        "odom_time": odom.time,
        "scan_time": scan.time,
        "mount": [scan.mount.x, scan.mount.y, scan.mount.theta],
        "true": true,
        "ahead": float(np.median(ranges[np.isfinite(ranges)])),
        "params": _params(robot.drive_params()),
        "footprint": robot.footprint(),
    }


def apply(robot: Ros1Robot, separation: float, left: float, right: float) -> dict[str, Any]:
    from dynamic_reconfigure.client import Client

    before = robot.drive_params()
    new = DriveParams(before.wheel_separation, before.wheel_radius, separation, left, right)
    result = robot.apply(new, "reconfigure")
    client = Client("/diff_drive_controller", timeout=10.0)
    held = client.get_configuration(timeout=10.0)
    client.close()
    return {
        "method": result.method,
        "active": result.active,
        "message": result.message,
        "file": result.file,
        "before": _params(before),
        "after": _params(robot.drive_params()),
        "held": {k: v for k, v in held.items() if k.endswith("multiplier")},
    }


def coarse_fault(robot: Ros1Robot, fault: str) -> dict[str, Any]:
    """The coarse turning check, the node's IMU told to ``fault`` (``mute_imu``,
    ``freeze_imu``) a wall second in (its first rest or turn), mended after."""
    from umbmark.routines.coarse import coarse_turning
    from umbmark.routines.measure import Measure

    control = rospy.Publisher("/sim/control", String, queue_size=1, latch=True)
    time.sleep(0.5)  # connections
    timer = threading.Timer(1.0, control.publish, [String(fault)])
    timer.start()
    try:
        check = coarse_turning(robot, Measure("lidar"), DriveLimits())
    finally:
        timer.join()
        control.publish(String("mend_imu"))
        time.sleep(0.3)
    return check.to_dict()


def stale(robot: Ros1Robot) -> dict[str, Any]:
    heard: list[Any] = []
    sub = rospy.Subscriber("/cmd_vel", Twist, heard.append, tcp_nodelay=True)
    control = rospy.Publisher("/sim/control", String, queue_size=1, latch=True)
    time.sleep(0.5)  # connections
    # mute the odometry once the robot drives (1 wall second: 8 s into the square)
    threading.Timer(1.0, control.publish, [String("mute_odom")]).start()
    error = ""
    try:
        drive_square(robot, 1.0, Direction.CCW, DriveLimits())
    except SafetyError as exc:
        error = str(exc)
    time.sleep(0.3)
    moving = sum(1 for m in heard if abs(m.linear.x) + abs(m.angular.z) > 0.05)
    last = heard[-1] if heard else None
    control.publish(String("unmute_odom"))
    robot.wait(0.3)
    odom = robot.odometry()
    assert odom is not None
    sub.unregister()
    return {
        "error": error,
        "moving_commands": moving,
        "heard": len(heard),
        "last": None if last is None else [last.linear.x, last.angular.z],
        "odom_age_after": robot.now() - odom.time,
    }


def watch() -> dict[str, Any]:
    """Print ``moving`` at the first non-zero /cmd_vel; at the end of stdin, the last
    command heard and the true pose twice, half a wall second apart."""
    rospy.init_node("watch", anonymous=True, disable_signals=True)
    heard: list[Any] = []
    rospy.Subscriber("/cmd_vel", Twist, heard.append, tcp_nodelay=True)
    while not any(abs(m.linear.x) + abs(m.angular.z) > 0.05 for m in list(heard)):
        time.sleep(0.01)
    print("moving", flush=True)
    sys.stdin.read()
    time.sleep(0.3)
    a = _true_pose()
    time.sleep(0.5)
    b = _true_pose()
    return {"last": [heard[-1].linear.x, heard[-1].angular.z], "pose_a": a, "pose_b": b}


def main() -> None:
    check = sys.argv[1]
    if check == "watch":
        out = watch()
    elif check == "held":
        rospy.init_node("held", anonymous=True, disable_signals=True)
        from dynamic_reconfigure.client import Client

        held = Client("/diff_drive_controller", timeout=10).get_configuration(timeout=10)
        out = {k: v for k, v in held.items() if k.endswith("multiplier")}
    elif check == "coarse-fault":
        robot = Ros1Robot(RosOptions(timeout=10.0))
        try:
            out = coarse_fault(robot, sys.argv[2])
        finally:
            robot.close()
    elif check == "imu":
        from robot_node_imu import imu_probe

        given = None if "--no-imu" in sys.argv[2:] else ""
        robot = Ros1Robot(RosOptions(timeout=10.0, imu=given))
        try:
            out = imu_probe(robot, lambda: _true_pose()[2])
        finally:
            robot.close()
    else:
        params_file = sys.argv[2] if len(sys.argv) > 2 else None
        robot = Ros1Robot(RosOptions(params_file=params_file, timeout=10.0))
        try:
            if check == "read":
                out = read(robot)
            elif check == "reconfigure":
                out = apply(robot, 0.97, 0.998, 1.002)
            elif check == "outside":
                out = apply(robot, 1.6, 0.9, 1.1)
            elif check == "stale":
                out = stale(robot)
            else:
                raise SystemExit(f"unknown check {check!r}")
        finally:
            robot.close()
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()

"""Drives a :class:`umbmark.robot.ros2.Ros2Robot` against tests/ros2_robot_node.py and prints
what it observed as one JSON line (for tests/test_ros2.py and benchmarks/bench_ros2.py).
Run it with the ROS 2 wheels' Python (``.venv-ros2``) and the node's ROS_DOMAIN_ID.

- ``read``: sim time, the odometry's and scan's stamps, the laser's mounting, the controller's
  parameters, the velocity type found on the graph;
- ``drive SECONDS``: the 50 Hz drive loop (a velocity each period of sim time) at 0.2 m/s
  for SECONDS of sim time: loops per sim second and per wall second, the odometry's travel;
- ``plan [--reload]``: what ``can_apply`` and ``apply_note`` say (which way applying goes);
- ``watch``: subscribes the velocity topic (TwistStamped) and prints ``moving`` at the first
  non-zero command; when stdin closes, the last command and two true poses 0.3 s apart.
"""

from __future__ import annotations

import json
import math
import sys
import threading
import time

from umbmark.robot.ros2 import Ros2Robot
from umbmark.robot.ros_common import RosOptions


def msg_frame(robot: Ros2Robot) -> str:
    """The frame of the latest scan message."""
    msg = robot._scan.get()
    assert msg is not None
    return str(msg.header.frame_id)


def read() -> dict[str, object]:
    robot = Ros2Robot(RosOptions(timeout=10.0))
    try:
        start = robot.now()
        robot.wait(0.5)
        waited = robot.now()
        scan = None
        deadline = time.monotonic() + 10.0
        while scan is None and time.monotonic() < deadline:
            scan = robot.scan()
            robot.wait(0.02)
        odom, now = robot.odometry(), robot.now()
        assert odom is not None
        assert scan is not None
        params = robot.drive_params()
        return {
            "start": start,
            "waited": waited,
            "now": now,
            "odom_time": odom.time,
            "scan_time": scan.time,
            "mount": [scan.mount.x, scan.mount.y, scan.mount.theta],
            "upside_down": robot._mount(msg_frame(robot)).upside_down,
            "stamped": robot._stamped,
            "params": [params.wheel_separation, params.wheel_radius],
        }
    finally:
        robot.close()


def drive(seconds: float) -> dict[str, object]:
    robot = Ros2Robot(RosOptions(timeout=10.0))
    try:
        robot.wait(0.5)  # both ends of the new velocity topic matched (DDS discovery)
        first = robot.odometry()
        assert first is not None
        loops, t0, wall0 = 0, robot.now(), time.monotonic()
        while robot.now() - t0 < seconds:
            robot.send_velocity(0.2, 0.0)
            robot.wait(0.02)
            loops += 1
        robot.send_velocity(0.0, 0.0)
        stop = robot.now()
        sim, wall = stop - t0, time.monotonic() - wall0
        last = robot.odometry()
        deadline = time.monotonic() + 20.0
        while last is None or last.time < stop + 0.5:  # stopped, as its odometry says
            assert time.monotonic() < deadline, "no odometry after the stop"
            robot.wait(0.05)
            last = robot.odometry()
        return {
            "loops_per_sim_second": loops / sim,
            "loops_per_wall_second": loops / wall,
            "sim_per_wall": sim / wall,
            "sim": sim,
            "travel": math.hypot(last.pose.x - first.pose.x, last.pose.y - first.pose.y),
        }
    finally:
        robot.close()


def watch() -> dict[str, object]:
    import rclpy
    from geometry_msgs.msg import PoseStamped, TwistStamped

    rclpy.init()
    node = rclpy.create_node("umbmark_watch")
    last: list[list[float]] = []
    truth: list[list[float]] = []
    moving = threading.Event()

    def on_cmd(msg: TwistStamped) -> None:
        v = [msg.twist.linear.x, msg.twist.angular.z]
        last[:] = [v]
        if (v[0] or v[1]) and not moving.is_set():
            moving.set()
            print("moving", flush=True)

    def on_truth(msg: PoseStamped) -> None:
        truth[:] = [[msg.pose.position.x, msg.pose.position.y]]

    node.create_subscription(TwistStamped, "/diff_drive_controller/cmd_vel", on_cmd, 10)
    node.create_subscription(PoseStamped, "/ground_truth", on_truth, 10)
    spin = threading.Thread(target=rclpy.spin, args=(node,), daemon=True)
    spin.start()
    sys.stdin.read()  # until the test closes it
    deadline = time.monotonic() + 10.0  # a loaded machine: the first truth may come late
    while not truth and time.monotonic() < deadline:
        time.sleep(0.05)
    a = list(truth[0]) if truth else None
    time.sleep(0.3)
    b = list(truth[0]) if truth else None
    out = {"last": last[0] if last else None, "pose_a": a, "pose_b": b}
    rclpy.try_shutdown()
    spin.join(2.0)
    return out


def plan(reload: bool) -> dict[str, object]:
    robot = Ros2Robot(RosOptions(timeout=10.0, reload=reload))
    try:
        return {"can_apply": robot.can_apply(), "note": robot.apply_note()}
    finally:
        robot.close()


def main() -> None:
    what = sys.argv[1]
    if what == "read":
        out = read()
    elif what == "drive":
        out = drive(float(sys.argv[2]))
    elif what == "watch":
        out = watch()
    elif what == "plan":
        out = plan("--reload" in sys.argv[2:])
    else:
        raise SystemExit(f"unknown probe {what!r}")
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()

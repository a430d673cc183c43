"""Drives a :class:`umbmark.robot.ros2.Ros2Robot` against tests/ros2_robot_node.py and prints
what it observed as one JSON line (for tests/test_ros2.py and benchmarks/bench_ros2.py).
Run it with the ROS 2 wheels' Python (``.venv-ros2``) and the node's ROS_DOMAIN_ID.

- ``read``: sim time, the odometry's and scan's stamps, the laser's mounting, the controller's
  parameters, the velocity topic and type found on the graph;
- ``drive SECONDS``: the 50 Hz drive loop (a velocity each period of sim time) at 0.2 m/s
  for SECONDS of sim time: loops per sim second and per wall second, the odometry's travel;
- ``plan [--reload]``: what ``can_apply`` and ``apply_note`` say (which way applying goes);
- ``watch``: subscribes the velocity topic (TwistStamped) and prints ``moving`` at the first
  non-zero command; when stdin closes, the last command and two true poses 0.3 s apart;
- ``graph``: the subscribers of the controller's two velocity topics (node, type);
- ``lifecycle``: the subscribers of the controller's two velocity topics (node, type) on the
  graph, active as the node starts, then after each call to the controller manager:
  deactivate, cleanup, configure, activate (1 s of discovery after each);
- ``imu [TOPIC]``: the IMU found on the graph (or TOPIC), its mounting and readings over
  a turn (:func:`robot_node_imu.imu_probe`).
"""

from __future__ import annotations

import json
import math
import sys
import threading
import time
from typing import Any

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
            "cmd_vel": robot.options.cmd_vel,
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


#: The controller's two velocity topics (Humble's unstamped one, and ~/cmd_vel).
VELOCITY_TOPICS = ("/diff_drive_controller/cmd_vel_unstamped", "/diff_drive_controller/cmd_vel")


def _discovered(node: Any) -> None:
    """Wait (up to 30 s) until the controller's node is discovered: its odometry publisher
    is seen (its other endpoints come with it)."""
    deadline = time.monotonic() + 30.0
    while node.count_publishers("/diff_drive_controller/odom") == 0:
        assert time.monotonic() < deadline, "the controller's node was not discovered"
        time.sleep(0.05)


def _graph(node: Any) -> dict[str, list[str]]:
    """Each velocity topic's subscribers, as ``NODE TYPE``, after 1 s of discovery (on one
    machine, endpoints come and go within it)."""
    time.sleep(1.0)
    return {
        topic: sorted(
            f"{i.node_namespace.rstrip('/')}/{i.node_name} {i.topic_type}"
            for i in node.get_subscriptions_info_by_topic(topic)
        )
        for topic in VELOCITY_TOPICS
    }


def graph() -> dict[str, object]:
    import rclpy

    rclpy.init()
    node = rclpy.create_node("umbmark_graph")
    try:
        _discovered(node)
        return dict(_graph(node))
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def lifecycle() -> dict[str, object]:
    import rclpy
    from controller_manager_msgs.srv import CleanupController, ConfigureController, SwitchController

    rclpy.init()
    node = rclpy.create_node("umbmark_lifecycle")
    spin = threading.Thread(target=rclpy.spin, args=(node,), daemon=True)
    spin.start()

    def graph() -> dict[str, list[str]]:
        return _graph(node)

    def call(kind: Any, name: str, request: Any) -> bool:
        client = node.create_client(kind, f"/controller_manager/{name}")
        assert client.wait_for_service(timeout_sec=20.0), name
        future = client.call_async(request)
        deadline = time.monotonic() + 20.0
        while not future.done():
            assert time.monotonic() < deadline, f"{name} did not answer"
            time.sleep(0.01)
        return bool(future.result().ok)

    def switch(activate: list[str], deactivate: list[str]) -> bool:
        request = SwitchController.Request()
        request.activate_controllers, request.deactivate_controllers = activate, deactivate
        request.strictness = SwitchController.Request.STRICT
        return call(SwitchController, "switch_controller", request)

    name = "diff_drive_controller"
    _discovered(node)
    out: dict[str, object] = {"active": graph()}
    out["deactivate"] = [switch([], [name]), graph()]
    out["cleanup"] = [call(CleanupController, "cleanup_controller",
                           CleanupController.Request(name=name)), graph()]  # fmt: skip
    out["configure"] = [call(ConfigureController, "configure_controller",
                             ConfigureController.Request(name=name)), graph()]  # fmt: skip
    out["activate"] = [switch([name], []), graph()]
    node.destroy_node()
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
    elif what == "graph":
        out = graph()
    elif what == "lifecycle":
        out = lifecycle()
    elif what == "plan":
        out = plan("--reload" in sys.argv[2:])
    elif what == "imu":
        from robot_node_imu import imu_probe

        given = sys.argv[2] if len(sys.argv) > 2 else ""
        robot = Ros2Robot(RosOptions(timeout=10.0, truth="/ground_truth", imu=given))

        def heading() -> float:  # the node's /ground_truth is its true pose
            truth = robot.ground_truth()
            assert truth is not None
            return truth.pose.theta

        try:
            out = imu_probe(robot, heading)
        finally:
            robot.close()
    else:
        raise SystemExit(f"unknown probe {what!r}")
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()

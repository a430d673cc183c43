"""Reads ``/diagnostics`` as the statuses arrive and prints each as one JSON line (for
tests/monitor_graph.py, which collects them; ROS 1 and ROS 2 alike):

``python tests/diagnostics_probe.py --ros1|--ros2 [--odom TOPIC]``

- each ``diagnostic_msgs/DiagnosticArray``'s statuses: ``{"kind": "status", "wall": s
  (time.monotonic() when it came), "stamp": s (the array's header, ROS time), "name",
  "level" (0 to 3; ROS 2's byte as an integer), "message", "hardware_id", "values": {key:
  value}}``;
- with ``--odom TOPIC``, ``nav_msgs/Odometry`` there, one a second of its stamps at most:
  ``{"kind": "odom", "stamp", "frame", "child", "x", "y", "yaw", "pose_covariance"}``;
- a line ``control WORD`` on stdin publishes WORD on ``/sim/control`` (``std_msgs/String``:
  the robot nodes' controls); stdin closed, SIGINT or SIGTERM: it ends.

Prints ``ready`` once subscribed. As tests/ros1_probe.py and tests/ros2_probe.py, it runs
as a subprocess: rospy and rclpy keep their threads for the rest of a process.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

_out = threading.Lock()


def _say(row: dict[str, Any]) -> None:
    with _out:
        print(json.dumps(row), flush=True)


def status_row(status: Any, stamp: float) -> dict[str, Any]:
    """One ``DiagnosticStatus`` as its JSON line."""
    level = status.level
    level = level[0] if isinstance(level, (bytes, bytearray)) else int(level)
    return {
        "kind": "status", "wall": time.monotonic(), "stamp": stamp, "name": status.name,
        "level": level, "message": status.message, "hardware_id": status.hardware_id,
        "values": {kv.key: kv.value for kv in status.values},
    }  # fmt: skip


def odom_row(msg: Any, stamp: float) -> dict[str, Any]:
    """A ``nav_msgs/Odometry`` as its JSON line."""
    p, q = msg.pose.pose.position, msg.pose.pose.orientation
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    return {
        "kind": "odom", "wall": time.monotonic(), "stamp": stamp, "frame": msg.header.frame_id,
        "child": msg.child_frame_id, "x": p.x, "y": p.y, "yaw": yaw,
        "pose_covariance": [float(v) for v in msg.pose.covariance],
    }  # fmt: skip


class Thinned:
    """At most one call a second of stamps."""

    def __init__(self, say: Callable[[Any, float], None]) -> None:
        self.say, self.last = say, -math.inf

    def __call__(self, msg: Any, stamp: float) -> None:
        if stamp - self.last >= 1.0:
            self.last = stamp
            self.say(msg, stamp)


def _commands(publish: Callable[[str], None], stop: threading.Event) -> None:
    for line in sys.stdin:
        word = line.strip()
        if word.startswith("control "):
            publish(word.split(" ", 1)[1])
    stop.set()


def ros1(args: argparse.Namespace, stop: threading.Event) -> None:
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    from nav_msgs.msg import Odometry
    from std_msgs.msg import String

    rospy.init_node("diagnostics_probe", anonymous=True, disable_signals=True)

    def on_array(msg: DiagnosticArray) -> None:
        for status in msg.status:
            _say(status_row(status, msg.header.stamp.to_sec()))

    rospy.Subscriber("/diagnostics", DiagnosticArray, on_array, queue_size=50)
    if args.odom:
        odom = Thinned(lambda m, s: _say(odom_row(m, s)))
        rospy.Subscriber(args.odom, Odometry, lambda m: odom(m, m.header.stamp.to_sec()),
                         queue_size=10)  # fmt: skip
    control = rospy.Publisher("/sim/control", String, queue_size=10)
    reader = threading.Thread(target=_commands, args=(lambda w: control.publish(String(w)), stop),
                              daemon=True)  # fmt: skip
    reader.start()
    _say({"kind": "ready"})
    stop.wait()
    rospy.signal_shutdown("done")


def ros2(args: argparse.Namespace, stop: threading.Event) -> None:
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions
    from std_msgs.msg import String

    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("diagnostics_probe")

    def seconds(s: Any) -> float:
        return float(s.sec) + 1e-9 * float(s.nanosec)

    def on_array(msg: DiagnosticArray) -> None:
        for status in msg.status:
            _say(status_row(status, seconds(msg.header.stamp)))

    node.create_subscription(DiagnosticArray, "/diagnostics", on_array, 50)
    if args.odom:
        odom = Thinned(lambda m, s: _say(odom_row(m, s)))
        node.create_subscription(Odometry, args.odom,
                                 lambda m: odom(m, seconds(m.header.stamp)), 10)  # fmt: skip
    control = node.create_publisher(String, "/sim/control", 10)
    reader = threading.Thread(
        target=_commands, args=(lambda w: control.publish(String(data=w)), stop), daemon=True
    )
    reader.start()
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    _say({"kind": "ready"})
    try:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    side = parser.add_mutually_exclusive_group(required=True)
    side.add_argument("--ros1", action="store_true")
    side.add_argument("--ros2", action="store_true")
    parser.add_argument("--odom", default=None, help="an Odometry topic to report too")
    args = parser.parse_args()
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    (ros1 if args.ros1 else ros2)(args, stop)


if __name__ == "__main__":
    main()

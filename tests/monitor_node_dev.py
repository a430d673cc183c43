"""The monitor's ROS 2 node with the recording core (tests/monitor_recording_core.py), for
developing the node only: ``python tests/monitor_node_dev.py [options as keyword=value]
[--ros-args ...]``. The real tests start ``umbmark monitor --ros2``."""

from __future__ import annotations

import sys

sys.path.insert(0, __file__.rsplit("/", 1)[0])

from monitor_recording_core import RecordingCore
from umbmark.monitor.ros2_node import Found, run_ros2
from umbmark.monitor.ros_node import split_ros_args


def main() -> int:
    argv = split_ros_args(sys.argv[1:])
    given = dict(a.split("=", 1) for a in argv.own)

    def make(found: Found) -> RecordingCore:
        return RecordingCore(found.options.robot)

    if given.pop("ros1", None):
        from umbmark.monitor.ros1_node import run_ros1

        return run_ros1(given, argv.ros1, make)
    return run_ros2(given, argv.ros2, make)


if __name__ == "__main__":
    raise SystemExit(main())

"""The monitor's node loop without ROS (umbmark.monitor.node_loop), fed by the recording
core of tests/monitor_recording_core.py (what it is fed counted; the monitor's own
figures are the real core's tests): silence said STALE and going on, a bad message one
line, applying at rest only when asked and due, the result told to the core."""

from __future__ import annotations

import time

import numpy as np

from monitor_recording_core import RecordingCore
from umbmark.core.errors import InputError, SafetyError
from umbmark.monitor.node_loop import MonitorLoop, Outputs
from umbmark.monitor.ros_node import NodeOptions
from umbmark.robot.base import ApplyResult, DriveParams, Pose2D, ScanSweep


class _Outputs:
    def __init__(self, apply_raises: bool = False) -> None:
        self.statuses: list = []
        self.corrected: list = []
        self.lines: list[str] = []
        self.applied: list[DriveParams] = []
        self.raises = apply_raises

    def outputs(self, apply: bool = True) -> Outputs:
        def do_apply(params: DriveParams) -> ApplyResult:
            self.applied.append(params)
            if self.raises:
                raise SafetyError("the controller manager refused to deactivate it")
            return ApplyResult("set_parameters", True, "configured")

        return Outputs(self.statuses.append, self.corrected.append,
                       do_apply if apply else None, self.lines.append)  # fmt: skip


def _sweep() -> ScanSweep:
    return ScanSweep(time=1.0, angle_min=0.0, angle_increment=0.1, ranges=np.ones(3),
                     range_min=0.1, range_max=10.0)  # fmt: skip


def test_a_silent_topic_is_stale_and_the_monitor_goes_on_when_it_returns() -> None:
    core = RecordingCore("r1")
    out = _Outputs()
    options = NodeOptions(robot="r1", stale_after=0.05, imu_topic=None)
    loop = MonitorLoop(core, options, out.outputs(), lambda: 100.0, "/odom")
    loop.odometry(1.0, Pose2D())
    loop.scan(_sweep)
    assert loop.tick().level == "OK"  # type: ignore[union-attr]
    time.sleep(0.08)
    loop.odometry(2.0, Pose2D())  # the wheels speak, the laser does not
    status = loop.tick()
    assert status is not None
    assert (status.level, status.stale) == ("STALE", ("/scan",))
    assert status.message.startswith("silent: /scan")
    loop.scan(_sweep)
    assert loop.tick().level == "OK"  # type: ignore[union-attr]
    assert core.counts == {"wheels": 0, "odometry": 2, "scan": 2, "imu": 0}
    assert "umbmark_monitor: /scan back: going on" in out.lines
    assert len(out.statuses) == 3
    assert [c.time for c in out.corrected] == [1.0, 2.0]  # once per new wheel reading


def test_the_wheels_are_stale_before_they_ever_speak_a_missing_imu_is_not() -> None:
    loop = MonitorLoop(RecordingCore(), NodeOptions(stale_after=0.01), _Outputs().outputs(),
                       lambda: 0.0, "/odom")  # fmt: skip
    time.sleep(0.03)
    assert loop.tick().stale == ("/odom",)  # type: ignore[union-attr]


def test_a_bad_message_is_one_line_and_counted_not_raised() -> None:
    out = _Outputs()
    loop = MonitorLoop(RecordingCore(), NodeOptions(), out.outputs(), lambda: 0.0, "/odom")

    def bad() -> ScanSweep:
        raise InputError("a rotation quaternion of length 0")

    for _ in range(3):
        loop.scan(bad)
    assert loop.faults == 3
    assert out.lines == ["umbmark_monitor: a scan left out (a rotation quaternion of length 0)"]


def test_applying_at_rest_once_due_and_told_to_the_core() -> None:
    params = DriveParams(0.34, 0.075, 1.02, 0.99, 1.01)
    core = RecordingCore(apply=params)
    out = _Outputs()
    loop = MonitorLoop(core, NodeOptions(apply="at-rest"), out.outputs(), lambda: 5.0, "/o")
    loop.odometry(1.0, Pose2D())
    loop.tick()
    loop.tick()
    assert out.applied == [params]
    assert core.results == [ApplyResult("set_parameters", True, "configured")]
    assert out.statuses[-1].applied == "set_parameters: configured"
    said = (
        "umbmark_monitor: the robot is at rest: applying wheel_separation_multiplier 1.02, "
        "left_wheel_radius_multiplier 0.99, right_wheel_radius_multiplier 1.01"
    )
    assert said in out.lines


def test_an_apply_that_fails_is_said_and_not_applied() -> None:
    core = RecordingCore(apply=DriveParams(0.34, 0.075, 1.02))
    out = _Outputs(apply_raises=True)
    loop = MonitorLoop(core, NodeOptions(apply="at-rest"), out.outputs(), lambda: 5.0, "/o")
    loop.tick()
    (result,) = core.results
    assert (result.method, result.active) == ("none", False)
    assert "refused to deactivate" in result.message


def test_never_applies_unless_asked() -> None:
    core = RecordingCore(apply=DriveParams(0.34, 0.075, 1.02))
    out = _Outputs()
    MonitorLoop(core, NodeOptions(), out.outputs(), lambda: 5.0, "/o").tick()
    assert (out.applied, core.results) == ([], [])


def test_after_its_stop_the_loop_takes_nothing_and_says_nothing() -> None:
    """ROS calls back with what its subscriptions still hold while the node shuts down:
    after :meth:`MonitorLoop.stop` none of it reaches the core, the corrected odometry
    or the terminal (its last line is the node's stop line)."""
    core = RecordingCore("r1")
    out = _Outputs()
    loop = MonitorLoop(core, NodeOptions(robot="r1"), out.outputs(), lambda: 1.0, "/odom")
    loop.odometry(1.0, Pose2D())
    loop.stop()
    loop.odometry(2.0, Pose2D())
    loop.scan(_sweep)
    loop._fault("corrected odometry", RuntimeError("publish() to a closed topic"))
    assert core.counts == {"wheels": 0, "odometry": 1, "scan": 0, "imu": 0}
    assert [c.time for c in out.corrected] == [1.0]
    assert (out.lines, loop.faults) == ([], 0)

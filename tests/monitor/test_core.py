"""The monitor's core on plain inputs (quick): faults, stale topics, nothing applied
while moving or without a confirmed change, the status's form."""

from __future__ import annotations

import math

import numpy as np

from umbmark.monitor.core import Monitor
from umbmark.monitor.setup import MonitorSetup
from umbmark.robot.base import DriveParams, Pose2D

PARAMS = DriveParams(0.34, 0.075)


def _drive(core: Monitor, t0: float, t1: float, speed: float = 4.0, start: float = 0.0) -> float:
    """The wheels at 50 Hz turning at ``speed`` [rad/s] from ``t0`` to ``t1``; the angle."""
    angle = start
    for k in range(round((t1 - t0) * 50)):
        t = t0 + 0.02 * k
        angle = start + speed * (t - t0)
        core.wheels(t, angle, angle)
    return angle


def test_the_clock_going_back_restarts_the_window() -> None:
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("wheels",)))
    _drive(core, 0.0, 30.0)
    assert core.window
    assert core.odometer > 0
    _drive(core, 0.0, 15.0)  # a simulation reset
    assert core.restarts == 1
    assert sum(c.driving.metres for _, c in core.window) < 15 * 4 * 0.075


def test_out_of_order_and_stale() -> None:
    from umbmark.robot.base import ScanSweep

    core = Monitor(MonitorSetup("r", PARAMS, inputs=("wheels", "scan"), stale_after=2.0))
    core.scan(ScanSweep(0.0, -1.0, 0.01, np.full(200, 3.0), 0.1, 10.0))
    _drive(core, 0.0, 5.0)
    core.wheels(4.5, 0.0, 0.0)  # late
    assert core.arrivals.dropped["wheels: out of order"] == 1
    status = core.status(5.0)
    assert status.level == "STALE"
    assert status.stale == ("scan",)
    assert dict(status.key_values())["stale topics"] == "scan"


def test_a_controller_restart_keeps_the_odometry_going() -> None:
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("odometry",)))
    for k in range(100):
        core.odometry(0.02 * k, Pose2D(5.0 + 0.01 * k, 2.0, 0.5))
    before = core.corrected()
    assert before is not None
    for k in range(100, 150):  # the controller restarted at the origin
        core.odometry(0.02 * k, Pose2D(0.01 * (k - 100), 0.0, 0.0))
    after = core.corrected()
    assert core.angles.breaks == 1
    assert after is not None
    # the corrected odometry went on by the 0.49 m driven after the restart, no jump
    moved = math.hypot(after.pose.x - before.pose.x, after.pose.y - before.pose.y)
    assert abs(moved - 0.50) < 0.02


def test_nothing_to_apply_without_a_confirmed_change_or_while_moving() -> None:
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("wheels",), apply="at-rest", rest_time=1.0))
    angle = _drive(core, 0.0, 20.0)
    assert core.apply_due(20.0) is None  # moving
    for k in range(200):
        core.wheels(20.0 + 0.02 * k, angle, angle)
    assert core.rested(24.0) > 3.0
    assert core.apply_due(24.0) is None  # at rest, but nothing changed


def test_the_status_says_every_figure() -> None:
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("wheels",)))
    _drive(core, 0.0, 12.0)
    status = core.status(12.0)
    assert [f.name for f in status.figures][:3] == ["E_d", "E_b", "E_s"]
    notes = {f.name: f.note for f in status.figures}
    assert notes["laser_x"] == "no laser"
    assert notes["k_g"] == "no gyro"
    assert status.level == "OK"


def test_the_options_defaults_are_the_setups() -> None:
    import inspect

    from umbmark.jobs.monitor import monitor_sim
    from umbmark.options.monitor import MONITOR

    signature = inspect.signature(monitor_sim).parameters
    setup = MonitorSetup("r", PARAMS)
    for name, spec in MONITOR.items():
        if name != "robot":
            assert signature[name].default == spec.default == getattr(setup, name), name


def test_the_nodes_make_the_core_from_what_they_found() -> None:
    from umbmark.monitor.core import make_monitor
    from umbmark.monitor.ros2_node import Found
    from umbmark.monitor.ros_node import NodeOptions

    found = Found({"window_metres": 80.0, "tolerance": None}, NodeOptions(robot="amr",
                  imu_topic=None), PARAMS, sim_time=False)  # fmt: skip
    core = make_monitor(found)
    assert core.setup.robot == "amr"
    assert core.setup.window_metres == 80.0
    assert core.setup.inputs == ("wheels", "scan")


def test_the_odometry_then_joint_states_stamped_before_it_go_on() -> None:
    """A node feeds the odometry until joint states with the wheels come, then those:
    joint states stamped before the last odometry are dropped and counted, the wheels
    then go on in new chunks: 0.3 m/s for the two whole chunks of 10 s after the switch
    (the third not yet ended), 6 m."""
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("odometry",)))
    for k in range(100):  # 2 s at 0.3 m/s straight ahead
        core.odometry(0.02 * k, Pose2D(0.006 * k, 0.0, 0.0))
    for k in range(1500):  # the joint states: 4 rad/s x 0.075 m, from 0.1 s before
        t = 1.9 + 0.02 * k
        core.wheels(t, 4.0 * t, 4.0 * t)
    assert core.arrivals.dropped["wheels: not after the last wheel reading"] == 5
    assert abs(core.odometer - 0.3 * 20.0) < 0.05


def test_a_core_that_leaves_silence_to_its_node_says_no_stale() -> None:
    setup = MonitorSetup("r", PARAMS, inputs=("wheels", "scan"), stale_after=2.0,
                         judge_silence=False)  # fmt: skip
    core = Monitor(setup)
    _drive(core, 0.0, 5.0)
    status = core.status(60.0)  # nothing for 55 s of the robot's clock
    assert (status.level, status.stale) == ("OK", ())

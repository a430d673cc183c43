"""The monitor's core on plain inputs (quick): faults, stale topics, nothing applied
while moving or without a confirmed change, the status's form; its faults with a history
(the odometer, a monitor started again, the wall clock after a reset, an apply)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from umbmark.monitor.core import Monitor
from umbmark.monitor.course import StretchPoint
from umbmark.monitor.setup import MonitorSetup
from umbmark.robot.base import ApplyResult, DriveParams, Pose2D

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
    then go on in new chunks: the odometer keeps the 0.594 m of the odometry's chunk in
    progress (99 steps of 6 mm), then 0.3 m/s for the two whole chunks of 10 s after the
    switch (the third not yet ended), 6 m."""
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("odometry",)))
    for k in range(100):  # 2 s at 0.3 m/s straight ahead
        core.odometry(0.02 * k, Pose2D(0.006 * k, 0.0, 0.0))
    for k in range(1500):  # the joint states: 4 rad/s x 0.075 m, from 0.1 s before
        t = 1.9 + 0.02 * k
        core.wheels(t, 4.0 * t, 4.0 * t)
    assert core.arrivals.dropped["wheels: not after the last wheel reading"] == 5
    assert abs(core.odometer - (0.594 + 0.3 * 20.0)) < 0.05


def test_a_core_that_leaves_silence_to_its_node_says_no_stale() -> None:
    setup = MonitorSetup("r", PARAMS, inputs=("wheels", "scan"), stale_after=2.0,
                         judge_silence=False)  # fmt: skip
    core = Monitor(setup)
    _drive(core, 0.0, 5.0)
    status = core.status(60.0)  # nothing for 55 s of the robot's clock
    assert (status.level, status.stale) == ("OK", ())


# --- faults with a history: the odometer never goes back, a monitor started again goes on
# from what it last said, a simulation's wall clock goes on after a reset, an apply is
# recorded and not made twice (the ROS twins: tests/test_monitor_ros2_faults.py) ---------

#: The wheels at 4 rad/s on 0.075 m: 0.3 m/s.
_SPEED = 4.0 * 0.075


def test_the_odometer_does_not_go_back_when_the_clock_does(tmp_path: Path) -> None:
    """25 s at 0.3 m/s (7.5 m: two chunks of 10 s and half of the third), the clock back
    to 0: the chunk in progress is kept in the odometer, which then goes on."""
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("wheels",)))
    angle = _drive(core, 0.0, 25.0)
    said = core.status(25.0).odometer
    assert said == pytest.approx(_SPEED * 24.98, abs=0.01)
    _drive(core, 0.0, 5.0, start=angle)  # a simulation reset; the wheels' counts go on
    assert core.restarts == 1
    assert core.status(5.0).odometer == pytest.approx(said + _SPEED * 4.98, abs=0.02)


def test_the_odometer_does_not_go_back_when_the_controller_restarts() -> None:
    """The odometry 0.3 m/s along x for 15 s, then from the origin again (a controller
    restarted): its chunk in progress (5 s, 1.5 m) kept, 4.5 m and 3 m after."""
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("odometry",)))
    for k in range(750):
        core.odometry(0.02 * k, Pose2D(5.0 + 0.006 * k, 2.0, 0.0))
    said = core.status(15.0).odometer
    for k in range(750, 1250):
        core.odometry(0.02 * k, Pose2D(0.006 * (k - 750), 0.0, 0.0))
    assert core.angles.breaks == 1
    assert said == pytest.approx(0.006 * 749, abs=0.01)
    assert core.status(25.0).odometer == pytest.approx(said + 0.006 * 499, abs=0.02)


def test_a_simulations_stretches_keep_their_wall_clock_going_after_a_reset() -> None:
    """A clock from 0 is put on the wall clock from its first message; after it went back,
    its times map to wall times after those before."""
    core = Monitor(MonitorSetup("r", PARAMS, inputs=("wheels",)))
    angle = _drive(core, 0.0, 30.0)
    assert core._epoch is not None
    wall_before = 29.98 + core._epoch
    _drive(core, 0.0, 5.0, start=angle)
    assert 0.0 + core._epoch >= wall_before


def test_a_monitor_started_again_goes_on_from_what_it_last_said(tmp_path: Path) -> None:
    """No stretch recorded yet (the wheels alone determine nothing): the odometer a
    monitor said is kept all the same, and one started again on the history goes on from
    it."""
    history = tmp_path / "h.sqlite3"
    setup = MonitorSetup("r", PARAMS, inputs=("wheels",), history=history)
    first = Monitor(setup)
    _drive(first, 0.0, 25.0)
    said = first.status(25.0).odometer
    assert said > 7.0
    again = Monitor(setup)
    assert again.status(26.0).odometer >= said
    assert again.status(26.0).odometer == pytest.approx(said)


def test_the_nodes_give_the_core_its_history(tmp_path: Path) -> None:
    from umbmark.monitor.core import make_monitor
    from umbmark.monitor.ros2_node import Found
    from umbmark.monitor.ros_node import NodeOptions

    history = tmp_path / "h.sqlite3"
    found = Found({"history": str(history)}, NodeOptions(robot="amr", imu_topic=None), PARAMS,
                  sim_time=False)  # fmt: skip
    core = make_monitor(found)
    assert core.setup.history == str(history)
    assert core._store is not None
    assert make_monitor(Found({}, NodeOptions(robot="amr"), PARAMS, False))._store is None


def _course_with_a_step(core: Monitor) -> None:
    """Eight stretches of 20 m: E_d 1.000 then 1.010 from the sixth, E_b and E_s 1; the
    odometer at their end (160 m) where it is short of it."""
    core.odometer = max(core.odometer, 160.0)
    for k in range(8):
        t, odometer = 100.0 * k, 20.0 * k
        e_d = 1.0 if k < 5 else 1.01
        for name, value, se in (("E_d", e_d, 1e-4), ("E_b", 1.0, 5e-4), ("E_s", 1.0, 5e-4)):
            core.course.add(name, StretchPoint(value, se, t, odometer, 1.7e9 + t))
    core._judge()


def test_an_apply_is_recorded_and_not_made_again(tmp_path: Path) -> None:
    """A confirmed step of E_d to 1.010, the wheels at rest 6 s: the multipliers the
    present state asks for (c_L = 2 E_s / (1 + E_d) = 2 / 2.01, c_R = E_d c_L, the
    separation E_b = 1) applied, recorded as a calibration marked applied; a monitor
    started again on the history does not apply it again."""
    history = tmp_path / "h.sqlite3"
    setup = MonitorSetup("r", PARAMS, inputs=("wheels",), apply="at-rest", rest_time=5.0,
                         history=history)  # fmt: skip
    core = Monitor(setup)
    _course_with_a_step(core)
    angle = _drive(core, 0.0, 2.0)
    for k in range(300):  # at rest 6 s
        core.wheels(2.0 + 0.02 * k, angle, angle)
    params = core.apply_due(8.0)
    assert params is not None
    assert params.left_wheel_radius_multiplier == pytest.approx(2.0 / 2.01, rel=1e-6)
    assert params.right_wheel_radius_multiplier == pytest.approx(1.01 * 2.0 / 2.01, rel=1e-6)
    assert params.wheel_separation_multiplier == pytest.approx(1.0, rel=1e-6)
    core.applied(8.0, ApplyResult("set_parameters", True, "configured"))
    assert core.status(8.0).applied is not None
    from umbmark.store.history import History

    (applied,) = [c for c in History(history).calibrations("r") if c.applied]
    assert applied.new["c_R"] == pytest.approx(1.01 * 2.0 / 2.01, rel=1e-6)
    assert applied.robot_E_d == pytest.approx(1.01, rel=1e-6)
    again = Monitor(setup)
    _course_with_a_step(again)
    for k in range(400):
        again.wheels(10.0 + 0.02 * k, angle, angle)
    assert again.rested(18.0) > 5.0
    assert again.apply_due(18.0) is None

"""What the ROS adapters share, without ROS: messages as values (plain namespaces shaped
like rospy's and rclpy's messages), TF mountings, the apply plan, the parameter file."""

from __future__ import annotations

import math
import os
import threading
from pathlib import Path
from types import SimpleNamespace as Msg

import numpy as np
import pytest

from umbmark.core.errors import InputError
from umbmark.robot.base import DriveParams, Pose2D
from umbmark.robot.ros_common import (
    Latest,
    Mount,
    held_problem,
    master_problem,
    mount_from_transform,
    plan_apply,
    planar_pose,
    range_reading,
    scan_from_message,
    stamp_seconds,
    wait_on_clock,
    write_params,
)
from umbmark.sources.params.reader import read_controller_params


def _q(x: float, y: float, z: float, w: float) -> Msg:
    return Msg(x=x, y=y, z=z, w=w)


def _pose(px: float, py: float, q: Msg) -> Msg:
    return Msg(position=Msg(x=px, y=py, z=0.0), orientation=q)


# --- stamps -------------------------------------------------------------------------------


def test_stamps_of_ros1_and_ros2() -> None:
    assert stamp_seconds(Msg(secs=12, nsecs=500_000_000)) == 12.5
    assert stamp_seconds(Msg(sec=3, nanosec=250_000_000)) == 3.25
    with pytest.raises(InputError, match="a stamp without seconds"):
        stamp_seconds(Msg(seconds=1.0))


# --- planar poses from quaternions ----------------------------------------------------------


def test_yaw_of_a_quarter_turn() -> None:
    """A rotation by theta about z is (0, 0, sin(theta/2), cos(theta/2)): 90 degrees is
    (0, 0, 1/sqrt 2, 1/sqrt 2)."""
    h = math.sqrt(0.5)
    pose = planar_pose(_pose(1.0, -2.0, _q(0.0, 0.0, h, h)))
    assert (pose.x, pose.y) == (1.0, -2.0)
    assert pose.theta == pytest.approx(math.pi / 2, abs=1e-12)


def test_yaw_of_a_rolled_pose_and_an_unnormalized_quaternion() -> None:
    """Yaw 30 degrees then a roll of 180 degrees: q_yaw * q_roll = (c, 0, 0, 0)(...) works
    out to (cos 15, sin 15, 0, 0); its x axis still points at 30 degrees. Scaling a
    quaternion does not change its rotation."""
    c, s = math.cos(math.radians(15)), math.sin(math.radians(15))
    assert planar_pose(_pose(0, 0, _q(c, s, 0, 0))).theta == pytest.approx(math.radians(30))
    h = math.sqrt(0.5)
    assert planar_pose(_pose(0, 0, _q(0, 0, -2 * h, 2 * h))).theta == pytest.approx(-math.pi / 2)


def test_nested_messages_and_a_zero_quaternion() -> None:
    odom = Msg(header=Msg(), pose=Msg(pose=_pose(0.5, 0.25, _q(0, 0, 0, 1)), covariance=[]))
    assert planar_pose(odom) == Pose2D(0.5, 0.25, 0.0)
    transform = Msg(transform=Msg(translation=Msg(x=1, y=2, z=3), rotation=_q(0, 0, 0, 1)))
    assert planar_pose(transform) == Pose2D(1.0, 2.0, 0.0)
    with pytest.raises(InputError, match="quaternion of length 0"):
        planar_pose(_pose(0, 0, _q(0, 0, 0, 0)))
    with pytest.raises(InputError, match="no pose"):
        planar_pose(Msg(header=Msg()))


# --- mountings ------------------------------------------------------------------------------


def test_mounting_from_a_transform() -> None:
    h = math.sqrt(0.5)
    t = Msg(translation=Msg(x=0.1, y=-0.05, z=0.3), rotation=_q(0, 0, h, h))
    mount = mount_from_transform(t)
    assert mount.pose.x == 0.1
    assert mount.pose.y == -0.05
    assert mount.pose.theta == pytest.approx(math.pi / 2)
    assert mount.upside_down is False
    assert mount.lift == pytest.approx((0.3, 0.0, 0.0))


def test_a_laser_rolled_by_180_degrees_is_upside_down() -> None:
    """Roll pi about x: q = (1, 0, 0, 0), its z axis points down, its x axis still ahead."""
    mount = mount_from_transform(Msg(translation=Msg(x=0, y=0, z=0), rotation=_q(1, 0, 0, 0)))
    assert mount.upside_down is True
    assert mount.pose.theta == pytest.approx(0.0)
    assert mount.lift is not None
    assert (mount.lift[0], abs(mount.lift[1]), mount.lift[2]) == pytest.approx((0.0, math.pi, 0.0))


def test_the_height_and_tilt_of_a_mounting() -> None:
    """Roll 0.1, pitch -0.2, yaw 0.3 rad as a quaternion (the half-angle product of
    Rz(yaw) Ry(pitch) Rx(roll), written out): the mounting keeps z, roll and pitch."""
    roll, pitch, yaw = 0.1, -0.2, 0.3
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    q = _q(
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )
    mount = mount_from_transform(Msg(translation=Msg(x=0.12, y=-0.04, z=0.25), rotation=q))
    assert mount.pose.theta == pytest.approx(yaw)
    assert mount.lift == pytest.approx((0.25, roll, pitch))
    scan = scan_from_message(_scan_msg(-0.5, 0.25, [1, 2, 3, 4]), mount, "/base_footprint")
    assert (scan.lift, scan.frame, scan.base) == (mount.lift, "laser", "base_footprint")


# --- scans and ranges -----------------------------------------------------------------------


def _scan_msg(angle_min: float, increment: float, ranges: list[float]) -> Msg:
    return Msg(
        header=Msg(stamp=Msg(secs=5, nsecs=0), frame_id="laser"),
        angle_min=angle_min,
        angle_increment=increment,
        ranges=ranges,
        range_min=0.05,
        range_max=10.0,
    )


def test_scan_of_an_upright_laser() -> None:
    mount = Mount(Pose2D(0.1, 0.0, 0.0))
    scan = scan_from_message(_scan_msg(-0.5, 0.25, [1, 2, 3, 4]), mount)
    assert scan.time == 5.0
    assert scan.angles() == pytest.approx([-0.5, -0.25, 0.0, 0.25])
    assert scan.ranges.tolist() == [1, 2, 3, 4]
    assert scan.mount == Pose2D(0.1, 0.0, 0.0)


def test_scan_of_an_upside_down_laser() -> None:
    """Upside down, the laser's angle phi looks at -phi in the base frame: its beams at
    -0.5, -0.25, 0, 0.25 (ranges 1, 2, 3, 4) look at 0.5, 0.25, 0, -0.25, so counter-
    clockwise from -0.25 the ranges are 4, 3, 2, 1."""
    scan = scan_from_message(_scan_msg(-0.5, 0.25, [1, 2, 3, 4]), Mount(Pose2D(), True))
    assert scan.angles() == pytest.approx([-0.25, 0.0, 0.25, 0.5])
    assert scan.ranges.tolist() == [4, 3, 2, 1]


def test_range_readings_no_echo_and_time() -> None:
    def msg(r: float, secs: int) -> Msg:
        return Msg(header=Msg(stamp=Msg(secs=secs, nsecs=0)), range=r, min_range=0.02, max_range=3)

    mounts = [Mount(Pose2D(0, 0.1, 0)), Mount(Pose2D(0, -0.1, 0)), Mount(Pose2D(0, 0, 1.5))]
    reading = range_reading([msg(1.0, 7), msg(3.5, 8), msg(math.inf, 6)], mounts)
    assert reading.time == 8.0
    assert reading.ranges[0] == 1.0
    assert np.isnan(reading.ranges[1:]).all()
    assert reading.mounts == tuple(m.pose for m in mounts)


# --- applying -------------------------------------------------------------------------------


def _params(sep: float, left: float, right: float) -> DriveParams:
    return DriveParams(0.34, 0.075, sep, left, right)


def test_plan_inside_the_reconfigure_bounds() -> None:
    assert plan_apply(_params(0.97, 0.998, 1.002), "reconfigure").method == "reconfigure"
    assert plan_apply(_params(0.5, 1.5, 1.0), "reconfigure").method == "reconfigure"  # bounds
    assert plan_apply(_params(0.97, 1, 1), "yaml").method == "yaml"
    assert plan_apply(_params(0.97, 1, 1), "none").method == "none"


@pytest.mark.parametrize(("values", "named"), [
    ((1.6, 1.0, 1.0), "wheel_separation_multiplier 1.6"),
    ((1.0, 0.49, 1.0), "left_wheel_radius_multiplier 0.49"),
    ((1.0, 1.0, 1.5000001), "right_wheel_radius_multiplier 1.5"),
])  # fmt: skip
def test_plan_outside_the_bounds_writes_the_yaml(
    values: tuple[float, float, float], named: str
) -> None:
    plan = plan_apply(_params(*values), "reconfigure")
    assert plan.method == "yaml"
    assert named in plan.reason
    assert "outside 0.5 to 1.5" in plan.reason


def test_plan_refuses_nonpositive_multipliers() -> None:
    with pytest.raises(InputError, match=r"wheel_separation_multiplier 0\.0 is not a positive"):
        plan_apply(_params(0.0, 1, 1), "reconfigure")
    with pytest.raises(InputError, match="not a positive"):
        plan_apply(_params(1, math.nan, 1), "yaml")


def test_held_problem_names_a_clamped_value() -> None:
    asked = _params(0.97, 0.998, 1.002)
    held = {
        "wheel_separation_multiplier": 0.97,
        "left_wheel_radius_multiplier": 0.998,
        "right_wheel_radius_multiplier": 1.002,
    }
    assert held_problem(asked, held) is None
    problem = held_problem(_params(1.6, 0.998, 1.002), {**held, "wheel_separation_multiplier": 1.5})
    assert problem is not None
    assert "holds wheel_separation_multiplier 1.5, not 1.6" in problem


def test_write_params_new_ros1_file_is_read_back(tmp_path: Path) -> None:
    path = tmp_path / "controller.yaml"
    done = write_params(path, _params(0.97, 0.998, 1.002), "/diff_drive_controller", ros2=False)
    assert done.backup is None
    assert done.edited.removed == ()
    assert done.line().startswith(f"wrote {path} (new): diff_drive_controller's ")
    read = read_controller_params(path, "/diff_drive_controller")
    assert read.ros2 is False
    assert (
        read.wheel_separation_multiplier,
        read.left_wheel_radius_multiplier,
        read.right_wheel_radius_multiplier,
    ) == (0.97, 0.998, 1.002)


def test_write_params_ros2_overlay_is_read_back(tmp_path: Path) -> None:
    path = tmp_path / "overlay.yaml"
    write_params(path, _params(1.6, 0.9, 1.1), "/diff_drive_controller", ros2=True)
    read = read_controller_params(path, "/diff_drive_controller")
    assert read.ros2 is True
    assert read.wheel_separation_multiplier == 1.6
    assert "ros__parameters" in path.read_text()


def test_write_params_keeps_the_rest_of_an_existing_file(tmp_path: Path) -> None:
    path = tmp_path / "controller.yaml"
    path.write_text(
        "diff_drive_controller:\n"
        "  type: diff_drive_controller/DiffDriveController\n"
        "  wheel_separation: 0.34\n"
        "  wheel_radius_multiplier: 1.01\n"
        "joint_state_controller:\n"
        "  publish_rate: 50\n"
    )
    done = write_params(path, _params(0.97, 0.998, 1.002), "/diff_drive_controller", ros2=False)
    assert done.edited.removed == ("  wheel_radius_multiplier: 1.01",)
    read = read_controller_params(path, "/diff_drive_controller")
    assert read.wheel_separation == 0.34
    assert read.left_wheel_radius_multiplier == 0.998
    assert read.radius_multiplier is None
    text = path.read_text()
    assert "joint_state_controller" in text
    assert "publish_rate: 50" in text


def test_write_params_is_atomic(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A write that fails at the rename leaves the old file whole and no temporary file."""
    path = tmp_path / "controller.yaml"
    write_params(path, _params(0.97, 0.998, 1.002), "/diff_drive_controller", ros2=False)
    before = path.read_text()

    def fail(*args: object) -> None:
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises((OSError, InputError)):
        write_params(path, _params(1.2, 1.1, 0.9), "/diff_drive_controller", ros2=False)
    assert path.read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["controller.yaml"]


# --- time and connection --------------------------------------------------------------------


def test_wait_on_clock_runs_with_the_clock_and_refuses_a_stopped_one() -> None:
    ticks = threading.Condition()
    t = [100.0]

    def ticking() -> float:
        t[0] += 0.01
        return t[0]

    wait_on_clock(ticking, 0.5, ticks, stall=1.0, slice_=0.001)
    assert t[0] >= 100.5
    with pytest.raises(InputError, match=r"ROS time stopped at 7\.000 s"):
        wait_on_clock(lambda: 7.0, 1.0, ticks, stall=0.05, slice_=0.01)
    back = iter([10.0, 9.0])
    with pytest.raises(InputError, match=r"went back from 10\.000 s to 9\.000 s"):
        wait_on_clock(lambda: next(back), 1.0, ticks, stall=1.0)


def test_latest_waits_for_a_first_value() -> None:
    latest: Latest[int] = Latest()
    assert latest.wait(0.01) is None
    threading.Timer(0.02, latest.put, [7]).start()
    assert latest.wait(2.0) == 7
    assert latest.count == 1


def test_master_problem_without_a_master() -> None:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # bound, not listening: refused
        problem = master_problem(f"http://127.0.0.1:{port}", 1.0)
    assert problem is not None
    assert problem.startswith(f"no ROS master at http://127.0.0.1:{port}")
    assert master_problem("localhost:11311", 1.0) == (
        "ROS_MASTER_URI 'localhost:11311' is not an http:// address"
    )


# --- the adapters without their client libraries --------------------------------------------


def test_ros1_without_rospy_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    from umbmark.robot.ros1 import Ros1Robot
    from umbmark.robot.ros_common import RosOptions

    monkeypatch.setitem(sys.modules, "rospy", None)  # import rospy raises ImportError
    with pytest.raises(InputError, match="--ros1 needs rospy"):
        Ros1Robot(RosOptions())


def test_ros2_without_rclpy_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    from umbmark.robot.ros2 import Ros2Robot
    from umbmark.robot.ros_common import RosOptions

    monkeypatch.setitem(sys.modules, "rclpy", None)
    with pytest.raises(InputError, match="--ros2 needs rclpy"):
        Ros2Robot(RosOptions())


def test_a_missing_ros1_piece_skips_here_and_fails_under_ci(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The ROS 1 tests skip, naming the package, only where it cannot be had; CI (which
    installs everything) fails instead."""
    from helpers import unavailable

    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match="install python3-nav-msgs"):
        unavailable("--ros1 needs nav_msgs, ...: install python3-nav-msgs (Debian)")
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match=r"python3-nav-msgs.*\(CI installs it"):
        unavailable("--ros1 needs nav_msgs, ...: install python3-nav-msgs (Debian)")


def test_ci_installs_every_ros1_package_imported() -> None:
    """.ci/run (and so the README's test command) installs the package of every module the
    ROS 1 adapter, the tests' robot node and probe import directly, and rosmaster; the
    packages beneath them are their Debian dependencies. Its check and its install name
    the same packages."""
    import re

    from umbmark.robot.ros1 import ROS1_MODULES, ROS1_PACKAGES

    from helpers import ROOT, ROS1_TEST_MODULES

    run = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    checked = re.search(r"dpkg -s ([^>]+)>", run)
    installed = re.search(r"apt-get install -y -qq ([^>]+)>", run)
    assert checked is not None
    assert installed is not None
    assert checked.group(1).split() == installed.group(1).split()
    tops = {m.split(".")[0] for m in (*ROS1_MODULES, *ROS1_TEST_MODULES)}
    needed = {ROS1_PACKAGES[top] for top in tops} | {"python3-rosmaster"}
    assert needed - set(installed.group(1).split()) == set()

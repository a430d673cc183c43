"""The robot description read without ROS: mountings and wheel geometry from a URDF, with
expected values worked out by hand from the joints' origins."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from umbmark.core.errors import InputError
from umbmark.robot.base import DriveParams, Pose2D
from umbmark.robot.ros_common import RosOptions, default_topics, laser_mount, restart_commands
from umbmark.robot.urdf import static_mount, urdf_geometry, urdf_mount
from umbmark.routines.resume import SelfCalState, pending_problem, read_state, write_state

#: base_link -> chassis (0.05 m ahead, turned 90 deg) -> laser (0.1 m along the chassis'
#: x axis, rolled 180 deg: upside down); wheels 0.2 m either side of base_link, radius 0.06.
URDF = """<?xml version="1.0"?>
<robot name="r">
  <link name="base_link"/>
  <link name="chassis"/>
  <joint name="chassis_joint" type="fixed">
    <parent link="base_link"/><child link="chassis"/>
    <origin xyz="0.05 0 0.1" rpy="0 0 1.5707963267948966"/>
  </joint>
  <link name="laser"/>
  <joint name="laser_joint" type="fixed">
    <parent link="chassis"/><child link="laser"/>
    <origin xyz="0.1 0 0.2" rpy="3.141592653589793 0 0"/>
  </joint>
  <link name="wheel_l"><collision><geometry><cylinder radius="0.06" length="0.03"/>
  </geometry></collision></link>
  <link name="wheel_r"><visual><geometry><cylinder radius="0.06" length="0.03"/>
  </geometry></visual></link>
  <joint name="left_wheel_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_l"/>
    <origin xyz="0 0.2 0.06" rpy="-1.5707963267948966 0 0"/>
  </joint>
  <joint name="right_wheel_joint" type="continuous">
    <parent link="base_link"/><child link="wheel_r"/>
    <origin xyz="0 -0.2 0.06" rpy="-1.5707963267948966 0 0"/>
  </joint>
</robot>
"""


def test_a_mounting_through_a_chain_of_joints() -> None:
    """The chassis is turned 90 deg, so the laser's 0.1 m along it is +y in base_link:
    (0.05, 0.1); its x axis points along +y (yaw 90 deg); rolled 180 deg it is upside down."""
    mount = urdf_mount(URDF, "base_link", "laser")
    assert mount is not None
    assert (mount.pose.x, mount.pose.y) == pytest.approx((0.05, 0.1))
    assert mount.pose.theta == pytest.approx(math.pi / 2)
    assert mount.upside_down
    # 0.1 + 0.2 m up; Rz(90 deg) Rx(180 deg) is rpy (180 deg, 0, 90 deg)
    assert mount.lift is not None
    assert (mount.lift[0], abs(mount.lift[1]), mount.lift[2]) == pytest.approx((0.3, math.pi, 0))
    chassis = urdf_mount(URDF, "base_link", "chassis")
    assert chassis is not None
    assert not chassis.upside_down
    assert urdf_mount(URDF, "base_link", "sonar") is None


def test_a_mounting_through_static_transforms() -> None:
    """/tf_static as the same chain: base_link -> chassis (0.05 m ahead, turned 90 deg:
    quaternion (0, 0, sin 45, cos 45)) -> laser (0.1 m along the chassis, rolled 180 deg:
    (1, 0, 0, 0)): the laser at (0.05, 0.1), pointing along +y, upside down; frames given
    with a leading slash are the same frames; one not under base_link has no mounting."""
    h = math.sqrt(0.5)
    edges = {
        "chassis": ("base_link", (0.05, 0.0, 0.1), (0.0, 0.0, h, h)),
        "laser": ("chassis", (0.1, 0.0, 0.2), (1.0, 0.0, 0.0, 0.0)),
        "camera": ("map", (1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
    }
    mount = static_mount(edges, "base_link", "/laser")
    assert mount is not None
    assert (mount.pose.x, mount.pose.y) == pytest.approx((0.05, 0.1))
    assert mount.pose.theta == pytest.approx(math.pi / 2)
    assert mount.upside_down
    chassis = static_mount(edges, "base_link", "chassis")
    assert chassis is not None
    assert not chassis.upside_down
    assert static_mount(edges, "base_link", "camera") is None
    assert static_mount(edges, "base_link", "sonar") is None


def test_the_wheel_geometry() -> None:
    assert urdf_geometry(URDF) == pytest.approx((0.4, 0.06))
    one_wheel = URDF.replace('name="right_wheel_joint"', 'name="caster_joint"')
    assert urdf_geometry(one_wheel) is None


def test_a_bad_description_is_one_line() -> None:
    with pytest.raises(InputError, match="not a URDF"):
        urdf_mount("<robot", "base_link", "laser")
    with pytest.raises(InputError, match="not three numbers"):
        urdf_mount(URDF.replace('xyz="0.1 0 0.2"', 'xyz="a b"'), "base_link", "laser")


def test_topics_default_from_the_controller() -> None:
    ros2 = default_topics(RosOptions(controller="/robot1/diff_cont"), ros2=True)
    assert (ros2.cmd_vel, ros2.odom) == ("/robot1/diff_cont/cmd_vel", "/robot1/diff_cont/odom")
    ros1 = default_topics(RosOptions(), ros2=False)
    assert (ros1.cmd_vel, ros1.odom) == ("/cmd_vel", "/odom")
    given = default_topics(RosOptions(cmd_vel="/my_vel"), ros2=True)
    assert (given.cmd_vel, given.odom) == ("/my_vel", "/diff_drive_controller/odom")


def test_laser_mount_option() -> None:
    assert laser_mount("0.1,-0.02,180") == Pose2D(0.1, -0.02, math.pi)
    with pytest.raises(InputError, match="--laser-mount"):
        laser_mount("0.1,0")


def test_restart_commands_name_the_overlay_and_the_values() -> None:
    params = DriveParams(0.34, 0.075, 0.97, 0.998, 1.002)
    text = restart_commands("/diff_drive_controller", params, "/x/restart-overlay.yaml")
    assert "spawner diff_drive_controller --param-file YOUR_FILE --param-file " in text
    assert "/x/restart-overlay.yaml" in text
    assert "wheel_separation_multiplier: 0.97" in text


def test_the_resume_state_round_trips(tmp_path: Path) -> None:
    params = DriveParams(0.34, 0.075)
    pending = DriveParams(0.34, 0.075, 0.97, 0.998, 1.002)
    settings = {"side_length": 1.0, "runs": 2, "measure": "lidar", "max_passes": 1,
                "verify": True}  # fmt: skip
    write_state(tmp_path, SelfCalState(settings, (("pass 1", "pass-1", params),), pending))
    state = read_state(tmp_path)
    assert state == SelfCalState(settings, (("pass 1", "pass-1", params),), pending)
    assert pending_problem(pending, pending) is None
    problem = pending_problem(params, pending)
    assert problem is not None
    assert "wheel_separation_multiplier 1, not 0.97" in problem


def test_resume_without_a_state_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="not a self-calibration stopped"):
        read_state(tmp_path)
    (tmp_path / "selfcal-state.json").write_text('{"version": 1, "settings": {}, "passes": '
                                                 '[{"label": "p", "folder": "../x"}]}')  # fmt: skip
    with pytest.raises(InputError, match="outside it"):
        read_state(tmp_path)


def test_the_wheel_geometry_by_the_controllers_joint_names() -> None:
    """ros_controllers names its wheels' joints (left_wheel, right_wheel): the distance
    between those joints' origins, whatever else has "wheel" in its name."""
    caster = URDF.replace(
        "</robot>",
        '<link name="caster"/><joint name="caster_wheel_joint" type="fixed">'
        '<parent link="base_link"/><child link="caster"/><origin xyz="-0.3 0.5 0"/></joint>'
        "</robot>",
    )
    assert urdf_geometry(caster) is None  # the farthest left is the caster: no radius
    named = urdf_geometry(caster, left=("left_wheel_joint",), right=("right_wheel_joint",))
    assert named == pytest.approx((0.4, 0.06))
    assert urdf_geometry(caster, left=("nope",), right=("right_wheel_joint",)) is None

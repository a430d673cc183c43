"""A user's controller parameter file changed in place (``selfcal --params-file``): only
the three multipliers change, every other byte stays, the previous file is kept beside
it, and the line for people names the file and the change.

The expected texts are written out by hand: the old file with the changed value
substrings replaced (and, where a key is missing, the one line added), compared byte for
byte."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from umbmark.core.errors import InputError
from umbmark.robot.base import DriveParams
from umbmark.robot.ros_common import write_params
from umbmark.sources.params.reader import read_controller_params


def _params(separation: float, left: float, right: float) -> DriveParams:
    return DriveParams(
        wheel_separation=0.35,
        wheel_radius=0.05,
        wheel_separation_multiplier=separation,
        left_wheel_radius_multiplier=left,
        right_wheel_radius_multiplier=right,
    )


ROS2 = """\
# my_controllers.yaml: hand-tuned, do not lose these comments!
controller_manager:
  ros__parameters:
    update_rate: 100  # Hz

    diff_cont:
      type: diff_drive_controller/DiffDriveController

diff_cont:
  ros__parameters:
    publish_rate: 50.0   # Hz
    base_frame_id: "base_link"
    left_wheel_names: ['left_wheel_joint']
    right_wheel_names: [ "right_wheel_joint" ]

    wheel_separation: 0.35   # m, measured with a tape
    wheel_radius: 0.05 # m
    wheel_separation_multiplier: 1.0   # calibrated 2024-03
    left_wheel_radius_multiplier: &left 1.0
    # right_wheel_radius_multiplier is missing: umbmark adds it
    open_loop: false
    pose_covariance_diagonal: &cov [0.001, 0.001, 0.001, 0.001, 0.001, 0.01]
    twist_covariance_diagonal: *cov

joint_broad:
  ros__parameters: {}
"""

ROS2_AFTER = (
    ROS2.replace(
        "wheel_separation_multiplier: 1.0   # calibrated",
        "wheel_separation_multiplier: 0.97   # calibrated",
    )
    .replace("left_wheel_radius_multiplier: &left 1.0", "left_wheel_radius_multiplier: &left 0.998")
    .replace(
        "    twist_covariance_diagonal: *cov\n",
        "    twist_covariance_diagonal: *cov\n    right_wheel_radius_multiplier: 1.002\n",
    )
)


def test_a_ros2_file_keeps_every_other_byte_and_its_previous_copy(tmp_path: Path) -> None:
    path = tmp_path / "my_controllers.yaml"
    path.write_bytes(ROS2.encode())
    done = write_params(path, _params(0.97, 0.998, 1.002), "/diff_cont", ros2=True)
    assert path.read_bytes() == ROS2_AFTER.encode()
    backup = tmp_path / "my_controllers.yaml.bak"
    assert done.backup == backup
    assert backup.read_bytes() == ROS2.encode()
    read = read_controller_params(path, "diff_cont")
    assert (
        read.wheel_separation_multiplier,
        read.left_wheel_radius_multiplier,
        read.right_wheel_radius_multiplier,
    ) == (0.97, 0.998, 1.002)
    line = done.line()
    assert line.startswith(f"changed {path}: diff_cont's ")
    assert "wheel_separation_multiplier 1.0 -> 0.97" in line
    assert "left_wheel_radius_multiplier 1.0 -> 0.998" in line
    assert "right_wheel_radius_multiplier 1.002 (added)" in line
    assert line.endswith(f"the previous file kept as {backup}")


def test_a_second_write_keeps_the_first_backup(tmp_path: Path) -> None:
    path = tmp_path / "my_controllers.yaml"
    path.write_bytes(ROS2.encode())
    write_params(path, _params(0.97, 0.998, 1.002), "diff_cont", ros2=True)
    second = write_params(path, _params(0.98, 0.999, 1.001), "diff_cont", ros2=True)
    assert (tmp_path / "my_controllers.yaml.bak").read_bytes() == ROS2.encode()
    assert second.backup == tmp_path / "my_controllers.yaml.bak.2"
    assert second.backup.read_bytes() == ROS2_AFTER.encode()
    assert path.read_text() == (
        ROS2_AFTER.replace("multiplier: 0.97 ", "multiplier: 0.98 ")
        .replace("&left 0.998", "&left 0.999")
        .replace("right_wheel_radius_multiplier: 1.002", "right_wheel_radius_multiplier: 1.001")
    )


ROS1 = """\
# ROS 1 controllers of the robot (rosparam load)
robot1:
  diff_cont:
    type: "diff_drive_controller/DiffDriveController"
    left_wheel: 'left_wheel_joint'
    right_wheel: right_wheel_joint
    wheel_separation: 0.35    # m
    wheel_radius_multiplier: 1.01   # both wheels (hand-tuned)
    left_wheel_radius_multiplier: 1.0
    right_wheel_radius_multiplier: 1.0
    wheel_separation_multiplier: 1.0
    pose_covariance_diagonal: [0.001, 0.001, 1000000.0, 1000000.0, 1000000.0, 1000.0]

  joint_state_controller:
    type: joint_state_controller/JointStateController
    publish_rate: 50   # Hz
"""


def test_a_ros1_file_loses_only_its_both_wheels_multiplier(tmp_path: Path) -> None:
    path = tmp_path / "control.yaml"
    path.write_bytes(ROS1.encode())
    done = write_params(path, _params(0.97, 0.998, 1.002), "/robot1/diff_cont", ros2=False)
    expected = (
        ROS1.replace("    wheel_radius_multiplier: 1.01   # both wheels (hand-tuned)\n", "")
        .replace("left_wheel_radius_multiplier: 1.0", "left_wheel_radius_multiplier: 0.998")
        .replace("right_wheel_radius_multiplier: 1.0", "right_wheel_radius_multiplier: 1.002")
        .replace("    wheel_separation_multiplier: 1.0", "    wheel_separation_multiplier: 0.97")
    )
    assert path.read_text() == expected
    assert (tmp_path / "control.yaml.bak").read_text() == ROS1
    assert "removed 'wheel_radius_multiplier: 1.01   # both wheels (hand-tuned)'" in done.line()
    assert done.line().startswith(f"changed {path}: robot1/diff_cont's ")
    read = read_controller_params(path, "/robot1/diff_cont")
    assert read.ros2 is False
    assert read.radius_multiplier is None


def test_a_ros2_wildcard_block_with_windows_line_ends(tmp_path: Path) -> None:
    path = tmp_path / "params.yaml"
    old = "/**:\r\n  ros__parameters:\r\n    wheel_separation: 0.35  # m\r\n"
    path.write_bytes(old.encode())
    write_params(path, _params(0.97, 0.998, 1.002), "/diff_cont", ros2=True)
    added = (
        "    wheel_separation_multiplier: 0.97\r\n"
        "    left_wheel_radius_multiplier: 0.998\r\n"
        "    right_wheel_radius_multiplier: 1.002\r\n"
    )
    assert path.read_bytes() == (old + added).encode()


def test_a_file_without_the_controller_gets_its_block_at_the_end(tmp_path: Path) -> None:
    path = tmp_path / "params.yaml"
    old = "# other nodes\ncamera:\n  ros__parameters:\n    fps: 30  # Hz\n"
    path.write_text(old)
    write_params(path, _params(0.97, 0.998, 1.0), "/robot1/diff_cont", ros2=True)
    assert path.read_text() == old + (
        "\nrobot1:\n  diff_cont:\n    ros__parameters:\n"
        "      wheel_separation_multiplier: 0.97\n"
        "      left_wheel_radius_multiplier: 0.998\n"
        "      right_wheel_radius_multiplier: 1.0\n"
    )


def test_a_multiplier_behind_an_alias_is_refused_and_nothing_written(tmp_path: Path) -> None:
    path = tmp_path / "params.yaml"
    old = (
        "defaults:\n  one: &one 1.0\n"
        "diff_cont:\n  ros__parameters:\n    wheel_separation: 0.35\n"
        "    wheel_separation_multiplier: *one\n"
    )
    path.write_text(old)
    with pytest.raises(InputError, match="wheel_separation_multiplier is not a number written"):
        write_params(path, _params(0.97, 0.998, 1.0), "diff_cont", ros2=True)
    assert path.read_text() == old
    assert sorted(os.listdir(tmp_path)) == ["params.yaml"]


def test_a_shared_anchor_is_refused(tmp_path: Path) -> None:
    """Changing the anchored value would change the alias's too: refused."""
    path = tmp_path / "params.yaml"
    old = (
        "diff_cont:\n  ros__parameters:\n    wheel_separation: 0.35\n"
        "    wheel_separation_multiplier: &m 1.0\n"
        "other:\n  gain: *m\n"
    )
    path.write_text(old)
    with pytest.raises(InputError, match="only the multipliers change"):
        write_params(path, _params(0.97, 0.998, 1.0), "diff_cont", ros2=True)
    assert path.read_text() == old
    assert sorted(os.listdir(tmp_path)) == ["params.yaml"]


def test_a_file_of_comments_only_keeps_them(tmp_path: Path) -> None:
    path = tmp_path / "params.yaml"
    path.write_text("# to be filled in\n")
    done = write_params(path, _params(0.97, 0.998, 1.0), "diff_cont", ros2=True)
    assert path.read_text() == (
        "# to be filled in\ndiff_cont:\n  ros__parameters:\n"
        "    wheel_separation_multiplier: 0.97\n"
        "    left_wheel_radius_multiplier: 0.998\n"
        "    right_wheel_radius_multiplier: 1.0\n"
    )
    assert done.backup == tmp_path / "params.yaml.bak"

"""The laser's mounting in the forms a user applies (:mod:`umbmark.outputs.mounting`): the
URDF origin and the static transform publishers' arguments, written out by hand from a
known mounting, and the arguments' order checked against what the upstream programs do
with them (ros/geometry2 and ros2/geometry2, tf2_ros/src/static_transform_broadcaster_
program.cpp: ROS 1 at bbc5c296cc25, ROS 2 at 1b005c6556cf)."""

from __future__ import annotations

import math
import shlex

import numpy as np
import pytest

from umbmark.model.scans import LaserMounting
from umbmark.outputs.mounting import MountingForms

#: x = 0.12 m, y = -0.04 m, yaw = 4 deg = 0.0698132 rad; the laser 0.25 m up.
FITTED = LaserMounting(0.12, -0.04, math.radians(4.0), lift=(0.25, 0.0, 0.0))
#: 1 mm and 0.05 deg of standard error: 95 % half-widths 1.96 mm, 0.098 deg.
SE = (0.001, 0.001, math.radians(0.05))


def _forms(fitted: LaserMounting, stated: LaserMounting | None) -> MountingForms:
    values = (fitted.x, fitted.y, fitted.yaw)
    intervals = tuple((v - 1.96 * s, v + 1.96 * s) for v, s in zip(values, SE, strict=True))
    return MountingForms(fitted, SE, intervals, stated)


def test_the_forms_of_a_known_mounting() -> None:
    forms = _forms(FITTED, None)
    assert (
        forms.urdf_origin() == '<origin xyz="0.1200 -0.0400 0.2500" rpy="0.00000 0.00000 0.06981"/>'
    )
    assert forms.ros2_command() == (
        "ros2 run tf2_ros static_transform_publisher --x 0.1200 --y -0.0400 --z 0.2500 "
        "--roll 0.00000 --pitch 0.00000 --yaw 0.06981 --frame-id base_link "
        "--child-frame-id laser"
    )
    assert forms.ros1_command() == (
        "rosrun tf2_ros static_transform_publisher 0.1200 -0.0400 0.2500 0.06981 0.00000 "
        "0.00000 base_link laser"
    )
    assert forms.difference() is None
    assert "no stated mounting" in forms.verdict()
    # nothing stated of the height and tilt: 0, and the forms say so
    flat = _forms(LaserMounting(0.12, -0.04, math.radians(4.0)), None)
    assert 'xyz="0.1200 -0.0400 0.0000"' in flat.urdf_origin()
    assert "0 is written" in flat.lift_note()


def _rotation_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF's rpy (and tf2's setRPY): Rz(yaw) Ry(pitch) Rx(roll), written out."""
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def _quaternion_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _ros1_program(args: list[str]) -> tuple[np.ndarray, np.ndarray, str, str]:
    """What ROS 1's static_transform_publisher does with 8 arguments (its argc == 9
    branch, transcribed): x y z, then yaw pitch roll to a quaternion, frame, child."""
    half_yaw, half_pitch, half_roll = (0.5 * float(a) for a in args[3:6])
    cy, sy = math.cos(half_yaw), math.sin(half_yaw)
    cp, sp = math.cos(half_pitch), math.sin(half_pitch)
    cr, sr = math.cos(half_roll), math.sin(half_roll)
    q = (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )
    t = np.array([float(a) for a in args[:3]])
    return t, _quaternion_matrix(*q), args[6], args[7]


def _ros2_program(args: list[str]) -> tuple[np.ndarray, np.ndarray, str, str]:
    """What ROS 2's static_transform_publisher does with its flags: setRPY(roll, pitch,
    yaw), the frame and child by name."""
    flags = dict(zip(args[::2], args[1::2], strict=True))
    t = np.array([float(flags[f"--{k}"]) for k in "xyz"])
    r = _rotation_rpy(*(float(flags[f"--{k}"]) for k in ("roll", "pitch", "yaw")))
    return t, r, flags["--frame-id"], flags["--child-frame-id"]


def test_the_arguments_mean_the_same_transform_upstream() -> None:
    """A mounting with roll, pitch and yaw all different: the ROS 1 positional order
    (yaw pitch roll) and the ROS 2 flags give the rotation the URDF origin states."""
    tilted = LaserMounting(0.12, -0.04, 0.3, lift=(0.25, 0.1, -0.2), base="base", frame="scan")
    forms = _forms(tilted, None)
    want_t = np.array([0.12, -0.04, 0.25])
    want_r = _rotation_rpy(0.1, -0.2, 0.3)
    ros1 = shlex.split(forms.ros1_command())
    assert ros1[:3] == ["rosrun", "tf2_ros", "static_transform_publisher"]
    ros2 = shlex.split(forms.ros2_command())
    assert ros2[:4] == ["ros2", "run", "tf2_ros", "static_transform_publisher"]
    for t, r, frame, child in (_ros1_program(ros1[3:]), _ros2_program(ros2[4:])):
        assert t == pytest.approx(want_t, abs=1e-4)
        assert r == pytest.approx(want_r, abs=2e-5)
        assert (frame, child) == ("base", "scan")
    # the swapped order would be another rotation: the check can fail
    assert not np.allclose(_rotation_rpy(0.3, -0.2, 0.1), want_r, atol=1e-3)
    assert 'rpy="0.10000 -0.20000 0.30000"' in forms.urdf_origin()


def test_the_difference_from_the_stated_mounting() -> None:
    # stated 20 mm behind, 10 mm left of, 2 deg right of the fitted one: far outside
    stated = LaserMounting(0.10, -0.03, math.radians(2.0), source="/tf_static")
    forms = _forms(FITTED, stated)
    dx, dy, dyaw = forms.difference() or (0.0, 0.0, 0.0)
    assert (dx, dy) == pytest.approx((0.02, -0.01), abs=1e-12)
    assert math.degrees(dyaw) == pytest.approx(2.0, abs=1e-9)
    assert forms.outside() == (True, True, True)
    assert "outside the fit's 95 % interval in x, y, yaw" in forms.verdict()
    assert "22.4 mm and 2.00 deg" in forms.verdict()  # hypot(20, 10) = 22.36
    lines = forms.lines()
    assert "x +20.0 mm, y -10.0 mm, yaw +2.000 deg" in lines[1]
    assert "(/tf_static)" in lines[1]
    # 1 mm and 0.05 deg off: inside the half-widths (1.96 mm, 0.098 deg) but y 3 mm off
    near = LaserMounting(0.121, -0.043, math.radians(4.05))
    assert _forms(FITTED, near).outside() == (False, True, False)
    same = _forms(FITTED, LaserMounting(0.1205, -0.0395, math.radians(3.98)))
    assert same.outside() == (False, False, False)
    assert "nothing to change" in same.verdict()
    # yaw across +-180 deg: the short way round
    back = _forms(LaserMounting(0.0, 0.0, math.radians(179.0)), LaserMounting(0.0, 0.0, -math.pi))
    assert math.degrees((back.difference() or (0, 0, 0))[2]) == pytest.approx(-1.0, abs=1e-9)
    assert back.outside() == (False, False, True)
    data = forms.to_dict()
    assert data["xyz"] == pytest.approx([0.12, -0.04, 0.25])
    assert data["rpy"] == pytest.approx([0.0, 0.0, math.radians(4.0)])
    assert data["outside_interval_95"] == [True, True, True]

"""A robot's description (URDF) read without ROS: where its sensors are mounted and its
wheels' geometry, as a ROS 2 robot publishes it on ``/robot_description`` and a ROS 1 robot
keeps it in the ``robot_description`` parameter (for robots without tf2 at hand, and
controllers that take their geometry from it)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from umbmark.core.errors import InputError
from umbmark.robot.base import Pose2D
from umbmark.robot.ros_common import Mount

__all__ = ["MAX_URDF", "urdf_geometry", "urdf_mount"]

#: The longest robot description read [characters].
MAX_URDF = 10_000_000


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF's ``rpy``: fixed-axis roll, pitch, yaw, ``Rz(yaw) Ry(pitch) Rx(roll)`` (3, 3)."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    out: np.ndarray = rz @ ry @ rx
    return out


def _numbers(text: str | None, what: str) -> tuple[float, float, float]:
    try:
        a, b, c = (float(v) for v in (text or "0 0 0").split())
    except ValueError:
        raise InputError(f"the robot description's {what} {text!r} is not three numbers") from None
    return a, b, c


def _urdf_joints(text: str) -> tuple[dict[str, tuple[str, np.ndarray, np.ndarray]], Any]:
    """The URDF's joints by child link: (parent, translation (3,), rotation (3, 3)), and
    the parsed document."""
    import xml.etree.ElementTree as ET

    if len(text) > MAX_URDF:
        raise InputError(f"the robot description is longer than {MAX_URDF} characters")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise InputError(f"the robot description is not a URDF ({exc})") from None
    joints: dict[str, tuple[str, np.ndarray, np.ndarray]] = {}
    for joint in root.iter("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            continue
        origin = joint.find("origin")
        xyz = _numbers(None if origin is None else origin.get("xyz"), "joint origin xyz")
        rpy = _numbers(None if origin is None else origin.get("rpy"), "joint origin rpy")
        joints[child.get("link", "")] = (
            parent.get("link", ""), np.asarray(xyz, dtype=np.float64), _rotation(*rpy),
        )  # fmt: skip
    return joints, root


def _in_base(
    joints: dict[str, tuple[str, np.ndarray, np.ndarray]], base: str, frame: str
) -> tuple[np.ndarray, np.ndarray] | None:
    """``frame``'s translation (3,) and rotation (3, 3) in ``base`` through the URDF's
    fixed chain (None: ``frame`` does not hang under ``base``)."""
    t, r = np.zeros(3), np.eye(3)
    link = frame
    for _ in range(len(joints) + 1):
        if link == base:
            return t, r
        joint = joints.get(link)
        if joint is None:
            return None
        parent, jt, jr = joint
        t, r = jt + jr @ t, jr @ r
        link = parent
    return None


def urdf_mount(text: str, base: str, frame: str) -> Mount | None:
    """A sensor frame's mounting in ``base`` from the robot description (URDF), as
    :func:`mount_from_transform` takes it from TF (None: the frame is not in it)."""
    joints, _root = _urdf_joints(text)
    found = _in_base(joints, base, frame)
    if found is None:
        return None
    t, r = found
    yaw = math.atan2(float(r[1, 0]), float(r[0, 0]))
    return Mount(Pose2D(float(t[0]), float(t[1]), yaw), upside_down=bool(r[2, 2] < 0.0))


def urdf_geometry(text: str, base: str = "base_link") -> tuple[float, float] | None:
    """The wheel separation and radius [m] from the robot description, as ros_controllers'
    diff_drive_controller takes them from it: the two wheel joints (names containing
    ``wheel``, under ``base``) farthest apart sideways, and the radius of the left wheel's
    cylinder (collision, else visual). None: no two such wheels."""
    joints, root = _urdf_joints(text)
    wheels = []
    for joint in root.iter("joint"):
        child = joint.find("child")
        if child is None or "wheel" not in joint.get("name", "").lower():
            continue
        link = child.get("link", "")
        found = _in_base(joints, base, link)
        if found is not None:
            wheels.append((float(found[0][1]), link))
    if len(wheels) < 2:
        return None
    wheels.sort()
    (y_right, _), (y_left, left) = wheels[0], wheels[-1]
    separation = y_left - y_right
    radius = None
    for link in root.iter("link"):
        if link.get("name") != left:
            continue
        for kind in ("collision", "visual"):
            cylinder = link.find(f"{kind}/geometry/cylinder")
            if cylinder is None:
                cylinder = link.find(f"{kind}/geometry/sphere")
            if cylinder is not None and cylinder.get("radius"):
                radius = float(cylinder.get("radius", "nan"))
                break
    if radius is None or not (radius > 0.0 and separation > 0.0):
        return None
    return separation, radius

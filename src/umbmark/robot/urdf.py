"""A robot's description (URDF) read without ROS: where its sensors are mounted and its
wheels' geometry, as a ROS 2 robot publishes it on ``/robot_description`` and a ROS 1 robot
keeps it in the ``robot_description`` parameter (for robots without tf2 at hand, and
controllers that take their geometry from it); and a mounting through static transforms
(``/tf_static`` without a tf2 buffer)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from umbmark.core.errors import InputError
from umbmark.robot.base import Pose2D
from umbmark.robot.ros_common import Mount, lift_of

__all__ = ["MAX_URDF", "static_mount", "urdf_footprint", "urdf_geometry", "urdf_mount"]

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
    return _mount(*found)


def _mount(t: np.ndarray, r: np.ndarray) -> Mount:
    """The planar mounting of a frame at ``t`` (3,) turned by ``r`` (3, 3) in the base:
    where its x axis points, and whether its z axis points down."""
    yaw = math.atan2(float(r[1, 0]), float(r[0, 0]))
    pose = Pose2D(float(t[0]), float(t[1]), yaw)
    return Mount(pose, upside_down=bool(r[2, 2] < 0.0), lift=lift_of(float(t[2]), r[2]))


def static_mount(
    edges: Mapping[str, tuple[str, Sequence[float], Sequence[float]]], base: str, frame: str
) -> Mount | None:
    """A sensor frame's mounting in ``base`` through static transforms, as ``/tf_static``
    holds them: ``edges`` maps each child frame to its parent, translation ``(x, y, z)``
    [m] and rotation quaternion ``(x, y, z, w)`` (None: ``frame`` does not hang under
    ``base`` by them)."""
    joints = {
        child: (parent, np.asarray(t, dtype=np.float64), _quaternion_matrix(q))
        for child, (parent, t, q) in edges.items()
    }
    found = _in_base(joints, base.lstrip("/"), frame.lstrip("/"))
    return None if found is None else _mount(*found)


def _quaternion_matrix(q: Sequence[float]) -> np.ndarray:
    """The rotation (3, 3) of a quaternion ``(x, y, z, w)`` (normalized here)."""
    x, y, z, w = (float(v) for v in q)
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def urdf_geometry(
    text: str,
    base: str = "base_link",
    left: Sequence[str] = (),
    right: Sequence[str] = (),
) -> tuple[float, float] | None:
    """The wheel separation and radius [m] from the robot description, as ros_controllers'
    diff_drive_controller takes them from it: the distance between the left and right wheel
    joints (``left``, ``right``: its ``left_wheel``/``right_wheel`` joint names; not given,
    the two joints with ``wheel`` in their names farthest apart sideways) and the radius of
    the left wheel's cylinder or sphere (collision, else visual). None: no such wheels."""
    joints, root = _urdf_joints(text)
    by_name = {}
    for joint in root.iter("joint"):
        child = joint.find("child")
        if child is not None:
            by_name[joint.get("name", "")] = child.get("link", "")
    placed = []
    for name, link in by_name.items():
        if left or right:
            if name not in (*left, *right):
                continue
        elif "wheel" not in name.lower():
            continue
        found = _in_base(joints, base, link)
        if found is not None:
            placed.append((name, link, found[0]))
    if left and right:
        lefts = [p for p in placed if p[0] in left]
        rights = [p for p in placed if p[0] in right]
    else:
        placed.sort(key=lambda p: float(p[2][1]))
        lefts, rights = placed[-1:], placed[:1]
    if not lefts or not rights or lefts[0][0] == rights[0][0]:
        return None
    (_, link, t_left), (_, _, t_right) = lefts[0], rights[0]
    separation = float(np.linalg.norm(t_left - t_right))
    radius = _radius(root, link)
    if radius is None or not (radius > 0.0 and separation > 0.0):
        return None
    return separation, radius


def _radius(root: Any, link_name: str) -> float | None:  # noqa: ANN401 (an ElementTree)
    """The radius of a link's cylinder or sphere (collision first), None: none."""
    for link in root.iter("link"):
        if link.get("name") != link_name:
            continue
        for kind in ("collision", "visual"):
            for shape in ("cylinder", "sphere"):
                found = link.find(f"{kind}/geometry/{shape}")
                if found is not None and found.get("radius"):
                    try:
                        return float(found.get("radius", "nan"))
                    except ValueError:
                        raise InputError(
                            f"the robot description's {link_name} radius is not a number"
                        ) from None
    return None


def urdf_footprint(text: str, base: str = "base_link") -> tuple[float, float, float] | None:
    """The robot's footprint from its description: the base link's collision (else
    visual) box or cylinder seen from above, as ``length, width, offset`` [m] (the
    outline's centre ``offset`` ahead of the base frame's origin; a cylinder: a square
    its diameter across). None: the base link has no box or cylinder."""
    _, root = _urdf_joints(text)
    for link in root.iter("link"):
        if link.get("name") != base:
            continue
        for kind in ("collision", "visual"):
            for element in link.findall(kind):
                found = _outline(element, base)
                if found is not None:
                    return found
    return None


def _outline(element: Any, base: str) -> tuple[float, float, float] | None:  # noqa: ANN401
    """A collision or visual element's box or cylinder: length, width, offset [m]."""
    origin = element.find("origin")
    x, _, _ = _numbers(None if origin is None else origin.get("xyz"), f"{base} origin")
    _, _, yaw = _numbers(None if origin is None else origin.get("rpy"), f"{base} origin")
    box = element.find("geometry/box")
    if box is not None:
        sx, sy, _ = _numbers(box.get("size"), f"{base} box size")
        c, s = abs(math.cos(yaw)), abs(math.sin(yaw))
        length, width = c * sx + s * sy, s * sx + c * sy  # its extent in the base frame
    else:
        cylinder = element.find("geometry/cylinder")
        if cylinder is None:
            return None
        try:
            length = width = 2.0 * float(cylinder.get("radius", "nan"))
        except ValueError:
            raise InputError(f"the robot description's {base} radius is not a number") from None
    if not (length > 0.0 and width > 0.0 and math.isfinite(length + width)):
        raise InputError(f"the robot description's {base} outline is not a positive size")
    return length, width, x

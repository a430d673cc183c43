"""The wheelbase and wheel diameter from a robot description (URDF) recorded in the bag.

ROS 2's ``robot_state_publisher`` publishes the URDF it was given on
``/robot_description`` (``std_msgs/String``, transient local: recorded once, at the
start); ROS 1 keeps it as a parameter, which bags do not hold, unless a node republishes
it. When a bag holds one, :func:`bag_robot_description` reads from it what the odometry
needs:

- the wheel joints: the two joints (or pairs of joints, averaged per side) of type
  ``continuous`` or ``revolute`` that the options name, else those whose names differ by
  left for right and hold ``wheel`` (casters left out);
- the wheelbase: the lateral distance between the left and right wheel joints' origins in
  the root link's frame (every joint's ``<origin xyz rpy>`` composed from the root down),
  ``mean y of the left wheels - mean y of the right wheels``;
- the wheel diameter: twice the radius of the wheel links' ``<cylinder>`` (their
  collision geometry, else their visual one; a ``<sphere>`` also serves), averaged;
- the mountings: every link fixed to the robot (a chain of ``fixed`` joints up to
  ``base_link`` or ``base_footprint``, else the root link), its pose ``x, y, yaw`` there
  (a laser's nominal mounting, for the scan matching's first guess).

Parsing is bounded: a description of more than :data:`MAX_URDF_CHARS` characters, or one
with a document type declaration or entities (which could expand without bound), is
refused before any parsing; the standard library's ``xml.etree`` parses the rest.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError, option
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.msgtypes import STRING, String
from umbmark.sources.bag.names import BASE_LINKS, mirrored_pairs

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = [
    "MAX_URDF_CHARS",
    "RobotDescription",
    "bag_robot_description",
    "described_geometry",
    "description_text",
    "description_topics",
    "fixed_joints",
    "parse_robot_description",
    "read_description",
    "robot_urdf",
]


#: Longest robot description read [characters] (a full robot with meshes named, not
#: embedded, is tens of kilobytes).
MAX_URDF_CHARS = 4_000_000
_DECLARATION = re.compile(r"<!\s*(DOCTYPE|ENTITY)", re.IGNORECASE)
_WHEEL_TYPES = ("continuous", "revolute")


@dataclass(frozen=True)
class RobotDescription:
    """What a robot description says about the wheels.

    Attributes
    ----------
    wheelbase : float
        Lateral distance between the left and right wheels [m].
    wheel_diameter : float or None
        Twice the wheels' radius [m]; None where a wheel link has no cylinder or sphere
        (a mesh only).
    left_joints, right_joints : tuple of str
        The wheel joints of each side.
    topic : str
        Where it came from (the bag's topic).
    mountings : dict of str to (float, float, float)
        The links fixed to the robot and their pose ``x, y, yaw`` [m, m, rad] in
        ``base_link`` or ``base_footprint`` (else the root link), of the link's frame
        right side up (its origin and x axis).
    name : str
        The robot's name (the URDF's ``<robot name>``; empty where it has none).
    """

    wheelbase: float
    wheel_diameter: float | None
    left_joints: tuple[str, ...]
    right_joints: tuple[str, ...]
    topic: str = ""
    mountings: Mapping[str, tuple[float, float, float]] = field(
        default_factory=dict, repr=False, compare=False
    )
    name: str = field(default="", compare=False)

    def describe(self) -> str:
        """``wheelbase 0.16 m and wheel diameter 0.066 m from /robot_description
        (joints wheel_left_joint, wheel_right_joint)`` for people."""
        joints = ", ".join((*self.left_joints, *self.right_joints))
        diameter = (
            f" and wheel diameter {self.wheel_diameter:.6g} m"
            if self.wheel_diameter is not None
            else " (no wheel diameter: the wheel links have no cylinder)"
        )
        return (
            f"wheelbase {self.wheelbase:.6g} m{diameter} from "
            f"{self.topic or 'the robot description'} (joints {joints})"
        )

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``wheelbase``, ``wheel_diameter`` [m], the joints and the topic."""
        return {
            "wheelbase": self.wheelbase,
            "wheel_diameter": self.wheel_diameter,
            "left_joints": list(self.left_joints),
            "right_joints": list(self.right_joints),
            "topic": self.topic,
        }


def _numbers(text: str | None, count: int, what: str) -> list[float]:
    parts = (text or "").split()
    if not parts:
        return [0.0] * count
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"{what} {text!r:.60} is not {count} numbers") from None
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ValueError(f"{what} {text!r:.60} is not {count} finite numbers")
    return values


def _rotation(rpy: list[float]) -> FloatArray:
    """URDF's ``rpy``: roll about x, then pitch about y, then yaw about z (fixed axes)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


@dataclass(frozen=True)
class _Joint:
    name: str
    kind: str
    parent: str
    child: str
    xyz: list[float]
    rpy: list[float]


def _radius(link: ET.Element) -> float | None:
    """The radius [m] of a link's cylinder (or sphere): collision first, then visual."""
    for part in ("collision", "visual"):
        for element in link.findall(part):
            for shape in ("cylinder", "sphere"):
                found = element.find(f"geometry/{shape}")
                if found is not None:
                    radius = _numbers(found.get("radius"), 1, f"the radius of {shape}")[0]
                    if radius > 0:
                        return radius
    return None


def _parse(text: str) -> ET.Element:
    """The URDF's ``<robot>`` element, parsed within the bounds (module notes)."""
    if len(text) > MAX_URDF_CHARS:
        raise ValueError(f"is longer than {MAX_URDF_CHARS:,} characters")
    if _DECLARATION.search(text):
        raise ValueError("declares a document type or entities, which are not read")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as err:
        raise ValueError(f"is not valid XML: {err}") from None
    if root.tag != "robot":
        raise ValueError(f"is not a URDF (its root element is <{root.tag:.40}>, not <robot>)")
    return root


def _joints(root: ET.Element) -> dict[str, _Joint]:
    """Every joint of the URDF by name, with its origin."""
    joints: dict[str, _Joint] = {}
    for element in root.findall("joint"):
        origin = element.find("origin")
        name = element.get("name", "")
        parent, child = element.find("parent"), element.find("child")
        joints[name] = _Joint(
            name=name,
            kind=element.get("type", ""),
            parent="" if parent is None else parent.get("link", ""),
            child="" if child is None else child.get("link", ""),
            xyz=_numbers(None if origin is None else origin.get("xyz"), 3, f"joint {name} xyz"),
            rpy=_numbers(None if origin is None else origin.get("rpy"), 3, f"joint {name} rpy"),
        )
    return joints


def fixed_joints(text: str) -> dict[str, tuple[str, FloatArray]]:
    """The links a ``fixed`` joint holds to another, each with that parent link and its
    rotation there, shape (3, 3) (its axes in the parent's: the joint's ``rpy``).

    Raises
    ------
    ValueError
        The text is too long, declares entities, or is no URDF.
    """
    joints = _joints(_parse(text)).values()
    return {j.child: (j.parent, _rotation(j.rpy)) for j in joints if j.kind == "fixed"}


def parse_robot_description(
    text: str,
    left: tuple[str, ...] = (),
    right: tuple[str, ...] = (),
    source: str = "",
) -> RobotDescription:
    """The wheels of a URDF (see the module docstring).

    Parameters
    ----------
    text : str
        The URDF.
    left, right : tuple of str
        The wheel joints of each side; empty: found by their names.
    source : str
        Where the text came from, for the result and messages.

    Raises
    ------
    ValueError
        The text is too long, declares entities, is no URDF, or its wheels cannot be
        told (the message says why).
    """
    root = _parse(text)
    links = {link.get("name", ""): link for link in root.findall("link")}
    joints = _joints(root)
    left, right = _wheel_joints(joints, links, left, right)
    by_child = {j.child: j for j in joints.values()}

    def position(joint: _Joint) -> FloatArray:
        """The joint's origin in the root link's frame, shape (3,)."""
        point = np.array(joint.xyz)
        above = by_child.get(joint.parent)
        seen = {joint.name}
        while above is not None and above.name not in seen:
            seen.add(above.name)
            point = _rotation(above.rpy) @ point + np.array(above.xyz)
            above = by_child.get(above.parent)
        return point

    y_left = float(np.mean([position(joints[n])[1] for n in left]))
    y_right = float(np.mean([position(joints[n])[1] for n in right]))
    wheelbase = y_left - y_right
    if not wheelbase > 0:
        raise ValueError(
            f"puts the left wheel joints ({', '.join(left)}) at y = {y_left:.4g} m, not left "
            f"of the right ones ({', '.join(right)}, y = {y_right:.4g} m)"
        )
    radii = []
    for name in (*left, *right):
        link = links.get(joints[name].child)
        radii.append(None if link is None else _radius(link))
    known = [r for r in radii if r is not None]
    diameter = 2.0 * float(np.mean(known)) if len(known) == len(radii) else None
    return RobotDescription(
        wheelbase, diameter, left, right, source, _mountings(joints, by_child),
        str(root.get("name", ""))[:200],
    )  # fmt: skip


def _mountings(
    joints: dict[str, _Joint], by_child: dict[str, _Joint]
) -> dict[str, tuple[float, float, float]]:
    """The links fixed to the robot and their planar poses (:class:`RobotDescription`)."""
    out: dict[str, tuple[float, float, float]] = {}
    for joint in joints.values():
        rotation, point = np.eye(3), np.zeros(3)
        at: _Joint | None = joint
        seen: set[str] = set()
        while at is not None and at.kind == "fixed" and at.name not in seen:
            seen.add(at.name)
            turn = _rotation(at.rpy)
            point, rotation = turn @ point + np.array(at.xyz), turn @ rotation
            at = None if at.parent in BASE_LINKS else by_child.get(at.parent)
        if at is None and seen:  # every joint up the chain is fixed
            yaw = math.atan2(float(rotation[1, 0]), float(rotation[0, 0]))
            out[joint.child] = (float(point[0]), float(point[1]), yaw)
    return out


def _wheel_joints(
    joints: dict[str, _Joint],
    links: dict[str, ET.Element],
    left: tuple[str, ...],
    right: tuple[str, ...],
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The wheel joints of each side: as named, else found by their names."""
    if left and right:
        for name in (*left, *right):
            if name not in joints:
                raise ValueError(f"has no joint {name}")
        return left, right
    rotating = [
        name
        for name, joint in joints.items()
        if joint.kind in _WHEEL_TYPES and "caster" not in name.lower()
    ]
    pairs = [
        (a, b) for a, b in mirrored_pairs(rotating) if "wheel" in a.lower() and "wheel" in b.lower()
    ]
    if not pairs:
        shown = ", ".join(rotating[:10]) or "none"
        raise ValueError(
            f"has no left and right wheel joints that tell themselves apart (rotating joints: "
            f"{shown})"
        )
    return tuple(a for a, _ in pairs), tuple(b for _, b in pairs)


def description_topics(topics: dict[str, str]) -> list[str]:
    """The topics of a bag that may hold its robot description."""
    return [
        name
        for name, msgtype in topics.items()
        if msgtype == STRING and name.rstrip("/").rsplit("/", 1)[-1] == "robot_description"
    ]


def read_description(
    reader: AnyReader,
    topics: dict[str, str],
    src: str,
    left: tuple[str, ...] = (),
    right: tuple[str, ...] = (),
) -> tuple[RobotDescription | None, str | None]:
    """What :func:`bag_robot_description` returns, from the open bag."""
    found = description_topics(topics)
    if not found:
        return None, None
    text = _read_text(reader, topics, found[0], src)
    if text is None:
        return None, f"{found[0]} holds no description"
    try:
        return parse_robot_description(text, left, right, found[0]), None
    except ValueError as err:
        return None, f"the robot description on {found[0]} {err}"


def description_text(reader: AnyReader, topics: dict[str, str], src: str) -> tuple[str, str] | None:
    """The bag's robot description: its topic and text (the last non-empty one, bounded),
    or None where it holds none."""
    found = description_topics(topics)
    text = None if not found else _read_text(reader, topics, found[0], src)
    return None if text is None else (found[0], text)


def _read_text(reader: AnyReader, topics: dict[str, str], topic: str, src: str) -> str | None:
    """The last non-empty description on ``topic`` (bounded), or None."""
    conns = [c for c in reader.connections if c.topic == topic]
    text: str | None = None
    for _, raw in bag_reader.raw_messages(reader, conns, topic, src):
        if len(raw) > MAX_URDF_CHARS * 4 + 16:
            raise InputError(
                f"the robot description on {topic} is longer than {MAX_URDF_CHARS:,} characters",
                source=src,
            )
        msg: String = bag_reader.deserialize(reader, raw, topics[topic], topic, src)  # type: ignore[assignment]
        if str(msg.data).strip():
            text = str(msg.data)
    return text


def bag_robot_description(
    path: str | Path, left: tuple[str, ...] = (), right: tuple[str, ...] = ()
) -> tuple[RobotDescription | None, str | None]:
    """The wheels of the robot description a bag holds.

    Returns
    -------
    description : RobotDescription or None
        None when the bag holds none, or it does not say the wheels.
    problem : str or None
        Why not, when the bag holds a description that does not say the wheels.

    Raises
    ------
    InputError
        The bag cannot be read.
    """
    src = str(path)
    with bag_reader.open_bag(Path(path), src) as reader:
        return read_description(reader, bag_reader.topic_types(reader), src, left, right)


def described_geometry(
    path: str | Path,
    left: tuple[str, ...],
    right: tuple[str, ...],
    wheelbase: float | None,
    diameter: float | None,
) -> tuple[float, float, str]:
    """The wheelbase and wheel diameter [m] not given, from the bag's robot description,
    and a note saying where they came from.

    Parameters
    ----------
    path : path
        The bag.
    left, right : tuple of str
        The wheel joints, if named (else found by their names).
    wheelbase, diameter : float or None
        What the options give; None: from the description.

    Raises
    ------
    InputError
        The bag holds no description that says them.
    """
    src = str(path)
    description, problem = bag_robot_description(path, left, right)
    if description is None or (diameter is None and description.wheel_diameter is None):
        why = (
            f"; {problem}"
            if problem
            else "; the bag holds no robot_description"
            if description is None
            else f"; its robot description gives no wheel diameter ({description.describe()})"
        )
        raise InputError(
            f"a bag needs the wheel parameters: give {option('wheelbase')} and "
            f"{option('wheel_diameter')} (or {option('current_params')} with wheel_separation "
            f"and wheel_radius){why}",
            source=src,
        )
    taken = [
        label
        for label, value in (("wheelbase", wheelbase), ("wheel diameter", diameter))
        if value is None
    ]
    from umbmark.core.messages import info

    note = info(
        f"{' and '.join(taken)} from the bag's robot description: "
        f"{description.describe()} (give --wheelbase / --wheel-diameter to override)"
    )
    chosen = diameter if diameter is not None else description.wheel_diameter
    assert chosen is not None
    return (description.wheelbase if wheelbase is None else wheelbase), chosen, note


def robot_urdf(
    wheelbase: float,
    wheel_diameter: float,
    laser_pose: tuple[float, float, float] | None,
    joints: tuple[str, str] = ("left_wheel_joint", "right_wheel_joint"),
    laser_frame: str = "laser",
    name: str = "umbmark_simulated",
    imu: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None,
    imu_frame: str = "imu_link",
) -> str:
    """A differential-drive robot's URDF, as a bag's ``/robot_description`` holds it: the
    wheels ``joints`` (left, right) ``wheelbase`` [m] apart with cylinders of
    ``wheel_diameter`` [m], the laser ``laser_frame`` at ``laser_pose`` ``x, y, yaw``
    [m, m, rad] on ``base_link`` (none where None), and the IMU ``imu_frame`` at ``imu``
    ``(xyz [m], rpy [rad])`` where given (the wheels and mountings
    :func:`parse_robot_description` and :func:`fixed_joints` read back); the robot called
    ``name``."""
    half, radius = 0.5 * wheelbase, 0.5 * wheel_diameter
    links = [name.removesuffix("_joint") + "_link" for name in joints]
    wheels = "".join(
        f'<joint name="{name}" type="continuous"><parent link="base_link"/>'
        f'<child link="{link}"/><origin xyz="0 {side * half!r} 0" rpy="{-math.pi / 2!r} 0 0"/>'
        f'<axis xyz="0 0 1"/></joint><link name="{link}"><collision><geometry>'
        f'<cylinder length="0.02" radius="{radius!r}"/></geometry></collision></link>\n'
        for name, link, side in zip(joints, links, (1.0, -1.0), strict=True)
    )
    mounted = []
    if laser_pose is not None:
        x, y, yaw = laser_pose
        mounted.append((laser_frame, (x, y, 0.2), (0.0, 0.0, yaw)))
    if imu is not None:
        mounted.append((imu_frame, *imu))
    fixed = "".join(
        f'<joint name="{frame}_joint" type="fixed"><parent link="base_link"/>'
        f'<child link="{frame}"/><origin xyz="{" ".join(map(repr, map(float, xyz)))}" '
        f'rpy="{" ".join(map(repr, map(float, rpy)))}"/></joint><link name="{frame}"/>\n'
        for frame, xyz, rpy in mounted
    )
    return (
        f'<?xml version="1.0"?>\n<robot name="{name}">\n<link name="base_link"/>\n'
        f"{wheels}{fixed}</robot>\n"
    )

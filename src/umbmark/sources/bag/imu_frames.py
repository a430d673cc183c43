"""Where a bag's IMU is mounted: the rotation of its frame into the robot's base frame.

An IMU's readings are in its own frame (``header.frame_id``, ``imu_link``); the
calibration needs them in the base frame (``base_link``, else ``base_footprint``:
:data:`~umbmark.sources.bag.names.BASE_LINKS`). :func:`imu_mounting` finds the chain of
transforms between the two and composes their rotations, in 3D (an IMU mounted tilted,
turned about z, or upside down), from, in this order:

1. ``/tf_static`` (every transform of it, read whole);
2. ``/tf``, where the chain is not complete without it: the transforms that do not move
   in its first :data:`MAX_TF_MESSAGES` messages (of the window read), as an older
   ``robot_state_publisher`` publishes fixed joints;
3. the recorded robot description (``/robot_description``): its ``fixed`` joints
   (:func:`umbmark.sources.bag.urdf.fixed_joints`).

A transform of an earlier source is kept where a later one states it too. The chain may
go through other links (``imu_link -> chassis -> base_link``) and walk a transform
backwards (``chassis -> imu_link`` beside ``chassis -> base_link``). A frame with no
chain to a base frame is one line naming the bag, the topic, the frame and the frames
the bag has.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.msgtypes import TF_STATIC_TOPIC, TF_TOPIC, TF_TYPES, TFMessage
from umbmark.sources.bag.names import BASE_LINKS
from umbmark.sources.bag.urdf import description_text, fixed_joints

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = [
    "MAX_TF_MESSAGES",
    "Edges",
    "ImuMounting",
    "imu_mounting",
    "mounting_in",
    "quaternion_matrix",
]

#: ``/tf`` messages looked into at most for transforms that do not move.
MAX_TF_MESSAGES = 5000
#: Frames held at most (a robot with many links has hundreds).
_MAX_FRAMES = 10_000

#: Transforms by ``(parent, child)``: the child's axes in the parent's, shape (3, 3), and
#: where it was stated (``/tf_static``, a topic, the robot description).
Edges = dict[tuple[str, str], tuple[FloatArray, str]]
_Edges = Edges


@dataclass(frozen=True)
class ImuMounting:
    """An IMU frame's orientation in the robot's base frame.

    Attributes
    ----------
    frame, base : str
        The IMU's frame and the base frame.
    rotation : array, shape (3, 3)
        The IMU's axes in the base frame's: ``v_base = rotation @ v_imu``.
    source : str
        Where the chain was stated (``/tf_static``, ``/tf``, ``/robot_description``), for
        people.
    """

    frame: str
    base: str
    rotation: FloatArray
    source: str

    @property
    def rpy(self) -> tuple[float, float, float]:
        """Roll, pitch, yaw [rad] (fixed axes x, y, z: the URDF's ``rpy``; pitch within
        +-90 degrees)."""
        r = self.rotation
        return (
            math.atan2(float(r[2, 1]), float(r[2, 2])),
            math.atan2(-float(r[2, 0]), math.hypot(float(r[2, 1]), float(r[2, 2]))),
            math.atan2(float(r[1, 0]), float(r[0, 0])),
        )

    @property
    def upside_down(self) -> bool:
        """Its z axis points down in the base frame."""
        return float(self.rotation[2, 2]) < 0.0

    def describe(self) -> str:
        """``imu_link in base_link (/tf_static): roll 0.00, pitch 1.00, yaw 90.00 deg``."""
        roll, pitch, yaw = (
            math.degrees(a) if abs(math.degrees(a)) >= 0.005 else 0.0 for a in self.rpy
        )
        down = ", upside down" if self.upside_down else ""
        return (
            f"{self.frame} in {self.base} ({self.source}): roll {roll:.2f}, pitch "
            f"{pitch:.2f}, yaw {yaw:.2f} deg{down}"
        )


def quaternion_matrix(x: float, y: float, z: float, w: float) -> FloatArray | None:
    """The rotation of the quaternion ``x, y, z, w`` (normalized here), shape (3, 3); None
    for one that is no rotation (zero or not finite)."""
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not (math.isfinite(norm) and norm > 1e-9):
        return None
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def imu_mounting(
    reader: AnyReader, topics: dict[str, str], frame: str, topic: str, src: str
) -> ImuMounting:
    """The mounting of the IMU whose readings are in ``frame`` (module notes).

    Raises
    ------
    InputError
        ``frame`` is empty, or has no chain of transforms to a base frame.
    """
    frame = frame.lstrip("/")
    if frame in BASE_LINKS:
        return ImuMounting(frame, frame, np.eye(3), "the IMU's own frame")
    edges: _Edges = {}
    problems: list[str] = []
    found = None
    for add in (_static_edges, _tf_edges, _urdf_edges):
        add(reader, topics, src, edges, problems)
        found = mounting_in(edges, frame) if frame else None
        if found is not None:
            break
    if found is None:
        frames = sorted({name for pair in edges for name in pair})
        known = (
            f"frames in the bag: {bag_reader.listing(frames)}"
            if frames
            else "the bag has no transforms"
        )
        why = "".join(f"; {p}" for p in problems)
        if not frame:
            raise InputError(
                f"{topic}: the IMU's messages name no frame (header.frame_id is empty), so "
                f"its mounting is unknown; {known}{why}",
                source=src,
            )
        raise InputError(
            f"{topic}: the IMU's frame {frame} has no transform to "
            f"{' or '.join(BASE_LINKS)} (on /tf_static, /tf or in the robot description): "
            f"publish its mounting on /tf_static; {known}{why}",
            source=src,
        )
    return found


def mounting_in(edges: Edges, frame: str, bases: Sequence[str] = BASE_LINKS) -> ImuMounting | None:
    """The mounting of ``frame`` in the nearest of ``bases`` through the transforms
    ``edges`` (module notes: the chain may pass other links and walk a transform
    backwards); None where no chain joins them. What the bag reader and a live robot's
    IMU (:mod:`umbmark.robot.ros_imu`) share."""
    frame = frame.lstrip("/")
    if frame in bases:
        return ImuMounting(frame, frame, np.eye(3), "the IMU's own frame")
    found = _chain(edges, frame, bases) if frame else None
    if found is None:
        return None
    base, rotation, sources = found
    return ImuMounting(frame, base, rotation, ", ".join(sources))


def _chain(
    edges: _Edges, frame: str, bases: Sequence[str] = BASE_LINKS
) -> tuple[str, FloatArray, list[str]] | None:
    """The nearest of ``bases`` to ``frame`` through ``edges`` (walked either way), the
    rotation of ``frame`` in it, and the sources of the transforms on the way."""
    neighbours: dict[str, list[tuple[str, FloatArray, str]]] = {}
    for (parent, child), (rotation, source) in edges.items():
        # from the child up to the parent: R_parent_child; down: its transpose
        neighbours.setdefault(child, []).append((parent, rotation, source))
        neighbours.setdefault(parent, []).append((child, rotation.T, source))
    previous: dict[str, tuple[str, FloatArray, str] | None] = {frame: None}
    queue = deque([frame])
    while queue:
        at = queue.popleft()
        if at in bases:
            rotation, sources = np.eye(3), []
            node = at
            while (step := previous[node]) is not None:
                below, turn, source = step
                rotation = rotation @ turn  # R_base_below = R_base_node R_node_below
                if source not in sources:
                    sources.append(source)
                node = below
            return at, rotation, sources
        for nxt, turn, source in neighbours.get(at, []):
            if nxt not in previous:
                previous[nxt] = (at, turn, source)
                queue.append(nxt)
    return None


def _transforms(
    reader: AnyReader, topics: dict[str, str], topic: str, src: str, most: int | None
) -> list[tuple[str, str, FloatArray | None]]:
    """``(parent, child, rotation or None)`` of every transform in the first ``most``
    messages of ``topic`` (all: None), in their order."""
    msgtype = topics.get(topic)
    if msgtype not in TF_TYPES:
        return []
    conns = [c for c in reader.connections if c.topic == topic]
    out: list[tuple[str, str, FloatArray | None]] = []
    stream = bag_reader.raw_messages(reader, conns, topic, src)
    try:
        for k, (_, raw) in enumerate(stream):
            if most is not None and k >= most:
                break
            msg: TFMessage = bag_reader.deserialize(reader, raw, msgtype, topic, src)  # type: ignore[assignment]
            for tf in msg.transforms:
                q = tf.transform.rotation
                rotation = quaternion_matrix(float(q.x), float(q.y), float(q.z), float(q.w))
                out.append(
                    (tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/"), rotation)
                )
            if len(out) > 50 * _MAX_FRAMES:
                break
    finally:
        stream.close()
    return out


def _static_edges(
    reader: AnyReader, topics: dict[str, str], src: str, edges: _Edges, problems: list[str]
) -> None:
    """Every transform of ``/tf_static`` into ``edges`` (a later one of a pair wins)."""
    for parent, child, rotation in _transforms(reader, topics, TF_STATIC_TOPIC, src, None):
        if rotation is not None and len(edges) < _MAX_FRAMES:
            edges[(parent, child)] = (rotation, TF_STATIC_TOPIC)


def _tf_edges(
    reader: AnyReader, topics: dict[str, str], src: str, edges: _Edges, problems: list[str]
) -> None:
    """The transforms of ``/tf`` that do not move (module notes) into ``edges``, where
    ``/tf_static`` does not state them."""
    first: dict[tuple[str, str], FloatArray] = {}
    moving: set[tuple[str, str]] = set()
    for parent, child, rotation in _transforms(reader, topics, TF_TOPIC, src, MAX_TF_MESSAGES):
        pair = (parent, child)
        if rotation is None or pair in moving:
            continue
        if pair not in first:
            first[pair] = rotation
        elif not np.allclose(first[pair], rotation, atol=1e-9, rtol=0.0):
            moving.add(pair)
    for pair, rotation in first.items():
        if pair not in moving and pair not in edges and len(edges) < _MAX_FRAMES:
            edges[pair] = (rotation, TF_TOPIC)


def _urdf_edges(
    reader: AnyReader, topics: dict[str, str], src: str, edges: _Edges, problems: list[str]
) -> None:
    """The fixed joints of the recorded robot description into ``edges``, where the
    transform topics do not state their child; why not into ``problems``."""
    found = description_text(reader, topics, src)
    if found is None:
        return
    topic, text = found
    try:
        joints = fixed_joints(text)
    except ValueError as err:
        problems.append(f"the robot description on {topic} {err}")
        return
    children = {child for _, child in edges}
    for child, (parent, rotation) in joints.items():
        if child not in children and len(edges) < _MAX_FRAMES:
            edges[(parent, child)] = (rotation, topic)

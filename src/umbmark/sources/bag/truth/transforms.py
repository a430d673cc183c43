"""Planar transforms from ``/tf`` and ``/tf_static``, chained between any two frames.

A ground truth or an odometry often comes as a chain of transforms: ``map -> odom`` from
a localization (AMCL), ``odom -> base_link`` from the controller, ``world -> marker``
from motion capture with a static ``marker -> base_link``. Every transform of the bag is
read into an :class:`Edge` (its own time series, or one value if static), the path of
edges between the two frames is found in the frame tree (edges walked either way), and
the chain is composed at the sample times of its most frequent dynamic edge, the others
interpolated linearly in time (headings unwrapped) and the chain kept to the span they
all cover. Poses are planar: ``x, y`` of the translation and the yaw of the rotation.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.core.geometry import compose, invert, quaternion_yaw
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.msgtypes import TF_STATIC_TOPIC, TF_TOPIC, TF_TYPES, TFMessage

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = ["MAX_TRANSFORMS", "Edge", "chain_poses", "chain_steps", "read_edges"]

#: Transform messages read at most: about a day of 100 Hz TF with ten frames.
MAX_TRANSFORMS = 50_000_000


@dataclass(frozen=True)
class Edge:
    """One transform ``parent -> child`` over time.

    Attributes
    ----------
    parent, child : str
        Frame names (leading slashes removed).
    time : array, shape (k,)
        Stamps [s], strictly increasing (one sample for a static transform).
    poses : array, shape (k, 3)
        ``x, y`` [m] and yaw [rad] (unwrapped) of the child in the parent frame.
    static : bool
        From ``/tf_static`` (one value for all time).
    """

    parent: str
    child: str
    time: FloatArray
    poses: FloatArray
    static: bool

    def at(self, time: FloatArray) -> FloatArray:
        """The transform at ``time`` (shape (n,)), linearly interpolated, shape (n, 3)."""
        if self.static or self.time.size == 1:
            return np.repeat(self.poses[:1], time.size, axis=0)
        return np.column_stack([np.interp(time, self.time, self.poses[:, k]) for k in range(3)])


def _yaw(qx: float, qy: float, qz: float, qw: float) -> float:
    norm = float(np.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)) or 1.0
    return float(quaternion_yaw(qx / norm, qy / norm, qz / norm, qw / norm))


def read_edges(
    reader: AnyReader, topics: dict[str, str], src: str, *, header: bool = True
) -> dict[tuple[str, str], Edge]:
    """Every transform on ``/tf`` and ``/tf_static``, by ``(parent, child)``.

    Raises
    ------
    InputError
        If the bag has neither topic, or a message cannot be read.
    """
    samples: dict[tuple[str, str], list[tuple[float, float, float, float]]] = {}
    static: set[tuple[str, str]] = set()
    present = [t for t in (TF_TOPIC, TF_STATIC_TOPIC) if t in topics]
    if not present:
        raise InputError(
            f"has no /tf or /tf_static topic; topics present: {bag_reader.listing(sorted(topics))}",
            source=src,
        )
    count = 0
    for topic in present:
        msgtype = topics[topic]
        if msgtype not in TF_TYPES:
            raise InputError(
                f"topic {topic} has messages of type {msgtype}, not tf2_msgs/msg/TFMessage",
                source=src,
            )
        conns = [c for c in reader.connections if c.topic == topic]
        for bag_ns, raw in bag_reader.messages(reader, conns, topic, src):
            msg: TFMessage = bag_reader.deserialize(reader, raw, msgtype, topic, src)  # type: ignore[assignment]
            for tf in msg.transforms:
                count += 1
                if count > MAX_TRANSFORMS:
                    raise InputError(
                        f"holds more than {MAX_TRANSFORMS:,} transforms: cut the recording "
                        "to the runs first (ros2 bag convert, rosbag filter)",
                        source=src,
                    )
                pair = (tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/"))
                stamp = tf.header.stamp
                t = int(stamp.sec) + int(stamp.nanosec) * 1e-9 if header else bag_ns * 1e-9
                tr, q = tf.transform.translation, tf.transform.rotation
                samples.setdefault(pair, []).append(
                    (
                        t,
                        float(tr.x),
                        float(tr.y),
                        _yaw(float(q.x), float(q.y), float(q.z), float(q.w)),
                    )
                )
                if topic == TF_STATIC_TOPIC:
                    static.add(pair)
    edges = {}
    for pair, values in samples.items():
        array = np.array(values, dtype=np.float64)
        array = array[np.all(np.isfinite(array), axis=1)]
        if array.shape[0] == 0:
            continue
        array = array[np.argsort(array[:, 0], kind="stable")]
        keep = np.ones(array.shape[0], np.bool_)
        keep[1:] = np.diff(array[:, 0]) > 0
        array = array[keep]
        poses = array[:, 1:].copy()
        poses[:, 2] = np.unwrap(poses[:, 2])
        edges[pair] = Edge(pair[0], pair[1], array[:, 0], poses, pair in static)
    return edges


def _path(
    edges: dict[tuple[str, str], Edge], parent: str, child: str
) -> list[tuple[Edge, bool]] | None:
    """The edges from ``parent`` to ``child`` (each with whether it is walked backwards)."""
    neighbours: dict[str, list[tuple[str, Edge, bool]]] = {}
    for edge in edges.values():
        neighbours.setdefault(edge.parent, []).append((edge.child, edge, False))
        neighbours.setdefault(edge.child, []).append((edge.parent, edge, True))
    previous: dict[str, tuple[str, Edge, bool] | None] = {parent: None}
    queue = deque([parent])
    while queue:
        frame = queue.popleft()
        if frame == child:
            break
        for nxt, edge, backwards in neighbours.get(frame, []):
            if nxt not in previous:
                previous[nxt] = (frame, edge, backwards)
                queue.append(nxt)
    if child not in previous:
        return None
    steps: list[tuple[Edge, bool]] = []
    frame = child
    while (link := previous[frame]) is not None:
        frame, edge, backwards = link
        steps.append((edge, backwards))
    return steps[::-1]


def chain_steps(
    edges: dict[tuple[str, str], Edge], parent: str, child: str
) -> list[tuple[Edge, bool]] | None:
    """The transforms from ``parent`` to ``child`` (each with whether it is walked
    backwards), or None if the frames are not connected."""
    return _path(edges, parent.lstrip("/"), child.lstrip("/"))


def chain_poses(
    edges: dict[tuple[str, str], Edge], parent: str, child: str, src: str
) -> tuple[FloatArray, FloatArray]:
    """The pose of ``child`` in ``parent`` through the frame tree.

    Returns
    -------
    time : array, shape (n,)
        The samples of the chain's most frequent dynamic edge inside the span every
        dynamic edge covers [s].
    poses : array, shape (n, 3)
        ``x, y`` [m], yaw [rad] (unwrapped).

    Raises
    ------
    InputError
        If the frames are not connected, or the chain holds no moving transform.
    """
    parent, child = parent.lstrip("/"), child.lstrip("/")
    steps = _path(edges, parent, child)
    if steps is None:
        pairs = [f"{p}->{c}" for p, c in sorted(edges)]
        raise InputError(
            f"no chain of transforms from {parent} to {child} in /tf; parent->child pairs "
            f"present: {bag_reader.listing(pairs) if pairs else 'none'}",
            source=src,
        )
    dynamic = [edge for edge, _ in steps if not edge.static and edge.time.size > 1]
    if not dynamic:
        raise InputError(f"the transforms from {parent} to {child} never move", source=src)
    start = max(float(edge.time[0]) for edge in dynamic)
    end = min(float(edge.time[-1]) for edge in dynamic)
    base = max(dynamic, key=lambda edge: edge.time.size)
    time = base.time[(base.time >= start) & (base.time <= end)]
    if time.size < 2:
        raise InputError(
            f"the transforms from {parent} to {child} do not overlap in time",
            source=src,
        )
    poses = np.zeros((time.size, 3))
    for edge, backwards in steps:
        value = edge.at(time)
        poses = compose(poses, invert(value) if backwards else value)
    return time, poses

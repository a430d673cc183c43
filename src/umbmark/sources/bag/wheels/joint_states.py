"""Wheel rotation from ``sensor_msgs/JointState``: the wheel joints' positions (or their
velocities, integrated), named by the options or found in the messages
(:mod:`umbmark.sources.bag.bag_options` says what is read).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.model.recording import WheelSeries
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.bag_options import DEFAULT_JOINTS, BagOptions
from umbmark.sources.bag.fastpath import POSITION, VELOCITY, Decoded, Sample, fast_layout
from umbmark.sources.bag.msgtypes import JOINT_STATE, JointState
from umbmark.sources.bag.samples import clean, read_topic, stamp, time_ns

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = ["MAX_INSPECTED", "MOVING", "read_joint_states", "wheel_joints"]

#: Joint states inspected to find the wheel joints, at most.
MAX_INSPECTED = 2_000
#: Rotation [rad] over the recording above which a joint counts as moving.
MOVING = 1.0


def wheel_joints(
    reader: AnyReader, conns: Sequence[Connection], msgtype: str, topic: str, src: str
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The wheel joints of a joint-states topic, when the options do not name them.

    ``left_wheel_joint`` and ``right_wheel_joint`` if present; else the joints that move
    (turn more than :data:`MOVING` rad over up to :data:`MAX_INSPECTED` messages spread
    over the recording), split by ``left`` and ``right`` in their names: one or more per
    side (a skid-steer's four wheels are averaged per side).

    Raises
    ------
    InputError
        The moving joints do not split into left and right; the message names them.
    """
    stride = max(1, bag_reader.message_count(conns) // MAX_INSPECTED)
    low: dict[str, float] = {}
    high: dict[str, float] = {}
    for k, (_, raw) in enumerate(bag_reader.messages(reader, conns, topic, src)):
        if k % stride:
            continue
        msg: JointState = bag_reader.deserialize(reader, raw, msgtype, topic, src)  # type: ignore[assignment]
        names = list(msg.name)
        if set(DEFAULT_JOINTS) <= set(names):
            return (DEFAULT_JOINTS[0],), (DEFAULT_JOINTS[1],)
        values = msg.position if len(msg.position) == len(names) else ()
        for name, value in zip(names, values, strict=False):
            if math.isfinite(value):
                low[name] = min(low.get(name, value), float(value))
                high[name] = max(high.get(name, value), float(value))
    moving = sorted(name for name in low if high[name] - low[name] > MOVING)
    left = tuple(name for name in moving if "left" in name.lower())
    right = tuple(name for name in moving if "right" in name.lower())
    if left and right and not set(left) & set(right) and len(left) + len(right) == len(moving):
        return left, right
    present = bag_reader.listing(moving) if moving else "none"
    raise InputError(
        f"which joints of {topic} are the wheels? give {option('left_joint')} and "
        f"{option('right_joint')} "
        f"(or a controller file with left_wheel_names); joints that move: {present}",
        source=src,
    )


def read_joint_states(
    reader: AnyReader,
    topics: dict[str, str],
    options: BagOptions,
    src: str,
) -> WheelSeries:
    """Wheel rotation from the joints of ``options.wheel_topic`` (named, or found by
    :func:`wheel_joints`); several joints per side are averaged per side.

    Raises
    ------
    InputError
        The topic or a joint is missing, the joints never appear together, or the
        messages mix positions with velocities.
    """
    topic = options.wheel_topic
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (JOINT_STATE,), "wheel joint states", src
    )
    left, right = options.left_joints, options.right_joints
    named = bool(left and right)
    if not named:
        left, right = left or DEFAULT_JOINTS[:1], right or DEFAULT_JOINTS[1:]
    scan, seen = _scan_joints(reader, conns, msgtype, topic, src, left, right)
    if scan.values.shape[0] == 0 and not named:
        found = wheel_joints(reader, conns, msgtype, topic, src)
        left = options.left_joints or found[0]
        right = options.right_joints or found[1]
        scan, seen = _scan_joints(reader, conns, msgtype, topic, src, left, right)
    joints = left + right
    if scan.values.shape[0] == 0:
        missing = [name for name in joints if name not in seen]
        present = bag_reader.listing(sorted(seen)) if seen else "none"
        if missing:
            raise InputError(
                f"no joint {_quoted(missing)} in {topic}; joints present: {present}", source=src
            )
        raise InputError(
            f"the joints {_quoted(joints)} never appear in the same message of {topic}",
            source=src,
        )
    header = options.time_source == "header"
    kinds = np.unique(scan.kind)
    if kinds.size > 1:
        raise InputError(
            f"{topic} mixes messages with wheel positions and messages with only velocities",
            source=src,
        )
    # several wheels per side: their mean, as ros2_control's diff_drive_controller takes
    per_side = np.column_stack(
        [scan.values[:, : len(left)].mean(axis=1), scan.values[:, len(left) :].mean(axis=1)]
    )
    times_ns, time, values = clean(
        time_ns(scan, header), per_side, f"topic {topic}", src, header=header
    )
    if kinds[0] == VELOCITY:
        dt = np.diff(times_ns).astype(np.float64) * 1e-9
        steps = 0.5 * (values[1:] + values[:-1]) * dt[:, None]
        values = np.concatenate([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    return WheelSeries(time=time, angles=values)


def _scan_joints(
    reader: AnyReader,
    conns: Sequence[Connection],
    msgtype: str,
    topic: str,
    src: str,
    left: tuple[str, ...],
    right: tuple[str, ...],
) -> tuple[Decoded, set[str]]:
    """The joints' samples, and the names seen in messages without all of them."""
    joints = left + right
    seen: set[str] = set()

    def decode(msg: JointState) -> list[Sample]:
        names = list(msg.name)
        try:
            where = [names.index(joint) for joint in joints]
        except ValueError:
            seen.update(names)
            return []
        sec, nsec = stamp(msg)
        position, velocity = msg.position, msg.velocity
        if len(position) > max(where):
            return [(sec, nsec, tuple(float(position[i]) for i in where), POSITION)]
        if len(velocity) > max(where):
            return [(sec, nsec, tuple(float(velocity[i]) for i in where), VELOCITY)]
        raise InputError(
            f"a message of {topic} (stamp {sec + nsec * 1e-9:.9f} s) has neither position"
            f" nor velocity for the joints {_quoted(joints)}",
            source=src,
        )

    scan = read_topic(
        reader,
        conns,
        msgtype,
        topic,
        src,
        width=len(joints),
        decode=decode,
        layout_of=fast_layout(msgtype, joints),
    )
    return scan, seen


def _quoted(names: Sequence[str]) -> str:
    return " and ".join(repr(name) for name in names)

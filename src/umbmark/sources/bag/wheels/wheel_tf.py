"""Wheel rotation published only as transforms: ``base_link -> wheel_left_link`` on ``/tf``.

Some recordings hold no ``sensor_msgs/JointState`` of the wheels, only what
``robot_state_publisher`` made of them: for every continuous joint, the transform from its
parent link to the wheel link, the joint's fixed origin composed with the rotation by the
joint's angle about its axis. The angle is recovered from the rotation between
consecutive transforms: ``q_k (x) q_(k-1)^*`` is the rotation the wheel made in between,
expressed in the parent frame, and its angle (``2 atan2(|q_xyz|, q_w)``, ``q_w >= 0``)
signed by its axis's ``y`` is the wheel's turn about the parent's ``y`` axis, positive
when the wheel rolls forward (REP-103: ``x`` forward, ``y`` left; a wheel rolling forward turns
positively about ``y`` whatever its joint's axis says). The turns are summed
(unwrapped), so every step must be under half a turn: transforms at the joint-state rate
(tens of hertz) are. The parent frame must be the robot's base frame (or a frame
aligned with it).

The two wheels' transforms are usually stamped alike (one message per joint-state
update); where they are not, the right wheel's angle is interpolated onto the left
wheel's times.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import FloatArray, IntArray
from umbmark.core.errors import InputError
from umbmark.model.recording import WheelSeries
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.msgtypes import TF_TOPIC, TF_TYPES, TFMessage
from umbmark.sources.bag.samples import clean, on_left_times

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = ["MAX_STEP", "read_wheel_transforms", "turns_about_y"]


#: Largest turn [rad] of a wheel between two of its transforms that can be followed.
MAX_STEP = 0.5 * math.pi


def turns_about_y(quaternions: FloatArray) -> FloatArray:
    """The cumulative turn [rad] about the parent's ``y`` axis of a frame whose rotations
    are ``quaternions`` (shape (k, 4), ``x, y, z, w``), 0 at the first: shape (k,)."""
    q = quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)
    x1, y1, z1, w1 = q[1:].T
    x0, y0, z0, w0 = q[:-1].T
    # q1 (x) conj(q0): the rotation from one sample to the next, in the parent frame
    w = w1 * w0 + x1 * x0 + y1 * y0 + z1 * z0
    x = x1 * w0 - w1 * x0 + z1 * y0 - y1 * z0
    y = y1 * w0 - w1 * y0 + x1 * z0 - z1 * x0
    z = z1 * w0 - w1 * z0 + y1 * x0 - x1 * y0
    sign = np.where(w < 0, -1.0, 1.0)
    # the whole turn, signed by its axis's y: a joint axis a little off y (camber, an
    # origin's rounded rpy) loses nothing
    half = np.hypot(np.hypot(x, y), z)
    step = 2.0 * np.arctan2(np.where(sign * y < 0, -half, half), sign * w)
    return np.concatenate([[0.0], np.cumsum(step)])


def _collect(
    reader: AnyReader, topics: dict[str, str], frames: tuple[str, str], header: bool, src: str
) -> dict[str, list[tuple[int, str, tuple[float, float, float, float]]]]:
    """``(time [ns], parent, quaternion)`` of every transform to each of ``frames``."""
    if TF_TOPIC not in topics:
        raise InputError(
            f"has no {TF_TOPIC} topic for the wheel frames; topics present: "
            f"{bag_reader.listing(sorted(topics))}",
            source=src,
        )
    msgtype = topics[TF_TOPIC]
    if msgtype not in TF_TYPES:
        raise InputError(
            f"topic {TF_TOPIC} has messages of type {msgtype}, not tf2_msgs/msg/TFMessage",
            source=src,
        )
    out: dict[str, list[tuple[int, str, tuple[float, float, float, float]]]] = {
        f: [] for f in frames
    }
    conns = [c for c in reader.connections if c.topic == TF_TOPIC]
    for bag_ns, raw in bag_reader.messages(reader, conns, TF_TOPIC, src):
        msg: TFMessage = bag_reader.deserialize(reader, raw, msgtype, TF_TOPIC, src)  # type: ignore[assignment]
        for tf in msg.transforms:
            child = str(tf.child_frame_id).lstrip("/")
            if child not in out:
                continue
            stamp = tf.header.stamp
            t = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec) if header else bag_ns
            q = tf.transform.rotation
            parent = str(tf.header.frame_id).lstrip("/")
            out[child].append((t, parent, (float(q.x), float(q.y), float(q.z), float(q.w))))
    return out


def _wheel(
    samples: list[tuple[int, str, tuple[float, float, float, float]]],
    frame: str,
    header: bool,
    src: str,
) -> tuple[IntArray, FloatArray]:
    """Time [ns] and cumulative turn [rad] of one wheel frame."""
    parents = sorted({parent for _, parent, _ in samples})
    if len(parents) > 1:
        raise InputError(
            f"the wheel frame {frame} has transforms from several parents on {TF_TOPIC} "
            f"({bag_reader.listing(parents)}): one is needed",
            source=src,
        )
    time_ns = np.array([t for t, _, _ in samples], np.int64)
    quats = np.array([q for _, _, q in samples], np.float64).reshape(-1, 4)
    what = f"the transforms {parents[0]} -> {frame}" if parents else f"the wheel frame {frame}"
    kept, _, quats = clean(time_ns, quats, what, src, header=header)
    turns = turns_about_y(quats)
    steps = np.abs(np.diff(turns))
    if steps.size and float(steps.max()) > MAX_STEP:
        k = int(np.argmax(steps))
        raise InputError(
            f"{what} turn by {float(steps[k]):.2f} rad between two transforms (more than "
            f"{MAX_STEP:.2f} rad): too sparse to follow the wheel; record /tf at the joint-"
            "state rate, or the joint states themselves",
            source=src,
        )
    return kept, turns


def read_wheel_transforms(
    reader: AnyReader,
    topics: dict[str, str],
    left: str,
    right: str,
    header: bool,
    src: str,
) -> WheelSeries:
    """Wheel angles from the transforms to the wheel frames ``left`` and ``right``.

    Returns
    -------
    WheelSeries
        ``time`` [s], ``angles`` shape (n, 2) [rad], 0 at the first transform of each.

    Raises
    ------
    InputError
        No ``/tf``, a frame without transforms (the message lists the frames that
        move), transforms too sparse, or the two wheels' transforms not overlapping.
    """
    left, right = left.lstrip("/"), right.lstrip("/")
    if left == right:
        raise InputError(f"the left and right wheel frames are the same: {left}", source=src)
    found = _collect(reader, topics, (left, right), header, src)
    missing = [frame for frame in (left, right) if not found[frame]]
    if missing:
        raise InputError(
            f"no transform to the wheel frame {missing[0]} on {TF_TOPIC}; give the child "
            "frames of the wheels' transforms (umbmark info lists them)",
            source=src,
        )
    time, angles = on_left_times(
        _wheel(found[left], left, header, src),
        _wheel(found[right], right, header, src),
        f"the transforms to {left} and {right} overlap in time in fewer than 2 samples",
        src,
    )
    return WheelSeries(time=time, angles=angles)

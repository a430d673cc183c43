"""Samples of one topic: reading its messages, their times, and cleaning the series.

Shared by the readers of :mod:`umbmark.sources.bag.wheels` and
:mod:`umbmark.sources.bag.truth`: :func:`read_topic` decodes every message of a
topic (the fast path of :mod:`umbmark.sources.bag.fastpath` where the layout allows),
:func:`time_ns` picks header stamps or bag times, :func:`clean` drops non-finite samples
and sorts by time, :func:`truth_series` turns positions and quaternions into planar poses.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.core.arrays import FloatArray, IntArray
from umbmark.core.errors import InputError
from umbmark.core.geometry import quaternion_yaw
from umbmark.model.recording import PoseSeries
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.fastpath import Decoded, LayoutOf, Sample, decode_messages
from umbmark.sources.bag.msgtypes import Quaternion, Stamped, Vector

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = ["clean", "on_left_times", "pose_values", "read_topic", "seconds", "stamp", "time_ns"]
__all__ += ["truth_series"]


def read_topic(
    reader: AnyReader,
    conns: Sequence[Connection],
    msgtype: str,
    topic: str,
    src: str,
    *,
    width: int,
    decode: Callable[[Any], list[Sample]],
    layout_of: LayoutOf | None,
) -> Decoded:
    """Every sample of ``topic``: ``decode`` turns a deserialized message into samples.

    The fast path of :func:`~umbmark.sources.bag.fastpath.decode_messages` reads the
    messages that fit ``layout_of``; the rest are deserialized by rosbags and decoded.

    Raises
    ------
    InputError
        The topic has no messages, or one cannot be read or deserialized.
    """

    def deserialize_and_decode(raw: bytes) -> list[Sample]:
        return decode(bag_reader.deserialize(reader, raw, msgtype, topic, src))

    scan = decode_messages(
        bag_reader.messages(reader, conns, topic, src),
        ros2=bool(reader.is2),
        width=width,
        decode=deserialize_and_decode,
        layout_of=layout_of,
    )
    if scan.messages == 0:
        raise InputError(f"topic {topic} has no messages", source=src)
    return scan


def time_ns(scan: Decoded, header: bool) -> IntArray:
    """Sample times [ns], shape (k,): header stamps or bag receive times."""
    if header:
        return scan.sec * 1_000_000_000 + scan.nsec
    return scan.bag_ns


def seconds(time_ns: IntArray) -> FloatArray:
    """Times [s] of ``time_ns`` [ns], shape (k,), as ``sec + nanosec * 1e-9``."""
    sec, nsec = np.divmod(time_ns, 1_000_000_000)
    return np.asarray(sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9)


def stamp(msg: Stamped) -> tuple[int, int]:
    stamp = msg.header.stamp
    return int(stamp.sec), int(stamp.nanosec)


def clean(
    time_ns: IntArray, values: FloatArray, what: str, src: str, *, header: bool
) -> tuple[IntArray, FloatArray, FloatArray]:
    """Drop non-finite samples, sort by time, keep the first of equal times.

    Returns
    -------
    time_ns : array, shape (k,)
        Times [ns], strictly increasing: differences are exact, for integrating over.
    time : array, shape (k,)
        The same times in seconds, strictly increasing. Float seconds since 1970 resolve
        only about 0.2 microseconds, so of stamps closer than that only the first is kept.
    values : array, shape (k, w)
    """
    finite = np.all(np.isfinite(values), axis=1)
    time_ns, values = time_ns[finite], values[finite]
    order = np.argsort(time_ns, kind="stable")
    time_ns, values = time_ns[order], values[order]
    time = seconds(time_ns)
    keep = np.ones(time.size, np.bool_)
    keep[1:] = np.diff(time) > 0
    time_ns, time, values = time_ns[keep], time[keep], values[keep]
    if time.size < 2:
        hint = " (are the header stamps all equal? try the bag time)" if header else ""
        plural = "" if time_ns.size == 1 else "s"
        raise InputError(
            f"{what} has {time_ns.size} usable sample{plural} with distinct times, at least 2"
            f" are needed{hint}",
            source=src,
        )
    return time_ns, time, values


def truth_series(
    time_ns: IntArray, values: FloatArray, what: str, src: str, *, header: bool
) -> PoseSeries:
    """Ground truth from ``values`` shape (k, 6): ``x, y`` and quaternion ``x, y, z, w``."""
    quat = values[:, 2:6]
    with np.errstate(invalid="ignore", divide="ignore"):
        quat = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    qx, qy, qz, qw = quat.T
    yaw = quaternion_yaw(qx, qy, qz, qw)
    poses = np.column_stack([values[:, 0], values[:, 1], yaw])
    _, time, poses = clean(time_ns, poses, what, src, header=header)
    return PoseSeries(time=time, poses=poses)


def on_left_times(
    left: tuple[IntArray, FloatArray], right: tuple[IntArray, FloatArray], few: str, src: str
) -> tuple[FloatArray, FloatArray]:
    """Two wheels sampled at their own times: ``(time [ns], value)``, each shape (k,), the
    times strictly increasing (:func:`clean`). Returns the left wheel's times [s] inside
    the right wheel's, shape (n,), and both wheels' values there, shape (n, 2): the
    right's interpolated linearly, on times from a common origin (exact to the
    nanosecond). ``few`` is the message when they share fewer than 2 samples."""
    (t_left, v_left), (t_right, v_right) = left, right
    inside = (t_left >= t_right[0]) & (t_left <= t_right[-1])
    if np.count_nonzero(inside) < 2:
        raise InputError(few, source=src)
    origin = min(int(t_left[0]), int(t_right[0]))
    at = (t_left[inside] - origin).astype(np.float64)
    right = np.interp(at, (t_right - origin).astype(np.float64), v_right)
    return seconds(t_left[inside]), np.column_stack([v_left[inside], right])


def pose_values(p: Vector, q: Quaternion) -> tuple[float, ...]:
    """``x, y`` of ``p`` and the quaternion ``q``'s ``x, y, z, w``."""
    return (float(p.x), float(p.y), float(q.x), float(q.y), float(q.z), float(q.w))

"""Reading a planar laser's sweeps (``sensor_msgs/LaserScan``) from a bag into a
:class:`umbmark.model.scans.ScanSeries`.

Every message of the topic is deserialized by rosbags (the ranges come as one array, so
this is not where the time goes) and streamed: only the ranges of the sweeps kept are
held, as float32 until the end, at most ``max_scans`` of them (default
:data:`MAX_SCANS`). ``min_period`` thins a fast scanner while reading: a sweep closer
than that to the last one kept is skipped.

Time: the header stamps (default) or the bag's receive times (``header=False``), as the
wheel readers; sweeps are sorted by time and of equal stamps the first is kept. The
sweeps of a topic must share their beams: the count, ``angle_min``,
``angle_increment`` and the range limits; a sweep that differs ends the read with one
line naming the bag, the topic and what changed.

The motion during a sweep: the first sweep's ``time_increment`` (its absolute value)
goes into the series, so that the matcher can undo the scanner's motion between its first
and its last beam; a value that is not finite or makes a sweep last more than
:data:`MAX_SWEEP` is not believed (0: the sweep is taken as measured at once).

Upside down: given, or (``upside_down=None``) read from ``/tf_static``: the scanner's
frame (``header.frame_id``) is upside down when, composed up its chain of static
transforms to the root, its z axis points down (as :mod:`umbmark.robot.ros_common` reads
a live robot's mountings). No ``/tf_static`` or no chain for the frame: right side up.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from umbmark.core.errors import InputError
from umbmark.model.scans import ScanSeries
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.msgtypes import LASER_SCAN, TF_STATIC_TOPIC, TF_TYPES, LaserScan, TFMessage
from umbmark.sources.bag.names import BASE_LINKS

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

__all__ = [
    "MAX_BEAMS",
    "MAX_SCANS",
    "MAX_SWEEP",
    "bag_span",
    "read_scan_bag",
    "read_scans",
    "scan_mounting",
    "upside_down_frame",
]

#: Sweeps held at most (about 2.8 hours at 10 Hz; 720 beams take 2.9 kB each).
MAX_SCANS = 100_000
#: Beams a sweep may have at most.
MAX_BEAMS = 16_384
#: Longest sweep [s] whose ``time_increment`` is believed (longer: taken as 0).
MAX_SWEEP = 1.0


def read_scan_bag(
    path: str | Path,
    topic: str,
    *,
    header: bool = True,
    upside_down: bool | None = None,
    min_period: float = 0.0,
    max_scans: int = MAX_SCANS,
    window: tuple[int, int] | None = None,
) -> ScanSeries:
    """The sweeps of ``topic`` in the bag at ``path`` (:func:`read_scans`), those received
    within ``window`` (bag times [ns] from and before) where given."""
    src = str(path)
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)
        return read_scans(
            reader,
            topics,
            topic,
            src,
            header=header,
            upside_down=upside_down,
            min_period=min_period,
            max_scans=max_scans,
            window=window,
        )


def bag_span(path: str | Path) -> tuple[int, int]:
    """The bag's first and last message times [ns]."""
    src = str(path)
    with bag_reader.open_bag(Path(path), src) as reader:
        return int(reader.start_time), int(reader.end_time)


def read_scans(
    reader: AnyReader,
    topics: dict[str, str],
    topic: str,
    src: str,
    *,
    header: bool = True,
    upside_down: bool | None = None,
    min_period: float = 0.0,
    max_scans: int = MAX_SCANS,
    window: tuple[int, int] | None = None,
) -> ScanSeries:
    """The sweeps of ``topic`` from the open bag (the module's docstring).

    Parameters
    ----------
    reader, topics : the open bag and its :func:`~umbmark.sources.bag.reader.topic_types`
    topic : str
        A ``sensor_msgs/LaserScan`` topic.
    src : str
        The bag's path, for messages.
    header : bool
        Stamp with the header stamps (True) or the bag's receive times.
    upside_down : bool or None
        The scanner is mounted upside down; None: as ``/tf_static`` says.
    min_period : float
        Skip sweeps closer than this [s] to the last one kept.
    max_scans : int
        Most sweeps kept; more is an error.
    window : (int, int), optional
        Only the sweeps received from the first and before the second bag time [ns].

    Raises
    ------
    InputError
        The topic is absent or not of laser scans, has fewer than 2 sweeps, sweeps that
        change their beams, too many sweeps, or cannot be read.
    """
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (LASER_SCAN,), "laser scans", src
    )
    where = f"{topic}: "
    beams: tuple[int, float, float, float, float] | None = None
    frame = ""
    time_increment = 0.0
    stamps: list[int] = []
    rows: list[NDArray[np.float32]] = []
    last = -math.inf
    stream = bag_reader.messages(reader, conns, topic, src, window)
    for k, (bag_ns, raw) in enumerate(stream):
        msg: LaserScan = bag_reader.deserialize(reader, raw, msgtype, topic, src)  # type: ignore[assignment]
        ranges = np.asarray(msg.ranges, dtype=np.float32)
        these = (
            int(ranges.size),
            float(msg.angle_min),
            float(msg.angle_increment),
            float(msg.range_min),
            float(msg.range_max),
        )
        if beams is None:
            _check_beams(these, where, src)
            beams, frame = these, str(msg.header.frame_id).lstrip("/")
            time_increment = abs(float(msg.time_increment))
            if not (math.isfinite(time_increment) and time_increment * these[0] <= MAX_SWEEP):
                time_increment = 0.0
        elif these != beams:
            raise InputError(
                f"{where}sweep {k + 1} has {_describe(these)}, the first {_describe(beams)}: "
                "read the sweeps of one scanner setting at a time",
                source=src,
            )
        stamp = msg.header.stamp
        ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec) if header else int(bag_ns)
        if min_period > 0.0 and abs(ns * 1e-9 - last) < min_period:
            continue
        last = ns * 1e-9
        if len(rows) >= max_scans:
            raise InputError(
                f"{where}more than {max_scans:,} sweeps: cut the recording, or thin the "
                "sweeps (a longer minimum period)",
                source=src,
            )
        stamps.append(ns)
        rows.append(ranges)
    if beams is None:
        raise InputError(f"topic {topic} has no messages", source=src)
    time_ns = np.array(stamps, dtype=np.int64)
    order = np.argsort(time_ns, kind="stable")
    time_ns = time_ns[order]
    keep = np.ones(time_ns.size, np.bool_)
    keep[1:] = np.diff(time_ns) > 0
    if np.count_nonzero(keep) < 2:
        hint = " (are the header stamps all equal? read the bag time)" if header else ""
        raise InputError(f"{where}fewer than 2 sweeps with distinct times{hint}", source=src)
    ranges_all = np.stack(rows)[order[keep]].astype(np.float64)
    sec, nsec = np.divmod(time_ns[keep], 1_000_000_000)
    times = sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9
    if upside_down is None:
        upside_down = upside_down_frame(reader, topics, frame, src)
    _, angle_min, increment, range_min, range_max = beams
    return ScanSeries(
        times=np.asarray(times, dtype=np.float64),
        ranges=ranges_all,
        angle_min=angle_min,
        angle_increment=increment,
        range_min=range_min,
        range_max=range_max,
        upside_down=upside_down,
        time_increment=time_increment,
        frame=frame,
        source=f"{src} {topic}",
    )


def _describe(beams: tuple[int, float, float, float, float]) -> str:
    count, angle_min, increment, range_min, range_max = beams
    return (
        f"{count} beams from {math.degrees(angle_min):.2f} deg by "
        f"{math.degrees(increment):.4f} deg, ranges {range_min:g} .. {range_max:g} m"
    )


def _check_beams(beams: tuple[int, float, float, float, float], where: str, src: str) -> None:
    count, angle_min, increment, range_min, range_max = beams
    problem = ""
    if not 3 <= count <= MAX_BEAMS:
        problem = f"{count} beams (3 .. {MAX_BEAMS} can be matched)"
    elif not (math.isfinite(angle_min) and math.isfinite(increment) and increment != 0.0):
        problem = f"angle_min {angle_min} and angle_increment {increment} give no beam angles"
    elif not (math.isfinite(range_min) and 0.0 <= range_min < range_max):
        problem = f"range limits {range_min} .. {range_max} m are not a range"
    if problem:
        raise InputError(f"{where}the sweeps have {problem}", source=src)


_Static = dict[str, tuple[str, tuple[float, float, float], tuple[float, float, float, float]]]


def _static_tree(reader: AnyReader, topics: dict[str, str], src: str) -> _Static:
    """Every frame of ``/tf_static``: its parent, translation [m] and rotation (``x, y,
    z, w``); at most 10 000 frames."""
    msgtype = topics.get(TF_STATIC_TOPIC)
    parents: _Static = {}
    if msgtype not in TF_TYPES:
        return parents
    conns = [c for c in reader.connections if c.topic == TF_STATIC_TOPIC]
    for _, raw in bag_reader.messages(reader, conns, TF_STATIC_TOPIC, src):
        msg: TFMessage = bag_reader.deserialize(reader, raw, msgtype, TF_STATIC_TOPIC, src)  # type: ignore[assignment]
        for tf in msg.transforms:
            q, t = tf.transform.rotation, tf.transform.translation
            parents[tf.child_frame_id.lstrip("/")] = (
                tf.header.frame_id.lstrip("/"),
                (float(t.x), float(t.y), float(t.z)),
                (float(q.x), float(q.y), float(q.z), float(q.w)),
            )
        if len(parents) > 10_000:
            break
    return parents


def _compose_up(
    parents: _Static, frame: str, stop: tuple[str, ...] = ()
) -> tuple[str, tuple[float, float, float], tuple[float, float, float, float]]:
    """``frame``'s pose in the root of its static chain (or the first frame of ``stop``
    on the way): that frame, the translation and the rotation."""
    total = (0.0, 0.0, 0.0, 1.0)
    position = (0.0, 0.0, 0.0)
    seen = {frame}
    at = frame
    while at in parents and at not in stop:
        at, shift, rotation = parents[at]
        # parent <- child: the parent's rotation on the left, its translation added
        rx, ry, rz = _rotate(rotation, position)
        position = (rx + shift[0], ry + shift[1], rz + shift[2])
        total = _product(rotation, total)
        if at in seen:
            break
        seen.add(at)
    return at, position, total


def upside_down_frame(reader: AnyReader, topics: dict[str, str], frame: str, src: str) -> bool:
    """Whether ``frame`` is upside down in its tree of static transforms (module notes)."""
    if not frame or topics.get(TF_STATIC_TOPIC) not in TF_TYPES:
        return False
    _, _, total = _compose_up(_static_tree(reader, topics, src), frame)
    x, y, _, _ = total
    norm = sum(c * c for c in total) or 1.0
    return 1.0 - 2.0 * (x * x + y * y) / norm < 0.0


def scan_mounting(
    path: str | Path, frame: str
) -> tuple[str, tuple[float, float, float], tuple[float, float, float]] | None:
    """The scanner's mounting as the bag's ``/tf_static`` states it: the base frame (the
    first of :data:`BASE_LINKS` up the chain, else its root), the pose ``x, y, yaw``
    [m, m, rad] of ``frame`` in it (of its frame right side up: the same origin and x
    axis), and its height and tilt ``z, roll, pitch`` [m, rad, rad] (fixed axes, yaw
    last, pitch within +-90 degrees: the URDF's ``rpy``). None without a static transform
    for ``frame``.

    Raises
    ------
    InputError
        The bag cannot be read.
    """
    src = str(path)
    frame = frame.lstrip("/")
    with bag_reader.open_bag(Path(path), src) as reader:
        parents = _static_tree(reader, bag_reader.topic_types(reader), src)
    if not frame or frame not in parents:
        return None
    base, (x, y, z), rotation = _compose_up(parents, frame, BASE_LINKS)
    ex, ey, _ = _rotate(rotation, (1.0, 0.0, 0.0))
    r20, r21, r22 = _rotate(_conjugate(rotation), (0.0, 0.0, 1.0))  # the matrix's last row
    roll = math.atan2(r21, r22)
    pitch = math.atan2(-r20, math.hypot(r21, r22))
    return base, (x, y, math.atan2(ey, ex)), (z, roll, pitch)


def _conjugate(q: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """The inverse rotation of the quaternion ``q`` (``x, y, z, w``)."""
    return -q[0], -q[1], -q[2], q[3]


def _rotate(
    q: tuple[float, float, float, float], v: tuple[float, float, float]
) -> tuple[float, float, float]:
    """The vector ``v`` rotated by the quaternion ``q`` (``x, y, z, w``, normalized here)."""
    norm = math.sqrt(sum(c * c for c in q)) or 1.0
    x, y, z, w = (c / norm for c in q)
    # v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    cx, cy, cz = y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0]
    return (
        v[0] + 2.0 * (w * cx + y * cz - z * cy),
        v[1] + 2.0 * (w * cy + z * cx - x * cz),
        v[2] + 2.0 * (w * cz + x * cy - y * cx),
    )


def _product(
    a: tuple[float, float, float, float], b: tuple[float, float, float, float]
) -> tuple[float, float, float, float]:
    """The quaternion product ``a b`` (``x, y, z, w``)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )

"""A bag's IMUs, for ``umbmark info``: each ``sensor_msgs/Imu`` topic, its frame, whether
it gives a gyro's readings, and its mounting in the base frame, within bounds.

Of each IMU topic at most :data:`MAX_LOOKED` messages are looked into, in
:data:`STRETCHES` stretches spread over its time span (a robot resting at first, under a
gyro that reads exact zeros at rest, still shows its gyro): their frame
(``header.frame_id``, of the first) and whether any gives an angular velocity (its
``angular_velocity_covariance[0]`` not -1, the angular velocity not exactly 0). The
frame's mounting is found as the reader finds it
(:func:`umbmark.sources.bag.imu_frames.imu_mounting`). An IMU with a gyro and a mounting
is suggested (``--imu-topic``); the others say why not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.imu_frames import ImuMounting, imu_mounting
from umbmark.sources.bag.msgtypes import IMU, Imu

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader

    from umbmark.sources.bag.info.scan import ScannedTopic

__all__ = ["MAX_LOOKED", "STRETCHES", "ImuInfo", "imu_infos"]

#: Messages of each IMU topic looked into at most ...
MAX_LOOKED = 200
#: ... in this many stretches of its time span.
STRETCHES = 5


@dataclass(frozen=True)
class ImuInfo:
    """One IMU topic of a bag.

    Attributes
    ----------
    topic : str
    rate : float or None
        Messages a second [Hz] (the bag's count over its receive times).
    frame : str
        The frame of its first message.
    gyro : bool
        Some message looked into gives an angular velocity.
    mounting : ImuMounting or None
        The frame's orientation in the base frame; None where none is found.
    problem : str or None
        Why it is not suggested (no gyro, no mounting).
    """

    topic: str
    rate: float | None
    frame: str
    gyro: bool
    mounting: ImuMounting | None
    problem: str | None = None

    @property
    def options(self) -> tuple[tuple[str, str], ...]:
        """The option that reads it (``--imu-topic /imu``); none with a problem."""
        return () if self.problem is not None else (("--imu-topic", self.topic),)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``topic``, ``rate`` [Hz], ``frame``, ``has_gyro``, ``mounting``
        (``base``, ``rpy`` [rad], ``source``; or None) and ``problem``."""
        mounted = self.mounting
        return {
            "topic": self.topic,
            "rate": self.rate,
            "frame": self.frame,
            "has_gyro": self.gyro,
            "mounting": None
            if mounted is None
            else {"base": mounted.base, "rpy": list(mounted.rpy), "source": mounted.source},
            "problem": self.problem,
        }

    def describe(self) -> str:
        """For people: ``/imu, 200.0 Hz, imu_link in base_link (/tf_static): roll ...``."""
        rate = "" if self.rate is None else f", {self.rate:.1f} Hz"
        where = self.mounting.describe() if self.mounting is not None else f"frame {self.frame!r}"
        return f"{self.topic}{rate}, {where}"


def imu_infos(
    reader: AnyReader, topics: dict[str, str], scanned: list[ScannedTopic], src: str
) -> list[ImuInfo]:
    """Every ``sensor_msgs/Imu`` topic of the open bag (the module's notes), in the order
    of ``scanned``."""
    out = []
    for topic in scanned:
        if topic.msgtype != IMU:
            continue
        frame, gyro = _looked(reader, topics, topic, src)
        mounting, problem = None, None
        try:
            mounting = imu_mounting(reader, topics, frame, topic.name, src)
        except InputError as err:
            problem = err.problem.removeprefix(f"{topic.name}: ")
        if not topic.count:
            problem = "the topic has no messages"
        elif not gyro:
            problem = (
                "its messages give no angular velocity (angular_velocity_covariance[0] = -1, "
                "or exactly 0): no gyro"
            )
        rate = topic.rate
        out.append(ImuInfo(topic.name, rate if rate and math.isfinite(rate) else None, frame,
                           gyro, mounting, problem))  # fmt: skip
    return out


def _looked(
    reader: AnyReader, topics: dict[str, str], topic: ScannedTopic, src: str
) -> tuple[str, bool]:
    """The frame of the topic's first message, and whether any of the messages looked
    into (the module's notes) gives an angular velocity."""
    conns = [c for c in reader.connections if c.topic == topic.name]
    first, last = topic.scan.first, topic.scan.last
    starts = [None] if first is None or last is None else [
        first + (last - first) * k // STRETCHES for k in range(STRETCHES)
    ]  # fmt: skip
    frame: str | None = None
    for start in starts:
        stream = bag_reader.raw_messages(reader, conns, topic.name, src, start)
        try:
            for k, (_, raw) in enumerate(stream):
                if k >= MAX_LOOKED // len(starts):
                    break
                msgtype = topics[topic.name]
                msg: Imu = bag_reader.deserialize(reader, raw, msgtype, topic.name, src)  # type: ignore[assignment]
                frame = str(msg.header.frame_id) if frame is None else frame
                w = msg.angular_velocity
                given = float(msg.angular_velocity_covariance[0]) != -1.0
                if given and any(v != 0.0 and math.isfinite(v) for v in (w.x, w.y, w.z)):
                    return frame, True
        finally:
            stream.close()
    return frame or "", False

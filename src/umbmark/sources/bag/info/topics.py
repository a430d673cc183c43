"""What ``umbmark info`` says of single topics: each topic's counts and rate, the joints
of a ``sensor_msgs/JointState`` topic, the models of Gazebo's model states
(:mod:`umbmark.sources.bag.info.summary` gathers them into a ``BagInfo``).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from umbmark.sources.bag.truth.references import ModelMotion

__all__ = ["JointInfo", "JointStateInfo", "ModelStatesInfo", "TopicInfo"]


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a bag.

    Attributes
    ----------
    name, msgtype : str
        Topic and message type (``sensor_msgs/msg/JointState``; several joined by ``", "``).
    count : int
        Messages in the bag.
    duration : float or None
        Receive time from the first to the last message [s]; None without messages.
    rate : float or None
        ``(count - 1) / duration`` [Hz]; None with fewer than two distinct times.
    scanned : int
        Messages deserialized to look into them (0 for types not looked into).
    """

    name: str
    msgtype: str
    count: int
    duration: float | None
    rate: float | None
    scanned: int = 0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``name``, ``type``, ``count``, ``rate`` [Hz], ``duration`` [s] and
        ``scanned``."""
        return {
            "name": self.name,
            "type": self.msgtype,
            "count": self.count,
            "rate": self.rate,
            "duration": self.duration,
            "scanned": self.scanned,
        }


@dataclass(frozen=True)
class JointInfo:
    """One joint of a ``sensor_msgs/JointState`` topic, in the messages read.

    Attributes
    ----------
    name : str
    samples : int
        Messages read that carry it.
    position_range : float or None
        ``max - min`` of its finite positions [rad, or m for prismatic joints]; None
        without positions.
    max_speed : float or None
        Largest ``|velocity|`` [rad/s]; without velocities, the largest change of its
        position over time between consecutive messages read (header stamps, else bag
        times); None without either.
    moving : bool
        ``position_range > MOVING_ANGLE`` or ``max_speed > MOVING_SPEED``.
    speed_from : {"velocity", "positions"} or None
        Where ``max_speed`` comes from.
    """

    name: str
    samples: int
    position_range: float | None
    max_speed: float | None
    moving: bool
    speed_from: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the attributes by name."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class JointStateInfo:
    """The joints of a ``sensor_msgs/JointState`` topic.

    Attributes
    ----------
    topic : str
    joints : tuple of JointInfo
        In order of first appearance, at most :data:`~umbmark.sources.bag.info.summary.MAX_LISTED`.
    not_listed : int
        Joints found beyond those listed.
    scanned : int
        Messages read.
    complete : bool
        Every message of the topic was read.
    """

    topic: str
    joints: tuple[JointInfo, ...]
    not_listed: int
    scanned: int
    complete: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``topic``, ``scanned``, ``complete``, ``joints``, ``joints_not_listed``."""
        return {
            "topic": self.topic,
            "scanned": self.scanned,
            "complete": self.complete,
            "joints": [joint.to_dict() for joint in self.joints],
            "joints_not_listed": self.not_listed,
        }


@dataclass(frozen=True)
class ModelStatesInfo:
    """The models of a ``gazebo_msgs/ModelStates`` topic, in the messages read.

    Attributes
    ----------
    topic : str
    models : tuple of ModelMotion
        In order of first appearance, at most :data:`~umbmark.sources.bag.info.summary.MAX_LISTED`.
    not_listed : int
    scanned : int
        Messages read.
    """

    topic: str
    models: tuple[ModelMotion, ...]
    not_listed: int
    scanned: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``topic``, ``scanned``, ``models`` (``name``, ``samples``,
        ``position_range`` [m], ``moving``), ``models_not_listed``."""
        return {
            "topic": self.topic,
            "scanned": self.scanned,
            "models": [
                {
                    "name": m.name,
                    "samples": m.samples,
                    "position_range": m.position_range,
                    "moving": m.moving,
                }
                for m in self.models
            ],
            "models_not_listed": self.not_listed,
        }

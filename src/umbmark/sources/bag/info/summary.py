"""What is in a bag: topics, wheel joints, transforms, and the options to read it with.

:func:`bag_info` lists every topic of a ROS 1 or ROS 2 bag with its message type, count,
rate and duration; for ``sensor_msgs/JointState`` topics the joints and which of them
move; the parent->child pairs of ``/tf`` and ``/tf_static`` and the chains they form
from their roots (``map -> odom -> base_link``); the models of Gazebo's
``gazebo_msgs/ModelStates`` and which of them move; the wheelbase and wheel diameter of a
recorded robot description (:mod:`umbmark.sources.bag.urdf`), or which of them are still
needed; and the candidates for each input, ranked, with their rates and the
``--max-gap`` they need (:mod:`umbmark.sources.bag.info.candidates`). When no reference
independent of the odometry is found, a note says so. :func:`truth_candidates` is the
short version for an error message that asks for ground truth.

The work is bounded
-------------------
Counts come from the bag's index. Times are receive (bag) times: a topic's first message
is read, and its last one found by reading a few messages at a time from the end of the
bag (bisection). Only the topics whose content matters are deserialized, at most
``max_messages`` messages each (default :data:`DEFAULT_MAX_MESSAGES`): all of them when
the topic has no more, else ``max_messages`` spread over
:data:`~umbmark.sources.bag.info.scan.CHUNKS` stretches evenly
spaced over its time span, so that a robot that stands still at first still shows its
wheels moving (:mod:`umbmark.sources.bag.info.scan`). Transform rates are the topic's
rate times each pair's share of the messages read. At most :data:`MAX_LISTED` names
(topics, joints, transforms, candidates) and :data:`MAX_CHAINS` chains are listed; the
rest are counted.

"Moving" means, in the messages read: a joint's position range over
:data:`~umbmark.sources.bag.info.scan.MOVING_ANGLE` [rad] or a speed over
:data:`~umbmark.sources.bag.info.scan.MOVING_SPEED` [rad/s] (its ``velocity``, else its
position's change over time between consecutive messages read); a pose's position range
over :data:`~umbmark.sources.bag.info.scan.MOVING_DISTANCE` [m]; a counter's range of at
least one count; a Gazebo model's position range over
:data:`umbmark.sources.bag.truth.references.MOVING_DISTANCE`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from umbmark.core.errors import InputError, option
from umbmark.core.messages import split_messages
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.info.candidates import (
    Candidate,
    controller_odometry,
    odometry_candidates,
    wheel_candidates,
)
from umbmark.sources.bag.info.candidates import truth_candidates as _rank_truth
from umbmark.sources.bag.info.frames import (
    TransformInfo,
    odometry_transform,
    pair_gaps,
    tf_chains,
    transform_infos,
)
from umbmark.sources.bag.info.imus import ImuInfo, imu_infos
from umbmark.sources.bag.info.scan import ScannedTopic, inspect_topics
from umbmark.sources.bag.info.topics import JointInfo, JointStateInfo, ModelStatesInfo, TopicInfo
from umbmark.sources.bag.msgtypes import (
    JOINT_STATE,
    LASER_SCAN,
    MODEL_STATES,
    ODOMETRY,
    REFERENCE_TYPES,
    TF_STATIC_TOPIC,
    TF_TOPIC,
)
from umbmark.sources.bag.urdf import RobotDescription, read_description

__all__ = [
    "DEFAULT_MAX_MESSAGES",
    "MAX_CHAINS",
    "MAX_LISTED",
    "BagInfo",
    "ImuInfo",
    "JointInfo",
    "JointStateInfo",
    "ModelStatesInfo",
    "TopicInfo",
    "bag_info",
    "truth_candidates",
]

#: Messages deserialized per topic at most.
DEFAULT_MAX_MESSAGES = 2000
#: Names listed at most (topics, joints of a topic, transforms, candidates of a role).
MAX_LISTED = 50
#: Chains listed at most.
MAX_CHAINS = 20


# --- what the report holds -------------------------------------------------------------


@dataclass(frozen=True)
class BagInfo:
    """What is in a bag (see the module docstring).

    Attributes
    ----------
    path : str
    storage : str
        ``ros1``, ``sqlite3`` or ``mcap``.
    start : float or None
        Receive time of the first message [s since 1970]; None for an empty bag.
    duration : float
        From the first to the last message [s].
    messages : int
        Messages in the bag.
    topics : tuple of TopicInfo
        Sorted by name, at most :data:`MAX_LISTED`; ``topics_not_listed`` more.
    joint_states : tuple of JointStateInfo
    transforms : tuple of TransformInfo
        ``/tf`` pairs, then ``/tf_static`` pairs, at most :data:`MAX_LISTED`.
    chains : tuple of tuple of str
        Frames from a root down to the last frame that moves (``("map", "odom",
        "base_link")``): transforms that only mount sensors are left out. At most
        :data:`MAX_CHAINS`.
    wheels, odometry, truth : tuple of Candidate
        The candidates of each input, likeliest first.
    max_messages : int
        Messages deserialized per topic at most.
    complete : bool
        Every message of the topics looked into was read.
    notes : tuple of str
        What people should know that is information.
    warnings : tuple of str
        What people should know that is doubtful (topics that could not be decoded, empty
        stamps, no independent reference, a robot description without wheels).
    model_states : tuple of ModelStatesInfo
        Gazebo's model-state topics and their models.
    robot : RobotDescription or None
        The wheels of a recorded robot description.
    robot_problem : str or None
        Why a recorded robot description says no wheels.
    independent : bool
        Whether a ground-truth candidate without a warning was found.
    laser_scans : tuple of str
        The ``sensor_msgs/LaserScan`` topics.
    imus : tuple of ImuInfo
        The ``sensor_msgs/Imu`` topics (:mod:`umbmark.sources.bag.info.imus`).
    """

    path: str
    storage: str
    start: float | None
    duration: float
    messages: int
    topics: tuple[TopicInfo, ...]
    topics_not_listed: int
    joint_states: tuple[JointStateInfo, ...]
    transforms: tuple[TransformInfo, ...]
    transforms_not_listed: int
    chains: tuple[tuple[str, ...], ...]
    chains_not_listed: int
    wheels: tuple[Candidate, ...]
    odometry: tuple[Candidate, ...]
    truth: tuple[Candidate, ...]
    max_messages: int
    complete: bool
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    empty_stamps: tuple[str, ...] = field(default=(), repr=False)
    model_states: tuple[ModelStatesInfo, ...] = ()
    robot: RobotDescription | None = None
    robot_problem: str | None = None
    independent: bool = True
    laser_scans: tuple[str, ...] = ()
    imus: tuple[ImuInfo, ...] = ()

    @property
    def suggested_options(self) -> str | None:
        """Options to read the wheels and the ground truth with, from the likeliest
        candidates: ``--truth-topic /mocap/pose --left-joint wheel_left_joint ...``; the
        controller's odometry instead of the wheels when no wheel candidate is found.

        The ground truth is the first candidate without a warning, with the ``--max-gap``
        it needs where that is more than the default. Options that equal the defaults are
        left out; ``--time-source bag`` is added when a chosen topic's header stamps are
        empty or the ground truth has no header (Gazebo's model states); ``--imu-topic``
        the first IMU with a gyro and a mounting. None when the bag has neither wheels nor
        ground truth.
        """
        inputs = self.wheels[:1] or self.odometry[:1]
        truth = tuple(c for c in self.truth if c.warning is None)[:1]
        chosen = [c for c in (truth + inputs) if c.options]
        if not chosen:
            return None
        defaults = _DEFAULT_OPTIONS
        parts = [
            f"{flag} {value}"
            for candidate in chosen
            for flag, value in candidate.options
            if defaults.get(flag) != value
        ]
        gap = truth[0].gap_option if truth else None
        if gap is not None:
            parts.append(" ".join(gap))
        if any(_topic_of(c) in self.empty_stamps for c in chosen) or any(
            c.kind == "model" for c in truth
        ):
            parts.append("--time-source bag")
        parts += [f"{f} {v}" for imu in self.imus[:1] for f, v in imu.options]
        return " ".join(parts) or None

    @property
    def scan_options(self) -> str | None:
        """Options to calibrate the wheels against the laser's scan matching (``calibrate
        --scan-topic``): the first laser scan topic and the likeliest wheels (else the
        controller's odometry); None without both."""
        inputs = self.wheels[:1] or self.odometry[:1]
        if not self.laser_scans or not inputs or not inputs[0].options:
            return None
        wheels = [f"{f} {v}" for f, v in inputs[0].options if _DEFAULT_OPTIONS.get(f) != v]
        stamps = _topic_of(inputs[0]) in self.empty_stamps
        return " ".join(
            [f"--scan-topic {self.laser_scans[0]}", *wheels, *(["--time-source bag"] * stamps)]
        )

    @property
    def needs(self) -> tuple[str, ...]:
        """The options still needed for the wheel geometry: ``--wheelbase`` and
        ``--wheel-diameter``, less what a recorded robot description gives."""
        if self.robot is None:
            return ("--wheelbase", "--wheel-diameter")
        return () if self.robot.wheel_diameter is not None else ("--wheel-diameter",)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (seconds, hertz, radians, metres); see :class:`BagInfo`."""
        return {
            "storage": self.storage,
            "start": self.start,
            "duration": self.duration,
            "messages": self.messages,
            "max_messages": self.max_messages,
            "complete": self.complete,
            "topics": [topic.to_dict() for topic in self.topics],
            "topics_not_listed": self.topics_not_listed,
            "joint_states": [js.to_dict() for js in self.joint_states],
            "transforms": [tf.to_dict() for tf in self.transforms],
            "transforms_not_listed": self.transforms_not_listed,
            "chains": [list(chain) for chain in self.chains],
            "chains_not_listed": self.chains_not_listed,
            "candidates": {
                "wheels": [c.to_dict() for c in self.wheels],
                "odometry": [c.to_dict() for c in self.odometry],
                "truth": [c.to_dict() for c in self.truth],
            },
            "model_states": [ms.to_dict() for ms in self.model_states],
            "robot_description": None if self.robot is None else self.robot.to_dict(),
            "robot_description_problem": self.robot_problem,
            "needs": list(self.needs),
            "independent_reference": self.independent,
            "suggested_options": self.suggested_options,
            "laser_scans": list(self.laser_scans),
            "scan_options": self.scan_options,
            "imus": [imu.to_dict() for imu in self.imus],
            "notes": list(self.notes),
            "warnings": list(self.warnings),
        }


_DEFAULT_OPTIONS = {"--wheel-topic": BagOptions().wheel_topic}


def _topic_of(candidate: Candidate) -> str | None:
    options = dict(candidate.options)
    for flag in ("--truth-topic", "--wheel-topic", "--odom-topic"):
        if flag in options:
            return options[flag]
    return None


# --- the entry points -------------------------------------------------------------------


def _rank(
    scanned: Sequence[ScannedTopic],
    transforms: Sequence[TransformInfo],
    chains: Sequence[tuple[str, ...]],
) -> tuple[list[Candidate], str | None]:
    """The ground-truth candidates, and, when none of them is independent of the
    odometry, what the bag holds instead (for a note)."""
    found = _rank_truth(scanned, transforms, chains, pair_gaps(scanned))
    if any(c.warning is None for c in found):
        return found, None
    own = [t.name for t in scanned if controller_odometry(t)]
    own += [f"TF {tf.parent} -> {tf.child}" for tf in transforms if odometry_transform(tf)]
    flawed = [c.label for c in found]
    if not own and not flawed:
        return found, None
    held = [f"the robot's own odometry ({', '.join(own)})"] if own else []
    held += [f"{label}, listed with a warning" for label in flawed]
    return found, " and ".join(held)


def _storage(path: Path) -> str:
    if path.suffix == ".bag":
        return "ros1"
    folder = path if path.is_dir() else path.parent
    if path.suffix == ".mcap" or (path.is_dir() and any(folder.glob("*.mcap"))):
        return "mcap"
    return "sqlite3"


def _contents(
    scanned: Sequence[ScannedTopic],
) -> tuple[list[JointStateInfo], list[ModelStatesInfo]]:
    """The joints of the joint-state topics and the models of the model-state topics."""
    joint_states: list[JointStateInfo] = []
    model_states: list[ModelStatesInfo] = []
    for topic in scanned:
        if topic.msgtype == MODEL_STATES and topic.content is not None:
            models = topic.content.model_motion()
            model_states.append(
                ModelStatesInfo(
                    topic.name,
                    tuple(models[:MAX_LISTED]),
                    max(len(models) - MAX_LISTED, 0),
                    topic.content.decoded,
                )
            )
        if topic.msgtype == JOINT_STATE and topic.content is not None:
            joints = [
                JointInfo(
                    name, s.samples, s.position_range, s.max_speed[0], s.moving, s.max_speed[1]
                )
                for name, s in topic.content.joints.items()
            ]
            joint_states.append(
                JointStateInfo(
                    topic.name,
                    tuple(joints[:MAX_LISTED]),
                    max(len(joints) - MAX_LISTED, 0),
                    topic.content.decoded,
                    topic.scan.complete,
                )
            )
    return joint_states, model_states


def bag_info(path: str | Path, *, max_messages: int = DEFAULT_MAX_MESSAGES) -> BagInfo:
    """What is in a bag, and the options to read it with (see the module docstring).

    Parameters
    ----------
    path : str or Path
        A ROS 1 ``.bag`` file, a ROS 2 bag folder, or its ``.db3``/``.mcap`` file.
    max_messages : int
        Messages deserialized per topic at most (at least 1).

    Raises
    ------
    InputError
        The bag cannot be read.
    """
    src = str(path)
    if max_messages < 1:
        raise InputError(f"{option('max_messages', max_messages)}: must be at least 1")
    notes: list[str] = []
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)
        total = int(reader.message_count)
        start = int(reader.start_time) if total else None
        end = int(reader.end_time) - 1 if total else None
        scanned = inspect_topics(
            reader, topics, src, max_messages, wanted=lambda t, m: True, notes=notes
        )
        robot, robot_problem = read_description(reader, topics, src)
        imus = sorted(imu_infos(reader, topics, scanned, src), key=lambda i: i.problem is not None)
    transforms = transform_infos(scanned)
    chains = tf_chains(transforms)
    truth, instead = _rank(scanned, transforms, chains)
    if instead is not None:
        notes.append(
            f"no ground truth independent of the odometry: the bag holds only {instead}; "
            "calibrating against the odometry measures nothing: record a reference (motion "
            "capture, RTK GPS, a simulator's ground truth, a localization such as AMCL). "
            "(A simulator's diff-drive plugin that takes its odometry from the world pose, "
            "as gazebo_ros_diff_drive does by default in ROS 1, publishes the true pose "
            "there: give it with "
            "--truth-topic if so.)"
        )
    if robot_problem is not None:
        notes.append(robot_problem)
    joint_states, model_states = _contents(scanned)
    empty = []
    for topic in scanned:
        content = topic.content
        if content is not None and content.stamped and content.empty_stamps == content.stamped:
            empty.append(topic.name)
            notes.append(
                f"{topic.name}: every header stamp read is zero; read it with --time-source bag"
            )
    infos = [
        TopicInfo(
            t.name,
            t.msgtype,
            t.count,
            t.duration,
            t.rate,
            t.content.decoded if t.content is not None else 0,
        )
        for t in scanned
    ]
    complete = all(t.scan.complete for t in scanned if t.content is not None)
    return BagInfo(
        path=src,
        storage=_storage(Path(path)),
        start=None if start is None else start * 1e-9,
        duration=0.0 if start is None or end is None else (end - start) * 1e-9,
        messages=total,
        topics=tuple(infos[:MAX_LISTED]),
        topics_not_listed=max(len(infos) - MAX_LISTED, 0),
        joint_states=tuple(joint_states),
        transforms=tuple(transforms[:MAX_LISTED]),
        transforms_not_listed=max(len(transforms) - MAX_LISTED, 0),
        chains=tuple(chains[:MAX_CHAINS]),
        chains_not_listed=max(len(chains) - MAX_CHAINS, 0),
        wheels=tuple(wheel_candidates(scanned, transforms)[:MAX_LISTED]),
        odometry=tuple(odometry_candidates(scanned, transforms)[:MAX_LISTED]),
        truth=tuple(truth[:MAX_LISTED]),
        max_messages=max_messages,
        complete=complete,
        notes=split_messages(notes)[0],
        warnings=split_messages(notes)[1],
        empty_stamps=tuple(empty),
        model_states=tuple(model_states),
        robot=robot,
        robot_problem=robot_problem,
        independent=instead is None and any(c.warning is None for c in truth),
        laser_scans=tuple(t.name for t in scanned if t.msgtype == LASER_SCAN),
        imus=tuple(imus[:MAX_LISTED]),
    )


def truth_candidates(
    path: str | Path, *, max_messages: int = 200
) -> tuple[list[Candidate], str | None]:
    """The ground-truth candidates of a bag, likeliest first, from a quick look: pose,
    odometry, model-state and position topics, and the transforms of ``/tf`` and
    ``/tf_static``, with at most ``max_messages`` messages of each looked into (spread
    over its time span).

    Returns
    -------
    candidates : list of Candidate
    instead : str or None
        When no candidate is independent of the odometry: what the bag holds instead
        (``the robot's own odometry (/odom)``).

    Raises
    ------
    InputError
        The bag cannot be read.
    """
    src = str(path)
    with bag_reader.open_bag(Path(path), src) as reader:
        topics = bag_reader.topic_types(reader)

        def wanted(topic: str, msgtype: str) -> bool:
            return msgtype in (*REFERENCE_TYPES, ODOMETRY) or topic in (TF_TOPIC, TF_STATIC_TOPIC)

        scanned = inspect_topics(reader, topics, src, max_messages, wanted=wanted, notes=[])
    transforms = transform_infos(scanned)
    return _rank(scanned, transforms, tf_chains(transforms))

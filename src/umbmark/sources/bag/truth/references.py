"""Ground truth beyond pose topics: Gazebo's model states and position-only references.

``gazebo_msgs/ModelStates``
    What Gazebo (classic) publishes on ``/gazebo/model_states`` (ROS 1) or
    ``/model_states`` (ROS 2, ``gazebo_ros_state``): the ``name``, ``pose`` and ``twist``
    of every model in the world, and no header. One model is the robot: the one named by
    ``truth_model``, else the only one that moves (:func:`moving_models`; the ground
    plane and the furniture stand still). Samples are stamped with the bag's receive
    times. Bags that do not carry the type's definition (ROS 2 sqlite3 before Iron) get
    the definition of ``gazebo_msgs/msg/ModelStates`` from here (:data:`MODEL_STATES_MSG`).
``geometry_msgs/PointStamped``
    A tracked point (a total station's prism, a UWB tag, a marker's centroid): ``x, y``
    of ``point``, no heading.
``sensor_msgs/NavSatFix``
    A GNSS receiver's fixes (RTK for a useful reference): latitude, longitude [deg] and
    altitude [m] on WGS84, converted to east and north [m] of a local tangent plane about
    the first fix (:func:`enu`), with their ``position_covariance`` (east, north block,
    [m^2]; NaN where ``position_covariance_type`` is unknown). Fixes without a fix
    (``status.status < 0``) are dropped, with a note.

Position-only references give a :class:`~umbmark.model.recording.PoseSeries` with
``headings=False`` (NaN headings): the estimators that use end positions only take them,
those that need headings refuse them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError, option
from umbmark.core.messages import info
from umbmark.model.recording import PoseSeries
from umbmark.sources.bag import custom
from umbmark.sources.bag import reader as bag_reader
from umbmark.sources.bag.fastpath import POSITION, Sample
from umbmark.sources.bag.msgtypes import (
    MODEL_STATES,
    NAV_SAT_FIX,
    POINT_STAMPED,
    ModelStates,
    NavSatFix,
    PointStamped,
)
from umbmark.sources.bag.samples import clean, pose_values, read_topic, stamp, time_ns, truth_series

if TYPE_CHECKING:
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import Connection

__all__ = [
    "MODEL_STATES_MSG",
    "ModelMotion",
    "ModelRanges",
    "enu",
    "moving_models",
    "read_model_states",
    "read_positions",
    "register_model_states",
]


#: ``gazebo_msgs/msg/ModelStates`` (gazebo_ros_pkgs, ROS 1 and ROS 2 alike).
MODEL_STATES_MSG = """\
string[] name
geometry_msgs/Pose[] pose
geometry_msgs/Twist[] twist
"""
#: Model-state messages looked into to find the model that moves, at most.
MAX_INSPECTED = 2_000
#: A model whose position ranges over more than this [m] moves.
MOVING_DISTANCE = 0.05
#: Models Gazebo's worlds hold that are never the robot.
_SCENERY = ("ground_plane", "sun")

# WGS84
_A = 6_378_137.0
_F = 1.0 / 298.257223563
_E2 = _F * (2.0 - _F)


def register_model_states(reader: AnyReader, src: str) -> None:
    """Give rosbags the definition of ``gazebo_msgs/msg/ModelStates`` if the bag lacks it."""
    store = reader.typestore
    if not custom.missing_types(store.fielddefs, MODEL_STATES):
        return
    from rosbags.typesys import get_types_from_msg

    try:
        store.register(get_types_from_msg(MODEL_STATES_MSG, MODEL_STATES))
    except Exception as err:  # a clash with a different definition in the bag
        raise InputError(
            f"cannot use the definition of {MODEL_STATES}: {bag_reader.one_line(err)}",
            source=src,
        ) from None


@dataclass(frozen=True)
class ModelMotion:
    """One model of a ``gazebo_msgs/ModelStates`` topic, in the messages looked into.

    Attributes
    ----------
    name : str
    samples : int
        Messages that hold it.
    position_range : float
        Largest range of its ``x`` or ``y`` [m].
    """

    name: str
    samples: int
    position_range: float

    @property
    def moving(self) -> bool:
        """Whether it moves more than :data:`MOVING_DISTANCE`."""
        return self.position_range > MOVING_DISTANCE


@dataclass
class ModelRanges:
    """How far each model of ``gazebo_msgs/ModelStates`` messages moved: the messages
    added one at a time (:meth:`add`), at most ``limit`` models tracked (None: all)."""

    limit: int | None = None
    ranges: dict[str, list[float]] = field(default_factory=dict)  # x, y low; x, y high; count

    def add(self, msg: ModelStates) -> None:
        """The finite positions of one message's models."""
        for raw, pose in zip(msg.name, msg.pose, strict=False):
            x, y = float(pose.position.x), float(pose.position.y)
            if not (math.isfinite(x) and math.isfinite(y)):
                continue
            name = str(raw)
            v = self.ranges.get(name)
            if v is None:
                if self.limit is not None and len(self.ranges) >= self.limit:
                    continue
                v = self.ranges[name] = [x, y, x, y, 0.0]
            v[0], v[1], v[2], v[3] = min(v[0], x), min(v[1], y), max(v[2], x), max(v[3], y)
            v[4] += 1

    def motion(self) -> list[ModelMotion]:
        """The models, in order of first appearance, and how far they moved."""
        return [
            ModelMotion(name, int(v[4]), max(v[2] - v[0], v[3] - v[1]))
            for name, v in self.ranges.items()
        ]


def moving_models(models: Sequence[ModelMotion]) -> list[str]:
    """The models that move, scenery (the ground plane, the sun) left out."""
    return [m.name for m in models if m.moving and m.name not in _SCENERY]


def _choose_model(
    reader: AnyReader, conns: Sequence[Connection], topic: str, model: str | None, src: str
) -> str:
    """``model``, or the one model of ``topic`` that moves."""
    total = bag_reader.message_count(conns)
    stride = max(1, total // MAX_INSPECTED)
    ranges = ModelRanges()
    for k, (_, raw) in enumerate(bag_reader.raw_messages(reader, conns, topic, src)):
        if k % stride == 0:
            ranges.add(bag_reader.deserialize(reader, raw, MODEL_STATES, topic, src))  # type: ignore[arg-type]
    models = ranges.motion()
    names = [m.name for m in models]
    if model is not None:
        if model not in names:
            raise InputError(
                f"no model {model!r} in {topic}; models present: "
                f"{bag_reader.listing(names) if names else 'none'}",
                source=src,
            )
        return model
    moving = moving_models(models)
    if len(moving) == 1:
        return moving[0]
    if moving:
        raise InputError(
            f"several models of {topic} move ({bag_reader.listing(moving)}): name the robot "
            f"with {option('truth_model')}",
            source=src,
        )
    raise InputError(
        f"no model of {topic} moves more than {MOVING_DISTANCE:g} m; models present: "
        f"{bag_reader.listing(names) if names else 'none'} (name the robot with "
        f"{option('truth_model')})",
        source=src,
    )


def read_model_states(
    reader: AnyReader, topics: dict[str, str], topic: str, model: str | None, src: str
) -> tuple[PoseSeries, str]:
    """The pose of one model of a ``gazebo_msgs/ModelStates`` topic over bag time.

    Returns
    -------
    truth : PoseSeries
        ``x, y`` [m], yaw [rad] of the model, at the bag's receive times [s].
    model : str
        The model read (``model``, or the one that moves).

    Raises
    ------
    InputError
        The topic is missing or of another type, the model is absent, or no single model
        moves.
    """
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (MODEL_STATES,), "ground truth", src
    )
    register_model_states(reader, src)
    chosen = _choose_model(reader, conns, topic, model, src)

    def decode(msg: ModelStates) -> list[Sample]:
        names = list(msg.name)
        if chosen not in names:
            return []
        pose = msg.pose[names.index(chosen)]
        return [(0, 0, pose_values(pose.position, pose.orientation), POSITION)]

    scan = read_topic(reader, conns, msgtype, topic, src, width=6, decode=decode, layout_of=None)
    what = f"model {chosen} of topic {topic}"
    return truth_series(time_ns(scan, False), scan.values, what, src, header=False), chosen


# --- position-only references ------------------------------------------------------------


def enu(latitude: FloatArray, longitude: FloatArray, altitude: FloatArray) -> FloatArray:
    """East, north [m] of WGS84 fixes (degrees, metres; shape (k,)) on the tangent plane
    at the first fix, shape (k, 2): exact through Earth-centred coordinates."""
    lat, lon = np.radians(latitude), np.radians(longitude)
    n = _A / np.sqrt(1.0 - _E2 * np.sin(lat) ** 2)
    x = (n + altitude) * np.cos(lat) * np.cos(lon)
    y = (n + altitude) * np.cos(lat) * np.sin(lon)
    z = (n * (1.0 - _E2) + altitude) * np.sin(lat)
    dx, dy, dz = x - x[0], y - y[0], z - z[0]
    s0, c0 = math.sin(lat[0]), math.cos(lat[0])
    sl, cl = math.sin(lon[0]), math.cos(lon[0])
    east = -sl * dx + cl * dy
    north = -s0 * cl * dx - s0 * sl * dy + c0 * dz
    return np.column_stack([east, north])


def read_positions(
    reader: AnyReader, topics: dict[str, str], topic: str, header: bool, src: str
) -> tuple[PoseSeries, list[str]]:
    """A position-only reference: ``geometry_msgs/PointStamped`` or ``sensor_msgs/NavSatFix``.

    Returns
    -------
    truth : PoseSeries
        ``x, y`` [m] (east, north of the first fix for NavSatFix), NaN headings
        (``headings=False``), with the fixes' covariance for NavSatFix.
    notes : list of str
        Fixes dropped for having no fix; the fixes' typical standard deviation.
    """
    conns, msgtype = bag_reader.topic_connections(
        reader, topics, topic, (POINT_STAMPED, NAV_SAT_FIX), "ground truth", src
    )
    what = f"topic {topic}"
    if msgtype == POINT_STAMPED:

        def decode_point(msg: PointStamped) -> list[Sample]:
            sec, nsec = stamp(msg)
            return [(sec, nsec, (float(msg.point.x), float(msg.point.y)), POSITION)]

        scan = read_topic(
            reader, conns, msgtype, topic, src, width=2, decode=decode_point, layout_of=None
        )
        _, time, xy = clean(time_ns(scan, header), scan.values, what, src, header=header)
        poses = np.column_stack([xy, np.full(time.size, np.nan)])
        return PoseSeries(time=time, poses=poses, headings=False), []

    no_fix = 0

    def decode_fix(msg: NavSatFix) -> list[Sample]:
        nonlocal no_fix
        if int(msg.status.status) < 0:
            no_fix += 1
            return []
        sec, nsec = stamp(msg)
        c = np.asarray(msg.position_covariance, dtype=np.float64)
        known = int(msg.position_covariance_type) > 0 and c.size == 9
        cov = (float(c[0]), float(c[1]), float(c[4])) if known else (math.nan,) * 3
        values = (float(msg.latitude), float(msg.longitude), float(msg.altitude), *cov)
        return [(sec, nsec, values, POSITION)]

    scan = read_topic(
        reader, conns, msgtype, topic, src, width=6, decode=decode_fix, layout_of=None
    )
    notes: list[str] = []
    if no_fix:
        notes.append(info(f"{topic}: left out {no_fix} message(s) without a fix (status < 0)"))
    values = scan.values
    finite = np.all(np.isfinite(values[:, :3]), axis=1)
    stamps = time_ns(scan, header)
    covariance = values[:, 3:6]
    _, time, rows = clean(
        stamps[finite],
        np.column_stack([values[finite, :3], np.arange(int(finite.sum()))]),
        what,
        src,
        header=header,
    )
    kept = rows[:, 3].astype(np.int64)
    cov = covariance[finite][kept]
    matrices = np.stack(
        [np.stack([cov[:, 0], cov[:, 1]], axis=1), np.stack([cov[:, 1], cov[:, 2]], axis=1)],
        axis=1,
    )
    xy = enu(rows[:, 0], rows[:, 1], rows[:, 2])
    poses = np.column_stack([xy, np.full(time.size, np.nan)])
    sigma = np.sqrt(0.5 * (cov[:, 0] + cov[:, 2]))
    if np.any(np.isfinite(sigma)):
        typical = float(np.nanmedian(sigma))
        notes.append(
            info(
                f"{topic}: GNSS fixes with a median horizontal standard deviation of "
                f"{1000 * typical:.0f} mm (their position_covariance)"
            )
        )
    return PoseSeries(time=time, poses=poses, headings=False, covariance=matrices), notes

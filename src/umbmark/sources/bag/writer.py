"""Writing ROS bags: a robot's wheels, odometry and ground truth, as a ROS robot records them.

The counterpart of :mod:`.reader`: :func:`write_bag` writes a recording with rosbags'
writers, typestores (ROS 1 Noetic, ROS 2 Humble) and serializers, on the topics a
differential-drive robot with motion capture publishes (names in :class:`BagTopics`):

* ``/joint_states`` (``sensor_msgs/JointState``): the left and right wheel joints'
  positions [rad] and velocities [rad/s] (the position differences over time);
* ``/odom`` (``nav_msgs/Odometry``, ``odom -> base_link``): the robot's own odometry,
  with its body twist (the pose differences over time, in ``base_link``);
* ``/tf`` (``tf2_msgs/TFMessage``): the same pose as the transform ``odom -> base_link``;
* ``/mocap/robot/pose`` (``geometry_msgs/PoseStamped``, frame ``world``): the ground truth;
* with ``scans``: ``/scan`` (``sensor_msgs/LaserScan``, frame ``laser``), the sweeps as
  given, and ``/tf_static`` with the mounting ``base_link -> laser`` (``laser_pose``,
  rolled by 180 degrees for a scanner mounted upside down);
* with ``imu``: ``/imu`` (``sensor_msgs/Imu``, frame ``imu_link``), its readings
  (:mod:`umbmark.sources.bag.imu_writer`), and its mounting ``base_link -> imu_link`` on
  ``/tf_static`` (one message with the laser's, where both are written);
* with ``description``: ``/robot_description`` (``std_msgs/String``), a URDF, once at
  the start (:func:`umbmark.sources.bag.urdf.robot_urdf` writes one).

Header stamps and bag (receive) times are equal: the recording's start epoch plus each
sample's time, in nanoseconds; messages are written in time order.

The format comes from the path as with ``rosbags-convert``: ``NAME.bag`` is a ROS 1 bag,
any other name a ROS 2 bag folder with ``sqlite3`` (rosbags' default) or ``mcap`` storage.
A bag is written whole or not at all: into a temporary folder beside the target, then
renamed onto it; on any failure (``KeyboardInterrupt`` too) the temporary folder is
removed and an existing bag (replaced only on request) is left as it was.

rosbags is imported only by :func:`write_bag` and :func:`bag_target`; without it both
give the readers' one line (:func:`umbmark.sources.bag.reader.missing_rosbags`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.core.atomic import atomic_tree, fsync
from umbmark.core.errors import InputError, option
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.model.scans import ScanSeries
from umbmark.sources.bag.imu_writer import ImuTrack, imu_maker
from umbmark.sources.bag.msgtypes import (
    IMU,
    JOINT_STATE,
    LASER_SCAN,
    ODOMETRY,
    POSE_STAMPED,
    STRING,
    TF_MESSAGE,
    TF_STATIC_TOPIC,
    TF_TOPIC,
)
from umbmark.sources.bag.reader import missing_rosbags, one_line

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["BAG_STORAGES", "START_EPOCH", "BagFormat", "BagTarget", "BagTopics", "bag_target"]
__all__ += ["write_bag"]

BagFormat = Literal["ros1", "sqlite3", "mcap"]
#: Storage plugins of a ROS 2 bag; the first is rosbags' default.
BAG_STORAGES: tuple[Literal["sqlite3", "mcap"], ...] = ("sqlite3", "mcap")
#: The recording's first stamp [s since the Unix epoch]: 2024-01-01T00:00:00Z.
START_EPOCH = 1_704_067_200
#: Samples written between two progress reports.
_REPORT_EVERY = 2000

#: Where a robot description goes.
DESCRIPTION_TOPIC = "/robot_description"
_Make = Callable[[int, int], "_Msg"]  # (sample index, stamp [ns]) -> message object

TF_DEFINITION = "geometry_msgs/TransformStamped[] transforms"


@dataclass(frozen=True)
class BagTopics:
    """Topic, joint and frame names of a written bag."""

    joint_states: str = "/joint_states"
    left_joint: str = "left_wheel_joint"
    right_joint: str = "right_wheel_joint"
    odometry: str = "/odom"
    tf: str = TF_TOPIC
    truth: str = "/mocap/robot/pose"
    odom_frame: str = "odom"
    base_frame: str = "base_link"
    world_frame: str = "world"
    scan: str = "/scan"
    laser_frame: str = "laser"


@dataclass(frozen=True)
class BagTarget:
    """Where a bag goes and in which format, checked before any work (:func:`bag_target`).

    Attributes
    ----------
    path : Path
        The bag as the user named it: a ``.bag`` file or a ROS 2 bag folder.
    format : {"ros1", "sqlite3", "mcap"}
    """

    path: Path
    format: BagFormat


def bag_target(
    path: str | os.PathLike[str], storage: str | None = None, *, force: bool = False
) -> BagTarget:
    """The bag to write at ``path``: its format, checked before anything is written.

    Parameters
    ----------
    path : path
        ``NAME.bag`` (ROS 1) or a folder name (ROS 2).
    storage : {"sqlite3", "mcap"}, optional
        The storage of a ROS 2 bag; sqlite3 when not given. Not for a ``.bag``.
    force : bool
        Replace an existing bag (a ``.bag`` file, or a folder holding a ``metadata.yaml``
        or nothing).

    Raises
    ------
    InputError
        Without rosbags; for an unknown storage, a storage for a ROS 1 bag, a ROS 2 bag
        named like its storage file, an existing path (without ``force``, or that is not a
        bag), or a folder that cannot be written to.
    """
    shown = Path(path)
    try:
        import rosbags.rosbag2  # noqa: F401
    except ImportError:
        raise missing_rosbags(str(shown), "writing") from None
    if storage is not None and storage not in BAG_STORAGES:
        raise InputError(
            f"{option('bag_storage', repr(storage))}: use one of {', '.join(BAG_STORAGES)}"
        )
    if shown.suffix == ".bag":
        if storage is not None:
            raise InputError(
                f"{option('bag_storage')} is for ROS 2 bags (a folder); {shown} is a ROS 1 bag: "
                "name a folder (without .bag) for ROS 2"
            )
        fmt: BagFormat = "ros1"
    elif shown.suffix in (".db3", ".mcap"):
        raise InputError(
            f"a ROS 2 bag is a folder: give its name without {shown.suffix} "
            f"({option('bag', str(shown.with_suffix('')))} "
            f"{option('bag_storage', 'mcap' if shown.suffix == '.mcap' else 'sqlite3')}); "
            "NAME.bag writes ROS 1",
            source=shown,
        )
    else:
        fmt = "mcap" if storage == "mcap" else "sqlite3"
    real = shown.resolve()
    if real.exists() or real.is_symlink():
        if not force:
            raise InputError(f"exists already; pass {option('force')} to replace it", source=shown)
        if fmt == "ros1" and not real.is_file():
            raise InputError("exists and is not a file; not replaced", source=shown)
        if fmt != "ros1" and not _is_ros2_bag_or_empty(real):
            raise InputError(
                "exists and is not a ROS 2 bag (a folder with a metadata.yaml); not replaced",
                source=shown,
            )
    parent = real.parent
    if not parent.is_dir():
        raise InputError(f"cannot be written (no such folder: {parent})", source=shown)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"cannot be written (no permission in {parent})", source=shown)
    return BagTarget(shown, fmt)


def _is_ros2_bag_or_empty(folder: Path) -> bool:
    return folder.is_dir() and ((folder / "metadata.yaml").is_file() or not any(folder.iterdir()))


def write_bag(
    target: BagTarget,
    wheels: WheelSeries,
    odometry: PoseSeries,
    truth: PoseSeries,
    *,
    topics: BagTopics | None = None,
    start_epoch: float = START_EPOCH,
    progress: Callable[[float], None] | None = None,
    scans: ScanSeries | None = None,
    laser_pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
    description: str | None = None,
    imu: ImuTrack | None = None,
) -> Path:
    """Write the wheels, the odometry and the ground truth as a ROS bag (module notes).

    Parameters
    ----------
    target : BagTarget
        From :func:`bag_target`.
    wheels : WheelSeries
        Wheel rotation [rad], left and right.
    odometry : PoseSeries
        The robot's odometry in its odometry frame (``/odom`` and ``/tf``).
    truth : PoseSeries
        The ground truth in the world frame.
    topics : BagTopics, optional
        Names; the defaults of :class:`BagTopics`.
    start_epoch : float
        Stamp of time 0 [s since the Unix epoch].
    progress : callable, optional
        Called now and then with the fraction of messages written (0 to 1).
    scans : ScanSeries, optional
        A laser's sweeps, on the wheels' clock, written as ``/scan``.
    laser_pose : tuple of float
        The laser's mounting ``x, y, yaw`` [m, m, rad] in ``base_link`` (``/tf_static``).
    description : str, optional
        A URDF, written once at the start as ``/robot_description`` (``std_msgs/String``).
    imu : ImuTrack, optional
        An IMU's readings, on the wheels' clock, written as its topic with its mounting.

    Returns
    -------
    Path
        ``target.path``.

    Raises
    ------
    InputError
        Without rosbags, or when the bag cannot be written (the system's or rosbags'
        reason, on one line).
    """
    names = topics or BagTopics()
    shown = target.path
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise missing_rosbags(str(shown), "writing") from None
    store = get_typestore(Stores.ROS1_NOETIC if target.format == "ros1" else Stores.ROS2_HUMBLE)
    if TF_MESSAGE not in store.types:  # Noetic's store has no tf2_msgs: ROS 1's definition
        from rosbags.typesys import get_types_from_msg

        store.register(get_types_from_msg(TF_DEFINITION, TF_MESSAGE))
    import sqlite3

    from rosbags.rosbag1 import WriterError as Ros1WriterError
    from rosbags.rosbag2 import WriterError as Ros2WriterError

    try:
        with atomic_tree(shown) as fresh:
            _write(fresh, target.format, store, names, wheels, odometry, truth, start_epoch,
                   progress, scans, laser_pose, description, imu)  # fmt: skip
            for file in [fresh] if fresh.is_file() else sorted(fresh.iterdir()):
                fsync(file)
    except OSError as err:
        raise InputError(f"cannot be written ({err.strerror or err})", source=shown) from None
    except (sqlite3.Error, Ros1WriterError, Ros2WriterError) as err:
        raise InputError(f"cannot be written ({one_line(err)})", source=shown) from None
    if progress is not None:
        progress(1.0)
    return shown


def _stamps(time: FloatArray, start_epoch: float) -> NDArray[np.int64]:
    """Nanoseconds since the epoch of times [s] from the recording's start."""
    nanoseconds = np.round(time * 1e9).astype(np.int64)
    return np.asarray(nanoseconds + round(start_epoch * 1e9), dtype=np.int64)


def _rates(time: FloatArray, values: FloatArray) -> FloatArray:
    """Backward differences over time, shape of ``values``; zero at the first sample."""
    out = np.zeros_like(values)
    out[1:] = np.diff(values, axis=0) / np.diff(time)[:, None]
    return out


def _body_twist(odometry: PoseSeries) -> FloatArray:
    """Forward speed [m/s] and turn rate [rad/s] between samples, shape (n, 2)."""
    pose = odometry.poses
    heading = np.unwrap(pose[:, 2])
    d = _rates(odometry.time, np.column_stack([pose[:, :2], heading]))
    mid = heading - 0.5 * np.diff(heading, prepend=heading[:1])
    return np.column_stack([d[:, 0] * np.cos(mid) + d[:, 1] * np.sin(mid), d[:, 2]])


def _laser_mounting(
    pose: tuple[float, float, float], upside_down: bool
) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """The laser's translation and quaternion ``x, y, z, w`` in ``base_link``: yawed by
    ``pose``'s yaw, then (upside down) rolled by pi about the new x (``q_yaw q_roll``)."""
    x, y, yaw = pose
    c, s = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return (x, y, 0.0), ((c, s, 0.0, 0.0) if upside_down else (0.0, 0.0, s, c))


def _write(
    path: Path,
    fmt: BagFormat,
    store: Typestore,
    names: BagTopics,
    wheels: WheelSeries,
    odometry: PoseSeries,
    truth: PoseSeries,
    start_epoch: float,
    progress: Callable[[float], None] | None,
    scans: ScanSeries | None = None,
    laser_pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
    description: str | None = None,
    imu: ImuTrack | None = None,
) -> None:
    """Write the bag at ``path`` (which does not exist yet)."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2

    messages = _Messages(store, names, ros1=fmt == "ros1")
    series: list[tuple[str, str, FloatArray, _Make]] = [
        (names.joint_states, JOINT_STATE, wheels.time, messages.joint_states(wheels)),
        (names.odometry, ODOMETRY, odometry.time, messages.odometry(odometry)),
        (names.tf, TF_MESSAGE, odometry.time, messages.transform(odometry)),
        (names.truth, POSE_STAMPED, truth.time, messages.truth(truth)),
    ]
    mounted: list[tuple[str, tuple[float, ...], tuple[float, ...]]] = []
    earliest = [float(wheels.time[0])]
    if scans is not None:
        mounted.append((names.laser_frame, *_laser_mounting(laser_pose, scans.upside_down)))
        earliest.append(float(scans.times[0]))
        series.append((names.scan, LASER_SCAN, scans.times, messages.scan(scans)))
    if imu is not None:
        mounted.append((imu.frame, imu.translation, imu.rotation))
        earliest.append(float(imu.time[0]))
        make_imu = imu_maker(messages.t, messages.header, imu)
        series.append((imu.topic, IMU, imu.time, make_imu))  # type: ignore[arg-type]
    if mounted:
        at_start = np.array([min(earliest)])
        static = (TF_STATIC_TOPIC, TF_MESSAGE, at_start, messages.mounting(mounted))
        series.insert(4, static)  # before the sensors' first messages of the same stamp
    if description is not None:
        text = store.types[STRING](data=description)
        once = np.array([float(wheels.time[0])])
        series.append((DESCRIPTION_TOPIC, STRING, once, lambda i, stamp: text))
    writer: Writer1 | Writer2
    if fmt == "ros1":
        writer = Writer1(path)
        serialize = store.serialize_ros1
    else:
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=Writer2.VERSION_LATEST, storage_plugin=plugin)
        serialize = store.serialize_cdr
    # Every message in time order: (stamp, series) sorted, series order among equal stamps.
    stamps = [_stamps(s, start_epoch) for _, _, s, _ in series]
    when = np.concatenate(stamps)
    which = np.concatenate([np.full(s.size, k) for k, s in enumerate(stamps)])
    index = np.concatenate([np.arange(s.size) for s in stamps])
    order = np.lexsort((which, when))
    total = int(order.size)
    with writer:
        conns = [writer.add_connection(topic, typ, typestore=store) for topic, typ, _, _ in series]
        types = [typ for _, typ, _, _ in series]
        makers = [make for _, _, _, make in series]
        for first in range(0, total, _REPORT_EVERY):
            if progress is not None:
                progress(first / total)
            block = order[first : first + _REPORT_EVERY]
            for stamp, k, i in zip(
                when[block].tolist(), which[block].tolist(), index[block].tolist(), strict=True
            ):
                writer.write(conns[k], stamp, serialize(makers[k](i, stamp), types[k]))


class _Msg(Protocol):
    """A message object of a typestore (what rosbags' constructors take as a field)."""

    __msgtype__: ClassVar[str]


class _Messages:
    """Message objects of a typestore, made one sample at a time."""

    def __init__(self, store: Typestore, names: BagTopics, *, ros1: bool) -> None:
        self.t = store.types
        self.names = names
        self.ros1 = ros1
        self.seq: dict[str, int] = {}  # ROS 1 headers count their messages per topic

    def header(self, stamp: int, frame: str, topic: str) -> _Msg:
        t = self.t
        sec, nanosec = divmod(stamp, 1_000_000_000)
        time = t["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
        if not self.ros1:
            return t["std_msgs/msg/Header"](stamp=time, frame_id=frame)
        seq = self.seq.get(topic, 0)
        self.seq[topic] = seq + 1
        return t["std_msgs/msg/Header"](seq=seq, stamp=time, frame_id=frame)

    def quaternion(self, yaw: float) -> _Msg:
        return self.t["geometry_msgs/msg/Quaternion"](
            x=0.0, y=0.0, z=math.sin(0.5 * yaw), w=math.cos(0.5 * yaw)
        )

    def pose(self, x: float, y: float, yaw: float) -> _Msg:
        t = self.t
        return t["geometry_msgs/msg/Pose"](
            position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
            orientation=self.quaternion(yaw),
        )

    def vector(self, x: float, y: float, z: float) -> _Msg:
        return self.t["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)

    def joint_states(self, wheels: WheelSeries) -> _Make:
        """``/joint_states``: positions and velocities of the two wheel joints."""
        t, topic = self.t, self.names.joint_states
        joints = [self.names.left_joint, self.names.right_joint]
        position, velocity = wheels.angles, _rates(wheels.time, wheels.angles)
        no_effort = np.empty(0, dtype=np.float64)

        def make(i: int, stamp: int) -> _Msg:
            return t[JOINT_STATE](
                header=self.header(stamp, "", topic),
                name=joints,
                position=position[i].copy(),
                velocity=velocity[i].copy(),
                effort=no_effort,
            )

        return make

    def odometry(self, odometry: PoseSeries) -> _Make:
        """``/odom``: the pose in ``odom`` and the body twist in ``base_link``."""
        t, names = self.t, self.names
        poses, twist = odometry.poses, _body_twist(odometry)
        covariance = np.zeros(36, dtype=np.float64)

        def make(i: int, stamp: int) -> _Msg:
            v, w = twist[i].tolist()
            return t[ODOMETRY](
                header=self.header(stamp, names.odom_frame, names.odometry),
                child_frame_id=names.base_frame,
                pose=t["geometry_msgs/msg/PoseWithCovariance"](
                    pose=self.pose(*poses[i].tolist()), covariance=covariance
                ),
                twist=t["geometry_msgs/msg/TwistWithCovariance"](
                    twist=t["geometry_msgs/msg/Twist"](
                        linear=self.vector(v, 0.0, 0.0), angular=self.vector(0.0, 0.0, w)
                    ),
                    covariance=covariance,
                ),
            )

        return make

    def transform(self, odometry: PoseSeries) -> _Make:
        """``/tf``: ``odom -> base_link``."""
        t, names = self.t, self.names
        poses = odometry.poses

        def make(i: int, stamp: int) -> _Msg:
            x, y, yaw = poses[i].tolist()
            return t[TF_MESSAGE](
                transforms=[
                    t["geometry_msgs/msg/TransformStamped"](
                        header=self.header(stamp, names.odom_frame, names.tf),
                        child_frame_id=names.base_frame,
                        transform=t["geometry_msgs/msg/Transform"](
                            translation=self.vector(x, y, 0.0), rotation=self.quaternion(yaw)
                        ),
                    )
                ]
            )

        return make

    def truth(self, truth: PoseSeries) -> _Make:
        """The ground truth: ``geometry_msgs/PoseStamped`` in ``world``."""
        t, names = self.t, self.names
        poses = truth.poses

        def make(i: int, stamp: int) -> _Msg:
            return t[POSE_STAMPED](
                header=self.header(stamp, names.world_frame, names.truth),
                pose=self.pose(*poses[i].tolist()),
            )

        return make

    def mounting(self, mounted: list[tuple[str, tuple[float, ...], tuple[float, ...]]]) -> _Make:
        """``/tf_static``: ``base_link -> frame`` of every ``(frame, translation [m],
        quaternion x, y, z, w)``, in one message."""
        t, names = self.t, self.names

        def make(i: int, stamp: int) -> _Msg:
            return t[TF_MESSAGE](
                transforms=[
                    t["geometry_msgs/msg/TransformStamped"](
                        header=self.header(stamp, names.base_frame, TF_STATIC_TOPIC),
                        child_frame_id=frame,
                        transform=t["geometry_msgs/msg/Transform"](
                            translation=self.vector(*xyz),
                            rotation=t["geometry_msgs/msg/Quaternion"](
                                x=q[0], y=q[1], z=q[2], w=q[3]
                            ),
                        ),
                    )
                    for frame, xyz, q in mounted
                ]
            )

        return make

    def scan(self, scans: ScanSeries) -> _Make:
        """``/scan``: the sweeps as given (float32 ranges)."""
        t, names = self.t, self.names
        ranges = np.ascontiguousarray(scans.ranges, dtype=np.float32)
        angle_max = scans.angle_min + scans.angle_increment * (scans.beams - 1)
        period = float(np.median(np.diff(scans.times))) if len(scans) > 1 else 0.0
        empty = np.empty(0, dtype=np.float32)

        def make(i: int, stamp: int) -> _Msg:
            return t[LASER_SCAN](
                header=self.header(stamp, names.laser_frame, names.scan),
                angle_min=scans.angle_min,
                angle_max=angle_max,
                angle_increment=scans.angle_increment,
                time_increment=scans.time_increment,
                scan_time=period,
                range_min=scans.range_min,
                range_max=scans.range_max,
                ranges=ranges[i],
                intensities=empty,
            )

        return make

"""A ROS robot's IMU, without ROS (as :mod:`umbmark.robot.ros_common`, so it is tested
without rospy or rclpy): which ``sensor_msgs/Imu`` topic of the graph to take, the
readings its messages carry, and its frame's mounting in the base frame.

- **The topic** (:func:`pick_imu`): the one ``--imu-topic`` names, else the graph's
  ``sensor_msgs/Imu`` topic; of several, a filtered one before a raw one (``imu/data``
  before ``imu/data_raw``: the same gyro, the filter passes it through), then the
  shortest name, and the check line names the others.
- **The readings** (:class:`ImuBuffer`): each message's stamp (ROS time), angular
  velocity and linear acceleration in the IMU's frame, held for
  :data:`umbmark.robot.base.IMU_HELD` seconds at most; left out, and counted, as the bag
  reader leaves them out (:mod:`umbmark.sources.bag.imu`): messages that say they have no
  angular velocity (``angular_velocity_covariance[0] == -1``), readings that are not
  finite numbers, stamps not after the one before. An accelerometer-only stream (the
  angular velocity exactly 0 in every message) and one without a gyro are refused
  before the robot moves (:func:`gyro_problem`).
- **The mounting** (:func:`imu_mounting_of`): the chain of transforms from the IMU's
  frame (``header.frame_id``) to the base frame, composed in 3D (tilted, turned, upside
  down), from ``/tf_static`` (TF) and then the robot description's fixed joints: the
  bag reader's frame logic (:func:`umbmark.sources.bag.imu_frames.mounting_in`,
  :func:`umbmark.sources.bag.urdf.fixed_joints`).
"""

from __future__ import annotations

import math
import threading
from collections import Counter, deque
from collections.abc import Mapping, Sequence

import numpy as np

from umbmark.core.errors import InputError, option
from umbmark.model.gyro_series import GyroSeries
from umbmark.robot.base import IMU_HELD
from umbmark.robot.ros_common import stamp_seconds
from umbmark.sources.bag.imu_frames import Edges, ImuMounting, mounting_in, quaternion_matrix

__all__ = [
    "IMU_TYPES",
    "MAX_HELD",
    "ImuBuffer",
    "gyro_problem",
    "imu_edges",
    "imu_mounting_of",
    "imu_problem",
    "pick_imu",
]

#: The IMU's message type as ROS 1 and ROS 2 name it.
IMU_TYPES = ("sensor_msgs/Imu", "sensor_msgs/msg/Imu")
#: Readings held at most (:data:`IMU_HELD` seconds at 2 kHz).
MAX_HELD = round(2000 * IMU_HELD)
#: Messages looked at before the robot moves, for a gyro that gives nothing.
_FIRST = 10


def pick_imu(topics: Sequence[tuple[str, str]], given: str) -> tuple[str, str] | None:
    """The IMU topic to subscribe, and how it was chosen (for the check line).

    Parameters
    ----------
    topics : sequence of (name, type)
        The graph's topics (one row per type of a topic).
    given : str
        ``--imu-topic`` (empty: not given).

    Returns
    -------
    (topic, how) or None
        ``given`` where the graph has it as an IMU; else the graph's IMU topic (module
        notes); None: no IMU topic (or ``given`` not on the graph, or of another type:
        :func:`imu_problem` says which).
    """
    imus = sorted({name for name, kind in topics if kind in IMU_TYPES})
    if given:
        return (given, f"as given by {option('imu_topic')}") if given in imus else None
    if not imus:
        return None

    def rank(name: str) -> tuple[bool, int, int, str]:
        return (name.endswith("raw"), name.count("/"), len(name), name)

    chosen = min(imus, key=rank)
    others = [n for n in imus if n != chosen]
    if not others:
        return chosen, "found on the graph"
    return chosen, (
        f"found on the graph, of {', '.join(imus)} (a filtered one before a raw one; "
        f"{option('imu_topic')} takes another)"
    )


def imu_problem(topics: Sequence[tuple[str, str]], given: str) -> str:
    """Why ``given`` is no IMU topic of the graph (:func:`pick_imu` found none)."""
    kinds = sorted({kind for name, kind in topics if name == given})
    imus = sorted({name for name, kind in topics if kind in IMU_TYPES})
    found = f"the graph's IMU topics: {', '.join(imus)}" if imus else "the graph has no IMU"
    if kinds:
        return f"{option('imu_topic', given)} carries {', '.join(kinds)}, not sensor_msgs/Imu"
    return f"nobody publishes {option('imu_topic', given)}: {found} (--no-imu: none)"


class ImuBuffer:
    """The latest readings of an IMU topic, thread-safe: the subscriber's callback
    :meth:`put`s each message, the routine takes the readings since a time
    (:meth:`series`). In the IMU's own frame, the last :data:`IMU_HELD` seconds (and
    :data:`MAX_HELD` readings) at most."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._rows: deque[tuple[float, ...]] = deque(maxlen=MAX_HELD)
        self._frame: str | None = None
        self._seen = 0
        self._zero = 0  # messages whose angular velocity is exactly 0
        #: Messages left out, by reason (``no_gyro``, ``not_finite``, ``not_after``).
        self.dropped: Counter[str] = Counter()

    def put(self, msg: object) -> None:
        """Keep one ``sensor_msgs/Imu`` (called from the subscriber's thread)."""
        time = stamp_seconds(msg.header.stamp)  # type: ignore[attr-defined]
        w, a = msg.angular_velocity, msg.linear_acceleration  # type: ignore[attr-defined]
        rate = (float(w.x), float(w.y), float(w.z))
        accel = (float(a.x), float(a.y), float(a.z))
        if float(msg.linear_acceleration_covariance[0]) == -1.0:  # type: ignore[attr-defined]
            accel = (math.nan, math.nan, math.nan)
        with self._cond:
            self._seen += 1
            if self._frame is None:
                self._frame = str(msg.header.frame_id).lstrip("/")  # type: ignore[attr-defined]
            if float(msg.angular_velocity_covariance[0]) == -1.0:  # type: ignore[attr-defined]
                self.dropped["no_gyro"] += 1
            elif not all(math.isfinite(v) for v in (time, *rate)):
                self.dropped["not_finite"] += 1
            elif self._rows and time <= self._rows[-1][0]:
                self.dropped["not_after"] += 1
            else:
                self._zero += not any(rate)
                self._rows.append((time, *rate, *accel))
                while self._rows[0][0] < time - IMU_HELD:
                    self._rows.popleft()
            self._cond.notify_all()

    def wait_first(self, timeout: float, count: int = _FIRST) -> str | None:
        """The IMU's frame, once ``count`` messages came (or the first, after
        ``timeout`` wall seconds); None: none came."""
        import time

        deadline = time.monotonic() + timeout
        with self._cond:
            while self._seen < count:
                left = deadline - time.monotonic()
                if left <= 0.0:
                    break
                self._cond.wait(left)
            return self._frame

    def counts(self) -> tuple[int, int, int]:
        """Messages seen, readings kept, of them with an angular velocity of exactly 0."""
        with self._cond:
            return self._seen, len(self._rows), self._zero

    def series(self, since: float, mounting: ImuMounting, source: str) -> GyroSeries:
        """The readings stamped after ``since``, rotated into the base frame by
        ``mounting`` (accelerations only where every one of them gives them)."""
        with self._cond:
            rows = [r for r in self._rows if r[0] > since]
        values = np.asarray(rows, dtype=np.float64).reshape(-1, 7)
        rotation = mounting.rotation
        accel = values[:, 4:]
        return GyroSeries(
            time=values[:, 0].copy(),
            rate=values[:, 1:4] @ rotation.T,
            accel=accel @ rotation.T if np.isfinite(accel).all() else None,
            frame=mounting.frame,
            source=source,
        )


def gyro_problem(buffer: ImuBuffer, topic: str) -> str | None:
    """Why the IMU on ``topic`` gives no gyro readings, from its first messages (None:
    it does): none came, every one says it has none, or an angular velocity of exactly 0
    in every one (an accelerometer-only stream)."""
    seen, kept, zero = buffer.counts()
    fix = f"give another with {option('imu_topic')}, or leave it out with --no-imu"
    if seen == 0:
        return f"the IMU on {topic} said nothing: is it publishing? ({fix})"
    if kept == 0:
        why = dict(buffer.dropped)
        if why.get("no_gyro"):
            return (
                f"the IMU on {topic} says it has no angular velocity "
                f"(angular_velocity_covariance[0] = -1): no gyro readings ({fix})"
            )
        return f"the IMU on {topic} gives no finite, increasing readings ({why}; {fix})"
    if zero == kept:
        return (
            f"the IMU on {topic}: the angular velocity is exactly 0 in every message (an "
            f"accelerometer-only stream): no gyro readings ({fix})"
        )
    return None


def imu_edges(
    static: Mapping[str, tuple[str, Sequence[float], Sequence[float]]] | None = None,
    description: str | None = None,
) -> Edges:
    """The transforms an IMU frame is mounted by: ``static``, as ``/tf_static`` holds them
    (each child frame's parent, translation and quaternion ``x, y, z, w``), then the fixed
    joints of the robot ``description`` (URDF) whose child ``static`` does not state.

    Raises
    ------
    InputError
        The description is not a URDF (its reader's line).
    """
    from umbmark.sources.bag.urdf import fixed_joints

    edges: Edges = {}
    for child, (parent, _, q) in (static or {}).items():
        rotation = quaternion_matrix(*(float(v) for v in q))
        if rotation is not None:
            edges[(parent.lstrip("/"), child.lstrip("/"))] = (rotation, "/tf_static")
    if description:
        try:
            joints = fixed_joints(description)
        except ValueError as err:
            raise InputError(f"the robot description {err}") from None
        children = {child for _, child in edges}
        for child, (parent, rotation) in joints.items():
            if child not in children:
                edges[(parent, child)] = (rotation, "the robot description")
    return edges


def imu_mounting_of(edges: Edges, frame: str, base: str, topic: str) -> ImuMounting:
    """The IMU frame's mounting in ``base`` through ``edges`` (:func:`imu_edges`).

    Raises
    ------
    InputError
        The messages name no frame, or it has no transform to ``base``: one line naming
        the topic, the frame and what to publish.
    """
    if not frame:
        raise InputError(
            f"the IMU on {topic} names no frame (header.frame_id is empty): its mounting "
            "is unknown; publish its readings in its frame (--no-imu leaves it out)"
        )
    found = mounting_in(edges, frame, (base.lstrip("/"),))
    if found is None:
        known = sorted({name for pair in edges for name in pair})
        frames = f"frames known: {', '.join(known[:12])}" if known else "no transforms known"
        raise InputError(
            f"the IMU on {topic} reads in {frame}, which has no transform to {base} on "
            f"/tf_static nor in the robot description ({frames}): publish its mounting on "
            f"/tf_static ({option('base_frame')}; --no-imu leaves it out)"
        )
    return found

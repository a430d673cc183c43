"""What a ROS 1 and a ROS 2 robot share behind the :class:`~umbmark.robot.base.Robot`
interface, written once and exercised through the ROS 1 adapter (tested against a real
master): the latest odometry, scan, ranges and ground truth; the IMU's readings (its topic
found on the graph, its frame's mounting looked up once: :mod:`umbmark.robot.ros_imu`);
the velocity out and the zero velocity that stops the robot; the sensors' mountings,
looked up in TF once; waiting for the connection; sleeping on the robot's clock.

:mod:`umbmark.robot.ros1` and :mod:`umbmark.robot.ros2` add what differs: the node, its
clock, how a transform is looked up, how parameters are read and applied.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError, SafetyError, option
from umbmark.model.gyro_series import GyroSeries
from umbmark.robot.base import ImuSource, RangeReading, ScanSweep, StampedPose
from umbmark.robot.ros_common import (
    Latest,
    Mount,
    RosOptions,
    mount_from_transform,
    planar_pose,
    range_reading,
    scan_from_message,
    stamp_seconds,
    wait_on_clock,
)
from umbmark.robot.ros_imu import ImuBuffer, gyro_problem, imu_problem, pick_imu

if TYPE_CHECKING:
    from umbmark.sources.bag.imu_frames import ImuMounting

__all__ = ["RosRobot"]


class RosRobot:
    """The part of a ROS robot that does not depend on the ROS version.

    A subclass calls :meth:`_start` with its velocity publisher and the ``Twist`` type,
    subscribes its topics to :meth:`_on_odom`, :meth:`_on_truth` and the :class:`Latest`
    holders, the IMU topic :meth:`_find_imu` gives to :attr:`_imu_buffer`, and provides
    :meth:`now`, :meth:`_clock`, :meth:`_lookup` and :meth:`_imu_mounting`.
    """

    options: RosOptions
    name: str

    def _start(self, options: RosOptions, twist: type[Any], cmd: Any) -> None:  # noqa: ANN401
        """The shared state: ``cmd`` publishes ``twist`` messages on ``options.cmd_vel``."""
        self.options = options
        self._twist = twist
        self._cmd = cmd
        self._odom: Latest[StampedPose] = Latest()
        self._scan: Latest[Any] = Latest()
        self._truth: Latest[StampedPose] = Latest()
        self._ranges: list[Latest[Any]] = [Latest() for _ in options.ranges]
        self._mounts: dict[str, Mount] = {}
        self._imu_buffer = ImuBuffer()
        self._imu_topic: tuple[str, str] | None = None
        self._imu_source: ImuSource | None = None

    # --- what a subclass provides -------------------------------------------------------

    def now(self) -> float:
        """The robot's clock [s]."""
        raise NotImplementedError

    def _clock(self) -> threading.Condition:
        """Notified whenever the clock may have moved (a message came)."""
        raise NotImplementedError

    def _lookup(self, base: str, frame: str) -> Any:  # noqa: ANN401 (a TransformStamped)
        """The transform from ``base`` to ``frame``, waiting ``options.timeout``; raises
        whatever tf2 raises."""
        raise NotImplementedError

    def _imu_mounting(self, frame: str, topic: str) -> ImuMounting:
        """The IMU frame's mounting in the base frame (:mod:`umbmark.robot.ros_imu`);
        raises :class:`InputError` where there is none."""
        raise NotImplementedError

    # --- the IMU --------------------------------------------------------------------------

    def _find_imu(self, graph: Callable[[], list[tuple[str, str]]], grace: float) -> str | None:
        """The IMU topic to subscribe (:func:`~umbmark.robot.ros_imu.pick_imu`), the graph
        asked again for ``grace`` wall seconds where it shows none yet (discovery), for
        ``options.timeout`` where one was given; None: none used, or none on the graph.

        Raises
        ------
        InputError
            The topic given is not an IMU on the graph.
        """
        given = self.options.imu
        if given is None:
            return None
        deadline = time.monotonic() + (self.options.timeout if given else grace)
        while True:
            topics = graph()
            found = pick_imu(topics, given)
            if found is not None or time.monotonic() > deadline:
                break
            time.sleep(0.05)
        if found is None and given:
            self._stop()
            raise InputError(imu_problem(topics, given))
        self._imu_topic = found
        return None if found is None else found[0]

    # --- callbacks ------------------------------------------------------------------------

    def _on_odom(self, msg: Any) -> None:  # noqa: ANN401 (a nav_msgs Odometry)
        self._odom.put(StampedPose(stamp_seconds(msg.header.stamp), planar_pose(msg.pose.pose)))

    def _on_truth(self, msg: Any) -> None:  # noqa: ANN401 (a geometry_msgs PoseStamped)
        self._truth.put(StampedPose(stamp_seconds(msg.header.stamp), planar_pose(msg.pose)))

    # --- connection -----------------------------------------------------------------------

    def _wait_connected(
        self, subscribers: Callable[[], int], twist_type: str, odom_type: str
    ) -> None:
        """Wait for a subscriber of the velocity topic and the first odometry; from then on
        :meth:`send_velocity` checks that the subscriber stays."""
        timeout = self.options.timeout
        deadline = time.monotonic() + timeout
        while subscribers() == 0:
            if time.monotonic() > deadline:
                raise InputError(
                    f"nobody subscribes {self.options.cmd_vel} ({twist_type}) after "
                    f"{timeout:g} s: is the robot's controller running? ({option('cmd_vel')})"
                )
            time.sleep(0.01)
        if self._odom.wait(max(0.0, deadline - time.monotonic())) is None:
            raise InputError(
                f"no {odom_type} on {self.options.odom} in {timeout:g} s: "
                f"is the controller publishing it? ({option('odom_topic')})"
            )
        self._subscribers = subscribers

    def _mount(self, frame: str) -> Mount:
        """The sensor frame's mounting in the base frame, from TF (looked up once)."""
        mount = self._mounts.get(frame)
        if mount is not None:
            return mount
        base = self.options.base_frame
        try:
            transform = self._lookup(base, frame)
        except Exception as exc:  # tf2's LookupException, ConnectivityException, ...
            self._stop()
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise InputError(
                f"no TF from {base} to {frame!r} in {self.options.timeout:g} s ({detail}): "
                f"publish the sensor's mounting on /tf_static ({option('base_frame')})"
            ) from None
        mount = self._mounts[frame] = mount_from_transform(transform.transform)
        return mount

    # --- the Robot interface ----------------------------------------------------------

    def wait(self, duration: float) -> None:
        """Sleep ``duration`` seconds of the robot's clock, refusing to hang on a stopped
        one (after a zero velocity)."""
        try:
            wait_on_clock(self.now, duration, self._clock(), self.options.timeout)
        except InputError:
            self._stop()
            raise

    def send_velocity(self, linear: float, angular: float) -> None:
        """Publish a ``geometry_msgs`` Twist: ``linear.x`` [m/s], ``angular.z`` [rad/s]."""
        if not (math.isfinite(linear) and math.isfinite(angular)):
            self._stop()
            raise InputError(f"velocity ({linear!r}, {angular!r}) is not finite")
        subscribers = getattr(self, "_subscribers", None)
        if subscribers is not None and (linear or angular) and subscribers() == 0:
            self._stop()
            raise SafetyError(
                f"nobody subscribes {self.options.cmd_vel} any more: the controller stopped "
                "or is restarting"
            )
        self._cmd.publish(self._velocity(float(linear), float(angular)))

    def odometry(self) -> StampedPose | None:
        """The latest odometry pose, stamped with its header's time."""
        return self._odom.get()

    def scan(self) -> ScanSweep | None:
        """The latest scan with the laser's mounting from TF (None: no scan came)."""
        msg = self._scan.get()
        if msg is None:
            return None
        return scan_from_message(msg, self._mount(msg.header.frame_id), self.options.base_frame)

    def ranges(self) -> RangeReading | None:
        """The latest reading of each range sensor (None: a sensor said nothing yet)."""
        messages = [m for m in (latest.get() for latest in self._ranges) if m is not None]
        if not self._ranges or len(messages) < len(self._ranges):
            return None
        return range_reading(messages, [self._mount(m.header.frame_id) for m in messages])

    def ground_truth(self) -> StampedPose | None:
        """The latest ground-truth pose (None: no truth topic, or no message yet)."""
        return self._truth.get()

    def imu(self) -> ImuSource | None:
        """The IMU found on the graph (None: none, or ``--no-imu``), its frame's mounting
        looked up once its first messages came.

        Raises
        ------
        InputError
            Its messages say nothing, or carry no gyro, or its frame has no mounting.
        """
        if self._imu_topic is None:
            return None
        if self._imu_source is None:
            topic, how = self._imu_topic
            frame = self._imu_buffer.wait_first(self.options.timeout)
            problem = gyro_problem(self._imu_buffer, topic)
            if problem is not None:
                self._stop()
                raise InputError(problem)
            try:
                mounting = self._imu_mounting(frame or "", topic)
            except InputError:
                self._stop()
                raise
            self._imu_source = ImuSource(topic, mounting, how)
        return self._imu_source

    def gyro(self, since: float) -> GyroSeries | None:
        """The IMU's readings stamped after ``since``, in the base frame (None: no IMU)."""
        source = self.imu()
        if source is None:
            return None
        return self._imu_buffer.series(since, source.mounting, f"{self.name} {source.topic}")

    def _velocity(self, linear: float, angular: float) -> Any:  # noqa: ANN401 (a message)
        """The velocity message: a ``Twist`` (a ROS 2 subclass may stamp it)."""
        msg = self._twist()
        msg.linear.x, msg.angular.z = linear, angular
        return msg

    def _stop(self) -> None:
        """A zero velocity, whatever state ROS is in."""
        with contextlib.suppress(Exception):  # stopping must not raise
            self._cmd.publish(self._velocity(0.0, 0.0))

"""What the self-calibration needs of a robot, and the values it exchanges with one.

Frames and units follow :mod:`umbmark.core.conventions`: x forward, y to the left,
headings counter-clockwise positive, metres, radians, seconds. Poses are planar. The
odometry frame is the robot's own (``odom``); a sensor's mounting is its pose in the
robot's base frame (``base_link``), as TF gives it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol, runtime_checkable

import numpy as np

from umbmark.core.arrays import FloatArray

if TYPE_CHECKING:
    from umbmark.model.gyro_series import GyroSeries
    from umbmark.sources.bag.imu_frames import ImuMounting

__all__ = [
    "APPLY_METHODS",
    "IMU_HELD",
    "AppliedBy",
    "ApplyResult",
    "DriveParams",
    "ImuSource",
    "Pose2D",
    "RangeReading",
    "Robot",
    "ScanSweep",
    "StampedPose",
]


@dataclass(frozen=True)
class Pose2D:
    """A planar pose: position [m] and heading [rad]."""

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0

    def compose(self, other: Pose2D) -> Pose2D:
        """``self * other``: ``other`` (given in this pose's frame) in the outer frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            self.theta + other.theta,
        )

    def inverse(self) -> Pose2D:
        """The outer frame's origin seen from this pose."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return Pose2D(-c * self.x - s * self.y, s * self.x - c * self.y, -self.theta)

    def relative_to(self, origin: Pose2D) -> Pose2D:
        """This pose in the frame of ``origin`` (both in the same outer frame)."""
        return origin.inverse().compose(self)


@dataclass(frozen=True)
class StampedPose:
    """A pose at a time of the robot's clock [s]."""

    time: float
    pose: Pose2D


@dataclass(frozen=True)
class ScanSweep:
    """One sweep of a planar laser scanner (``sensor_msgs/LaserScan``).

    Attributes
    ----------
    time : float
        The robot's clock at the scan [s].
    angle_min, angle_increment : float
        Angle of the first beam and between beams [rad], in the laser's frame.
    ranges : array, shape (n,)
        Measured ranges [m]; NaN or inf, or outside ``range_min .. range_max``, is no return.
    range_min, range_max : float
        The scanner's valid range [m].
    mount : Pose2D
        The laser's pose in the robot's base frame (TF ``base_link -> laser``).
    lift : (float, float, float) or None
        The mounting's ``z, roll, pitch`` [m, rad, rad] as the robot states them (TF, its
        URDF: fixed-axis roll and pitch, yaw last), which the planar matching does not
        use; None where only the planar mounting is known.
    frame, base : str
        The laser's frame (``header.frame_id``) and the base frame (empty: not known).
    """

    time: float
    angle_min: float
    angle_increment: float
    ranges: FloatArray
    range_min: float
    range_max: float
    mount: Pose2D = field(default_factory=Pose2D)
    lift: tuple[float, float, float] | None = None
    frame: str = ""
    base: str = ""

    def angles(self) -> FloatArray:
        """Beam angles [rad], shape (n,), in the laser's frame."""
        return np.asarray(
            self.angle_min + self.angle_increment * np.arange(self.ranges.size), dtype=np.float64
        )


@dataclass(frozen=True)
class RangeReading:
    """Simultaneous readings of a few single-beam range sensors (``sensor_msgs/Range``),
    as the paper's "sonar calibrator": two facing one wall, one the other.

    Attributes
    ----------
    time : float
    ranges : array, shape (k,)
        Ranges [m] (NaN: no echo).
    mounts : tuple of Pose2D
        Each sensor's pose in the robot's base frame (it measures along its x axis).
    """

    time: float
    ranges: FloatArray
    mounts: tuple[Pose2D, ...]


#: How long a robot holds its IMU's readings [s] (:meth:`Robot.gyro`): ask more often.
IMU_HELD = 60.0


@dataclass(frozen=True)
class ImuSource:
    """The robot's IMU: where its readings come from and how its frame is mounted.

    Attributes
    ----------
    topic : str
        Its ``sensor_msgs/Imu`` topic (the virtual robot: what it would publish on).
    mounting : ImuMounting
        Its frame's rotation into the base frame, and where that was stated (TF, the
        robot's description): what its rates are put into the base frame with.
    chosen : str
        How the topic was chosen, for people (found on the graph, given, the virtual
        robot's).
    """

    topic: str
    mounting: ImuMounting
    chosen: str = ""

    def describe(self) -> str:
        """``the IMU on /imu (imu_link in base_link (/tf_static): roll 1.00, ...)``."""
        how = f"; {self.chosen}" if self.chosen else ""
        return f"the IMU on {self.topic} ({self.mounting.describe()}{how})"


@dataclass(frozen=True)
class DriveParams:
    """The odometry's parameters as a ``diff_drive_controller`` holds them.

    The UMBmark correction maps onto the multipliers one to one (``paper-notes.md``):
    ``left_wheel_radius_multiplier`` is ``c_L``, ``right_wheel_radius_multiplier`` is
    ``c_R``, ``wheel_separation_multiplier`` carries ``E_b``.
    """

    wheel_separation: float
    wheel_radius: float
    wheel_separation_multiplier: float = 1.0
    left_wheel_radius_multiplier: float = 1.0
    right_wheel_radius_multiplier: float = 1.0

    @property
    def wheelbase(self) -> float:
        """The wheelbase the odometry uses [m]."""
        return self.wheel_separation * self.wheel_separation_multiplier


ApplyMethod = Literal["reconfigure", "yaml", "none"]
#: How parameters reach a controller (:meth:`Robot.apply`).
APPLY_METHODS: tuple[ApplyMethod, ...] = ("reconfigure", "yaml", "none")


#: How parameters did reach a controller (:attr:`ApplyResult.method`): ``reconfigure``
#: (ROS 1's dynamic_reconfigure, the virtual robot at once), ``set_parameters`` (ROS 2:
#: set on the controller, which the controller manager then configures again),
#: ``reload`` (ROS 2: the parameter file appended to the controller's, which the manager
#: unloads and loads again), ``yaml`` (the parameter file written; the controller takes
#: it on a restart), ``none``.
AppliedBy = Literal["reconfigure", "set_parameters", "reload", "yaml", "none"]


@dataclass(frozen=True)
class ApplyResult:
    """What applying parameters did: the way they took (the one used, which may not be
    the one asked for), whether the controller now runs with them, a line for people, the
    file written (if any) and the line saying how it was changed."""

    method: AppliedBy
    active: bool
    message: str
    file: str | None = None
    wrote: str | None = None


@runtime_checkable
class Robot(Protocol):
    """A differential-drive robot, as the self-calibration drives and reads it.

    Every reading is the latest one with its time on the robot's clock (:meth:`now`), or
    None when there is none yet. :meth:`wait` lets the robot's time pass: a virtual robot
    simulates it (as fast as the computer allows), a real one sleeps on its clock (ROS
    time, so ``/use_sim_time`` works).
    """

    name: str

    def now(self) -> float:
        """The robot's clock [s]."""
        ...

    def wait(self, duration: float) -> None:
        """Let ``duration`` seconds of the robot's time pass."""
        ...

    def send_velocity(self, linear: float, angular: float) -> None:
        """Command a body velocity: ``linear`` [m/s] forward, ``angular`` [rad/s] ccw."""
        ...

    def odometry(self) -> StampedPose | None:
        """The latest odometry pose (frame ``odom``)."""
        ...

    def scan(self) -> ScanSweep | None:
        """The latest laser scan, if the robot has a scanner."""
        ...

    def ranges(self) -> RangeReading | None:
        """The latest range-sensor readings, if the robot has them."""
        ...

    def ground_truth(self) -> StampedPose | None:
        """The latest ground-truth pose (motion capture), if there is one."""
        ...

    def imu(self) -> ImuSource | None:
        """The robot's IMU, with its frame's mounting (None: it has none, or none is
        used); a ROS robot waits for its first reading to know its frame."""
        ...

    def gyro(self, since: float) -> GyroSeries | None:
        """The IMU's readings stamped after ``since`` [s] (the robot's clock), their rates
        in the base frame as read (scale error and bias in them), the last
        :data:`IMU_HELD` seconds at most; None: the robot has no IMU."""
        ...

    def drive_params(self) -> DriveParams:
        """The parameters the odometry runs with now."""
        ...

    def apply(self, params: DriveParams, method: ApplyMethod) -> ApplyResult:
        """Make the odometry run with ``params`` (or write them where the controller reads
        them, saying whether it runs with them yet)."""
        ...

    def close(self) -> None:
        """Stop the robot (a zero velocity) and release what the adapter holds."""
        ...

"""What the monitor is fed and what it says: the interface between its ROS-free core and
the nodes (ROS 1, ROS 2, the simulated robot) that feed it and publish what it says.

A node hands every message to a :class:`MonitorCore` as it arrives (the wheels' angles or
the controller's odometry, each laser sweep, each gyro reading: on the robot's clock,
``/clock`` where it runs) and asks it, once a second, for its :class:`MonitorStatus`, which
it publishes as a ``diagnostic_msgs/DiagnosticArray`` (:meth:`MonitorStatus.key_values`
are its key-values, each with its unit). The core never commands the robot: where
``--apply at-rest`` is asked, :meth:`MonitorCore.apply_due` names the parameters a node
applies through the robot's own apply paths, and :meth:`MonitorCore.applied` is told what
that did.

Units: SI (metres, radians, seconds) throughout; the frame and sign conventions of
``docs/conventions.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

from umbmark.core.arrays import FloatArray
from umbmark.robot.base import ApplyResult, DriveParams, Pose2D, ScanSweep

__all__ = [
    "FIGURES",
    "LEVELS",
    "ChangeFound",
    "CorrectedOdometry",
    "Figure",
    "Level",
    "MonitorCore",
    "MonitorStatus",
]

#: diagnostic_msgs/DiagnosticStatus levels, in its byte values' order (OK 0, WARN 1,
#: ERROR 2, STALE 3).
Level = Literal["OK", "WARN", "ERROR", "STALE"]
LEVELS: tuple[Level, ...] = ("OK", "WARN", "ERROR", "STALE")

#: The figures the monitor follows, in the order it says them, with their units.
FIGURES: tuple[tuple[str, str], ...] = (
    ("E_d", ""),
    ("E_b", ""),
    ("E_s", ""),
    ("laser_x", "m"),
    ("laser_y", "m"),
    ("laser_yaw", "rad"),
    ("k_g", ""),
    ("gyro_bias", "rad/s"),
)


@dataclass(frozen=True)
class Figure:
    """One figure's present estimate.

    Attributes
    ----------
    name : str
        One of :data:`FIGURES` (``E_d``, ``E_b``, ...).
    value : float or None
        The estimate (the robot's present state: since its last change); None while the
        window's motion does not determine it.
    half_width : float or None
        Half the width of its 95 % interval, in the figure's unit; None with ``value``.
    unit : str
        ``""`` for ratios, ``m``, ``rad``, ``rad/s``.
    note : str
        Why it is not determined (``"turned one way only"``, ``"no laser"``), or what it
        is relative to (``"relative to the gyro"``); empty otherwise.
    """

    name: str
    value: float | None
    half_width: float | None
    unit: str
    note: str = ""


@dataclass(frozen=True)
class ChangeFound:
    """A change of one figure on the monitor's own course.

    Attributes
    ----------
    figure : str
        Which figure changed.
    size, size_half_width : float
        The present value minus the value before [the figure's unit], and half its 95 %
        interval.
    since : float
        When the present state began: the robot's clock [s] at the first stretch of
        driving after the change.
    since_metres : float
        The odometer [m driven since the monitor started] at that moment.
    confirmed : bool
        False while only the latest stretch of driving shows it (to be confirmed by the
        next); True once a later one agrees (a step).
    beyond_tolerance : bool
        True where the change is more than the robot's navigation tolerates (the node's
        ``--tolerance``): the diagnostic's level is ERROR.
    """

    figure: str
    size: float
    size_half_width: float
    since: float
    since_metres: float
    confirmed: bool
    beyond_tolerance: bool


@dataclass(frozen=True)
class MonitorStatus:
    """What the monitor says at one moment, as ``/diagnostics`` carries it.

    Attributes
    ----------
    time : float
        The robot's clock [s].
    robot : str
        The robot's name: the diagnostic's ``hardware_id``.
    level : {"OK", "WARN", "ERROR", "STALE"}
        OK: no change; WARN: a change found; ERROR: a change beyond the tolerance; STALE:
        a topic the monitor needs fell silent (``stale`` names it).
    message : str
        One line for people (``"E_d changed by +0.0061 +- 0.0008 since 10:42:07, 23 m
        ago"``).
    figures : tuple of Figure
        Every figure of :data:`FIGURES`, in that order.
    metres, radians_left, radians_right : float
        The window's driving: metres driven, radians turned left (ccw) and right (cw).
    odometer : float
        Metres driven since the monitor started (taken up from the history on a restart),
        up to the latest wheel reading (the chunk being collected included).
    since : float or None
        When the present state began (the last change, or the start) [s].
    changes : tuple of ChangeFound
        The changes found since the monitor started, oldest first.
    stale : tuple of str
        The topics silent longer than the node's stale time.
    outliers : int
        Stretches left out because wheels and the other sensors disagreed (pushed, lifted,
        slipping): not a change.
    applied : str or None
        The last apply's line (what was applied, how, when), if any.
    """

    time: float
    robot: str
    level: Level
    message: str
    figures: tuple[Figure, ...]
    metres: float
    radians_left: float
    radians_right: float
    odometer: float
    since: float | None
    changes: tuple[ChangeFound, ...] = ()
    stale: tuple[str, ...] = ()
    outliers: int = 0
    applied: str | None = None

    def key_values(self) -> list[tuple[str, str]]:
        """The diagnostic's key-values: each figure as ``"1.00213 +- 0.00021"`` (or
        ``"not determined: <why>"``), its unit in the key (``laser_x [m]``), then the
        window's driving, the odometer, since when, the outliers and the stale topics."""
        rows: list[tuple[str, str]] = []
        for fig in self.figures:
            key = f"{fig.name} [{fig.unit}]" if fig.unit else fig.name
            if fig.value is None or fig.half_width is None:
                rows.append((key, f"not determined: {fig.note}" if fig.note else "not determined"))
            else:
                said = f"{fig.value:.6g} +- {fig.half_width:.2g}"
                rows.append((key, f"{said} ({fig.note})" if fig.note else said))
        rows += [
            ("metres observed [m]", f"{self.metres:.1f}"),
            ("turned left [rad]", f"{self.radians_left:.1f}"),
            ("turned right [rad]", f"{self.radians_right:.1f}"),
            ("odometer [m]", f"{self.odometer:.1f}"),
            ("since [s]", "" if self.since is None else f"{self.since:.3f}"),
            ("outliers", str(self.outliers)),
        ]
        if self.stale:
            rows.append(("stale topics", ", ".join(self.stale)))
        if self.applied:
            rows.append(("applied", self.applied))
        return rows


@dataclass(frozen=True)
class CorrectedOdometry:
    """The robot's odometry integrated from its wheels with the present calibration, in
    the controller's frames (``nav_msgs/Odometry``).

    Attributes
    ----------
    time : float
        The robot's clock [s] (the wheel reading it was integrated to).
    pose : Pose2D
        In the odom frame [m, m, rad].
    linear, angular : float
        Body velocities [m/s, rad/s].
    pose_covariance, twist_covariance : array, shape (6, 6)
        Row-major as nav_msgs/Odometry carries them (x, y, z, roll, pitch, yaw).
    """

    time: float
    pose: Pose2D
    linear: float
    angular: float
    pose_covariance: FloatArray
    twist_covariance: FloatArray


class MonitorCore(Protocol):
    """The monitor without ROS: fed every message as it arrives, asked what it says.

    Every method is cheap (a node calls them from its callbacks); the matching and the fits
    run inside them, decimated, within the budget the node is given. A time that goes back
    (a simulation reset) restarts the window; odometry that jumps (the controller
    restarted) starts a new stretch; a message older than the last of its kind is dropped
    and counted.
    """

    def wheels(self, time: float, left: float, right: float) -> None:
        """The wheels' angles [rad] (cumulative, positive forward) at ``time`` [s]."""
        ...

    def odometry(self, time: float, pose: Pose2D) -> None:
        """The controller's odometry pose at ``time`` [s], where no wheel angles come."""
        ...

    def scan(self, sweep: ScanSweep) -> None:
        """A laser sweep (its time, its stated mounting)."""
        ...

    def gyro(self, time: float, yaw_rate: float) -> None:
        """The gyro's rate about the base frame's z axis [rad/s] (already put in the base
        frame by the IMU's mounting)."""
        ...

    def status(self, now: float) -> MonitorStatus:
        """What the monitor says at ``now`` [s]: called at 1 Hz by the node."""
        ...

    def corrected(self) -> CorrectedOdometry | None:
        """The odometry integrated with the present calibration, or None before the
        first wheel reading."""
        ...

    def apply_due(self, now: float) -> DriveParams | None:
        """The parameters to apply now (``--apply at-rest``: a confirmed change whose
        verdict lets it be applied, the robot at rest for the stated time), else None."""
        ...

    def applied(self, now: float, result: ApplyResult) -> None:
        """What applying :meth:`apply_due`'s parameters did."""
        ...

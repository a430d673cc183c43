"""The IMU's mounting as its own readings show it: the gyro's turning axis, and gravity.

A robot on a level floor turns about the base's z axis. The gyro's rates, put in the base
frame by the IMU frame's stated transform, then turn about ``(0, 0, 1)`` if that transform
is right; an IMU rolled ``r`` and pitched ``p`` on the base that the transform does not
know reads the turns about ``(-sin p, sin r cos p, cos r cos p)`` (and gravity at rest
along the same direction). The axis is fitted per component to every interval's
integrated rates, ``R_c = a_c theta_odo + b_c T`` (the odometry's heading change, and the
bias over the interval), least squares; its direction is ``a / |a|``, its roll
``atan2(a_y, a_z)``, pitch ``atan2(-a_x, hypot(a_y, a_z))``, tilt ``atan2(hypot(a_x, a_y),
a_z)``. ``a_z < 0``, a tilt beyond 90 degrees, is an IMU upside down (or a z axis
reversed) that the transform does not say: its turns read backwards.

At rest the accelerometer reads gravity (+9.81 m/s^2 along the IMU's up): its mean over
the rests gives the same roll, pitch and tilt, independently (a floor that slopes tilts
both alike). A stated transform (``base <- imu`` rotation) lets the axis be said in the
IMU's own frame too, against the base's z as the transform puts it there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.scans.gyro_intervals import GyroIntervals

__all__ = ["GRAVITY", "NOTICEABLE_TILT", "GyroMounting", "gyro_mounting", "rpy_of"]

#: Standard gravity [m/s^2].
GRAVITY = 9.80665
#: A tilt beyond this [rad] (and its 3 standard errors) is said: 0.5 degree.
NOTICEABLE_TILT = math.radians(0.5)
#: The accelerometer's magnitude at rest within this share of gravity: in m/s^2.
_GRAVITY_SHARE = 0.1


@dataclass(frozen=True)
class GyroMounting:
    """What the readings say of the IMU's mounting (angles [rad]).

    Attributes
    ----------
    axis : array, shape (3,), or None
        The gyro's turning axis in the base frame as read (a unit vector); None where the
        intervals do not determine it (no turns, or turns one way only without rests).
    roll, pitch, tilt : float or None
        Of that axis (the module's documentation); ``tilt_error`` its standard error.
    upside_down : bool
        The axis points down: the turns read backwards.
    gravity : array, shape (3,), or None
        The mean acceleration at rest [m/s^2] (None without an accelerometer or rests).
    gravity_roll, gravity_pitch, gravity_tilt : float or None
        Of gravity's direction.
    axis_in_imu, stated_in_imu : array, shape (3,), or None
        With the stated transform: the axis found and the base's z as the transform puts
        it, both in the IMU's frame.
    stated_rotation : array, shape (3, 3), or None
        The stated rotation ``base <- imu`` itself.
    frame : str
        The IMU's own frame.
    """

    axis: FloatArray | None = None
    roll: float | None = None
    pitch: float | None = None
    tilt: float | None = None
    tilt_error: float | None = None
    upside_down: bool = False
    gravity: FloatArray | None = None
    gravity_roll: float | None = None
    gravity_pitch: float | None = None
    gravity_tilt: float | None = None
    axis_in_imu: FloatArray | None = None
    stated_in_imu: FloatArray | None = None
    stated_rotation: FloatArray | None = None
    frame: str = "imu_link"

    @property
    def differs(self) -> bool:
        """The turning axis is off the base's z by more than what matters and its noise."""
        if self.tilt is None:
            return False
        error = self.tilt_error or 0.0
        return self.upside_down or self.tilt > max(NOTICEABLE_TILT, 3.0 * error)

    def found_rotation(self) -> FloatArray | None:
        """The rotation ``base <- imu`` (shape (3, 3)) the readings show: the stated one
        turned by the roll and pitch found, ``Ry(pitch) Rx(roll) R_stated`` (the readings
        turn about ``R^T z`` of that turn: the module's documentation; the yaw about the
        base's z is not seen by the turns, and stays as stated); None without a stated
        rotation or a turning axis."""
        if self.stated_rotation is None or self.roll is None or self.pitch is None:
            return None
        cr, sr = math.cos(self.roll), math.sin(self.roll)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
        ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
        return np.asarray(ry @ rx @ self.stated_rotation)

    def notes(self, frame: str = "imu_link") -> list[str]:
        """What it means, for people (degrees)."""
        out: list[str] = []
        if self.tilt is not None and self.upside_down:
            out.append(
                f"the gyro reads the turns backwards: its turning axis points down (tilt "
                f"{math.degrees(self.tilt):.1f} deg): {frame} is mounted upside down, or its "
                "z axis reversed, and its stated transform does not say so"
            )
        elif self.differs and self.tilt is not None:
            out.append(
                f"the gyro turns about an axis {math.degrees(self.tilt):.2f} +- "
                f"{math.degrees(self.tilt_error or 0.0):.2f} deg off the base's z (roll "
                f"{math.degrees(self.roll or 0.0):.2f}, pitch {math.degrees(self.pitch or 0.0):.2f}"
                f" deg): {frame}'s stated transform misses that tilt (or the floor slopes)"
            )
        if self.gravity is not None:
            norm = float(np.linalg.norm(self.gravity))
            if abs(norm / GRAVITY - 1.0) > _GRAVITY_SHARE:
                out.append(
                    f"the accelerometer reads {norm:.3g} m/s^2 at rest, not {GRAVITY:.2f}: its "
                    "unit or its calibration is off; its tilt is given by direction only"
                )
            if self.gravity_tilt is not None and self.gravity_tilt > NOTICEABLE_TILT:
                out.append(
                    f"at rest the accelerometer is tilted {math.degrees(self.gravity_tilt):.2f}"
                    f" deg from the base's z (roll {math.degrees(self.gravity_roll or 0.0):.2f},"
                    f" pitch {math.degrees(self.gravity_pitch or 0.0):.2f} deg)"
                )
        return out

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (radians, m/s^2)."""

        def listed(v: FloatArray | None) -> list[float] | None:
            return None if v is None else [float(x) for x in v]

        return {
            "axis": listed(self.axis),
            "roll": self.roll,
            "pitch": self.pitch,
            "tilt": self.tilt,
            "tilt_standard_error": self.tilt_error,
            "upside_down": self.upside_down,
            "differs_from_stated": self.differs,
            "gravity": listed(self.gravity),
            "gravity_roll": self.gravity_roll,
            "gravity_pitch": self.gravity_pitch,
            "gravity_tilt": self.gravity_tilt,
            "axis_in_imu": listed(self.axis_in_imu),
            "stated_in_imu": listed(self.stated_in_imu),
            "stated_rotation": None
            if self.stated_rotation is None
            else [listed(row) for row in self.stated_rotation],
            "frame": self.frame,
            "stated_rpy": None if self.stated_rotation is None else rpy_of(self.stated_rotation),
            "found_rpy": None if (found := self.found_rotation()) is None else rpy_of(found),
        }


def rpy_of(rotation: FloatArray) -> list[float]:
    """The roll, pitch and yaw [rad] of a rotation (shape (3, 3)) as a URDF origin's
    ``rpy`` states it: ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (fixed axes x, y, z)."""
    r = np.asarray(rotation, dtype=np.float64)
    pitch = math.asin(max(-1.0, min(1.0, -float(r[2, 0]))))
    roll = math.atan2(float(r[2, 1]), float(r[2, 2]))
    yaw = math.atan2(float(r[1, 0]), float(r[0, 0]))
    return [roll, pitch, yaw]


def _angles(v: FloatArray) -> tuple[float, float, float]:
    """Roll, pitch and tilt of the direction ``v`` (shape (3,))."""
    roll = math.atan2(float(v[1]), float(v[2]))
    pitch = math.atan2(-float(v[0]), math.hypot(float(v[1]), float(v[2])))
    tilt = math.atan2(math.hypot(float(v[0]), float(v[1])), float(v[2]))
    return roll, pitch, tilt


def _axis(intervals: GyroIntervals, theta_odo: FloatArray) -> tuple[FloatArray, float] | None:
    """The fitted ``a`` (shape (3,)) and its tilt's standard error, or None."""
    design = np.column_stack([theta_odo, intervals.duration])
    normal = design.T @ design
    if np.linalg.cond(normal) > 1e8 or float(np.abs(theta_odo).max(initial=0.0)) < 0.1:
        return None
    coef = np.linalg.solve(normal, design.T @ intervals.rotation)  # (2, 3)
    residual = intervals.rotation - design @ coef
    dof = max(len(intervals) - 2, 1)
    var_a = np.linalg.inv(normal)[0, 0] * (residual**2).sum(axis=0) / dof  # (3,)
    a = coef[0]
    size = float(np.linalg.norm(a))
    if size == 0.0:
        return None
    # tilt = angle off z: its gradient is the unit vector across the axis, in the plane
    # holding z and the axis (about z itself where the axis is along z)
    across = np.array([a[0] * a[2], a[1] * a[2], -(a[0] ** 2 + a[1] ** 2)])
    norm = float(np.linalg.norm(across))
    if norm < 1e-12 * size * size:
        error = math.sqrt(0.5 * float(var_a[0] + var_a[1])) / size
    else:
        g = across / norm / size
        error = math.sqrt(float(np.sum(g * g * var_a)))
    return a, error


def gyro_mounting(
    intervals: GyroIntervals, theta_odo: FloatArray, stated: FloatArray | None = None
) -> GyroMounting:
    """The mounting the intervals show (the module's documentation).

    Parameters
    ----------
    intervals : GyroIntervals
    theta_odo : array, shape (n,)
        The odometry's heading change over each interval [rad].
    stated : array, shape (3, 3), or None
        The stated rotation ``base <- imu`` the rates were put in the base frame with.
    """
    out: dict[str, object] = {"frame": intervals.frame}
    if stated is not None:
        out["stated_rotation"] = np.asarray(stated, dtype=np.float64)
    found = _axis(intervals, theta_odo)
    if found is not None:
        a, error = found
        axis = a / float(np.linalg.norm(a))
        roll, pitch, tilt = _angles(axis)
        out.update(axis=axis, roll=roll, pitch=pitch, tilt=tilt, tilt_error=error)
        out["upside_down"] = bool(axis[2] < 0.0)
        if stated is not None:
            out["axis_in_imu"] = stated.T @ axis
            out["stated_in_imu"] = stated.T @ np.array([0.0, 0.0, 1.0])
    rests = intervals.rest
    if intervals.accel is not None and rests.any():
        weights = intervals.duration[rests]
        gravity = (intervals.accel[rests] * weights[:, None]).sum(axis=0) / weights.sum()
        if float(np.linalg.norm(gravity)) > 0.0:
            g_roll, g_pitch, g_tilt = _angles(gravity)
            out.update(
                gravity=gravity, gravity_roll=g_roll, gravity_pitch=g_pitch, gravity_tilt=g_tilt
            )
    return GyroMounting(**out)  # type: ignore[arg-type]

"""CARMEN logs: a planar laser's sweeps and the odometry, as the classic 2D laser data
sets record them (the Radish and Freiburg logs, ``.clf`` / ``.log``, and the
``ROBOTLASER1`` lines of g2o's data sets).

Lines read (every other kind -- ``PARAM``, ``SYNC``, ``RLASER``, ``VERTEX_SE2``,
``EDGE_SE2``, ... -- and ``#`` comments are skipped)::

    FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_time host logger_time
    ROBOTLASER1 type start fov resolution max_range accuracy remission_mode n r_1 .. r_n
        m v_1 .. v_m laser_x laser_y laser_theta robot_x robot_y robot_theta
        tv rv forward_safety side_safety turn_axis ipc_time host logger_time
    ODOM x y theta tv rv accel ipc_time host logger_time

- **Times**: ``ipc_time`` [s]. Sweeps are sorted by it, a repeated stamp keeps the first.
- **The sweeps**: ``FLASER`` is the front laser: ``n`` beams from -90 degrees, as CARMEN
  guesses a SICK's (``carmen_laser_guess_angle_increment``): 1 degree apart for 180 or
  181 beams, 0.5 degree for 360 or 361, 0.25 degree for 400 or 401, else 180 degrees over
  ``n - 1`` steps; its maximum range is not in the line, and ranges of at least
  ``flaser_max_range`` (80 m, CARMEN's) are no return. ``ROBOTLASER1`` states its
  start angle, resolution and maximum range. Ranges at or beyond the maximum, and
  non-positive ones, become inf (no return). One log holds one scanner: the beams'
  count, angles and maximum range may not change.
- **The odometry**: the ``ODOM`` lines where the log has them, else the robot's pose each
  laser line carries (``FLASER``'s ``odom_*``, ``ROBOTLASER1``'s ``robot_*``): the wheel
  odometry [m, m, rad], not the wheels. A log holds no wheel rotation: turned back into
  it through a nominal geometry (:func:`umbmark.model.kinematics.wheel_travel_from_poses`)
  it serves the scan-matching calibration, whose results are then against that geometry
  (the odometry's own scale and turning, and the laser's mounting).
- **The stated mounting**: the laser's pose relative to the robot's on the laser lines
  (``x y theta`` against ``odom_*``, or ``laser_*`` against ``robot_*``), the median over
  the log; ``None`` where the two are the same (most logs state no mounting), or where
  they drift apart by more than 1 cm or 0.01 rad (a corrected log, whose laser poses are
  a SLAM's).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.model.kinematics import OdometryGeometry, wheel_travel_from_poses
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.model.scans import ScanSeries
from umbmark.sources.text import iter_content_lines

__all__ = [
    "FLASER_MAX_RANGE", "MAX_BEAMS", "MAX_SCANS", "CarmenLog", "odometry_wheels", "read_carmen",
]  # fmt: skip


#: The most sweeps read from one log (an hour at 25 Hz is 90 000).
MAX_SCANS = 100_000
#: The most beams of one sweep.
MAX_BEAMS = 16_384
#: ``FLASER`` ranges of at least this [m] are no return (the line states no maximum).
FLASER_MAX_RANGE = 80.0
#: CARMEN's angle between FLASER beams [rad] for a SICK's beam counts (else pi / (n - 1)).
_FLASER_INCREMENT = {
    n: math.pi / steps for pair, steps in (((180, 181), 180), ((360, 361), 360), ((400, 401), 720))
    for n in pair
}  # fmt: skip
#: Longest line [characters]: 16 384 beams of up to 10 characters.
_MAX_LINE = 200_000
#: Largest spread [m, rad] of the laser's pose on the robot for the log to state a mounting.
_MOUNTING_SPREAD = 0.01
#: Largest coordinate [m] and time [s] a line may hold.
_MAX_COORDINATE = 1e6
_MAX_TIME = 1e11


@dataclass(frozen=True)
class CarmenLog:
    """What a CARMEN log holds of a planar laser and the odometry.

    Attributes
    ----------
    scans : ScanSeries
        The sweeps, times [s] strictly increasing, ranges ``(n, beams)`` [m] (inf: no
        return).
    odometry : PoseSeries
        The wheel odometry ``(m, 3)`` [m, m, rad] at its times [s].
    stated_mounting : tuple of float or None
        The laser's pose on the robot ``x, y, yaw`` [m, m, rad] the log states, or None.
    """

    scans: ScanSeries
    odometry: PoseSeries
    stated_mounting: tuple[float, float, float] | None


@dataclass(frozen=True)
class _Scanner:
    start: float
    increment: float
    max_range: float


def _numbers(fields: list[str], path: str, row: int, what: str) -> FloatArray:
    try:
        values = np.array([float(f) for f in fields], dtype=np.float64)
    except ValueError:
        bad = next(f for f in fields if not _is_number(f))
        raise InputError(f"{what}: {bad!r} is not a number", source=path, row=row) from None
    if not np.all(np.isfinite(values)):
        raise InputError(f"{what}: not a finite number", source=path, row=row)
    return values


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _count(text: str, path: str, row: int, what: str, low: int) -> int:
    if not text.isdigit() or not low <= int(text) <= MAX_BEAMS:
        raise InputError(
            f"{what} is {text!r}, not a count of {low} to {MAX_BEAMS:,}", source=path, row=row
        )
    return int(text)


def _pose_tail(values: FloatArray, path: str, row: int, kind: str) -> None:
    if np.any(np.abs(values) > _MAX_COORDINATE):
        raise InputError(f"{kind}: a pose beyond +/-{_MAX_COORDINATE:g} m", source=path, row=row)


def _flaser(
    fields: list[str], path: str, row: int, max_range: float
) -> tuple[_Scanner, FloatArray, FloatArray, FloatArray, float]:
    n = _count(fields[1] if len(fields) > 1 else "", path, row, "FLASER's beam count", 3)
    if len(fields) != n + 11:
        raise InputError(
            f"FLASER of {n} beams has {len(fields)} fields, not {n + 11}", source=path, row=row
        )
    ranges = _numbers(fields[2 : 2 + n], path, row, "FLASER's ranges")
    tail = _numbers(fields[2 + n : 9 + n], path, row, "FLASER's poses and time")
    _pose_tail(tail[:6], path, row, "FLASER")
    scanner = _Scanner(-math.pi / 2, _FLASER_INCREMENT.get(n, math.pi / (n - 1)), max_range)
    return scanner, ranges, tail[0:3], tail[3:6], float(tail[6])


def _robotlaser(
    fields: list[str], path: str, row: int
) -> tuple[_Scanner, FloatArray, FloatArray, FloatArray, float]:
    kind = "ROBOTLASER1"
    if len(fields) < 10:
        raise InputError(f"{kind} has {len(fields)} fields: too few", source=path, row=row)
    head = _numbers(fields[2:7], path, row, f"{kind}'s scanner")
    start, _fov, increment, max_range, _accuracy = (float(v) for v in head)
    if not (abs(increment) > 0.0 and abs(start) <= 2 * math.pi and max_range > 0.0):
        raise InputError(
            f"{kind}: start angle {start:g}, resolution {increment:g}, maximum range "
            f"{max_range:g}: not a scanner's",
            source=path,
            row=row,
        )
    n = _count(fields[8], path, row, f"{kind}'s beam count", 3)
    if len(fields) < 10 + n:
        raise InputError(f"{kind} of {n} beams has {len(fields)} fields", source=path, row=row)
    ranges = _numbers(fields[9 : 9 + n], path, row, f"{kind}'s ranges")
    m = _count(fields[9 + n], path, row, f"{kind}'s remission count", 0)
    k = 10 + n + m
    if len(fields) != k + 14:
        raise InputError(
            f"{kind} of {n} beams and {m} remissions has {len(fields)} fields, not {k + 14}",
            source=path,
            row=row,
        )
    tail = _numbers(fields[k : k + 12], path, row, f"{kind}'s poses and time")
    _pose_tail(tail[:6], path, row, kind)
    return _Scanner(start, increment, max_range), ranges, tail[0:3], tail[3:6], float(tail[11])


def _odom(fields: list[str], path: str, row: int) -> tuple[FloatArray, float]:
    if len(fields) != 10:
        raise InputError(f"ODOM has {len(fields)} fields, not 10", source=path, row=row)
    values = _numbers(fields[1:8], path, row, "ODOM")
    _pose_tail(values[:3], path, row, "ODOM")
    _check_time(float(values[6]), path, row, "ODOM")
    return values[:3], float(values[6])


def _check_time(stamp: float, path: str, row: int, kind: str) -> None:
    if not 0.0 < abs(stamp) < _MAX_TIME:
        raise InputError(f"{kind}: time {stamp:g} s is not a time", source=path, row=row)


def _relative(laser: FloatArray, robot: FloatArray) -> FloatArray:
    """``laser`` ``(n, 3)`` in the frame of ``robot`` ``(n, 3)``."""
    dx, dy = laser[:, 0] - robot[:, 0], laser[:, 1] - robot[:, 1]
    c, s = np.cos(robot[:, 2]), np.sin(robot[:, 2])
    yaw = np.angle(np.exp(1j * (laser[:, 2] - robot[:, 2])))
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, yaw])


def _series(times: list[float], rows: list[FloatArray]) -> tuple[FloatArray, FloatArray]:
    t = np.array(times, dtype=np.float64)
    order = np.argsort(t, kind="stable")
    t = t[order]
    keep = np.concatenate([[True], np.diff(t) > 0.0]) if t.size else np.zeros(0, dtype=bool)
    return t[keep], np.array(rows, dtype=np.float64)[order][keep]


def read_carmen(
    path: str | os.PathLike[str],
    *,
    max_scans: int = MAX_SCANS,
    flaser_max_range: float = FLASER_MAX_RANGE,
) -> CarmenLog:
    """The sweeps and the odometry of a CARMEN log (the module's docstring).

    Parameters
    ----------
    path : path
        The log (text).
    max_scans : int
        The most sweeps read; a log with more is refused.
    flaser_max_range : float
        ``FLASER`` ranges of at least this [m] are no return.

    Raises
    ------
    InputError
        Not readable, a malformed line (named by its number), no sweep or fewer than 2
        odometry poses, more than ``max_scans`` sweeps, or a scanner that changes.
    """
    where = os.fspath(path)
    if not Path(where).is_file():
        raise InputError("no such file", source=where)
    scanner: _Scanner | None = None
    times: list[float] = []
    sweeps: list[FloatArray] = []
    lasers: list[FloatArray] = []
    robots: list[FloatArray] = []
    odom_times: list[float] = []
    odoms: list[FloatArray] = []
    for row, line in iter_content_lines(where, _MAX_LINE):
        fields = line.split()
        kind = fields[0]
        if kind == "ODOM":
            pose, stamp = _odom(fields, where, row)
            odom_times.append(stamp)
            odoms.append(pose)
            continue
        if kind == "FLASER":
            this, ranges, laser, robot, stamp = _flaser(fields, where, row, flaser_max_range)
        elif kind == "ROBOTLASER1":
            this, ranges, laser, robot, stamp = _robotlaser(fields, where, row)
        else:
            continue
        if scanner is None:
            scanner = this
        elif this != scanner or ranges.size != sweeps[0].size:
            raise InputError(
                f"{kind}: the scanner changed within the log ({ranges.size} beams from "
                f"{this.start:g} rad by {this.increment:g} rad, maximum {this.max_range:g} "
                f"m; the first sweep: {sweeps[0].size} beams from {scanner.start:g} rad by "
                f"{scanner.increment:g} rad, maximum {scanner.max_range:g} m)",
                source=where,
                row=row,
            )
        if len(sweeps) >= max_scans:
            raise InputError(
                f"more than {max_scans:,} sweeps: cut the log (max_scans)", source=where
            )
        _check_time(stamp, where, row, kind)
        ranges = np.where((ranges >= this.max_range) | (ranges <= 0.0), np.inf, ranges)
        times.append(stamp)
        sweeps.append(ranges)
        lasers.append(laser)
        robots.append(robot)
    if scanner is None:
        raise InputError("no FLASER or ROBOTLASER1 line: no laser sweeps", source=where)
    scan_times, ranges_ = _series(times, sweeps)
    _, robot_arr = _series(times, robots)
    _, laser_arr = _series(times, lasers)
    if odoms:
        odom_t, odom_arr = _series(odom_times, odoms)
    else:
        odom_t, odom_arr = scan_times, robot_arr
    if odom_t.size < 2:
        raise InputError("fewer than 2 odometry poses", source=where)
    relative = _relative(laser_arr, robot_arr)
    stated = np.median(relative, axis=0)
    spread = np.max(np.abs(relative - stated), axis=0)
    mounting: tuple[float, float, float] | None = None
    # a corrected log's laser poses (SLAM's) drift from its odometry: no mounting stated
    steady = spread[0] <= _MOUNTING_SPREAD and spread[1] <= _MOUNTING_SPREAD
    if steady and spread[2] <= _MOUNTING_SPREAD and not np.allclose(stated, 0.0, atol=1e-6):
        mounting = (float(stated[0]), float(stated[1]), float(stated[2]))
    scans = ScanSeries(
        times=scan_times,
        ranges=ranges_,
        angle_min=scanner.start,
        angle_increment=scanner.increment,
        range_min=0.0,
        range_max=scanner.max_range,
        frame="laser",
        source=where,
    )
    odometry = PoseSeries(time=odom_t, poses=odom_arr)
    return CarmenLog(scans=scans, odometry=odometry, stated_mounting=mounting)


def odometry_wheels(odometry: PoseSeries, geometry: OdometryGeometry) -> WheelSeries:
    """The wheel rotation that ``geometry`` turns into ``odometry``: between consecutive
    poses one arc (:func:`umbmark.model.kinematics.wheel_travel_from_poses`), each wheel's
    travel over its radius.

    A log's odometry is often sparse (a pose per sweep) and need not be a differential
    drive's (a synchro drive's B21): the motion across the arc is dropped, unlike
    :func:`umbmark.sources.bag.wheels.odometry.wheels_from_odometry`, which refuses it. The
    scan-matching calibration of these wheels is then against ``geometry``: ``E_s`` the
    odometry's scale of distance, ``E_b`` its scale of turning, ``E_d`` their asymmetry.

    Returns
    -------
    WheelSeries
        ``time`` shape (m,) [s]; ``angles`` shape (m, 2) [rad], 0 at the first pose.
    """
    poses = np.array(odometry.poses, dtype=np.float64)
    poses[:, 2] = np.unwrap(poses[:, 2])
    d_left, d_right, _ = wheel_travel_from_poses(poses, geometry.separation)
    angles = np.zeros((poses.shape[0], 2))
    angles[1:, 0] = np.cumsum(d_left) / geometry.left_radius
    angles[1:, 1] = np.cumsum(d_right) / geometry.right_radius
    return WheelSeries(time=np.asarray(odometry.time, dtype=np.float64), angles=angles)

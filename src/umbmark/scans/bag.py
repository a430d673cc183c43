"""Motion intervals straight from a bag: the laser's sweeps and the wheels, read and matched.

The wheels come from whatever :class:`umbmark.sources.bag.bag_options.BagOptions` names
(joint states, encoder ticks, fields of a custom type, wheel transforms, or the
controller's odometry turned back into wheel rotation), read by
:func:`umbmark.sources.bag.recording.read_recording` (its ground truth is not read);
the sweeps by :func:`umbmark.sources.bag.scans.read_scans`. Both on the clock
``time_source`` says.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from umbmark.core.messages import info
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.scans import LaserMounting
from umbmark.scans.intervals import (
    DEFAULT_OPTIONS,
    IntervalOptions,
    IntervalReport,
    OdometryGuess,
    match_intervals,
)
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import read_recording
from umbmark.sources.bag.scans import MAX_SCANS, read_scan_bag, scan_mounting

__all__ = ["intervals_from_bag", "scan_intervals_from_bag"]


def scan_intervals_from_bag(
    path: str | Path,
    scan_topic: str,
    wheels: BagOptions | None = None,
    options: IntervalOptions = DEFAULT_OPTIONS,
    *,
    upside_down: bool | None = None,
    min_period: float = 0.0,
    max_scans: int = MAX_SCANS,
    tf_mounting: bool = False,
) -> IntervalReport:
    """The motion intervals of a bag and what was left out.

    Parameters
    ----------
    path : str or Path
        A ROS 1 ``.bag``, a ROS 2 bag folder, or its ``.db3``/``.mcap`` file.
    scan_topic : str
        The ``sensor_msgs/LaserScan`` topic.
    wheels : BagOptions, optional
        Where the wheels are (default: :class:`BagOptions`' defaults, the joint states);
        its ground-truth options are ignored. With the controller's odometry
        (``odom_geometry``) and no guess in ``options``, its geometry is the guess.
    options : IntervalOptions
        How intervals are chosen and matched (:mod:`umbmark.scans.intervals`).
    upside_down : bool or None
        The scanner is mounted upside down; None: as ``/tf_static`` says.
    min_period, max_scans
        Thin the sweeps while reading; most sweeps held
        (:func:`umbmark.sources.bag.scans.read_scans`).
    tf_mounting : bool
        With a guess: its laser pose is the mounting ``/tf_static`` states for the
        sweeps' frame (:func:`~umbmark.sources.bag.scans.scan_mounting`), else the bag's
        robot description (:attr:`~umbmark.sources.bag.urdf.RobotDescription.mountings`),
        where either states one; a note in the report says so.

    Raises
    ------
    InputError
        The bag, its sweeps or its wheels cannot be read (one line naming the bag).
    """
    bag = dataclasses.replace(
        wheels or BagOptions(), truth_topic=None, tf_parent=None, tf_child=None, truth_model=None
    )
    wheel_series = read_recording(path, bag).wheels
    scans = read_scan_bag(
        path,
        scan_topic,
        header=bag.time_source == "header",
        upside_down=upside_down,
        min_period=min_period,
        max_scans=max_scans,
    )
    geometry = bag.odom_geometry
    if options.guess is None and geometry is not None:
        guess = OdometryGuess(geometry.left_radius, geometry.right_radius, geometry.separation)
        options = dataclasses.replace(options, guess=guess)
    notes: tuple[str, ...] = ()
    mounted = _mounting(path, scans.frame, bag) if tf_mounting and options.guess else None
    if options.guess is not None and mounted is not None:
        where, pose = mounted.source, (mounted.x, mounted.y, mounted.yaw)
        guess = dataclasses.replace(options.guess, laser_pose=pose)
        options = dataclasses.replace(options, guess=guess)
        notes = (
            info(
                f"the laser's nominal mounting from {where}: {scans.frame} at x = "
                f"{pose[0]:.4f} m, y = {pose[1]:.4f} m, yaw = {math.degrees(pose[2]):.2f} "
                "deg (the first guess of the scan matching only)"
            ),
        )
    report = match_intervals(scans, wheel_series, options)
    return dataclasses.replace(report, guess=options.guess, notes=notes, stated=mounted)


def _mounting(path: str | Path, frame: str, bag: BagOptions) -> LaserMounting | None:
    """The scanner's nominal mounting: from ``/tf_static`` (with its height and tilt),
    else from the bag's robot description (planar); its source says where, for people."""
    found = scan_mounting(path, frame)
    if found is not None:
        base, (x, y, yaw), lift = found
        return LaserMounting(x, y, yaw, lift, base, frame.lstrip("/"), f"/tf_static in {base}")
    from umbmark.sources.bag.urdf import bag_robot_description

    description, _ = bag_robot_description(path, bag.left_joints, bag.right_joints)
    if description is None or frame not in description.mountings:
        return None
    x, y, yaw = description.mountings[frame]
    where = f"the robot description ({description.topic})"
    return LaserMounting(x, y, yaw, frame=frame.lstrip("/"), source=where)


def intervals_from_bag(
    path: str | Path,
    scan_topic: str,
    wheels: BagOptions | None = None,
    options: IntervalOptions = DEFAULT_OPTIONS,
    *,
    upside_down: bool | None = None,
    min_period: float = 0.0,
    max_scans: int = MAX_SCANS,
) -> MotionIntervals:
    """The motion intervals of a bag (:func:`scan_intervals_from_bag` without the counts)."""
    return scan_intervals_from_bag(
        path,
        scan_topic,
        wheels,
        options,
        upside_down=upside_down,
        min_period=min_period,
        max_scans=max_scans,
    ).intervals

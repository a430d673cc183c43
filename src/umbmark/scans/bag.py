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

import numpy as np

from umbmark.core.errors import InputError
from umbmark.core.messages import info
from umbmark.model.motion_intervals import MotionIntervals
from umbmark.model.scans import LaserMounting, ScanSeries
from umbmark.scans.intervals import (
    DEFAULT_OPTIONS,
    IntervalOptions,
    IntervalReport,
    OdometryGuess,
    match_intervals,
)
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import read_recording
from umbmark.sources.bag.scans import MAX_SCANS, bag_span, read_scan_bag, scan_mounting

__all__ = ["WINDOW", "intervals_from_bag", "scan_intervals_from_bag"]

#: A long recording's sweeps are read and matched this many seconds at a time, so that
#: the memory it takes stays bounded whatever its length (the wheels, a few numbers a
#: sample, are read whole).
WINDOW = 600.0


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
    window: float = WINDOW,
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
    window : float
        Read and match the sweeps this many seconds [s] of the recording at a time: a
        recording longer than that takes the memory of one window's sweeps, not of all
        (an interval across two windows is left out).

    Raises
    ------
    InputError
        The bag, its sweeps or its wheels cannot be read (one line naming the bag).
    """
    bag = dataclasses.replace(
        wheels or BagOptions(), truth_topic=None, tf_parent=None, tf_child=None, truth_model=None
    )
    wheel_series = read_recording(path, bag).wheels
    windows = _windows(path, window)

    def sweeps(span: tuple[int, int] | None) -> ScanSeries:
        return read_scan_bag(
            path, scan_topic, header=bag.time_source == "header", upside_down=upside_down,
            min_period=min_period, max_scans=max_scans, window=span,
        )  # fmt: skip

    scans = sweeps(windows[0])
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
    reports = [match_intervals(scans, wheel_series, options)]
    for span in windows[1:]:  # a long recording: one window's sweeps at a time
        try:
            more = sweeps(span)
        except InputError:  # fewer than 2 sweeps in this window (the laser paused)
            continue
        reports.append(match_intervals(more, wheel_series, options))
    report = _joined(reports)
    return dataclasses.replace(report, guess=options.guess, notes=notes, stated=mounted)


def _windows(path: str | Path, window: float) -> list[tuple[int, int] | None]:
    """The bag's time cut into windows of ``window`` seconds [ns]: one, None, for a bag
    no longer than that."""
    if not window > 0.0:
        raise ValueError("a window must be a positive time")
    first, last = bag_span(path)
    step = int(window * 1e9)
    if last - first <= step:
        return [None]
    return [(a, min(a + step, last + 1)) for a in range(first, last + 1, step)]


def _joined(reports: list[IntervalReport]) -> IntervalReport:
    """The reports of a recording's windows as one."""
    if len(reports) == 1:
        return reports[0]
    kept = [r.intervals for r in reports if len(r.intervals)]
    left: dict[str, int] = {}
    for r in reports:
        for why, n in r.left_out.items():
            left[why] = left.get(why, 0) + n
    intervals = MotionIntervals.concatenate(kept) if kept else reports[0].intervals
    rms = np.concatenate([r.rms for r in reports])
    return IntervalReport(intervals, left, rms)


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

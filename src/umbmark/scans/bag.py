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
from umbmark.model.scans import LaserMounting
from umbmark.scans.intervals import (
    DEFAULT_OPTIONS,
    IntervalOptions,
    IntervalReport,
    OdometryGuess,
    match_intervals,
)
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.reader import time_windows
from umbmark.sources.bag.recording import read_recording
from umbmark.sources.bag.scans import MAX_SCANS, read_scan_bag, scan_mounting

__all__ = ["PAD", "WINDOW", "intervals_from_bag", "scan_intervals_from_bag"]

#: A long recording's sweeps and wheels are read and matched this many seconds at a time,
#: so that the memory it takes stays bounded whatever its length.
WINDOW = 300.0
#: The wheels of a window are read this much longer each side [s]: the sweeps at its
#: edges are matched to wheel samples around them (stamps lag the bag's clock a little).
PAD = 5.0


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
        Read and match the sweeps and the wheels this many seconds [s] of the recording
        at a time: a recording longer than that takes the memory of one window, not of
        all (an interval across two windows is left out; a window with fewer than two
        sweeps or no wheel readings, a pause, is passed over).

    Raises
    ------
    InputError
        The bag, its sweeps or its wheels cannot be read (one line naming the bag).
    """
    bag = dataclasses.replace(
        wheels or BagOptions(), truth_topic=None, tf_parent=None, tf_child=None, truth_model=None
    )
    geometry = bag.odom_geometry
    if options.guess is None and geometry is not None:
        guess = OdometryGuess(geometry.left_radius, geometry.right_radius, geometry.separation)
        options = dataclasses.replace(options, guess=guess)
    windows = _windows(path, window)
    notes: tuple[str, ...] = ()
    mounted: LaserMounting | None = None
    reports: list[IntervalReport] = []
    failed: InputError | None = None
    for span in windows:  # a long recording: one window's sweeps and wheels at a time
        try:
            wheel_series = read_recording(path, bag, window=_padded(span)).wheels
            scans = read_scan_bag(
                path, scan_topic, header=bag.time_source == "header", upside_down=upside_down,
                min_period=min_period, max_scans=max_scans, window=span,
            )  # fmt: skip
        except InputError as exc:  # a window with fewer than 2 sweeps or no wheels: a pause
            if len(windows) == 1:
                raise
            failed = failed or exc
            continue
        if not reports and tf_mounting and options.guess is not None:
            mounted = _mounting(path, scans.frame, bag)
            if mounted is not None:
                options, notes = _guessed_mounting(options, mounted, scans.frame)
        reports.append(match_intervals(scans, wheel_series, options))
    if not reports:
        assert failed is not None
        raise failed
    report = _joined(reports)
    return dataclasses.replace(report, guess=options.guess, notes=notes, stated=mounted)


def _guessed_mounting(
    options: IntervalOptions, mounted: LaserMounting, frame: str
) -> tuple[IntervalOptions, tuple[str, ...]]:
    """The options with the stated mounting as the guess's laser pose, and the note."""
    assert options.guess is not None
    pose = (mounted.x, mounted.y, mounted.yaw)
    guess = dataclasses.replace(options.guess, laser_pose=pose)
    note = info(
        f"the laser's nominal mounting from {mounted.source}: {frame} at x = "
        f"{pose[0]:.4f} m, y = {pose[1]:.4f} m, yaw = {math.degrees(pose[2]):.2f} "
        "deg (the first guess of the scan matching only)"
    )
    return dataclasses.replace(options, guess=guess), (note,)


def _padded(span: tuple[int, int] | None) -> tuple[int, int] | None:
    """A window of sweeps widened by :data:`PAD` each side: the wheels its sweeps need."""
    if span is None:
        return None
    pad = int(PAD * 1e9)
    return (max(0, span[0] - pad), span[1] + pad)


def _windows(path: str | Path, window: float) -> list[tuple[int, int] | None]:
    """The bag's time cut into windows of ``window`` seconds [ns]
    (:func:`~umbmark.sources.bag.reader.time_windows`)."""
    return time_windows(Path(path), str(path), window)


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
    off = [r for r in reports if r.guess_off is not None]  # the first window given up says
    first = off[0] if off else None
    return IntervalReport(
        intervals,
        left,
        rms,
        guess_off=None if first is None else first.guess_off,
        lost=None if first is None else first.lost,
    )


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

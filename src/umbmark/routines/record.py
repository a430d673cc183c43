"""Recording a self-calibration pass as a run log, the folder ``calibrate``, ``replay`` and
``report`` read.

One CSV per run (``runs: one per file``). The wheel columns are the wheel angles that
made the odometry move as it did, given the parameters the controller ran with
(:func:`umbmark.model.kinematics.wheel_travel_from_poses` over the odometry's poses,
divided by each wheel's effective radius): integrating them with those parameters, as
``calibrate`` does, gives the robot's odometry back. The ground truth is the corner fix,
written at the samples where the robot stood still before and after the run
(``truth: at stops``): its pose relative to the run's start is what UMBmark measures.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from umbmark.core.conventions import wrap_angle
from umbmark.core.errors import InputError
from umbmark.model.kinematics import wheel_travel_from_poses
from umbmark.robot.base import DriveParams, Pose2D
from umbmark.routines.corner import CornerFix
from umbmark.routines.drive import DrivenRun
from umbmark.sources.runlog.reader import LogMetadata
from umbmark.sources.runlog.writer import (
    as_written,
    clear_run_log,
    write_log_csv,
    write_metadata,
)

__all__ = [
    "OVERLAY_FILE",
    "REPORT_FILE",
    "MeasuredRun",
    "clear_selfcal",
    "pass_folder",
    "record_pass",
    "recorded_passes",
    "return_error",
    "return_error_words",
]

#: The page of all passes a self-calibration writes into its folder.
REPORT_FILE = "report.html"
#: The overlay of the final parameters it writes there.
OVERLAY_FILE = "overlay.yaml"
#: Its passes' run-log folders: ``pass-1``, ``pass-2``, ..., ``verification``.
_PASS_FOLDER = re.compile(r"pass-\d+|verification")
#: A pass's run files: ``run-01-cw.csv``, ``run-06-ccw.csv`` (:func:`record_pass`).
_RUN_FILE = re.compile(r"run-\d+-c?cw\.csv")


def pass_folder(folder: Path, label: str) -> Path:
    """The run-log folder of pass ``label`` (``pass 1``: ``folder/pass-1``)."""
    return folder / label.replace(" ", "-")


def recorded_passes(folder: Path) -> list[tuple[Path, int]]:
    """The passes' run-log folders in ``folder`` (``pass-1``, ..., ``verification``), each
    with the number of run files it holds (``run-NN-cw.csv``, ``run-NN-ccw.csv``); none
    where ``folder`` is no folder. Only looks: nothing is read or created."""
    if not folder.is_dir():
        return []
    found = []
    for entry in sorted(folder.iterdir()):
        if entry.is_dir() and not entry.is_symlink() and _PASS_FOLDER.fullmatch(entry.name):
            runs = [f for f in entry.iterdir() if _RUN_FILE.fullmatch(f.name) and f.is_file()]
            found.append((entry, len(runs)))
    return found


def clear_selfcal(folder: Path, *, remove: bool) -> None:
    """Check that ``folder`` holds only what a self-calibration wrote (its passes' run
    logs, :data:`REPORT_FILE`, :data:`OVERLAY_FILE`), and remove it when ``remove``: a new
    self-calibration replaces an earlier one whole, never mixed with it.

    Raises
    ------
    InputError
        Naming the first thing a self-calibration did not write (nothing is removed).
    """
    if not folder.is_dir():
        return
    passes = []
    for entry in sorted(folder.iterdir()):
        foreign: Path | None = entry
        if entry.is_dir() and not entry.is_symlink() and _PASS_FOLDER.fullmatch(entry.name):
            mine = clear_run_log(entry, remove=False)
            foreign = min(set(entry.iterdir()) - set(mine), default=None)
            passes.append(entry)
        elif entry.is_file() and entry.name in (REPORT_FILE, OVERLAY_FILE):
            foreign = None
        if foreign is not None:
            raise InputError(
                f"holds {foreign.relative_to(folder)}, which a self-calibration did not "
                "write: choose a new or empty folder",
                source=folder,
            )
    if remove:
        for entry in passes:
            clear_run_log(entry, remove=True)
            entry.rmdir()
        for name in (REPORT_FILE, OVERLAY_FILE):
            (folder / name).unlink(missing_ok=True)


@dataclass(frozen=True)
class MeasuredRun:
    """A run as driven by the odometry, with the corner fixes before and after it."""

    run: DrivenRun
    start: CornerFix
    end: CornerFix


def _samples(run: DrivenRun) -> np.ndarray:
    """The run's odometry readings, shape (n, 4), one per odometry time (the driver may
    read one update more than once)."""
    odometry = np.asarray(run.odometry, dtype=np.float64)
    keep = np.ones(odometry.shape[0], dtype=bool)
    keep[:-1] = np.diff(odometry[:, 0]) > 0.0
    return odometry[keep]


def _fixes(measured: MeasuredRun) -> tuple[Pose2D, Pose2D]:
    """The start and end fixes as the run file holds them (:func:`as_written`), the end
    heading unwrapped by the run's full turn (left for ccw)."""
    start, end = measured.start.pose, measured.end.pose
    turn = measured.run.direction.turn_sign * 2 * math.pi
    end_heading = start.theta + turn + math.remainder(end.theta - start.theta, 2 * math.pi)
    return (
        Pose2D(*as_written(start.x, start.y, start.theta)),
        Pose2D(*as_written(end.x, end.y, end_heading)),
    )


def return_error(measured: MeasuredRun) -> tuple[float, float, float]:
    """The run's return error, Eq. 3.1 (absolute minus calculated): the end fix seen from
    the start fix, less the odometry's end seen from its start (the first and last
    readings the run log holds): ``eps_x``, ``eps_y`` [m] and ``eps_theta`` [rad], wrapped
    into ``[-pi, pi)``. The fixes as the run file holds them: what ``calibrate`` reads
    back from the run log, run by run."""
    odometry = _samples(measured.run)
    start, end = (Pose2D(*(float(v) for v in odometry[i, 1:4])) for i in (0, -1))
    calculated = end.relative_to(start)
    first, last = _fixes(measured)
    absolute = last.relative_to(first)
    return (
        absolute.x - calculated.x,
        absolute.y - calculated.y,
        float(wrap_angle(absolute.theta - calculated.theta)),
    )


def return_error_words(error: tuple[float, float, float]) -> str:
    """A return error as the terminal, the run file and the page show it: ``x -22.3 mm,
    y -21.9 mm, +2.411 deg``."""
    return (
        f"x {error[0] * 1000:+.1f} mm, y {error[1] * 1000:+.1f} mm, "
        f"{math.degrees(error[2]):+.3f} deg"
    )


#: The odometry stands still while it changes by less than this [m, rad].
STILL = 1e-6


def _still(odometry: np.ndarray) -> tuple[int, int]:
    """``first, last``: the readings ``[:first]`` where the robot still stood at the start
    and ``[last:]`` where it stood at the end (the fixes hold there)."""
    pose = odometry[:, 1:4]
    moved_from_start = np.any(np.abs(pose - pose[0]) > STILL, axis=1)
    moved_from_end = np.any(np.abs(pose - pose[-1]) > STILL, axis=1)
    first = int(np.argmax(moved_from_start)) if moved_from_start.any() else pose.shape[0]
    last = pose.shape[0] - int(np.argmax(moved_from_end[::-1])) if moved_from_end.any() else 0
    return max(first, 1), min(last, pose.shape[0] - 1)


def _wheel_angles(odometry: np.ndarray, params: DriveParams) -> np.ndarray:
    """Cumulative wheel angles [rad], shape (n, 2), from odometry readings ``t, x, y,
    theta``, shape (n, 4)."""
    poses = np.array(odometry[:, 1:4], dtype=np.float64)
    poses[:, 2] = np.unwrap(poses[:, 2])
    d_left, d_right, _ = wheel_travel_from_poses(poses, params.wheelbase)
    r_left = params.wheel_radius * params.left_wheel_radius_multiplier
    r_right = params.wheel_radius * params.right_wheel_radius_multiplier
    angles = np.zeros((poses.shape[0], 2))
    angles[1:, 0] = np.cumsum(d_left) / r_left
    angles[1:, 1] = np.cumsum(d_right) / r_right
    return angles


def record_pass(
    folder: Path,
    runs: Sequence[MeasuredRun],
    params: DriveParams,
    side_length: float,
    method: str,
    robot: str,
) -> list[Path]:
    """Write ``folder/metadata.yaml`` and ``run-NN-cw.csv`` / ``run-NN-ccw.csv``.

    Returns
    -------
    list of Path
        The files written.
    """
    metadata = LogMetadata(
        wheel_diameter=2.0 * params.wheel_radius,
        wheelbase=params.wheel_separation,
        wheel_data="angles",
        side_length=side_length,
        c_left=params.left_wheel_radius_multiplier,
        c_right=params.right_wheel_radius_multiplier,
        separation_multiplier=params.wheel_separation_multiplier,
        extra={
            "runs": "one per file",
            "truth": "at stops",
            "measurement": method,
            "robot": robot,
        },
    )
    written = [write_metadata(folder, metadata)]
    for k, measured in enumerate(runs, start=1):
        run = measured.run
        odometry = _samples(run)
        time = odometry[:, 0]
        truth = np.full((time.size, 3), math.nan)
        first, last = _still(odometry)
        start, end = _fixes(measured)  # the end heading unwrapped by the run's full turn
        truth[:first] = (start.x, start.y, start.theta)
        truth[last:] = (end.x, end.y, end.theta)
        eps = return_error(measured)
        path = folder / f"run-{k:02d}-{run.direction.value}.csv"
        write_log_csv(
            path,
            time,
            truth,
            _wheel_angles(odometry, params),
            comment=(
                f"{run.direction.value} run {k} of a self-calibration: odometry turned back "
                f"into wheel angles; truth: corner fixes ({method}) where the robot stood\n"
                f"return error (Eq. 3.1, the corner fixes against the odometry): "
                f"{return_error_words(eps)}"
            ),
        )
        written.append(path)
    return written

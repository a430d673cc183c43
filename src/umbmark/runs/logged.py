"""From recordings to runs: association, splitting, start frames, odometry end poses.

Every logged source ends here, so that a run from a CSV log, an OptiOdom session or a
ROS bag is the same :class:`umbmark.model.run.Run` the estimators consume, with its time series
attached (:class:`umbmark.model.recording.RunLog`) for replay and trajectory estimation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError
from umbmark.core.geometry import relative_positions, to_start_frame
from umbmark.core.messages import info
from umbmark.model.kinematics import IntegrationMethod, WheelParams
from umbmark.model.recording import DEFAULT_MAX_GAP, Recording, RunLog, gap_mask
from umbmark.model.run import EndPose, Run
from umbmark.runs.association import Association, associate
from umbmark.runs.gaps import Gap, describe_gaps, find_gaps
from umbmark.runs.reproduced import check_not_reproduced
from umbmark.runs.rests import Reset, find_resets
from umbmark.runs.segmentation import (
    LeftOut,
    SplitOptions,
    cut_at_resets,
    find_runs,
    split_by_windows,
    trim_to_motion,
)

__all__ = [
    "LoadedRuns",
    "SplitMode",
    "check_motion",
    "runs_from_recordings",
]

SplitMode = Literal["rests", "none", "windows", "file"]

#: A wheel turning by more than this in one sample is a corrupt sample, not motion [rad].
MAX_WHEEL_STEP = 50.0
#: A wheel step this many times the steps' 99th percentile and above MIN_JUMP [rad]: a jump.
JUMP_FACTOR = 10.0
MIN_JUMP = 10.0
#: Spreads of the wheel angles [rad] and the ground truth [m, rad] below these: no motion.
STILL_WHEELS = 1e-9
STILL_TRUTH = 1e-9
#: Between two ground-truth samples the tracked point moves at most this far [m], or
#: :data:`MAX_TRUTH_SPEED` times the time between them if that is more: a larger step is
#: a corrupt sample (a cell of another unit, an overflow, a tracker that lost the robot).
MAX_TRUTH_STEP = 1.0
#: Fastest plausible motion of the ground truth [m/s].
MAX_TRUTH_SPEED = 10.0


@dataclass(frozen=True)
class LoadedRuns:
    """Runs read from recordings, and how they were found.

    Attributes
    ----------
    runs : list of Run
        Each with its :class:`RunLog` as ``log``.
    associations : list of (str, Association)
        Time matching of each recording.
    notes : list of str
        What was found and left out, for people.
    stretches : list of Run
        The motion left out of the runs, cut where no path crosses (a gap not bridged, a
        reset), each stretch with a reference a run of any shape.
    """

    runs: list[Run]
    associations: list[tuple[str, Association]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    stretches: list[Run] = field(default_factory=list)


def check_motion(
    name: str,
    time: FloatArray,
    angles: FloatArray,
    truth: FloatArray | None,
    *,
    headings: bool = True,
    resets: Sequence[Reset] = (),
) -> None:
    """Refuse a recording or run whose wheels never turn or jump, or whose truth never moves
    or jumps (:data:`MAX_TRUTH_STEP`).

    A jump is a wheel step too large for the time it took: above :data:`MAX_WHEEL_STEP`,
    or above both :data:`MIN_JUMP` and :data:`JUMP_FACTOR` times the 99th percentile of
    the steps, each limit scaled by the interval over the typical (median) one. Gaps in
    the samples (:func:`umbmark.model.recording.gap_mask`) are no jumps: they are looked at
    by :func:`umbmark.runs.gaps.find_gaps`.

    Parameters
    ----------
    name : str
        The recording or run, for the message.
    time : array, shape (n,)
        Wheel sample times [s].
    angles : array, shape (n, 2)
        Wheel angles [rad].
    truth : array, shape (m, 3), or None
        Ground-truth poses; rows with NaN are left out.
    headings : bool
        Whether ``truth`` has headings (else its ``theta`` column is NaN and only the
        positions are checked).
    resets : sequence of Reset
        Resets of the ground truth (:mod:`umbmark.runs.rests`): its jumps there are
        no corrupt samples.

    Raises
    ------
    InputError
        Naming ``name`` and the problem.
    """
    if not np.all(np.isfinite(angles)):
        raise InputError("wheel angles are not finite numbers (an overflow?)", source=name)
    if angles.shape[0] < 2 or float(np.max(np.ptp(angles, axis=0))) <= STILL_WHEELS:
        raise InputError(
            "the wheels never turn (every wheel angle is constant): no motion to calibrate "
            "from; check the wheel columns or topic",
            source=name,
        )
    _check_wheel_steps(name, time, angles)
    if truth is None:
        return
    if not headings:
        truth = truth[:, :2]
    rows = truth[np.all(np.isfinite(truth), axis=1)]
    if rows.shape[0] < 2:
        return
    if not np.all(np.isfinite(np.ptp(rows, axis=0))):
        raise InputError("ground-truth poses are not finite numbers (an overflow?)", source=name)
    if float(np.max(np.ptp(rows, axis=0))) <= STILL_TRUTH:
        raise InputError(
            "the ground truth never moves (every pose is the same): check the ground-truth "
            "columns or topic",
            source=name,
        )
    _check_truth_steps(name, time, truth, resets)


def _check_wheel_steps(name: str, time: FloatArray, angles: FloatArray) -> None:
    """Refuse a wheel step too large for the time it took (see :func:`check_motion`)."""
    dt = np.diff(time)
    steady = np.flatnonzero(~gap_mask(time))
    if steady.size == 0:
        return
    steps = np.abs(np.diff(angles, axis=0))[steady]
    limit = min(MAX_WHEEL_STEP, max(MIN_JUMP, JUMP_FACTOR * float(np.percentile(steps, 99))))
    limits = limit * np.maximum(1.0, dt[steady] / float(np.median(dt)))[:, None]
    over = steps > limits
    if np.any(over):
        k, wheel = np.unravel_index(int(np.argmax(np.where(over, steps, -1.0))), steps.shape)
        at = int(steady[k])
        raise InputError(
            f"the {('left', 'right')[int(wheel)]} wheel jumps by {float(steps[k, wheel]):.4g} "
            f"rad in one sample at {float(time[at + 1] - time[0]):.2f} s (more than "
            f"{float(limits[k, 0]):.3g} rad): a corrupt sample or wrong encoder units",
            source=name,
        )


def _check_truth_steps(
    name: str, time: FloatArray, truth: FloatArray, resets: Sequence[Reset] = ()
) -> None:
    """Refuse a ground-truth position that jumps between two samples (see
    :data:`MAX_TRUTH_STEP`) other than at a reset; ``truth`` has shape (n, 2 or 3) at
    ``time`` (n,), NaN rows skipped."""
    if truth.shape[0] != time.shape[0]:
        return
    kept = np.flatnonzero(np.all(np.isfinite(truth), axis=1))
    if kept.size < 2:
        return
    step = np.hypot(np.diff(truth[kept, 0]), np.diff(truth[kept, 1]))
    limit = np.maximum(MAX_TRUTH_STEP, MAX_TRUTH_SPEED * np.abs(np.diff(time[kept])))
    reset = np.zeros(time.size, dtype=np.int64)
    for r in resets:
        reset[r.first + 1 : r.last + 1] = 1
    in_reset = np.cumsum(reset)
    across_reset = in_reset[kept[1:]] - in_reset[kept[:-1]] > 0
    over = np.flatnonzero((step > limit) & ~across_reset)
    if over.size:
        k = int(over[0])
        raise InputError(
            f"the ground truth jumps by {float(step[k]):.4g} m between two samples at "
            f"{float(time[kept[k + 1]] - time[0]):.2f} s (more than {float(limit[k]):.3g} m): "
            "a corrupt sample, a cell in another unit, or a tracker that lost the robot",
            source=name,
        )


def _run(
    recording: Recording,
    truth: FloatArray,
    first: int,
    last: int,
    params: WheelParams,
    label: str,
    method: IntegrationMethod,
) -> Run | None:
    wheels = recording.wheels
    headings = recording.truth is None or recording.truth.headings
    known = _known(truth, headings)
    matched = np.flatnonzero(known[first : last + 1]) + first
    if matched.size < 2:
        return None
    a, b = int(matched[0]), int(matched[-1])
    sl = slice(a, b + 1)
    # Messages name the file (the label is its short name, and the run within it).
    where = recording.where + label[len(recording.name) :]
    check_motion(where, wheels.time[sl], wheels.angles[sl], truth[sl], headings=headings)
    log = RunLog(
        time=wheels.time[sl] - wheels.time[a],
        wheel_angles=wheels.angles[sl] - wheels.angles[a],
        truth=np.full((b - a + 1, 3), np.nan),
        source=label,
        start=float(wheels.time[a]),
        headings=headings,
    )
    odo = log.odometry(params, method)
    if not np.all(np.isfinite(odo[-1])):
        raise InputError(
            "the odometry overflows (not a finite number): check the wheel parameters and "
            "the encoder units",
            source=where,
        )
    ok = known[sl]
    if headings:
        log.truth[ok] = to_start_frame(truth[sl][ok])
        if recording.truth_at_stops:
            # Measured only at the stops, the truth cannot tell how many whole turns the
            # robot made in between: as many as its odometry (off by far less than a half
            # turn), the truth's heading within them.
            turns = np.round((odo[ok, 2] - log.truth[ok, 2]) / (2 * math.pi))
            log.truth[ok, 2] += 2 * math.pi * turns
        turned = float(log.truth[-1, 2])
    else:
        log.truth[ok, :2] = _positions_in_start_frame(truth[sl, :2], ok, odo)
        turned = float(odo[-1, 2])  # a position-only reference: the odometry's turn
    direction = Direction.CCW if turned >= 0 else Direction.CW
    end = log.truth[-1]
    return Run(
        direction=direction,
        true_end=EndPose(float(end[0]), float(end[1]), float(end[2]) if headings else None),
        odometry_end=EndPose(*(float(v) for v in odo[-1])),
        label=label,
        log=log,
    )


def _known(truth: FloatArray, headings: bool) -> NDArray[np.bool_]:
    """Samples with ground truth, shape (n,): a position (and a heading, if it has them)."""
    return np.asarray(np.all(np.isfinite(truth if headings else truth[:, :2]), axis=1))


#: A position-only reference's start heading is read over the first this many metres of
#: a run (or half of how far it strays from its start, if less).
ALIGN_DISTANCE = 1.0


def _positions_in_start_frame(
    positions: FloatArray, known: NDArray[np.bool_], odometry: FloatArray
) -> FloatArray:
    """Positions of a reference without headings, shape (k, 2) of the ``known`` rows of
    ``positions`` (n, 2), in the run's start frame.

    The frame's origin is the first position; its heading, which such a reference does
    not measure, is the direction the reference moved in over the run's first stretch
    (:data:`ALIGN_DISTANCE`) turned back by the direction the odometry (n, 3) moved in
    over the same samples: the start frame the odometry starts in. The odometry's own
    error over that stretch turns the frame by at most its heading drift there, which
    moves a return error ``eps`` by ``|eps|`` times that angle: second order.
    """
    rows = np.flatnonzero(known)
    origin = positions[rows[0]]
    moved = positions[rows] - origin
    odo = odometry[rows, :2] - odometry[rows[0], :2]
    reach = np.hypot(odo[:, 0], odo[:, 1])
    limit = min(ALIGN_DISTANCE, 0.5 * float(reach.max()))
    k = int(np.argmax(reach >= limit)) if limit > 0 else 0
    if k == 0:
        return np.asarray(moved)
    heading = math.atan2(moved[k, 1], moved[k, 0]) - math.atan2(odo[k, 1], odo[k, 0])
    return relative_positions(moved, heading)  # moved starts at 0: only turned


def runs_from_recordings(
    recordings: Sequence[Recording],
    params: WheelParams,
    *,
    split: SplitMode = "rests",
    windows: Sequence[tuple[float, float]] = (),
    split_options: SplitOptions | None = None,
    max_gap: float = DEFAULT_MAX_GAP,
    method: IntegrationMethod = "arc",
    keep_stretches: bool = False,
) -> LoadedRuns:
    """Find the runs in ``recordings`` and compute their true and odometry end poses.

    Parameters
    ----------
    recordings : sequence of Recording
        Each must have ground truth.
    params : WheelParams
        The odometry parameters the wheel data is integrated with.
    split : {"rests", "none", "windows", "file"}
        Split each recording at rests near the start and at resets of the ground truth
        (see :mod:`umbmark.runs.segmentation`), take each recording as one run (cut
        only where its ground truth was reset: the robot was put back), take each as
        the one run its file holds (``"file"``: OptiOdom files, run logs of one run per
        file; a reset inside leaves it out), or cut
        it by ``windows`` (seconds from its start). Windows are cut before any check: what
        they leave out is not looked at.
    keep_stretches : bool
        Where no run is left, the stretches of the motion left out (``stretches`` of
        :class:`LoadedRuns`) are the runs, paths of any shape for the estimators of whole
        trajectories, rather than an error.

    Gaps in the wheel samples (:mod:`umbmark.runs.gaps`) are bridged with a note, or
    the run holding one is left out with a note; so is a run (a window, a whole
    recording) across which the ground truth was reset. A recording in which no loop
    tells runs apart (a drive of any shape) is split at such a gap instead, the motion
    on either side a run. A ground truth that the wheels' odometry reproduces exactly is
    refused (:mod:`umbmark.runs.reproduced`).

    Raises
    ------
    InputError
        If a recording has no ground truth, its wheels never turn, its ground truth never
        moves or jumps, a wheel jumps in one sample (see :func:`check_motion`), a run has
        no motion, its odometry overflows, its ground truth is the wheels' odometry, or no
        run is found or left at all.
    """
    out = LoadedRuns(runs=[])
    left: list[tuple[str, str]] = []
    for recording in recordings:
        where = recording.where
        if recording.truth is None:
            raise InputError(
                "has no ground truth: name its topic or columns (see --help)", source=where
            )
        truth, association = associate(
            recording.wheels, recording.truth, max_gap=max_gap, source=where
        )
        out.associations.append((recording.name, association))
        # A truth measured only where the robot stood matches few samples, as intended.
        if association.fraction < 0.9 and not recording.truth_at_stops:
            out.notes.append(f"{recording.name}: only {association.describe()}")
        segments, left_out, whole = _segments(
            recording, truth, split, windows, split_options, out, params, method
        )
        gaps = find_gaps(recording.wheels.time, recording.wheels.angles, params)
        if whole:  # a path of any shape: what a gap leaves on either side is a run
            segments = _split_at_gaps(recording, segments, gaps, split_options, out.notes)
        found = 0
        first_run = len(out.runs)
        for first, last in segments:
            label = recording.name if len(segments) == 1 else f"{recording.name} run {found + 1}"
            why = _broken(recording, truth, gaps, first, last, split_options, params)
            if why is not None:
                left_out.append(LeftOut(first, last, why))
                continue
            run = _run(recording, truth, first, last, params, label, method)
            time = recording.wheels.time
            if run is None:
                out.notes.append(
                    f"{recording.name}: left out a run from {time[first] - time[0]:.2f} to "
                    f"{time[last] - time[0]:.2f} s: fewer than 2 samples with ground truth"
                )
                continue
            inside = [g for g in gaps if first <= g.index < last]
            out.notes.extend(  # bridged: the run stands as recorded
                info(f"{label}: {line}") for line in describe_gaps(inside, recording.wheel_sample)
            )
            found += 1
            out.runs.append(run)
        left += _said_left_out(recording, left_out, out.notes)
        out.stretches.extend(
            _stretches(recording, truth, left_out, gaps, split_options, params, method)
        )
        if found == 0:
            out.notes.append(f"{recording.name}: no run found")
        logs = [run.log for run in out.runs[first_run:] if run.log is not None]
        noiseless = check_not_reproduced(recording, logs, params)
        if noiseless is not None:
            out.notes.append(noiseless)
    if not out.runs and keep_stretches and out.stretches:
        seconds = sum(float(run.log.time[-1]) for run in out.stretches if run.log is not None)
        out.notes.append(
            info(
                f"no run is left: the {len(out.stretches)} stretch(es) of motion with a "
                f"reference ({seconds:.1f} s) are runs of any shape, for the estimators of "
                "whole trajectories"
            )
        )
        return LoadedRuns(out.stretches, out.associations, out.notes)
    if not out.runs:
        if left:
            name, line = left[0]
            raise InputError(f"{line}; no run is left", source=name)
        names = ", ".join(r.where for r in recordings) or "the recordings"
        raise InputError(f"found no run with ground truth in {names}", source=None)
    return out


def _said_left_out(
    recording: Recording, left_out: Sequence[LeftOut], notes: list[str]
) -> list[tuple[str, str]]:
    """A note of each piece of motion left out, in time order; ``(name, line)`` of each."""
    said = []
    time = recording.wheels.time
    for piece in sorted(left_out, key=lambda p: p.first):
        line = (
            f"left out the motion from {time[piece.first] - time[0]:.2f} to "
            f"{time[piece.last] - time[0]:.2f} s: {piece.why}"
        )
        notes.append(f"{recording.name}: {line}")
        said.append((recording.name, line))
    return said


def _segments(
    recording: Recording,
    truth: FloatArray,
    split: SplitMode,
    windows: Sequence[tuple[float, float]],
    split_options: SplitOptions | None,
    out: LoadedRuns,
    params: WheelParams,
    method: IntegrationMethod,
) -> tuple[list[tuple[int, int]], list[LeftOut], bool]:
    """The sample ranges of the runs of ``recording``, the motion left out, and whether
    no run could be told apart (the recording's motion is one run of any shape); the
    whole recording is checked first unless ``windows`` select parts of it."""
    time, angles = recording.wheels.time, recording.wheels.angles
    if split == "windows":
        return split_by_windows(time, windows, recording.where), [], False
    headings = recording.truth is None or recording.truth.headings
    if not headings:  # a position-only reference: the turns come from the odometry
        log = RunLog(time=time - time[0], wheel_angles=angles, truth=truth)
        truth = truth.copy()
        truth[:, 2] = np.where(_known(truth, False), log.odometry(params, method)[:, 2], np.nan)
    rest_speed = (split_options or SplitOptions()).rest_speed
    radius = _jump_radius(recording, params)
    resets = find_resets(time, angles, truth, rest_speed, radius)
    check_motion(recording.where, time, angles, truth, headings=headings, resets=resets)
    if split == "file":
        return [(0, time.size - 1)], [], False
    if split == "none":
        return cut_at_resets(recording, resets, rest_speed, out.notes), [], False
    found = find_runs(time, angles, truth, split_options, radius)
    out.notes.extend(
        info(f"{recording.name}: {reset.describe(time)}: a run ends there")
        for reset in found.resets
    )
    return found.runs, list(found.left_out), found.whole


def _stretches(
    recording: Recording,
    truth: FloatArray,
    left_out: Sequence[LeftOut],
    gaps: Sequence[Gap],
    split_options: SplitOptions | None,
    params: WheelParams,
    method: IntegrationMethod,
) -> list[Run]:
    """The motion ``left_out`` of a recording's runs cut at its gaps that are not bridged
    and at the resets of its ground truth ``truth``, each piece trimmed to its motion: the
    pieces with a reference (two samples of it, motion :func:`check_motion` accepts) as
    runs of any shape, labelled ``NAME stretch K``."""
    time, angles = recording.wheels.time, recording.wheels.angles
    rest_speed = (split_options or SplitOptions()).rest_speed
    radius = _jump_radius(recording, params)
    out: list[Run] = []
    for piece in sorted(left_out, key=lambda p: p.first):
        a, b = piece.first, piece.last
        sl = slice(a, b + 1)
        cuts = [(g.index, g.index + 1) for g in gaps if a <= g.index < b and not g.bridged]
        resets = find_resets(time[sl], angles[sl], truth[sl], rest_speed, radius)
        merged: list[tuple[int, int]] = []
        for i, j in sorted([*cuts, *((a + r.first, a + r.last) for r in resets)]):
            if merged and i <= merged[-1][1]:
                merged[-1] = (merged[-1][0], max(j, merged[-1][1]))
            else:
                merged.append((i, j))
        starts, ends = [a, *(j for _, j in merged)], [*(i for i, _ in merged), b]
        for c, d in zip(starts, ends, strict=True):
            if d <= c:
                continue
            for e, f in trim_to_motion(time[c : d + 1], angles[c : d + 1], rest_speed):
                label = f"{recording.name} stretch {len(out) + 1}"
                try:
                    run = _run(recording, truth, c + e, c + f, params, label, method)
                except InputError:  # no motion with a reference to fit
                    continue
                if run is not None:
                    out.append(run)
    return out


def _split_at_gaps(
    recording: Recording,
    segments: list[tuple[int, int]],
    gaps: Sequence[Gap],
    split_options: SplitOptions | None,
    notes: list[str],
) -> list[tuple[int, int]]:
    """``segments`` (a recording's motion as one run) cut at the gaps that are not
    bridged into stretches, each trimmed to its motion; a line for each cut to ``notes``."""
    rest_speed = (split_options or SplitOptions()).rest_speed
    time, angles = recording.wheels.time, recording.wheels.angles
    out: list[tuple[int, int]] = []
    for first, last in segments:
        cuts = [g for g in gaps if first <= g.index < last and not g.bridged]
        starts = [first, *(g.index + 1 for g in cuts)]
        ends = [*(g.index for g in cuts), last]
        pieces = []
        for a, b in zip(starts, ends, strict=True):
            if b > a:
                pieces += [
                    (a + c, a + d)
                    for c, d in trim_to_motion(time[a : b + 1], angles[a : b + 1], rest_speed)
                ]
        for gap in cuts:
            notes.append(
                info(
                    f"{recording.name}: split at the gap: {gap.describe(recording.wheel_sample)}:"
                    f" {gap.why}; the motion before and after it are runs apart"
                )
            )
        out += pieces
    return out


def _jump_radius(recording: Recording, params: WheelParams) -> float | None:
    """The wheel radius [m] the ground truth's jumps are judged with
    (:func:`umbmark.runs.rests.find_resets`); None for a truth measured only at stops."""
    if recording.truth_at_stops:
        return None
    return 0.5 * params.wheel_diameter * max(params.c_left, params.c_right)


def _broken(
    recording: Recording,
    truth: FloatArray,
    gaps: Sequence[Gap],
    first: int,
    last: int,
    split_options: SplitOptions | None,
    params: WheelParams,
) -> str | None:
    """Why the run from sample ``first`` to ``last`` cannot be used, or None: a gap that is
    not bridged, or a reset of the ground truth inside it."""
    broken = [g for g in gaps if first <= g.index < last and not g.bridged]
    if broken:
        return f"{broken[0].describe(recording.wheel_sample)}: {broken[0].why}"
    time, angles = recording.wheels.time, recording.wheels.angles
    sl = slice(first, last + 1)
    rest_speed = (split_options or SplitOptions()).rest_speed
    radius = _jump_radius(recording, params)
    resets = find_resets(time[sl], angles[sl], truth[sl], rest_speed, radius)
    inside = [r for r in resets if r.last > 0 and r.first < last - first]
    if inside:
        seen = inside[0].describe(time[first:], float(time[0]))
        return f"{seen}: a run cannot go on across it; split the runs there (--split rests)"
    return None

"""The robot's pose in an L-shaped corner from three range sensors (the paper's "sonar
calibrator"), from motion capture, and from a person with a tape measure.

Frames and the fix: :mod:`umbmark.routines.corner`. Walls are named by the corner frame's
axes: the *x wall* runs along x (a sensor facing it measures the robot's y), the *y wall*
along y.

Range sensors
    Two sensors face one wall, one faces the other, each measuring along its x axis from
    its mount in the base frame (:class:`~umbmark.robot.base.RangeReading`). The two
    echoes on one wall give that wall's line in the robot's frame (its direction is the
    heading), the third echo the other wall's, perpendicular to it. Several readings
    taken while the robot stands still are averaged.
Tape measure
    A person measures, at each stop, the distance from two marks on the robot to one
    wall and from a third mark to the other, each square to the wall (the shortest
    distance). The same geometry: the heading from the difference of the first two.
Motion capture
    The tracked pose, in the motion capture's frame or in the corner frame when the
    corner's pose in that frame is given.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.conventions import wrap_angle
from umbmark.core.errors import InputError
from umbmark.robot.base import Pose2D, RangeReading, StampedPose
from umbmark.routines.corner import CornerFix, CornerNotFoundError, fit_corner

__all__ = [
    "TapeMarks",
    "ask_tape",
    "fix_from_ground_truth",
    "fix_from_ranges",
    "fix_from_tape",
]

Wall = Literal["x", "y"]

#: The paper's layout: the first two sensors (or marks) face the y wall, the third the x wall.
PAPER_FACES: tuple[Wall, ...] = ("y", "y", "x")


def _check_faces(faces: Sequence[Wall], count: int, what: str) -> None:
    if len(faces) != count:
        raise InputError(f"{count} {what} but {len(faces)} walls named for them")
    if set(faces) != {"x", "y"} or any(f not in ("x", "y") for f in faces):
        raise InputError(f"{what}: two must face one wall and one the other, got {faces}")


def _gate(pose: Pose2D, prior: Pose2D | None, distance: float, angle: float) -> None:
    if prior is None:
        return
    d = math.hypot(pose.x - prior.x, pose.y - prior.y)
    a = abs(wrap_angle(pose.theta - prior.theta))
    if d > distance or a > angle:
        raise CornerNotFoundError(
            "not_where_expected",
            f"corner not where expected: the robot measures at ({pose.x:.3f} m, "
            f"{pose.y:.3f} m, {math.degrees(pose.theta):.1f} deg), {d:.3f} m and "
            f"{math.degrees(a):.1f} deg from the expected ({prior.x:.3f} m, {prior.y:.3f} m, "
            f"{math.degrees(prior.theta):.1f} deg)",
        )


def _ranges_pose(
    ranges: FloatArray, mounts: Sequence[Pose2D], faces: Sequence[Wall], max_incidence: float
) -> Pose2D:
    """The robot's pose from one set of ranges (echo points on the walls, fitted as a
    perpendicular corner: exactly determined by three)."""
    hits = np.array(
        [
            [m.x + r * math.cos(m.theta), m.y + r * math.sin(m.theta)]
            for r, m in zip(ranges, mounts, strict=True)
        ]
    )
    on_x = np.array([f == "x" for f in faces])
    pair = hits[on_x] if on_x.sum() == 2 else hits[~on_x]
    if math.hypot(*(pair[1] - pair[0])) < 0.02:
        raise CornerNotFoundError(
            "implausible",
            "implausible geometry: the two echoes on one wall are less than 2 cm apart",
        )
    fit = fit_corner(hits[on_x], hits[~on_x], extent_margin=math.inf)
    if fit is None or not fit.inside:
        raise CornerNotFoundError(
            "implausible",
            "implausible geometry: the echoes do not put the robot inside the corner "
            "(a sensor facing the other wall, or the walls named the other way round)",
        )
    square = {"x": -0.5 * math.pi, "y": math.pi}  # a beam square to the wall, corner frame
    for k, (m, f) in enumerate(zip(mounts, faces, strict=True)):
        incidence = abs(wrap_angle(fit.pose.theta + m.theta - square[f]))
        if incidence > max_incidence:
            raise CornerNotFoundError(
                "implausible",
                f"implausible geometry: sensor {k + 1} meets the {f} wall "
                f"{math.degrees(incidence):.0f} deg off square (at most "
                f"{math.degrees(max_incidence):.0f} deg)",
            )
    return fit.pose


def _propagate(
    solve: Callable[[FloatArray], Pose2D], values: FloatArray, sigma: float
) -> FloatArray:
    """Covariance of the pose ``solve(values)`` for independent errors of ``sigma`` in
    each value (first order, numerical Jacobian)."""
    base = solve(values)
    h = 1e-6
    jac = np.zeros((3, values.size))
    for k in range(values.size):
        v = values.copy()
        v[k] += h
        p = solve(v)
        jac[:, k] = [(p.x - base.x) / h, (p.y - base.y) / h, wrap_angle(p.theta - base.theta) / h]
    return np.asarray(sigma**2 * jac @ jac.T)


def fix_from_ranges(
    readings: Sequence[RangeReading],
    faces: Sequence[Wall] = PAPER_FACES,
    *,
    sigma: float = 0.002,
    prior: Pose2D | None = None,
    max_incidence: float = math.radians(45.0),
    max_spread: float = 0.01,
    prior_distance: float = 0.5,
    prior_angle: float = math.radians(20.0),
) -> CornerFix:
    """The robot's pose in the corner frame from three range sensors, averaged over
    ``readings`` taken while it stood still.

    Parameters
    ----------
    readings : sequence of RangeReading
        Each with three ranges [m] and the sensors' mounts (base frame).
    faces : three of ``"x"``, ``"y"``
        The wall each sensor faces [default: the first two the y wall, the third the x wall].
    sigma : float
        The sensors' range noise [m] (the fix's covariance comes from it).
    prior : Pose2D, optional
        The pose expected (last fix and odometry); the fix is refused farther than
        ``prior_distance`` [m] or ``prior_angle`` [rad] from it.
    max_incidence : float
        A beam meeting its wall farther from square than this [rad] is implausible.
    max_spread : float
        A sensor whose readings spread more than this [m] (standard deviation) saw
        something move.

    Raises
    ------
    CornerNotFoundError
        A missing echo in every reading (``missing_echo``), readings that disagree or a
        geometry that does not fit the corner (``implausible``), or a pose far from the
        prior (``not_where_expected``).
    """
    if not readings:
        raise CornerNotFoundError("missing_echo", "no range reading to find the corner with")
    mounts = readings[0].mounts
    _check_faces(faces, len(mounts), "range sensors")
    table = np.array([np.asarray(r.ranges, dtype=np.float64) for r in readings])
    if table.shape[1] != len(mounts):
        raise InputError(f"{table.shape[1]} ranges for {len(mounts)} sensor mounts")
    complete = np.all(np.isfinite(table) & (table > 0.0), axis=1)
    if not complete.any():
        missing = [k + 1 for k in range(len(mounts)) if not np.isfinite(table[:, k]).any()]
        which = f"sensor {missing[0]}" if missing else "some sensor"
        raise CornerNotFoundError(
            "missing_echo",
            f"missing echo: {which} has no echo in {'any' if len(readings) > 1 else 'the'} "
            f"of {len(readings)} reading(s)",
        )
    table = table[complete]
    if len(table) > 1:
        spread = table.std(axis=0, ddof=1)
        k = int(np.argmax(spread))
        if spread[k] > max_spread:
            raise CornerNotFoundError(
                "implausible",
                f"readings disagree: sensor {k + 1} spreads {spread[k] * 1000:.1f} mm "
                f"while the robot stands still (at most {max_spread * 1000:.1f} mm)",
            )
    mean = table.mean(axis=0)
    pose = _ranges_pose(mean, mounts, faces, max_incidence)
    _gate(pose, prior, prior_distance, prior_angle)
    cov = _propagate(
        lambda v: _ranges_pose(v, mounts, faces, math.pi), mean, sigma / math.sqrt(len(table))
    )
    return CornerFix(
        pose=pose,
        covariance=cov,
        method="ranges",
        time=max(r.time for r in readings),
        points=int(table.size),
        readings=len(table),
    )


# --- a person with a tape measure ---------------------------------------------------------


@dataclass(frozen=True)
class TapeMarks:
    """Three marks on the robot a person measures from, square to the walls.

    Attributes
    ----------
    marks : tuple of (x, y)
        Each mark's position in the robot's base frame [m].
    faces : three of ``"x"``, ``"y"``
        The wall each mark is measured to [default: the first two to the y wall].
    """

    marks: tuple[tuple[float, float], ...]
    faces: tuple[Wall, ...] = field(default=PAPER_FACES)


def _tape_pose(d: FloatArray, marks: TapeMarks, heading_hint: float) -> Pose2D:
    m = np.asarray(marks.marks, dtype=np.float64)
    on_x = np.array([f == "x" for f in marks.faces])
    pair = np.flatnonzero(on_x) if on_x.sum() == 2 else np.flatnonzero(~on_x)
    other = int(np.flatnonzero(on_x if on_x.sum() == 1 else ~on_x)[0])
    (a0, b0), (a1, b1) = m[pair[0]], m[pair[1]]
    dd = float(d[pair[0]] - d[pair[1]])
    pair_wall = marks.faces[int(pair[0])]
    # a mark (a, b)'s distance: to the y wall x + a cos t - b sin t; to the x wall
    # y + a sin t + b cos t. The pair's difference is A cos t + B sin t = dd.
    da, db = a0 - a1, b0 - b1
    A, B = (da, -db) if pair_wall == "y" else (db, da)
    R = math.hypot(A, B)
    if R < 0.02 or abs(dd) > R:
        raise CornerNotFoundError(
            "implausible",
            f"implausible distances: marks {pair[0] + 1} and {pair[1] + 1} differ by "
            f"{abs(dd) * 1000:.0f} mm, more than their {R * 1000:.0f} mm separation allows",
        )
    gamma, spread = math.atan2(B, A), math.acos(dd / R)
    theta = min(
        (wrap_angle(gamma + spread), wrap_angle(gamma - spread)),
        key=lambda t: abs(wrap_angle(t - heading_hint)),
    )
    c, s = math.cos(theta), math.sin(theta)

    def along(k: int, wall: str) -> float:  # the mark's offset from the robot, to the wall
        a, b = m[k]
        return float(a * c - b * s if wall == "y" else a * s + b * c)

    pair_coord = float(np.mean([d[k] - along(int(k), pair_wall) for k in pair]))
    other_wall = marks.faces[other]
    other_coord = float(d[other] - along(other, other_wall))
    x, y = (pair_coord, other_coord) if pair_wall == "y" else (other_coord, pair_coord)
    return Pose2D(x, y, theta)


def fix_from_tape(
    distances: Sequence[float],
    marks: TapeMarks,
    *,
    sigma: float = 0.001,
    prior: Pose2D | None = None,
    time: float = 0.0,
    square: float = 0.0,
) -> CornerFix:
    """The robot's pose in the corner frame from three distances [m] a person measured
    from ``marks`` on the robot, square to the walls.

    Two headings fit two distances to one wall (the robot facing one way or its mirror);
    the one nearer ``prior`` [default: the heading ``square``, the robot placed square in
    the corner: 0 with the corner behind and to its right, pi/2 with it to its left] is
    taken. ``sigma`` is the tape's reading error [m].
    """
    _check_faces(marks.faces, len(marks.marks), "tape marks")
    d = np.asarray(distances, dtype=np.float64)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or np.any(d <= 0.0):
        raise InputError(f"three positive distances needed, got {list(distances)}")
    hint = prior.theta if prior is not None else square
    pose = _tape_pose(d, marks, hint)
    if prior is not None:
        _gate(pose, prior, 0.5, math.radians(20.0))
    cov = _propagate(lambda v: _tape_pose(v, marks, pose.theta), d, sigma)
    return CornerFix(pose=pose, covariance=cov, method="tape", time=time, points=3)


def ask_tape(
    ask: Callable[[str], str],
    marks: TapeMarks,
    *,
    unit: Literal["mm", "cm", "m"] = "mm",
    attempts: int = 3,
) -> list[float]:
    """Prompt a person (``ask`` shows a prompt and returns the answer, ``input`` at a
    terminal) for the three distances; returns them in metres. An answer that is not a
    positive number is asked again, ``attempts`` times in all."""
    scale = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}[unit]
    out: list[float] = []
    for k, ((a, b), wall) in enumerate(zip(marks.marks, marks.faces, strict=True)):
        prompt = (
            f"distance from mark {k + 1} (x {a * 1000:.0f} mm, y {b * 1000:.0f} mm on the "
            f"robot) to the {wall} wall, square to the wall [{unit}]: "
        )
        for _ in range(attempts):
            answer = ask(prompt).strip()
            try:
                value = float(answer)
            except ValueError:
                continue
            if math.isfinite(value) and value > 0.0:
                out.append(value * scale)
                break
        else:
            raise InputError(f"mark {k + 1}: no distance in {attempts} answers (last: {answer!r})")
    return out


# --- motion capture -----------------------------------------------------------------------


def fix_from_ground_truth(
    poses: StampedPose | Sequence[StampedPose],
    *,
    corner: Pose2D | None = None,
    sigma_xy: float = 0.0005,
    sigma_theta: float = math.radians(0.05),
) -> CornerFix:
    """A fix from motion capture: the tracked pose (averaged over ``poses`` taken while
    the robot stood still), in the corner frame when ``corner`` (the corner frame's pose
    in the capture's frame) is given, else in the capture's own frame (all the routine
    needs: :func:`~umbmark.routines.corner.relative_motion` drops the frame out).
    ``sigma_xy`` [m] and ``sigma_theta`` [rad] are the system's accuracy."""
    stamped = [poses] if isinstance(poses, StampedPose) else list(poses)
    if not stamped:
        raise CornerNotFoundError("missing_echo", "no ground-truth pose to take the fix from")
    ref = stamped[0].pose.theta
    mean = Pose2D(
        float(np.mean([s.pose.x for s in stamped])),
        float(np.mean([s.pose.y for s in stamped])),
        wrap_angle(ref + float(np.mean([wrap_angle(s.pose.theta - ref) for s in stamped]))),
    )
    pose = mean.relative_to(corner) if corner is not None else mean
    cov = np.diag([sigma_xy**2, sigma_xy**2, sigma_theta**2])
    return CornerFix(
        pose=Pose2D(pose.x, pose.y, wrap_angle(pose.theta)),
        covariance=cov,
        method="ground_truth",
        time=max(s.time for s in stamped),
        points=len(stamped),
        readings=len(stamped),
    )

"""The robot's pose in an L-shaped corner from 2D laser scans.

For each scan (:func:`find_corner`):

1. the scan is cut into straight pieces (split-and-merge, :mod:`.corner_pieces`: clusters
   of neighbouring returns, split where they leave a line by more than
   ``split_distance``, collinear pieces merged again across gaps up to ``max_gap``);
2. pieces at least ``min_wall_length`` long with ``min_wall_points`` returns are walls;
   every two walls perpendicular within ``candidate_angle`` that the robot sees from
   inside (a box's outer corner is seen from outside) are a candidate corner;
3. the candidate consistent with the prior (the pose expected from the last fix and the
   odometry, within ``prior_distance`` and ``prior_angle``), or without one the
   longest, is the corner.

Then (:func:`fix_from_scans`) the returns on the two walls of all scans taken while the
robot stood still are pooled and the walls fitted jointly as perpendicular lines, in
range space (:mod:`.corner_beams`: unbiased for oblique beams), the returns re-chosen
within a shrinking band around each wall; the walls' angle is measured by fitting each
wall on its own: checked, not forced. The fix is refused, naming the cause, when a scan
has too few returns, no corner is found, the walls are not perpendicular (by more than
``perpendicular_tolerance`` and four standard errors of the measured angle), the range
residual's rms exceeds ``max_rms``, or the corner is not where expected.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from umbmark.core.conventions import wrap_angle
from umbmark.robot.base import Pose2D, ScanSweep
from umbmark.routines.corner import CornerFit, CornerFix, CornerNotFoundError, fit_corner, to_frame
from umbmark.routines.corner_beams import Beams, fit_corner_ranges, wall_angle
from umbmark.routines.corner_pieces import Piece, pieces

__all__ = ["LidarCorner", "find_corner", "fix_from_scans"]


@dataclass(frozen=True)
class LidarCorner:
    """How the corner is found in a scan and when a fix is refused (SI units).

    Attributes
    ----------
    split_distance : float
        A piece of a cluster is split where a point leaves its line by more [m]
        (about four to five times the range noise).
    jump : float
        Neighbouring returns farther apart than this [m] (or than four beam spacings at
        their range) are in different clusters.
    max_gap : float
        Two collinear pieces are one wall across a gap up to this long [m] (a person
        standing in front of it).
    min_wall_length, min_wall_points : float, int
        A wall is at least this long [m] and has this many returns in a scan.
    candidate_angle : float
        Two walls are a candidate corner when perpendicular within this [rad].
    perpendicular_tolerance : float
        The fitted walls' angle may differ from 90 degrees by this [rad] (and by four
        standard errors of its measurement, when they are more) before the fix is refused.
    max_rms : float
        The largest residual rms of the joint fit [m].
    band : float
        Points within this distance [m] of a wall are its points in the first pass of
        the joint fit (then four residual standard deviations, at least 1 cm).
    vertex_margin : float
        Points nearer the vertex than this [m] along a wall are left out (they may belong
        to either wall).
    prior_distance, prior_angle : float
        The corner must put the robot within this distance [m] and angle [rad] of the
        prior.
    """

    split_distance: float = 0.05
    jump: float = 0.1
    max_gap: float = 1.0
    min_wall_length: float = 0.4
    min_wall_points: int = 10
    candidate_angle: float = math.radians(5.0)
    perpendicular_tolerance: float = math.radians(0.5)
    max_rms: float = 0.02
    band: float = 0.05
    vertex_margin: float = 0.05
    prior_distance: float = 0.5
    prior_angle: float = math.radians(20.0)


@dataclass(frozen=True)
class _Candidate:
    fit: CornerFit
    score: float  # the two walls' total length [m]
    x_reach: float  # how far the x wall's points reach from the vertex [m]
    y_reach: float


@dataclass(frozen=True)
class _Found:
    """The corner in one scan: the first estimate and the scan's pieces."""

    candidate: _Candidate
    beams: Beams
    pieces: list[Piece]
    time: float


def _walls(scan: ScanSweep, config: LidarCorner) -> tuple[Beams, list[Piece], list[Piece]]:
    """The scan's returns, its straight pieces and the walls among them."""
    valid = np.isfinite(scan.ranges) & (scan.ranges >= scan.range_min)
    count = int(np.count_nonzero(valid & (scan.ranges <= scan.range_max)))
    if count < 2 * config.min_wall_points:
        raise CornerNotFoundError(
            "too_few_points",
            f"too few laser returns: {count} of {scan.ranges.size} beams "
            f"(a corner needs {2 * config.min_wall_points})",
        )
    beams, found = pieces(scan, config.split_distance, config.jump, config.max_gap)
    walls = [
        p
        for p in found
        if p.length >= config.min_wall_length and len(p.index) >= config.min_wall_points
    ]
    return beams, found, walls


def _candidates(walls: list[Piece], config: LidarCorner) -> list[_Candidate]:
    out: list[_Candidate] = []
    sin_tol = math.sin(config.candidate_angle)
    for i, p in enumerate(walls):
        for q in walls[i + 1 :]:
            if abs(float(p.direction @ q.direction)) > sin_tol:
                continue
            for wx, wy in ((p, q), (q, p)):
                fit = fit_corner(wx.points, wy.points)
                if fit is None or not fit.inside:
                    continue
                if fit.rms > 2.0 * config.max_rms:
                    continue
                x_reach = float(fit.x_points[:, 0].max())
                y_reach = float(fit.y_points[:, 1].max())
                out.append(_Candidate(fit, wx.length + wy.length, x_reach, y_reach))
    return out


def _distance(pose: Pose2D, prior: Pose2D) -> tuple[float, float]:
    return math.hypot(pose.x - prior.x, pose.y - prior.y), abs(wrap_angle(pose.theta - prior.theta))


def _describe(pose: Pose2D) -> str:
    return f"({pose.x:.3f} m, {pose.y:.3f} m, {math.degrees(pose.theta):.1f} deg)"


def find_corner(
    scan: ScanSweep, prior: Pose2D | None = None, config: LidarCorner | None = None
) -> tuple[Pose2D, float, float]:
    """Find the L-shaped corner in one scan: the robot's pose in the corner frame (a
    first estimate, from this scan's wall pieces) and how far the x and y walls reach
    from the vertex [m].

    Raises
    ------
    CornerNotFoundError
        Too few returns, no two long perpendicular walls seen from inside, or none within
        the prior's gate.
    """
    found = _find(scan, prior, config or LidarCorner())
    c = found.candidate
    return c.fit.pose, c.x_reach, c.y_reach


def _find(scan: ScanSweep, prior: Pose2D | None, config: LidarCorner) -> _Found:
    beams, all_pieces, walls = _walls(scan, config)
    found = _candidates(walls, config)
    if not found:
        raise CornerNotFoundError(
            "no_corner",
            f"no L-shaped corner in the scan: {len(walls)} wall(s) of at least "
            f"{config.min_wall_length:.2f} m, no two perpendicular within "
            f"{math.degrees(config.candidate_angle):.1f} deg seen from inside",
        )
    if prior is not None:
        near = [
            c
            for c in found
            if _distance(c.fit.pose, prior)[0] <= config.prior_distance
            and _distance(c.fit.pose, prior)[1] <= config.prior_angle
        ]
        if not near:
            nearest = min(
                found,
                key=lambda c: (
                    _distance(c.fit.pose, prior)[0] / config.prior_distance
                    + _distance(c.fit.pose, prior)[1] / config.prior_angle
                ),
            )
            d, a = _distance(nearest.fit.pose, prior)
            raise CornerNotFoundError(
                "not_where_expected",
                f"corner not where expected: the nearest L-shaped corner puts the robot at "
                f"{_describe(nearest.fit.pose)}, {d:.3f} m and {math.degrees(a):.1f} deg "
                f"from the expected {_describe(prior)} (gate {config.prior_distance:.2f} m, "
                f"{math.degrees(config.prior_angle):.1f} deg)",
            )
        found = near
    best = max(found, key=lambda c: c.score)
    return _Found(best, beams, all_pieces, scan.time)


def _median_pose(poses: Sequence[Pose2D]) -> Pose2D:
    ref = poses[0].theta
    dtheta = [wrap_angle(p.theta - ref) for p in poses]
    return Pose2D(
        float(np.median([p.x for p in poses])),
        float(np.median([p.y for p in poses])),
        wrap_angle(ref + float(np.median(dtheta))),
    )


def _select(
    found: _Found,
    pose: Pose2D,
    reach: tuple[float, float],
    band: float,
    config: LidarCorner,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """A scan's returns on the x wall and on the y wall.

    A return is on a wall when it belongs to a piece of the scan lying along the wall
    (parallel within ``candidate_angle``, centred within ``split_distance``: a box
    touching the wall is not the wall) and is not a doubtful return at a piece's end,
    lies within ``band`` of the wall's line, and its beam meets the line between the
    vertex (``vertex_margin`` left out) and a little past the wall's reach. Where a
    beam meets a line does not depend on its range noise, so choosing by it does not
    bias the fit (choosing by the noisy points would, near the vertex, where an oblique
    beam's noise moves its point along the wall).
    """
    beams = found.beams
    p, o = to_frame(pose, beams.points), to_frame(pose, beams.origins)
    alpha = -pose.theta  # the corner's x axis in the base frame
    ex = np.array([math.cos(alpha), math.sin(alpha)])
    members = [np.zeros(len(beams), dtype=bool), np.zeros(len(beams), dtype=bool)]
    sin_tol = math.sin(config.candidate_angle)
    for piece in found.pieces:
        centre = to_frame(pose, piece.centre[None, :])[0]
        along_x = abs(float(piece.direction @ np.array([-ex[1], ex[0]]))) < sin_tol
        along_y = abs(float(piece.direction @ ex)) < sin_tol
        if along_x and abs(centre[1]) < config.split_distance:
            members[0][piece.core] = True
        elif along_y and abs(centre[0]) < config.split_distance:
            members[1][piece.core] = True
    d = p - o
    with np.errstate(divide="ignore", invalid="ignore"):
        s_x = o[:, 0] - o[:, 1] * d[:, 0] / d[:, 1]  # where the beam meets y = 0
        s_y = o[:, 1] - o[:, 0] * d[:, 1] / d[:, 0]  # ... and x = 0
    margin = config.vertex_margin
    on_x = members[0] & (d[:, 1] < 0) & (s_x > margin) & (s_x < reach[0] + 0.2)
    on_y = members[1] & (d[:, 0] < 0) & (s_y > margin) & (s_y < reach[1] + 0.2)
    return on_x & (np.abs(p[:, 1]) < band), on_y & (np.abs(p[:, 0]) < band)


def fix_from_scans(
    scans: Sequence[ScanSweep],
    prior: Pose2D | None = None,
    config: LidarCorner | None = None,
) -> CornerFix:
    """The robot's pose in the corner frame from scans taken while it stood still.

    The corner is found in each scan (:func:`find_corner`, gated by ``prior``, the pose
    expected from the last fix and the odometry); scans where it is not found, or found
    off the others' median by more than 5 cm or 2 degrees, are left out (at least half
    must remain). The returns on the walls of the remaining scans are pooled and the
    walls fitted jointly as perpendicular lines, in range space
    (:mod:`umbmark.routines.corner_beams`); the covariance is the fit's, from its
    residuals.

    Raises
    ------
    CornerNotFoundError
        The cause in one line (too few returns, no corner, not where expected, walls not
        perpendicular, residual too large).
    """
    config = config or LidarCorner()
    if not scans:
        raise CornerNotFoundError("too_few_points", "no laser scan to find the corner in")
    found: list[_Found] = []
    failures: list[CornerNotFoundError] = []
    for scan in scans:
        try:
            found.append(_find(scan, prior, config))
        except CornerNotFoundError as error:
            failures.append(error)
    if 2 * len(found) < len(scans):
        cause = Counter(f.cause for f in failures).most_common(1)[0][0]
        first = next(f for f in failures if f.cause == cause)
        raise CornerNotFoundError(cause, f"{first.problem} ({len(failures)} of {len(scans)} scans)")
    centre = _median_pose([f.candidate.fit.pose for f in found])
    agree = [
        f
        for f in found
        if _distance(f.candidate.fit.pose, centre)[0] < 0.05
        and _distance(f.candidate.fit.pose, centre)[1] < math.radians(2.0)
    ]
    if 2 * len(agree) < len(scans):
        raise CornerNotFoundError(
            "implausible",
            f"the corner moved between scans taken standing still: only {len(agree)} of "
            f"{len(scans)} scans agree within 5 cm and 2 deg",
        )
    reach = (max(f.candidate.x_reach for f in agree), max(f.candidate.y_reach for f in agree))
    pose, band = centre, config.band
    for _ in range(3):
        masks = [_select(f, pose, reach, band, config) for f in agree]
        x_wall = _pool([f.beams.take(m[0]) for f, m in zip(agree, masks, strict=True)])
        y_wall = _pool([f.beams.take(m[1]) for f, m in zip(agree, masks, strict=True)])
        if min(len(x_wall), len(y_wall)) < config.min_wall_points:
            raise CornerNotFoundError(
                "too_few_points",
                f"too few points on the walls: {len(x_wall)} on the x wall, {len(y_wall)} "
                f"on the y wall (at least {config.min_wall_points} each)",
            )
        estimate = fit_corner_ranges(x_wall, y_wall, pose)
        pose = estimate.pose
        across = np.concatenate(
            [to_frame(pose, x_wall.points)[:, 1], to_frame(pose, y_wall.points)[:, 0]]
        )
        band = min(config.band, max(4.0 * float(np.sqrt(np.mean(across**2))), 0.01))
    if estimate.range_rms > config.max_rms:
        raise CornerNotFoundError(
            "poor_fit",
            f"residual too large: the walls' fit leaves {estimate.range_rms * 1000:.1f} mm "
            f"rms in range (at most {config.max_rms * 1000:.1f} mm)",
        )
    angle, angle_std = wall_angle(x_wall, y_wall, pose)
    if abs(angle - 0.5 * math.pi) > max(config.perpendicular_tolerance, 4.0 * angle_std):
        raise CornerNotFoundError(
            "not_perpendicular",
            f"walls not perpendicular: measured {math.degrees(angle):.2f} deg "
            f"+- {math.degrees(angle_std):.2f} (tolerance "
            f"{math.degrees(config.perpendicular_tolerance):.2f} deg)",
        )
    return CornerFix(
        pose=Pose2D(pose.x, pose.y, wrap_angle(pose.theta)),
        covariance=estimate.covariance,
        method="lidar",
        time=max(f.time for f in agree),
        points=len(x_wall) + len(y_wall),
        readings=len(agree),
        residual_rms=estimate.range_rms,
        wall_angle=angle,
        wall_angle_std=angle_std,
    )


def _pool(parts: Sequence[Beams]) -> Beams:
    return Beams(
        np.vstack([b.origins for b in parts]),
        np.vstack([b.directions for b in parts]),
        np.concatenate([b.ranges for b in parts]),
    )

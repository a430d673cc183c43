"""The 2D world a virtual robot sees: walls (line segments) and round things (circles),
a simulated planar laser scanner and single-beam range sensors.

The standard world (:func:`corner_world`) has an L-shaped corner behind and beside the
start, where the robot measures its pose (:mod:`umbmark.routines.corner`), out of the way
of the 4 x 4 m UMBmark squares driven from the start along +x (ccw to the left, cw to
the right). Frames follow :mod:`umbmark.robot.base`: the world frame is the start's
(x along the first leg, y to the left), poses are planar, metres and radians.

Ray casting is vectorized (every beam against every segment and circle at once); the
sensors draw their noise from a seeded ``numpy.random.Generator``, and nothing sleeps.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.model.recording import PoseSeries
from umbmark.model.scans import ScanSeries
from umbmark.robot.base import Pose2D, RangeReading, ScanSweep, StampedPose

__all__ = [
    "CORNER_SENSORS",
    "DEFAULT_LIDAR",
    "ROOM_LASER",
    "SCAN_LIDAR",
    "LCorner",
    "Lidar",
    "MotionCapture",
    "RangeSensors",
    "World",
    "box",
    "chair",
    "corner_world",
    "legs",
    "room_around",
    "room_world",
    "square_path",
    "sweeps_along",
]


#: Rays start this far along the beam: a hit closer than this is the sensor itself.
_EPS = 1e-9


@dataclass(frozen=True)
class LCorner:
    """An L-shaped corner: two walls from a common vertex.

    Its frame (the *corner frame*) has its origin at the vertex, x along the first wall
    (``x_length`` long, at ``heading`` in the world) and y perpendicular to it, to its
    left; the second wall leaves the vertex at ``angle`` from the first (``pi/2`` for a
    square corner, the y axis), ``y_length`` long. A robot inside the corner has x > 0,
    y > 0 in this frame.
    """

    vertex: tuple[float, float]
    heading: float
    x_length: float
    y_length: float
    angle: float = math.pi / 2

    @property
    def frame(self) -> Pose2D:
        """The corner frame's pose in the world."""
        return Pose2D(self.vertex[0], self.vertex[1], self.heading)

    def segments(self) -> FloatArray:
        """The two walls, shape (2, 4): ``x0, y0, x1, y1`` [m] in the world."""
        vx, vy = self.vertex
        a, b = self.heading, self.heading + self.angle
        return np.array(
            [
                [vx, vy, vx + self.x_length * math.cos(a), vy + self.x_length * math.sin(a)],
                [vx, vy, vx + self.y_length * math.cos(b), vy + self.y_length * math.sin(b)],
            ]
        )

    def in_corner(self, pose: Pose2D) -> Pose2D:
        """A world pose in the corner frame."""
        return pose.relative_to(self.frame)


@dataclass(frozen=True)
class Lidar:
    """A planar laser scanner: its beams, limits, noise and mounting.

    Attributes
    ----------
    mount : Pose2D
        The laser's pose in the robot's base frame.
    beams : int
        Beams per sweep; they start at ``angle_min`` and step by ``increment`` [rad].
    sigma : float
        Standard deviation of the range noise [m].
    dropout : float
        Fraction of beams that return nothing (NaN), at random.
    range_min, range_max : float
        The valid range [m]; beyond ``range_max`` (or hitting nothing) a beam reads inf.
    """

    mount: Pose2D = field(default_factory=Pose2D)
    beams: int = 720
    angle_min: float = -math.pi
    increment: float = 2 * math.pi / 720
    sigma: float = 0.01
    dropout: float = 0.02
    range_min: float = 0.05
    range_max: float = 12.0


#: The standard laser: 360 degrees in 720 beams, 1 cm noise, 2 % dropouts, 12 m range.
DEFAULT_LIDAR = Lidar()


@dataclass(frozen=True)
class RangeSensors:
    """Single-beam range sensors (the paper's "sonar calibrator" with today's sensors):
    each at its mount in the robot's base frame, measuring along its x axis.

    Attributes
    ----------
    mounts : tuple of Pose2D
        The sensors' poses in the base frame.
    sigma : float
        Standard deviation of the range noise [m].
    range_max : float
        Farther than this [m] (or nothing hit) reads NaN: no echo.
    """

    mounts: tuple[Pose2D, ...]
    sigma: float = 0.002
    range_max: float = 3.0


@dataclass(frozen=True)
class MotionCapture:
    """Ground truth as a motion-capture system gives it: the true pose in the world
    frame, with Gaussian noise of ``sigma_xy`` [m] and ``sigma_theta`` [rad]."""

    sigma_xy: float = 0.0005
    sigma_theta: float = math.radians(0.05)


#: The range sensors of the standard world: two at the back facing the wall behind the
#: start (0.5 m apart), one at the back right looking right and a little back (15
#: degrees off square) at the side wall, which ends behind the start: its beam meets that wall while
#: the robot stands near the start.
CORNER_SENSORS = RangeSensors(
    mounts=(
        Pose2D(-0.35, 0.25, math.pi),
        Pose2D(-0.35, -0.25, math.pi),
        Pose2D(-0.35, -0.25, -7 * math.pi / 12),
    )
)


@dataclass(frozen=True)
class World:
    """Walls and round things in the plane (the world frame), the robot's start in it and
    the robot's sensors.

    Attributes
    ----------
    segments : array, shape (m, 4)
        Walls and box sides, ``x0, y0, x1, y1`` [m].
    circles : array, shape (k, 3)
        Legs and posts, ``cx, cy, r`` [m].
    corner : LCorner, optional
        The L-shaped corner among the segments, if the world has one (the truth the
        corner measurement is tested against).
    start : Pose2D
        The robot's true pose at the start.
    lidar, sonars, mocap : optional
        The robot's laser scanner, range sensors and motion capture (None: it has none).
    """

    segments: FloatArray
    circles: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    corner: LCorner | None = None
    start: Pose2D = field(default_factory=Pose2D)
    lidar: Lidar | None = field(default_factory=Lidar)
    sonars: RangeSensors | None = None
    mocap: MotionCapture | None = None

    @classmethod
    def build(
        cls,
        segments: Iterable[Sequence[float]] | FloatArray = (),
        circles: Iterable[Sequence[float]] | FloatArray = (),
        corner: LCorner | None = None,
        *,
        start: Pose2D | None = None,
        lidar: Lidar | None = DEFAULT_LIDAR,
        sonars: RangeSensors | None = None,
        mocap: MotionCapture | None = None,
    ) -> World:
        """A world from walls and circles (the corner's walls are added to the walls),
        the robot's start [default: the origin] and sensors [default: the standard laser
        scanner, no range sensors, no motion capture]."""
        seg = np.asarray(list(segments) if not isinstance(segments, np.ndarray) else segments)
        seg = seg.reshape(-1, 4).astype(np.float64)
        if corner is not None:
            seg = np.vstack([corner.segments(), seg])
        circ = np.asarray(list(circles) if not isinstance(circles, np.ndarray) else circles)
        circ = circ.reshape(-1, 3).astype(np.float64)
        return cls(seg, circ, corner, start or Pose2D(), lidar, sonars, mocap)

    def cast(self, origins: FloatArray, angles: FloatArray) -> FloatArray:
        """Distance along each ray to the first thing it hits (inf: nothing).

        Parameters
        ----------
        origins : array, shape (n, 2) or (2,)
            Ray origins [m] (one for all rays, or one per ray).
        angles : array, shape (n,)
            Ray directions [rad] in the world.

        Returns
        -------
        array, shape (n,)
            Distances [m].
        """
        angles = np.asarray(angles, dtype=np.float64)
        o = np.asarray(origins, dtype=np.float64)
        # one origin for all rays stays one row: what depends on it alone is computed once
        o = o.reshape(1, 2) if o.ndim == 1 else o
        dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]
        ox, oy = o[:, 0:1], o[:, 1:2]
        best = np.full(angles.size, np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            if len(self.segments):
                s = self.segments
                ex, ey = (s[:, 2] - s[:, 0])[None, :], (s[:, 3] - s[:, 1])[None, :]
                px, py = s[:, 0][None, :] - ox, s[:, 1][None, :] - oy
                inv = 1.0 / (dx * ey - dy * ex)  # inf for a ray along the segment
                t = (px * ey - py * ex) * inv
                u = (px * dy - py * dx) * inv
                t[(t <= _EPS) | ~((u >= 0.0) & (u <= 1.0))] = np.inf  # NaN fails both
                best = np.minimum(best, t.min(axis=1))
            if len(self.circles):
                c = self.circles
                cx, cy = c[:, 0][None, :] - ox, c[:, 1][None, :] - oy
                b = cx * dx + cy * dy
                t = b - np.sqrt(b * b - (cx * cx + cy * cy - c[:, 2][None, :] ** 2))
                t[~(t > _EPS)] = np.inf  # NaN: the ray misses the circle
                best = np.minimum(best, t.min(axis=1))
        return best

    def scan(self, pose: Pose2D, time: float, rng: np.random.Generator) -> ScanSweep | None:
        """What the laser on a robot at the true ``pose`` (world frame) reads at ``time``
        (None: the robot has no laser)."""
        lidar = self.lidar
        if lidar is None:
            return None
        laser = pose.compose(lidar.mount)
        angles = lidar.angle_min + lidar.increment * np.arange(lidar.beams, dtype=np.float64)
        true = self.cast(np.array([laser.x, laser.y]), laser.theta + angles)
        ranges = true + lidar.sigma * rng.standard_normal(lidar.beams)
        ranges[~np.isfinite(true) | (ranges > lidar.range_max)] = np.inf
        ranges[rng.random(lidar.beams) < lidar.dropout] = np.nan
        return ScanSweep(
            time=time,
            angle_min=lidar.angle_min,
            angle_increment=lidar.increment,
            ranges=ranges,
            range_min=lidar.range_min,
            range_max=lidar.range_max,
            mount=lidar.mount,
        )

    def ranges(self, pose: Pose2D, time: float, rng: np.random.Generator) -> RangeReading | None:
        """What the range sensors on a robot at the true ``pose`` read (NaN: no echo;
        None: the robot has none)."""
        sonars = self.sonars
        if sonars is None:
            return None
        sensors = [pose.compose(m) for m in sonars.mounts]
        origins = np.array([[s.x, s.y] for s in sensors]).reshape(-1, 2)
        true = self.cast(origins, np.array([s.theta for s in sensors]))
        ranges = true + sonars.sigma * rng.standard_normal(true.size)
        ranges[~np.isfinite(true) | (ranges > sonars.range_max)] = np.nan
        return RangeReading(time=time, ranges=ranges, mounts=sonars.mounts)

    def truth(self, pose: Pose2D, time: float, rng: np.random.Generator) -> StampedPose | None:
        """The true ``pose`` as motion capture reports it (None: there is none)."""
        mocap = self.mocap
        if mocap is None:
            return None
        dx, dy = mocap.sigma_xy * rng.standard_normal(2)
        dtheta = mocap.sigma_theta * float(rng.standard_normal())
        return StampedPose(
            time, Pose2D(pose.x + float(dx), pose.y + float(dy), pose.theta + dtheta)
        )

    def clearance(self, path: FloatArray) -> float:
        """The smallest distance [m] from a polyline (shape (k, 2), world frame) to any wall
        or circle: 0 when the path crosses one. A robot of radius ``r`` driving the path
        touches nothing when this is more than ``r``."""
        p = np.asarray(path, dtype=np.float64)
        a, b = p[:-1], p[1:]
        best = math.inf
        if len(self.segments):
            s = self.segments
            c, d = s[:, :2], s[:, 2:]
            dist = np.minimum.reduce(
                [
                    _point_segment(a[:, None], c[None], d[None]),
                    _point_segment(b[:, None], c[None], d[None]),
                    _point_segment(c[None], a[:, None], b[:, None]),
                    _point_segment(d[None], a[:, None], b[:, None]),
                ]
            )
            dist[_crossing(a[:, None], b[:, None], c[None], d[None])] = 0.0
            best = min(best, float(dist.min()))
        if len(self.circles):
            cc = self.circles
            dist = _point_segment(cc[None, :, :2], a[:, None], b[:, None]) - cc[None, :, 2]
            best = min(best, max(0.0, float(dist.min())))
        return best


def _point_segment(p: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance from points ``p`` to segments ``a``-``b`` (broadcast, last axis x, y)."""
    ab = b - a
    length2 = np.maximum(np.sum(ab * ab, axis=-1), 1e-300)
    t = np.clip(np.sum((p - a) * ab, axis=-1) / length2, 0.0, 1.0)
    return np.asarray(np.hypot(*np.moveaxis(a + t[..., None] * ab - p, -1, 0)))


def _crossing(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> NDArray[np.bool_]:
    """Whether segments ``a``-``b`` and ``c``-``d`` cross (broadcast)."""

    def side(p: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
        return np.asarray(
            (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
            - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])
        )

    return np.asarray((side(a, b, c) * side(a, b, d) < 0) & (side(c, d, a) * side(c, d, b) < 0))


# --- things in the world ------------------------------------------------------------------


def box(cx: float, cy: float, width: float, depth: float, heading: float = 0.0) -> FloatArray:
    """A box's four sides, shape (4, 4): centre ``cx, cy`` [m], ``width`` along
    ``heading`` [rad] and ``depth`` across it."""
    c, s = math.cos(heading), math.sin(heading)
    half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * [width / 2, depth / 2]
    pts = half @ np.array([[c, s], [-s, c]]) + [cx, cy]
    return np.hstack([pts, np.roll(pts, -1, axis=0)])


def legs(cx: float, cy: float, heading: float = 0.0, radius: float = 0.06) -> FloatArray:
    """A standing person's legs, shape (2, 3): two circles 0.2 m apart across ``heading``."""
    ox, oy = -0.1 * math.sin(heading), 0.1 * math.cos(heading)
    return np.array([[cx + ox, cy + oy, radius], [cx - ox, cy - oy, radius]])


def chair(cx: float, cy: float, heading: float = 0.0, size: float = 0.45) -> FloatArray:
    """A chair's four legs, shape (4, 3): circles of 15 mm at the corners of a square."""
    corners = box(cx, cy, size, size, heading)[:, :2]
    return np.hstack([corners, np.full((4, 1), 0.015)])


def square_path(
    side: float = 4.0, direction: str = "ccw", start: Pose2D | None = None
) -> FloatArray:
    """The ideal UMBmark square from ``start`` [default: the world's origin], along its
    heading first, turning left (ccw) or right (cw): its five corners, shape (5, 2)."""
    start = start or Pose2D()
    sign = 1.0 if direction == "ccw" else -1.0
    local = [Pose2D(0, 0), Pose2D(side, 0), Pose2D(side, sign * side), Pose2D(0, sign * side)]
    pts = [start.compose(p) for p in [*local, local[0]]]
    return np.array([[p.x, p.y] for p in pts])


def corner_world(clutter: bool = True, side: Literal["right", "left"] = "right") -> World:
    """The standard world: an L-shaped corner behind and to the right of the start (vertex at
    (-1.6, -1.3) m: a 1.25 m wall along +x, 1.3 m to the right of the start, ending 0.35 m
    behind it, and a 2.8 m wall along +y 1.6 m behind the start), a far wall 6 m ahead and,
    with ``clutter``, a box in front of the back wall, a chair and a person standing aside.
    The robot starts at the origin heading +x and carries a 360 degree laser (720 beams, 1
    cm noise, 2 % dropouts) at its centre, the three range sensors of :data:`CORNER_SENSORS`
    (2 mm noise) and motion capture.

    The 4 x 4 m squares driven from the start (cw and ccw) keep at least 0.35 m from
    everything (:meth:`World.clearance`), and a robot ending a run up to about 1 m from the
    start in any direction still sees both walls well from inside the corner. In the corner
    frame the start is at ``(1.6, 1.3)`` m, heading 0.

    ``side="left"``: the same world mirrored across the start's heading (the corner behind
    and to the left, vertex at (-1.6, 1.3) m, the range sensors mirrored). Its corner frame
    is right-handed like every corner frame: x along the back wall (towards -y), y along the
    side wall (+x); the start is at ``(1.3, 1.6)`` m, heading 90 degrees.
    """
    walls = [np.array([[6.0, -5.5, 6.0, 5.5]])]
    circles: list[FloatArray] = []
    if clutter:
        walls.append(box(-0.75, 1.6, 0.3, 0.4))
        circles += [chair(-1.2, 2.6, 0.3), legs(-0.9, -2.4, 0.5)]
    if side == "right":
        corner = LCorner(vertex=(-1.6, -1.3), heading=0.0, x_length=1.25, y_length=2.8)
        sonars = CORNER_SENSORS
    elif side == "left":
        corner = LCorner(vertex=(-1.6, 1.3), heading=-0.5 * math.pi, x_length=2.8, y_length=1.25)
        sonars = RangeSensors(
            mounts=tuple(Pose2D(m.x, -m.y, -m.theta) for m in CORNER_SENSORS.mounts)
        )
        walls = [w * np.array([1.0, -1.0, 1.0, -1.0]) for w in walls]
        circles = [c * np.array([1.0, -1.0, 1.0]) for c in circles]
    else:
        raise InputError(f"corner side {side!r}: use right or left")
    return World.build(
        np.vstack(walls),
        np.vstack(circles) if circles else (),
        corner,
        lidar=DEFAULT_LIDAR,
        sonars=sonars,
        mocap=MotionCapture(),
    )


#: Where the virtual robot of ``umbmark selfcal --sim --routine anywhere`` carries its
#: laser: 120 mm ahead of the axle centre, 40 mm to the right, turned 4 degrees left.
ROOM_LASER = Pose2D(0.12, -0.04, math.radians(4.0))


def room_world(clutter: bool = True) -> World:
    """An ordinary room for scan matching: 8 x 6 m (x from -3 to 5 m, y from -3 to 3 m
    around the start) with a 0.9 m door gap in the left wall, a pillar and, with
    ``clutter``, a cupboard and a table against the walls, a chair and a person standing
    in the room. The robot starts at the origin heading +x and carries the standard laser
    at its centre (360 degrees in 720 beams, 1 cm noise, 2 % dropouts, 12 m range).

    The walls fix every direction of a scanner's motion from anywhere inside; a 2 x 2 m
    square of floor around the start is free.
    """
    walls = np.array(
        [
            [-3.0, -3.0, 5.0, -3.0],  # right
            [5.0, -3.0, 5.0, 3.0],  # ahead
            [5.0, 3.0, 1.9, 3.0],  # left, up to the door
            [1.0, 3.0, -3.0, 3.0],  # left, after the door
            [-3.0, 3.0, -3.0, -3.0],  # behind
        ]
    )
    parts = [walls, box(3.2, 1.6, 0.5, 0.5)]  # the pillar
    circles: list[FloatArray] = []
    if clutter:
        parts += [box(-2.7, -1.0, 0.5, 1.2), box(4.4, -2.0, 0.9, 1.6, 0.1)]
        circles += [chair(-1.8, 2.2, 0.4), legs(2.4, -1.8, 0.9)]
    return World.build(np.vstack(parts), np.vstack(circles) if circles else (), lidar=DEFAULT_LIDAR)


def room_around(path: FloatArray, margin: float = 1.5, lidar: Lidar | None = None) -> World:
    """A room for a path: four walls ``margin`` [m] beyond the extent of ``path`` (``(n,
    2)`` positions [m] in the world), a cupboard in one corner and a pillar in the opposite
    one (so that no motion along a wall matches itself), the laser ``lidar`` (360 beams, 1
    cm noise, 12 m by default).

    Each thing stands at least ``margin - 0.8`` m from the path's bounding box.
    """
    lo, hi = np.min(path, axis=0) - margin, np.max(path, axis=0) + margin
    (x0, y0), (x1, y1) = lo.tolist(), hi.tolist()
    walls = np.array(
        [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]], dtype=float
    )
    parts = [walls, box(x0 + 0.45, y0 + 0.4, 0.6, 0.5), box(x1 - 0.5, y1 - 0.6, 0.5, 0.8, 0.3)]
    return World.build(np.vstack(parts), lidar=lidar or SCAN_LIDAR)


#: The laser of :func:`room_around`: 0.1 m ahead of the axle centre, 360 beams over 360
#: degrees, 1 cm noise, 1 % dropouts, 12 m.
SCAN_LIDAR = Lidar(Pose2D(0.1, 0.0, 0.0), beams=360, increment=2 * math.pi / 360, dropout=0.01)


def sweeps_along(
    world: World, truth: PoseSeries, rate: float, rng: np.random.Generator
) -> ScanSeries:
    """The sweeps of ``world``'s laser on a robot at the true poses ``truth`` (the axle
    centre in the world, headings unwrapped), ``rate`` [Hz] from its first time to its
    last, each taken at one instant (poses interpolated).

    Raises
    ------
    ValueError
        When the world has no laser or ``rate`` is not positive.
    """
    lidar = world.lidar
    if lidar is None or not rate > 0.0:
        raise ValueError("sweeps need a laser and a rate > 0")
    times = np.arange(float(truth.time[0]), float(truth.time[-1]), 1.0 / rate)
    heading = np.unwrap(truth.poses[:, 2])
    x = np.interp(times, truth.time, truth.poses[:, 0])
    y = np.interp(times, truth.time, truth.poses[:, 1])
    theta = np.interp(times, truth.time, heading)
    ranges = np.empty((times.size, lidar.beams))
    for k in range(times.size):
        sweep = world.scan(Pose2D(float(x[k]), float(y[k]), float(theta[k])), 0.0, rng)
        assert sweep is not None
        ranges[k] = sweep.ranges
    return ScanSeries(
        times=times,
        ranges=ranges,
        angle_min=lidar.angle_min,
        angle_increment=lidar.increment,
        range_min=lidar.range_min,
        range_max=lidar.range_max,
    )

"""Differential-drive kinematics: wheel parameters, encoder conversion and odometry.

Knows nothing of files, runs or estimators. Everything is vectorized with numpy: any
leading batch dimensions (many runs, many robots) pass through unchanged.

Equations (Borenstein & Feng 1996)
----------------------------------
- Eq. 2.1: ``c_m = pi * D_n / (n * C_e)``, metres of wheel travel per encoder pulse.
- Eq. 2.2 / 4.33: ``dU_{L/R} = c_{L/R} * c_m * N_{L/R}``.
- Odometry: ``ds = (dU_R + dU_L) / 2``, ``dtheta = (dU_R - dU_L) / b``. Each sampling
  interval is integrated either as the exact circular arc it is when the wheel speeds are
  constant over the interval (``"arc"``), or as the straight segment of Borenstein et al.
  1996 (``"segment"``: heading updated first, then ``x += ds cos(theta_new)``), or as a
  straight segment along the mid-interval heading (``"midpoint"``, second-order).

Tyre scrub (beyond the paper)
-----------------------------
A real robot's effective wheelbase depends on how it moves: on the spot the tyres scrub
sideways about contact patches other than while rolling along an arc. The optional
*scrub model* gives each sampling interval its own wheelbase. With wheel travels
``dU_L``, ``dU_R`` over the interval, the turning share

``w = |dU_R - dU_L| / (|dU_R| + |dU_L|)``  (``w = 0`` when neither wheel moves)

is 0 on a straight line and 1 on an on-the-spot turn, and

``b_eff = b_arc + (b_spot - b_arc) * w``,  ``dtheta = (dU_R - dU_L) / b_eff``.

``b_arc`` is :attr:`WheelParams.wheelbase`, ``b_spot`` is
:attr:`WheelParams.spot_wheelbase`; without ``spot_wheelbase`` every interval uses
``wheelbase`` (the paper's model). See :func:`turning_share` and
:func:`effective_wheelbase`; :func:`integrate_odometry` takes a wheelbase per interval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.core.validation import check_positive, require_positive

__all__ = [
    "IntegrationMethod",
    "OdometryGeometry",
    "WheelParams",
    "chord_step",
    "effective_wheelbase",
    "integrate_odometry",
    "pose_increments",
    "turning_share",
    "wheel_displacements",
    "wheel_travel_from_poses",
]

IntegrationMethod = Literal["arc", "segment", "midpoint"]
INTEGRATION_METHODS: tuple[IntegrationMethod, ...] = ("arc", "segment", "midpoint")


@dataclass(frozen=True)
class WheelParams:
    """Parameters of a differential-drive robot's odometry model.

    Attributes
    ----------
    wheelbase : float
        ``b`` [m]: the distance between the wheels' contact points that the odometry uses.
    wheel_diameter : float
        ``D_n`` [m]: nominal wheel diameter.
    encoder_resolution : float
        ``C_e`` [pulses per motor revolution].
    gear_ratio : float
        ``n``: motor revolutions per wheel revolution.
    c_left, c_right : float
        Wheel correction factors ``c_L``, ``c_R`` (Eq. 4.33): the effective diameters are
        ``c_L * D_n`` and ``c_R * D_n``.
    spot_wheelbase : float or None
        ``b_spot`` [m] of the scrub model (module documentation): the wheelbase of
        on-the-spot turns, ``wheelbase`` then being that of straight motion and arcs
        (``b_arc``). None (the default): one wheelbase for all motion.
    """

    wheelbase: float
    wheel_diameter: float
    encoder_resolution: float = 1.0
    gear_ratio: float = 1.0
    c_left: float = 1.0
    c_right: float = 1.0
    spot_wheelbase: float | None = None

    def __post_init__(self) -> None:
        require_positive(
            self,
            "wheelbase",
            "wheel_diameter",
            "encoder_resolution",
            "gear_ratio",
            "c_left",
            "c_right",
        )
        if self.spot_wheelbase is not None:
            check_positive("spot_wheelbase", self.spot_wheelbase, unit="m")

    @property
    def conversion_factor(self) -> float:
        """``c_m`` [m per pulse], Eq. 2.1: ``pi * D_n / (n * C_e)``."""
        return math.pi * self.wheel_diameter / (self.gear_ratio * self.encoder_resolution)

    @property
    def diameter_left(self) -> float:
        """Effective left wheel diameter ``c_L * D_n`` [m]."""
        return self.c_left * self.wheel_diameter

    @property
    def diameter_right(self) -> float:
        """Effective right wheel diameter ``c_R * D_n`` [m]."""
        return self.c_right * self.wheel_diameter

    @property
    def radians_per_pulse(self) -> float:
        """Wheel rotation per encoder pulse [rad]: ``2 pi / (n * C_e)``."""
        return 2.0 * math.pi / (self.gear_ratio * self.encoder_resolution)

    def with_corrections(
        self,
        *,
        c_left: float | None = None,
        c_right: float | None = None,
        wheelbase: float | None = None,
    ) -> WheelParams:
        """A copy with some of ``c_L``, ``c_R`` and ``b`` replaced (``spot_wheelbase`` kept)."""
        return replace(
            self,
            c_left=self.c_left if c_left is None else c_left,
            c_right=self.c_right if c_right is None else c_right,
            wheelbase=self.wheelbase if wheelbase is None else wheelbase,
        )

    def step_wheelbase(self, d_left: ArrayLike, d_right: ArrayLike) -> float | FloatArray:
        """The wheelbase of each sampling interval [m].

        Parameters
        ----------
        d_left, d_right : array, shape (..., n)
            Wheel travel per interval [m].

        Returns
        -------
        float or array, shape (..., n)
            ``wheelbase`` without a ``spot_wheelbase``; else the scrub model's ``b_eff``
            per interval (:func:`effective_wheelbase`).
        """
        if self.spot_wheelbase is None:
            return self.wheelbase
        return effective_wheelbase(d_left, d_right, self.wheelbase, self.spot_wheelbase)


@dataclass(frozen=True)
class OdometryGeometry:
    """The geometry a controller's odometry was computed with (the effective values of
    ros2_controllers' ``diff_drive_controller``, multipliers applied).

    Attributes
    ----------
    left_radius, right_radius : float
        Effective wheel radii [m]: ``wheel_radius`` times the radius multiplier.
    separation : float
        Effective wheel separation [m]: ``wheel_separation`` times its multiplier.
    """

    left_radius: float
    right_radius: float
    separation: float

    def __post_init__(self) -> None:
        for name, value in (
            ("left_radius", self.left_radius),
            ("right_radius", self.right_radius),
            ("separation", self.separation),
        ):
            if not (math.isfinite(value) and 0.0 < value < 100.0):
                raise InputError(f"the odometry's {name} must be in (0, 100) m, not {value!r}")


def wheel_displacements(
    pulses_left: ArrayLike, pulses_right: ArrayLike, params: WheelParams
) -> tuple[FloatArray, FloatArray]:
    """Wheel travel per sampling interval from encoder pulse increments (Eqs. 2.2, 4.33).

    Parameters
    ----------
    pulses_left, pulses_right : array, shape (..., n)
        Encoder pulse increments ``N_L``, ``N_R`` per sampling interval.
    params : WheelParams

    Returns
    -------
    d_left, d_right : array, shape (..., n)
        ``dU_L = c_L c_m N_L`` and ``dU_R = c_R c_m N_R`` [m].
    """
    c_m = params.conversion_factor
    d_left = params.c_left * c_m * np.asarray(pulses_left, dtype=np.float64)
    d_right = params.c_right * c_m * np.asarray(pulses_right, dtype=np.float64)
    return d_left, d_right


def turning_share(d_left: ArrayLike, d_right: ArrayLike) -> FloatArray:
    """How much of each interval's motion is turning: ``|dU_R - dU_L| / (|dU_R| + |dU_L|)``.

    Parameters
    ----------
    d_left, d_right : array, shape (..., n)
        Wheel travel per interval [m].

    Returns
    -------
    w : array, shape (..., n)
        0 for straight motion, 1 for an on-the-spot turn (and for one wheel standing),
        in between on arcs; 0 where neither wheel moves.
    """
    left = np.asarray(d_left, dtype=np.float64)
    right = np.asarray(d_right, dtype=np.float64)
    total = np.abs(right) + np.abs(left)
    out = np.zeros(np.broadcast(left, right).shape)
    np.divide(np.abs(right - left), total, out=out, where=total > 0.0)
    return out


def effective_wheelbase(
    d_left: ArrayLike, d_right: ArrayLike, wheelbase: float, spot_wheelbase: float
) -> FloatArray:
    """The scrub model's wheelbase per interval: ``b_arc + (b_spot - b_arc) * w``.

    Parameters
    ----------
    d_left, d_right : array, shape (..., n)
        Wheel travel per interval [m].
    wheelbase, spot_wheelbase : float
        ``b_arc`` and ``b_spot`` [m] (module documentation).

    Returns
    -------
    b_eff : array, shape (..., n)
        [m], with ``w`` of :func:`turning_share`.
    """
    check_positive("wheelbase", wheelbase, unit="m")
    check_positive("spot_wheelbase", spot_wheelbase, unit="m")
    w = turning_share(d_left, d_right)
    return np.asarray(wheelbase + (spot_wheelbase - wheelbase) * w)


def _check_wheelbases(wheelbase: float | ArrayLike) -> float | FloatArray:
    """A scalar wheelbase checked as one, an array of them checked element by element."""
    if np.ndim(wheelbase) == 0:
        value = float(wheelbase)  # type: ignore[arg-type]
        check_positive("wheelbase", value, unit="m")
        return value
    values = np.asarray(wheelbase, dtype=np.float64)
    bad = ~(np.isfinite(values) & (values > 0))
    if np.any(bad):
        first = float(values[bad].flat[0])
        raise ValueError(f"wheelbase must be > 0 in every interval, got {first!r} m")
    return values


def pose_increments(
    d_left: ArrayLike, d_right: ArrayLike, wheelbase: float | ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Travel of the axle centre ``ds`` [m] and heading change ``dtheta`` [rad] per interval.

    Parameters
    ----------
    d_left, d_right : array, shape (..., n)
        Wheel travel per interval [m].
    wheelbase : float or array broadcastable to shape (..., n)
        ``b`` [m], one for all intervals or one per interval (the scrub model's ``b_eff``).

    Returns
    -------
    ds, dtheta : array, shape (..., n)
    """
    left = np.asarray(d_left, dtype=np.float64)
    right = np.asarray(d_right, dtype=np.float64)
    if left.shape != right.shape:
        raise ValueError(
            f"left and right wheel data differ in shape: {left.shape} vs {right.shape}"
        )
    return 0.5 * (right + left), (right - left) / np.asarray(wheelbase, dtype=np.float64)


def chord_step(
    ds: FloatArray, dtheta: FloatArray, theta_before: FloatArray, method: IntegrationMethod
) -> tuple[FloatArray, FloatArray]:
    """Displacement of one sampling interval as a chord: its length and direction.

    Parameters
    ----------
    ds, dtheta : array, shape (...)
        Travel of the axle centre [m] and heading change [rad] over the interval.
    theta_before : array, shape (...)
        Heading at the start of the interval [rad].
    method : {"arc", "midpoint", "segment"}
        See :func:`integrate_odometry`.

    Returns
    -------
    chord, heading : array, shape (...)
        The interval moves the centre by ``chord * (cos(heading), sin(heading))``.
    """
    if method == "arc":
        # An arc of length ds turning by dtheta has the chord ds * sin(h)/h, h = dtheta/2,
        # along the mid-interval heading.
        half = 0.5 * dtheta
        return ds * _sinc(half), theta_before + half
    if method == "midpoint":
        return ds, theta_before + 0.5 * dtheta
    return ds, theta_before + dtheta


def _sinc(h: FloatArray) -> FloatArray:
    """``sin(h) / h`` (1 at 0). Per sample ``|h|`` is tiny, where a series is exact to the
    last bit and much cheaper than ``np.sinc``; larger angles take ``np.sinc``."""
    h = np.asarray(h, dtype=np.float64)
    if h.size and float(np.max(np.abs(h))) < 0.01:
        # Next term h^8 / 9! < 3e-22 for |h| < 0.01: below double precision.
        h2 = h * h
        return np.asarray(1.0 - h2 / 6.0 * (1.0 - h2 / 20.0 * (1.0 - h2 / 42.0)))
    return np.asarray(np.sinc(h / np.pi))


def integrate_odometry(
    d_left: ArrayLike,
    d_right: ArrayLike,
    wheelbase: float | ArrayLike,
    method: IntegrationMethod = "arc",
    initial_pose: ArrayLike | None = None,
) -> FloatArray:
    """Integrate wheel travel into poses, for any number of runs at once.

    Parameters
    ----------
    d_left, d_right : array, shape (..., n)
        Wheel travel per sampling interval [m] (see :func:`wheel_displacements`).
    wheelbase : float or array broadcastable to shape (..., n)
        ``b`` [m]: one for all intervals, or one per interval (the scrub model's
        ``b_eff``, :meth:`WheelParams.step_wheelbase`).
    method : {"arc", "midpoint", "segment"}
        ``"arc"`` integrates each interval as an exact circular arc, ``"midpoint"`` as a
        chord along the mid-interval heading, ``"segment"`` as the straight segment of
        Borenstein et al. (1996), along the heading at the interval's end.
    initial_pose : array, shape (..., 3), optional
        Start pose ``(x, y, theta)``; the origin by default.

    Returns
    -------
    poses : array, shape (..., n + 1, 3)
        ``(x [m], y [m], theta [rad])`` at the start and after every interval; headings
        are not wrapped, so a full ccw loop ends near ``+2 pi``.
    """
    if method not in INTEGRATION_METHODS:
        raise ValueError(f"unknown integration method {method!r}; use arc, midpoint or segment")
    ds, dtheta = pose_increments(d_left, d_right, _check_wheelbases(wheelbase))
    batch = ds.shape[:-1]
    start = (
        np.zeros((*batch, 3))
        if initial_pose is None
        else np.broadcast_to(np.asarray(initial_pose, dtype=np.float64), (*batch, 3))
    )
    theta_after = start[..., 2:3] + np.cumsum(dtheta, axis=-1)
    chord, heading = chord_step(ds, dtheta, theta_after - dtheta, method)
    poses = np.empty((*batch, ds.shape[-1] + 1, 3))
    poses[..., 0, :] = start
    poses[..., 1:, 0] = start[..., 0:1] + np.cumsum(chord * np.cos(heading), axis=-1)
    poses[..., 1:, 1] = start[..., 1:2] + np.cumsum(chord * np.sin(heading), axis=-1)
    poses[..., 1:, 2] = theta_after
    return poses


def wheel_travel_from_poses(
    poses: ArrayLike, wheelbase: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The wheel travel between consecutive odometry poses: the inverse of the arc step.

    A differential-drive odometry (umbmark's ``"arc"`` method, and ros2_controllers' and
    ROS 1's ``diff_drive_controller``, whose exact integration moves along the same arc)
    advances between two poses along one circular arc: the heading changes by
    ``dtheta = (dU_R - dU_L) / b`` and the axle centre moves by the chord
    ``ds sinc(dtheta/2)`` along the mid-interval heading, ``ds = (dU_R + dU_L) / 2``. So,
    given the poses, ``dtheta`` is their heading change, ``ds`` the displacement's
    component along the mid-interval heading over ``sinc(dtheta/2)``, and
    ``dU_{R/L} = ds +- dtheta b / 2``. The displacement's component across that heading
    is what no single arc explains (several controller steps with different curvatures
    between two messages): it is returned, to judge whether the poses are dense enough.

    Parameters
    ----------
    poses : array, shape (n, 3)
        ``x, y`` [m] and heading [rad], unwrapped.
    wheelbase : float
        ``b`` [m] the odometry used.

    Returns
    -------
    d_left, d_right : array, shape (n - 1,)
        Wheel travel per interval [m].
    lateral : array, shape (n - 1,)
        The displacement across the mid-interval heading [m] (0 for exact arcs).
    """
    check_positive("wheelbase", wheelbase, unit="m")
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"poses must have shape (n, 3), got {p.shape}")
    dx, dy = np.diff(p[:, 0]), np.diff(p[:, 1])
    dtheta = np.diff(p[:, 2])
    mid = p[:-1, 2] + 0.5 * dtheta
    c, s = np.cos(mid), np.sin(mid)
    along = c * dx + s * dy
    lateral = -s * dx + c * dy
    ds = along / _sinc(0.5 * dtheta)
    half = 0.5 * dtheta * wheelbase
    return ds - half, ds + half, lateral

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .validation import check_positive, require_positive

__all__ = [
    "IntegrationMethod",
    "WheelParams",
    "chord_step",
    "integrate_odometry",
    "pose_increments",
    "wheel_displacements",
]

IntegrationMethod = Literal["arc", "segment", "midpoint"]
INTEGRATION_METHODS: tuple[IntegrationMethod, ...] = ("arc", "segment", "midpoint")

FloatArray = NDArray[np.float64]


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
    """

    wheelbase: float
    wheel_diameter: float
    encoder_resolution: float = 1.0
    gear_ratio: float = 1.0
    c_left: float = 1.0
    c_right: float = 1.0

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
        """A copy with some of ``c_L``, ``c_R`` and ``b`` replaced."""
        return replace(
            self,
            c_left=self.c_left if c_left is None else c_left,
            c_right=self.c_right if c_right is None else c_right,
            wheelbase=self.wheelbase if wheelbase is None else wheelbase,
        )


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


def pose_increments(
    d_left: ArrayLike, d_right: ArrayLike, wheelbase: float
) -> tuple[FloatArray, FloatArray]:
    """Travel of the axle centre ``ds`` [m] and heading change ``dtheta`` [rad] per interval.

    Parameters
    ----------
    d_left, d_right : array, shape (..., n)
        Wheel travel per interval [m].
    wheelbase : float
        ``b`` [m].

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
    return 0.5 * (right + left), (right - left) / wheelbase


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
    wheelbase: float,
    method: IntegrationMethod = "arc",
    initial_pose: ArrayLike | None = None,
) -> FloatArray:
    """Integrate wheel travel into poses, for any number of runs at once.

    Parameters
    ----------
    d_left, d_right : array, shape (..., n)
        Wheel travel per sampling interval [m] (see :func:`wheel_displacements`).
    wheelbase : float
        ``b`` [m].
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
    check_positive("wheelbase", wheelbase, unit="m")
    ds, dtheta = pose_increments(d_left, d_right, wheelbase)
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

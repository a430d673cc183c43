"""The virtual robot's IMU: a MEMS gyro and accelerometer on the body, read from the
simulated motion (``docs/simulator.md#the-imu``).

:class:`ImuSetup` is what the IMU is (its rate, the gyro's scale, bias, bias walk, noise
and full scale, its mounting), checked once by the options of
:mod:`umbmark.options.simulate` (:data:`~umbmark.options.simulate.IMU_OPTIONS`; SI units
here, the options' units on the command line). :func:`simulate_imu` reads it along a
simulated recording's true motion:

- the true motion between two simulation samples is an arc of constant speed and turn
  rate; reading ``i`` at ``t_i = t_0 + i / rate`` is the mean over its period
  ``[t_i - 1/rate, t_i]`` (a MEMS part's decimation filter);
- gyro, in the IMU's frame: ``omega_read = R^T omega_true / k_g + bias(t) + noise``,
  clipped at the full scale; ``R`` the IMU's axes in ``base_link`` (from roll, pitch,
  yaw, fixed axes as the URDF's ``rpy``); the bias starts at the z axis' given value
  (x and y: drawn, up to its size) and walks (Gaussian increments of ``walk^2 / rate``
  per reading and axis); the noise is white, of standard deviation ``density sqrt(rate)``
  per reading;
- accelerometer: the specific force at the IMU's point, ``R^T (a - g)``, with ``a`` the
  body's acceleration (forward ``dv/dt``, sideways ``v omega``, and the lever arm's
  ``alpha x r + omega x (omega x r)``), ``g`` pointing down, and white noise of
  :data:`ACCEL_NOISE`.

The convention of the gyro's scale is the estimators' (``omega_true = k_g (omega_read -
bias)``): the base frame's yaw rate read is ``omega_z / k_g + (R bias)_z + noise``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError, option
from umbmark.model.recording import PoseSeries
from umbmark.options.simulate import IMU, IMU_OPTIONS
from umbmark.sources.bag.imu_writer import ImuTrack

__all__ = [
    "ACCEL_NOISE",
    "GRAVITY",
    "IMU_TRANSLATION",
    "MAX_IMU_READINGS",
    "ImuSetup",
    "SimulatedImu",
    "simulate_imu",
]

#: Standard gravity [m/s^2].
GRAVITY = 9.80665
#: The accelerometer's white-noise density [m/s^2/sqrt(Hz)]: 400 ug/sqrt(Hz), the
#: MPU-6050's.
ACCEL_NOISE = 400e-6 * GRAVITY
#: Where the IMU sits in ``base_link`` [m]: behind the axle, off the centre line, above it.
IMU_TRANSLATION = (-0.05, 0.02, 0.12)
#: Most readings an IMU of one simulation may give (about 100 bytes each).
MAX_IMU_READINGS = 10_000_000
#: The SI value of one unit of each option's unit.
_SI = {
    "": 1.0,
    "Hz": 1.0,
    "deg": math.radians(1.0),
    "deg/s": math.radians(1.0),
    "deg/s/sqrt(s)": math.radians(1.0),
    "deg/s/sqrt(Hz)": math.radians(1.0),
}


@dataclass(frozen=True)
class ImuSetup:
    """The simulated IMU, in SI units (the options' in :data:`IMU`), checked when made.

    Attributes
    ----------
    imu_rate : float
        Readings a second [Hz].
    gyro_scale : float
        ``k_g``, the factor that corrects the gyro (``omega_true = k_g (omega_read -
        bias)``).
    gyro_bias : float
        The bias of the IMU's z axis at the start [rad/s].
    gyro_bias_walk : float
        The bias's random walk [rad/s/sqrt(s)].
    gyro_noise : float
        White-noise density [rad/s/sqrt(Hz)].
    gyro_range : float
        Full scale [rad/s].
    imu_roll, imu_pitch, imu_yaw : float
        The mounting in ``base_link`` [rad] (fixed axes, the URDF's ``rpy``).

    Raises
    ------
    InputError
        A value out of its option's range (named in the option's unit).
    """

    imu_rate: float = IMU["imu_rate"].default
    gyro_scale: float = IMU["gyro_scale"].default
    gyro_bias: float = math.radians(IMU["gyro_bias"].default)
    gyro_bias_walk: float = math.radians(IMU["gyro_bias_walk"].default)
    gyro_noise: float = math.radians(IMU["gyro_noise"].default)
    gyro_range: float = math.radians(IMU["gyro_range"].default)
    imu_roll: float = 0.0
    imu_pitch: float = 0.0
    imu_yaw: float = 0.0

    def __post_init__(self) -> None:
        for spec in IMU_OPTIONS:
            value = getattr(self, spec.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InputError(f"{option(spec.name)} must be a number, not {value!r:.24}")
            object.__setattr__(self, spec.name, float(value))
            spec.check(float(value) / _SI[spec.unit])

    @classmethod
    def of_options(cls, values: dict[str, Any]) -> ImuSetup:
        """The setup of option values in the options' units (degrees, deg/s, ...), by
        keyword; those not given keep their defaults."""
        known = {f.name for f in fields(cls)}
        return cls(**{k: float(v) * _SI[IMU[k].unit] for k, v in values.items() if k in known})

    @property
    def rotation(self) -> FloatArray:
        """The IMU's axes in ``base_link``, shape (3, 3): ``Rz(yaw) Ry(pitch) Rx(roll)``."""
        cr, sr = math.cos(self.imu_roll), math.sin(self.imu_roll)
        cp, sp = math.cos(self.imu_pitch), math.sin(self.imu_pitch)
        cy, sy = math.cos(self.imu_yaw), math.sin(self.imu_yaw)
        rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
        ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
        rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
        return np.asarray(rz @ ry @ rx, dtype=np.float64)

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """The same rotation as a quaternion ``x, y, z, w``: ``q_z q_y q_x``."""

        def product(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, ...]:
            ax, ay, az, aw = a
            bx, by, bz, bw = b
            return (
                aw * bx + ax * bw + ay * bz - az * by,
                aw * by - ax * bz + ay * bw + az * bx,
                aw * bz + ax * by - ay * bx + az * bw,
                aw * bw - ax * bx - ay * by - az * bz,
            )

        half = 0.5
        qx = (math.sin(half * self.imu_roll), 0.0, 0.0, math.cos(half * self.imu_roll))
        qy = (0.0, math.sin(half * self.imu_pitch), 0.0, math.cos(half * self.imu_pitch))
        qz = (0.0, 0.0, math.sin(half * self.imu_yaw), math.cos(half * self.imu_yaw))
        x, y, z, w = product(qz, product(qy, qx))
        return (x, y, z, w)


@dataclass(frozen=True)
class SimulatedImu:
    """An IMU read along a simulated recording, and its truth.

    Attributes
    ----------
    setup : ImuSetup
    track : ImuTrack
        The readings, in the IMU's frame, with its mounting (what the bag records).
    bias_start, bias_end : array, shape (3,)
        The gyro's bias on its x, y, z axes at the first and the last reading [rad/s].
    clipped : int
        Readings with an axis clipped at the full scale.
    """

    setup: ImuSetup
    track: ImuTrack
    bias_start: FloatArray
    bias_end: FloatArray
    clipped: int

    def truth(self) -> dict[str, Any]:
        """The IMU's truth, JSON-ready (SI units: rad, rad/s, m, Hz): what the estimators
        should find. ``yaw_bias``: the bias of the base frame's yaw rate, ``(R bias)_z``."""
        s, rotation = self.setup, self.setup.rotation
        return {
            "topic": self.track.topic,
            "frame": self.track.frame,
            "rate": s.imu_rate,
            "readings": int(self.track.time.size),
            "k_g": s.gyro_scale,
            "bias": [float(v) for v in self.bias_start],
            "bias_end": [float(v) for v in self.bias_end],
            "yaw_bias": float((rotation @ self.bias_start)[2]),
            "yaw_bias_end": float((rotation @ self.bias_end)[2]),
            "bias_walk": s.gyro_bias_walk,
            "noise_density": s.gyro_noise,
            "accel_noise_density": ACCEL_NOISE,
            "full_scale": s.gyro_range,
            "clipped": self.clipped,
            "mounting": {
                "parent": "base_link",
                "xyz": list(self.track.translation),
                "rpy": [s.imu_roll, s.imu_pitch, s.imu_yaw],
                "quaternion": list(self.track.rotation),
            },
        }


def simulate_imu(truth: PoseSeries, setup: ImuSetup, rng: np.random.Generator) -> SimulatedImu:
    """The IMU's readings along ``truth`` (the true pose of the axle centre over time,
    headings unwrapped; the module's notes), from one reading period after its start.

    Raises
    ------
    InputError
        More than :data:`MAX_IMU_READINGS` readings (a long recording at a high rate).
    """
    t, poses = truth.time, truth.poses
    period = 1.0 / setup.imu_rate
    count = math.floor((float(t[-1]) - float(t[0])) * setup.imu_rate + 1e-9)
    if count > MAX_IMU_READINGS:
        raise InputError(
            f"{option('imu_rate', setup.imu_rate, 'Hz')} over {t[-1] - t[0]:.0f} s is "
            f"{count:,} readings: at most {MAX_IMU_READINGS:,}; lower it"
        )
    if count < 2:
        raise InputError("the recording is too short for two IMU readings")
    time = np.asarray(float(t[0]) + period * np.arange(1, count + 1), dtype=np.float64)
    heading, travel = poses[:, 2], _travel(poses)

    def mean_rate(values: FloatArray, back: int) -> FloatArray:
        """The mean rate of ``values`` over the reading period ending ``back`` periods
        before each reading."""
        end = np.interp(time - back * period, t, values)
        return np.asarray((end - np.interp(time - (back + 1) * period, t, values)) / period)

    omega, speed = mean_rate(heading, 0), mean_rate(travel, 0)
    alpha = (omega - mean_rate(heading, 1)) / period
    forward = (speed - mean_rate(travel, 1)) / period
    rx, ry, _ = IMU_TRANSLATION
    force = np.column_stack(
        [
            forward - alpha * ry - omega**2 * rx,
            speed * omega + alpha * rx - omega**2 * ry,
            np.full(count, GRAVITY),
        ]
    )
    rotation = setup.rotation
    true_rate = np.column_stack([np.zeros(count), np.zeros(count), omega]) @ rotation
    start = np.array([_drawn(rng, setup.gyro_bias), _drawn(rng, setup.gyro_bias), setup.gyro_bias])
    steps = rng.normal(0.0, setup.gyro_bias_walk * math.sqrt(period), (count, 3))
    steps[0] = 0.0
    bias = start + np.cumsum(steps, axis=0)
    noise = rng.normal(0.0, setup.gyro_noise * math.sqrt(setup.imu_rate), (count, 3))
    rate = true_rate / setup.gyro_scale + bias + noise
    clipped = int(np.count_nonzero(np.any(np.abs(rate) > setup.gyro_range, axis=1)))
    rate = np.clip(rate, -setup.gyro_range, setup.gyro_range)
    accel = force @ rotation + rng.normal(0.0, ACCEL_NOISE * math.sqrt(setup.imu_rate), (count, 3))
    track = ImuTrack(
        time=time,
        rate=rate,
        accel=accel,
        translation=IMU_TRANSLATION,
        rotation=setup.quaternion,
        rate_variance=(setup.gyro_noise**2) * setup.imu_rate,
        accel_variance=(ACCEL_NOISE**2) * setup.imu_rate,
    )
    return SimulatedImu(setup, track, start, bias[-1].copy(), clipped)


def _drawn(rng: np.random.Generator, size: float) -> float:
    """A bias of up to ``size``'s magnitude, either sign."""
    return float(rng.uniform(-abs(size), abs(size)))


def _travel(poses: FloatArray) -> FloatArray:
    """The distance driven forward along ``poses`` (shape (n, 3)) from the first, shape
    (n,): each step's arc (its chord over ``sinc`` of half its turn), signed by its
    direction against the heading."""
    dx, dy, dh = np.diff(poses[:, 0]), np.diff(poses[:, 1]), np.diff(poses[:, 2])
    chord = np.hypot(dx, dy)
    half = 0.5 * dh
    with np.errstate(invalid="ignore", divide="ignore"):
        arc = np.where(np.abs(half) > 1e-9, chord * half / np.sin(half), chord)
    mid = poses[:-1, 2] + half
    sign = np.where(dx * np.cos(mid) + dy * np.sin(mid) < 0.0, -1.0, 1.0)
    return np.concatenate([[0.0], np.cumsum(sign * arc)])

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
    "ImuReadings",
    "ImuSetup",
    "ImuStream",
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
    start = _start_bias(rng, setup)
    read = _read(setup, rng, time, (t, poses[:, 2], _travel(poses)), start, first=True)
    track = ImuTrack(
        time=time,
        rate=read.rate,
        accel=read.accel,
        translation=IMU_TRANSLATION,
        rotation=setup.quaternion,
        rate_variance=(setup.gyro_noise**2) * setup.imu_rate,
        accel_variance=(ACCEL_NOISE**2) * setup.imu_rate,
    )
    return SimulatedImu(setup, track, start, read.bias[-1].copy(), read.clipped)


@dataclass(frozen=True)
class ImuReadings:
    """Readings of the simulated IMU, in its own frame, with the bias in each.

    Attributes
    ----------
    time : array, shape (k,)
        Reading times [s].
    rate : array, shape (k, 3)
        The gyro's rates about the IMU's axes [rad/s], as read.
    accel : array, shape (k, 3)
        The specific force along them [m/s^2].
    bias : array, shape (k, 3)
        The gyro's true bias in each reading [rad/s] (the truth, for checks).
    clipped : int
        Readings with an axis clipped at the full scale.
    """

    time: FloatArray
    rate: FloatArray
    accel: FloatArray
    bias: FloatArray
    clipped: int = 0


def _start_bias(rng: np.random.Generator, setup: ImuSetup) -> FloatArray:
    """The bias at the first reading: the z axis' given one, x and y drawn up to it."""
    return np.array([_drawn(rng, setup.gyro_bias), _drawn(rng, setup.gyro_bias), setup.gyro_bias])


def _read(
    setup: ImuSetup,
    rng: np.random.Generator,
    time: FloatArray,
    truth: tuple[FloatArray, FloatArray, FloatArray],
    bias: FloatArray,
    *,
    first: bool,
) -> ImuReadings:
    """The readings at ``time`` (shape (k,)) along ``truth`` (times, unwrapped headings and
    the distance driven forward, each shape (n,), joined by straight lines), the bias
    walking on from ``bias`` (its value at the reading before; ``first``: it is the first
    reading's own, no step taken to it)."""
    t, heading, travel = truth
    count = time.size
    period = 1.0 / setup.imu_rate

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
    steps = rng.normal(0.0, setup.gyro_bias_walk * math.sqrt(period), (count, 3))
    if first and count:
        steps[0] = 0.0
    walked = bias + np.cumsum(steps, axis=0)
    noise = rng.normal(0.0, setup.gyro_noise * math.sqrt(setup.imu_rate), (count, 3))
    rate = true_rate / setup.gyro_scale + walked + noise
    clipped = int(np.count_nonzero(np.any(np.abs(rate) > setup.gyro_range, axis=1)))
    rate = np.clip(rate, -setup.gyro_range, setup.gyro_range)
    accel = force @ rotation + rng.normal(0.0, ACCEL_NOISE * math.sqrt(setup.imu_rate), (count, 3))
    return ImuReadings(time, rate, accel, walked, clipped)


class ImuStream:
    """The same IMU read along a motion that goes on (the virtual robot's, as it drives):
    the true motion is given as it happens (:meth:`add`), the readings are made when asked
    for (:meth:`read`), each one as :func:`simulate_imu` makes it, its bias walking on
    from the one before; a reading is made once the motion up to its time is known.

    Parameters
    ----------
    setup : ImuSetup
    rng : numpy.random.Generator
    start : float
        The time of the motion's first sample [s]; the first reading is one period later.
    """

    def __init__(self, setup: ImuSetup, rng: np.random.Generator, start: float = 0.0) -> None:
        self.setup = setup
        self._rng = rng
        self._origin = float(start)
        self._next = 1  # the index of the next reading
        self._bias = _start_bias(rng, setup)
        self._first = True
        self._samples: list[tuple[float, float, float]] = []

    @property
    def bias(self) -> FloatArray:
        """The gyro's bias now (at the last reading made; the first's before it) [rad/s],
        shape (3,)."""
        return np.asarray(self._bias.copy())

    @property
    def pending(self) -> int:
        """Samples of the motion held for readings still to make."""
        return len(self._samples)

    def add(self, time: float, heading: float, travel: float) -> None:
        """The true motion at ``time`` [s]: heading [rad, unwrapped] and the distance
        driven forward since the start [m], times increasing."""
        self._samples.append((float(time), float(heading), float(travel)))

    def read(self) -> ImuReadings:
        """The readings whose times the motion given so far covers, not read before."""
        if not self._samples:
            return _no_readings()
        rate = self.setup.imu_rate
        last = math.floor((self._samples[-1][0] - self._origin) * rate + 1e-9)
        if last < self._next:
            return _no_readings()
        period = 1.0 / rate
        time = np.asarray(self._origin + period * np.arange(self._next, last + 1), np.float64)
        t, heading, travel = (np.asarray(c, np.float64) for c in zip(*self._samples, strict=True))
        read = _read(self.setup, self._rng, time, (t, heading, travel), self._bias,
                     first=self._first)  # fmt: skip
        self._first = False
        self._bias = read.bias[-1].copy()
        self._next = last + 1
        # keep what the next readings look back to: two periods before the next one
        keep = np.searchsorted(t, self._origin + period * (self._next - 2), side="right") - 1
        del self._samples[: max(int(keep), 0)]
        return read


def _no_readings() -> ImuReadings:
    return ImuReadings(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))


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

"""What the gyro estimator found (:mod:`umbmark.estimators.gyro`):
:class:`GyroCalibration`, the gyro's scale and bias and the wheels' errors, each with its
standard error or marked undetermined with what to drive."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from umbmark.core.arrays import FloatArray
from umbmark.estimators.gyro_mounting import GyroMounting
from umbmark.estimators.scan_excitation import Excitation
from umbmark.estimators.scan_matching import ScanCalibration

__all__ = ["FIGURES", "GyroCalibration"]

#: The figures, in the order of :attr:`GyroCalibration.values`.
FIGURES = ("E_d", "E_b_k_g", "E_b", "E_s", "k_g", "bias")


@dataclass(frozen=True)
class GyroCalibration:
    """The gyro's scale and bias and the wheels' errors, each with its standard error.

    Attributes
    ----------
    values : dict of str to float
        The determined figures of :data:`FIGURES`: ``E_d``; ``E_b_k_g`` (``E_b k_g /
        E_s``, what wheels and gyro alone identify); ``E_b`` (with a reference; ``E_b /
        E_s`` where the reference gives no distance); ``E_s`` (a reference with
        distance); ``k_g`` (with a reference); ``bias``, the bias's mean over the
        recording [rad/s].
    standard_errors : dict of str to float
        One sigma of each (``E_b`` without a reference: widened by the tolerance).
    undetermined : dict of str to str
        The figures the motion does not determine, and what to drive for them.
    relative_to_gyro : tuple of str
        Figures stated against the gyro's scale (``E_b`` without a reference).
    scale_tolerance : float
        The gyro scale tolerance ``E_b``'s interval is widened by (without a reference).
    bias_times, bias_values, bias_errors : array, shape (M,)
        The bias at its knots [s, rad/s, rad/s].
    bias_walk : float
        Its random walk, fitted [rad/s/sqrt(s)].
    noise : dict of str to float
        The rows' noise (:class:`~umbmark.estimators.gyro_fit.LinearFit`).
    mounting : GyroMounting
    reference : {"no reference", "heading changes", "scan matching"}
        What absolute reference joined.
    n_intervals, n_rests, n_reference, n_outliers : int
        Intervals used, of them rests; reference stretches; rows dropped as outliers.
    excitation : Excitation
        What the driving intervals hold.
    warnings : tuple of str
        Doubts (a :class:`~umbmark.core.messages.Blocking` among them: not for applying).
    extra : dict of str to float
        Figures of the reference's own (scan matching: the laser's mounting ``laser_x``,
        ``laser_y`` [m], ``laser_yaw`` [rad], ``wheel_diameter_left``,
        ``wheel_diameter_right``, ``wheelbase`` [m]), their standard errors in
        :attr:`standard_errors`.
    scan : ScanCalibration or None
        The same as a scan-matching calibration (the wheels and the laser's mounting, with
        their covariance), where the reference is scan matching.
    delays : dict of str to (float, float)
        ``gyro``: the gyro's readings' delay [s] and its standard error, against the
        wheels and the reference alike (positive: the gyro lags; a reading that is the
        mean over its period lags by half of it), where the motion determines it (turns
        that start and stop).
    """

    values: dict[str, float]
    standard_errors: dict[str, float]
    undetermined: dict[str, str]
    relative_to_gyro: tuple[str, ...]
    scale_tolerance: float
    bias_times: FloatArray
    bias_values: FloatArray
    bias_errors: FloatArray
    bias_walk: float
    noise: dict[str, float]
    mounting: GyroMounting
    reference: str
    n_intervals: int
    n_rests: int
    n_reference: int
    n_outliers: int
    excitation: Excitation
    warnings: tuple[str, ...] = ()
    extra: dict[str, float] = field(default_factory=dict)
    scan: ScanCalibration | None = field(default=None, compare=False)
    delays: dict[str, tuple[float, float]] = field(default_factory=dict)

    def get(self, name: str) -> float | None:
        """A figure's value, None where not determined (or not made)."""
        return self.values.get(name)

    def interval(self, name: str, level: float = 0.95) -> tuple[float, float] | None:
        """A figure's normal ``level`` interval, None where not determined."""
        from umbmark.core.stats import t_quantile

        value, se = self.values.get(name), self.standard_errors.get(name)
        if value is None or se is None or not math.isfinite(se):
            return None
        half = t_quantile(0.5 + 0.5 * level, math.inf) * se
        return (value - half, value + half)

    def to_apply(self) -> dict[str, Any]:
        """What to set, JSON-ready: ``scale_multiplier`` (``k_g``: a driver's gyro scale
        times it; None where not determined), ``bias`` [rad/s] and ``bias_deg_s`` (to
        subtract from the yaw rate), and the IMU frame's origin ``rpy`` found and stated
        [rad] (None where the stated one or the turning axis is not known), with
        ``rotation_offset``, the rotation of the readings that keeps the stated
        transform (ros2_controllers' ``imu_sensor_broadcaster``: ``Rz Ry Rx``), whether
        the mounting differs, and the scale tolerance ``E_b`` is relative to (None where
        ``k_g`` is determined)."""
        from umbmark.estimators.gyro_mounting import rpy_of

        v, mounting = self.values, self.mounting
        found, stated = mounting.found_rotation(), mounting.stated_rotation
        offset = None if found is None or stated is None else rpy_of(stated.T @ found)
        return {
            "scale_multiplier": v.get("k_g"),
            "bias": v.get("bias"),
            "bias_deg_s": None if "bias" not in v else math.degrees(v["bias"]),
            "frame": mounting.frame,
            "origin_rpy_found": None if found is None else rpy_of(found),
            "origin_rpy_stated": None if stated is None else rpy_of(stated),
            "rotation_offset": offset,
            "mounting_differs": mounting.differs,
            "scale_tolerance": None if "k_g" in v else self.scale_tolerance,
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (radians, rad/s); ``apply``: :meth:`to_apply`."""
        return {
            "values": dict(self.values),
            "standard_errors": dict(self.standard_errors),
            "intervals_95": {
                n: list(i) for n in self.values if (i := self.interval(n)) is not None
            },
            "undetermined": dict(self.undetermined),
            "relative_to_gyro": list(self.relative_to_gyro),
            "scale_tolerance": self.scale_tolerance,
            "bias": {
                "times": [float(t) for t in self.bias_times],
                "values": [float(v) for v in self.bias_values],
                "standard_errors": [float(v) for v in self.bias_errors],
                "random_walk": self.bias_walk,
            },
            "noise": dict(self.noise),
            "mounting": self.mounting.to_dict(),
            "reference": self.reference,
            "n_intervals": self.n_intervals,
            "n_rests": self.n_rests,
            "n_reference": self.n_reference,
            "n_outliers": self.n_outliers,
            "warnings": list(self.warnings),
            "delays": {
                name: {"value": value, "standard_error": se}
                for name, (value, se) in self.delays.items()
            },
            "apply": self.to_apply(),
            **({"reference_figures": self.extra} if self.extra else {}),
        }

"""A virtual differential-drive robot: its true geometry, its odometry model, its noise."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from umbmark.core.validation import check_positive, require_positive
from umbmark.model.kinematics import IntegrationMethod, WheelParams

__all__ = ["LABMATE", "ControlConfig", "NoiseModel", "SimRobot"]


@dataclass(frozen=True)
class NoiseModel:
    """Non-systematic errors (Sec. 2.1).

    Attributes
    ----------
    slip : float
        Wheel slip [m^(1/2)]: each wheel's travel over the floor differs from its rotation
        by a Gaussian error of standard deviation ``slip * sqrt(travel)``, independently
        per sample, so the variance grows with the distance driven whatever the sampling
        period.
    bump_rate : float
        Floor irregularities [1/m]: expected bumps per metre a wheel travels.
    bump_size : float
        Extra wheel rotation per bump, as a length [m]: the wheel turns (and its encoder
        counts) this much more than it travels over the floor.
    """

    slip: float = 0.0
    bump_rate: float = 0.0
    bump_size: float = 0.0

    def __post_init__(self) -> None:
        require_positive(self, "slip", "bump_rate", "bump_size", allow_zero=True)

    @property
    def is_noise_free(self) -> bool:
        """True when the robot has no non-systematic errors."""
        return self.slip == 0.0 and (self.bump_rate == 0.0 or self.bump_size == 0.0)


@dataclass(frozen=True)
class ControlConfig:
    """How the robot drives (Sec. 5: 0.2 m/s on the legs, stop, turn on the spot).

    Attributes
    ----------
    dt : float
        Sampling and control period [s] (the paper: under 10 ms).
    speed : float
        Cruise speed on the legs [m/s].
    turn_wheel_speed : float
        Wheel speed during on-the-spot turns [m/s] (the paper: about 0.2 m/s).
    acceleration : float
        Linear acceleration limit [m/s^2]; also the wheels' limit during turns.
    heading_gain, cross_track_gain : float
        Line-following gains on the odometry heading error [1/s] and the odometry
        cross-track error [1/(m s)].
    creep_speed : float
        Slowest speed when closing in on a target [m/s]; the robot stops within two
        encoder pulses of the target.
    method : {"arc", "midpoint", "segment"}
        How the robot's own odometry integrates its encoders.
    """

    dt: float = 0.01
    speed: float = 0.2
    turn_wheel_speed: float = 0.2
    acceleration: float = 0.5
    heading_gain: float = 4.0
    cross_track_gain: float = 8.0
    creep_speed: float = 0.005
    method: IntegrationMethod = "arc"

    def __post_init__(self) -> None:
        require_positive(self, "dt", "speed", "turn_wheel_speed", "acceleration", "creep_speed")


@dataclass(frozen=True)
class SimRobot:
    """A robot whose true geometry is known.

    Attributes
    ----------
    odometry : WheelParams
        What the robot believes: nominal diameter ``D_n``, wheelbase ``b``, encoder
        resolution ``C_e``, gear ratio ``n`` and its current ``c_L``, ``c_R``.
    diameter_left, diameter_right : float
        True wheel diameters [m].
    wheelbase : float
        True wheelbase [m].
    noise : NoiseModel
    """

    odometry: WheelParams
    diameter_left: float
    diameter_right: float
    wheelbase: float
    noise: NoiseModel = field(default_factory=NoiseModel)

    def __post_init__(self) -> None:
        require_positive(self, "diameter_left", "diameter_right", "wheelbase")

    @classmethod
    def with_errors(
        cls,
        odometry: WheelParams,
        E_d: float = 1.0,
        E_b: float = 1.0,
        E_s: float = 1.0,
        noise: NoiseModel | None = None,
    ) -> SimRobot:
        """A robot whose truth differs from ``odometry``'s nominal values by these errors.

        ``E_d = D_R / D_L`` (Eq. 2.3), ``E_b = b_actual / b`` (Eq. 2.4) and
        ``E_s = D_avg / D_n`` (Sec. 2.2), relative to ``odometry.wheel_diameter`` and
        ``odometry.wheelbase``.
        """
        for name, value in (("E_d", E_d), ("E_b", E_b), ("E_s", E_s)):
            check_positive(name, value)
        d_avg = E_s * odometry.wheel_diameter
        return cls(
            odometry=odometry,
            diameter_left=2.0 * d_avg / (E_d + 1.0),
            diameter_right=2.0 * d_avg * E_d / (E_d + 1.0),
            wheelbase=E_b * odometry.wheelbase,
            noise=NoiseModel() if noise is None else noise,
        )

    @property
    def E_d(self) -> float:
        """True ``D_R / D_L``."""
        return self.diameter_right / self.diameter_left

    @property
    def E_s(self) -> float:
        """True average diameter over the nominal one, ``D_avg / D_n``."""
        return 0.5 * (self.diameter_left + self.diameter_right) / self.odometry.wheel_diameter

    def calibrated(self, c_left: float, c_right: float, wheelbase: float) -> SimRobot:
        """The same robot with new odometry parameters (its truth unchanged)."""
        return replace(
            self,
            odometry=self.odometry.with_corrections(
                c_left=c_left, c_right=c_right, wheelbase=wheelbase
            ),
        )


#: A LabMate-like platform (Sec. 5): b = 340 mm, 150 mm wheels; the encoder figures are
#: typical of such a drive, not from the paper.
LABMATE = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20.0)

"""The odometry parameters active while runs were driven, and the correction composed
with them (Eqs. 4.31, 4.32 and 4.26 multiplied into the active factors; see
:mod:`umbmark.calibration.compose`)."""

from __future__ import annotations

from dataclasses import dataclass

from umbmark.core.validation import check_positive, require_positive
from umbmark.model.systematic import correction_factors

__all__ = ["ActiveParams"]


@dataclass(frozen=True)
class ActiveParams:
    """The odometry parameters that were active while the runs were driven.

    Attributes
    ----------
    wheelbase : float
        ``b`` [m] as configured (ros2_control ``wheel_separation``).
    c_left, c_right : float
        Wheel correction factors (ros2_control ``left/right_wheel_radius_multiplier``).
    separation_multiplier : float
        ros2_control ``wheel_separation_multiplier``.
    wheel_diameter : float or None
        Nominal wheel diameter ``D_n`` [m], when known.
    """

    wheelbase: float
    c_left: float = 1.0
    c_right: float = 1.0
    separation_multiplier: float = 1.0
    wheel_diameter: float | None = None

    def __post_init__(self) -> None:
        require_positive(self, "wheelbase", "c_left", "c_right", "separation_multiplier")
        if self.wheel_diameter is not None:
            check_positive("wheel_diameter", self.wheel_diameter, unit="m")

    @property
    def effective_wheelbase(self) -> float:
        """The wheelbase the odometry used [m]: ``b * separation_multiplier``."""
        return self.wheelbase * self.separation_multiplier

    def compose(self, E_d: float, E_b: float, scale: float = 1.0) -> tuple[float, float, float]:
        """The parameters that correct errors measured on these ones (Eqs. 4.31, 4.32 and
        4.26, multiplied into the active factors).

        Parameters
        ----------
        E_d, E_b : float
            Errors measured by runs driven with these parameters.
        scale : float
            ``E_s``, when known (both wheel factors are multiplied by it).

        Returns
        -------
        c_left, c_right, separation_multiplier : float
            The new absolute ``c_L``, ``c_R`` and ``wheel_separation_multiplier``.
        """
        c_left, c_right = correction_factors(E_d)
        return (
            self.c_left * (float(c_left) * scale),
            self.c_right * (float(c_right) * scale),
            self.separation_multiplier * E_b,
        )

    def robot_errors(self, E_d: float, E_b: float) -> tuple[float, float]:
        """What the robot is, from errors measured on these parameters: its ``D_R / D_L``
        and its effective wheelbase over the nominal ``b``, from :meth:`compose`
        (``c_R,new / c_L,new = E_d c_R / c_L`` and the new multiplier ``E_b x multiplier``).
        """
        c_left, c_right, separation = self.compose(E_d, E_b)
        return c_right / c_left, separation

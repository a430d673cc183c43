"""From estimated errors to new odometry parameters, composed with the active ones.

The runs were driven with some parameters active: a wheelbase ``b`` (possibly scaled by a
ros2_control ``wheel_separation_multiplier``) and wheel factors ``c_L``, ``c_R`` (ros2_control's
``left_wheel_radius_multiplier`` and ``right_wheel_radius_multiplier``). The errors UMBmark
measures are relative to those, so the correction multiplies into them (Sec. 5: a
compensated robot is a "new" uncompensated robot with different initial parameters):

- ``c_L,new = c_L,active * 2 / (E_d + 1)`` (Eq. 4.31)
- ``c_R,new = c_R,active * 2 / (1/E_d + 1)`` (Eq. 4.32)
- ``wheel_separation_multiplier,new = multiplier,active * E_b`` and
  ``b_new = E_b * b_effective`` (Eq. 4.26).

The new parameters are also what the robot *is* (:meth:`ActiveParams.robot_errors`): its
``D_R / D_L = c_R,new / c_L,new`` and its effective wheelbase over the nominal one, the new
multiplier. A pass on odometry already corrected measures errors near 1; composed with the
parameters active during it, they give the robot's own again.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from umbmark.core.bounds import Origin, geometry_origins
from umbmark.core.errors import InputError, option
from umbmark.estimators.base import ErrorEstimate
from umbmark.estimators.registry import SQUARE
from umbmark.model.active import ActiveParams
from umbmark.model.systematic import correction_factors

__all__ = ["Calibration", "check_calibration"]


@dataclass(frozen=True)
class Calibration:
    """An error estimate turned into corrected parameters."""

    estimate: ErrorEstimate
    active: ActiveParams

    @property
    def scale(self) -> float:
        """``E_s`` of estimators that see it (trajectory fits), else 1: the paper assumes
        the average diameter calibrated beforehand (Sec. 2.2)."""
        return 1.0 if self.estimate.E_s is None else self.estimate.E_s

    @property
    def c_L(self) -> float:
        """Left correction factor of this pass, Eq. 4.31 (times ``E_s`` when known)."""
        return float(correction_factors(self.estimate.E_d)[0]) * self.scale

    @property
    def c_R(self) -> float:
        """Right correction factor of this pass, Eq. 4.32 (times ``E_s`` when known)."""
        return float(correction_factors(self.estimate.E_d)[1]) * self.scale

    def _new(self) -> tuple[float, float, float]:
        return self.active.compose(self.estimate.E_d, self.estimate.E_b, self.scale)

    @property
    def new_c_left(self) -> float:
        """Absolute left factor to configure: ``c_L,active * c_L``."""
        return self._new()[0]

    @property
    def new_c_right(self) -> float:
        """Absolute right factor to configure: ``c_R,active * c_R``."""
        return self._new()[1]

    @property
    def new_separation_multiplier(self) -> float:
        """Absolute ``wheel_separation_multiplier`` to configure: ``active * E_b``."""
        return self._new()[2]

    @property
    def wheelbase_corrected(self) -> float:
        """Corrected effective wheelbase [m], Eq. 4.26: ``E_b * b_effective``."""
        return self.estimate.E_b * self.active.effective_wheelbase

    @property
    def wheel_diameter_left(self) -> float | None:
        """Corrected effective left wheel diameter ``c_L,new D_n`` [m], if ``D_n`` is known."""
        d = self.active.wheel_diameter
        return None if d is None else self.new_c_left * d

    @property
    def wheel_diameter_right(self) -> float | None:
        """Corrected effective right wheel diameter ``c_R,new D_n`` [m], if ``D_n`` is known."""
        d = self.active.wheel_diameter
        return None if d is None else self.new_c_right * d


def check_calibration(
    calibration: Calibration, origins: Mapping[str, Origin] | None = None
) -> None:
    """Refuse a calibration whose new factors are not positive finite numbers.

    Raises
    ------
    InputError
        Naming the first such factor: the runs and the parameters (named as ``origins``
        says where they came from, see :func:`check_square_geometry`) contradict each other.
    """
    active = calibration.active
    b_from, side_from, m_from, _ = geometry_origins(origins, active.separation_multiplier)
    named = [b_from.named(), *([m_from.named()] if m_from else [])]
    square = calibration.estimate.method in SQUARE
    if square:  # a square driven: its side counts
        gives = "the runs give"
        causes = f"{', '.join([side_from.named(), *named])} and the runs' units and directions"
    else:  # ordinary driving, a trajectory fit: no square, its wheels and their geometry
        gives = "the recording gives"
        d_from = (origins or {}).get("wheel_diameter", Origin(option("wheel_diameter")))
        causes = (
            f"{', '.join([*named, d_from.named()])} and the wheels' readings (which joint is "
            "left, their signs, the encoder resolution)"
        )
    for name, value in (
        ("E_d", calibration.estimate.E_d),
        ("E_b", calibration.estimate.E_b),
        ("c_L", calibration.new_c_left),
        ("c_R", calibration.new_c_right),
        ("wheel_separation_multiplier", calibration.new_separation_multiplier),
        ("wheelbase", calibration.wheelbase_corrected),
    ):
        if not (math.isfinite(value) and value > 0):
            raise InputError(
                f"{gives} {name} = {value:.6g}, which no robot can have: check {causes}"
            )

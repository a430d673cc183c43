"""Whether intervals of driving excite the parameters of the scan-matching calibration.

The first step of the calibration (:mod:`umbmark.estimators.scan_matching`) finds
``J21 = -r_L / b`` and ``J22 = r_R / b`` from the sensor's rotation against the wheels'
rotations, a linear least squares with the ``2 x 2`` normal matrix
``A = sum_k (Phi_L, Phi_R)_k^T (Phi_L, Phi_R)_k``. ``A`` is singular when the wheels
turned in one ratio only: straights alone (``Phi_L = Phi_R``) do not tell the two
radii apart from the wheelbase, turns on the spot alone (``Phi_L = -Phi_R``) do not
tell the radii from each other, and the second step needs translation too (the wheelbase
and the sensor's yaw) and rotation (the sensor's position). The reference implementation
refuses when the condition number of ``A`` exceeds 75; so does this module, saying which
motion is missing rather than "not very exciting data".

Each interval is classified by its wheel rotations: with ``f = (Phi_L + Phi_R) / 2``
(driving) and ``t = (Phi_R - Phi_L) / 2`` (turning), a turn on the spot has
``|f| <= 0.2 |t|``, a straight ``|t| <= 0.2 |f|``, an arc lies between; turning left is
``t > 0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray

__all__ = ["MAX_CONDITION", "Excitation", "excitation", "wheel_condition"]


#: The largest condition number of the first step's normal matrix accepted (the
#: reference implementation's default ``max_cond_number``).
MAX_CONDITION = 75.0
#: ``|f| <= SHARE |t|``: a turn on the spot; ``|t| <= SHARE |f|``: a straight.
_SHARE = 0.2
#: Wheel rotation [rad] below which an interval counts as standing still.
_STILL = 1e-3


def wheel_condition(phi_left: FloatArray, phi_right: FloatArray) -> float:
    """The condition number of the first step's normal matrix (inf when singular).

    ``phi_left``, ``phi_right``: ``(n,)`` wheel rotations [rad] over each interval.
    """
    a = np.column_stack([phi_left, phi_right])
    s = np.linalg.svd(a.T @ a, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0.0 else float("inf")


@dataclass(frozen=True)
class Excitation:
    """What motion a set of intervals holds.

    Attributes
    ----------
    n_spot, n_straight, n_arc : int
        Intervals turning on the spot, driving straight, driving arcs.
    n_left, n_right : int
        Intervals turning left (counter-clockwise) and right, on the spot or on arcs.
    n_still : int
        Intervals in which neither wheel turned by more than 1 mrad.
    condition : float
        Condition number of the first step's normal matrix.
    """

    n_spot: int
    n_straight: int
    n_arc: int
    n_left: int
    n_right: int
    n_still: int
    condition: float

    @property
    def excited(self) -> bool:
        """The first step is well conditioned (at most :data:`MAX_CONDITION`)."""
        return self.condition <= MAX_CONDITION

    def missing(self) -> list[str]:
        """The motion to drive more of, for people ("turns on the spot", ...)."""
        turning = self.n_spot + self.n_arc
        out = []
        if not self.excited and (self.n_spot < max(1, self.n_straight // 10)):
            out.append("turns on the spot")
        if not self.excited and (self.n_straight < max(1, self.n_spot // 10)):
            out.append("straights")
        if turning and (self.n_left == 0 or self.n_right == 0):
            out.append(f"turns in both directions (all {turning} turn {self._side()})")
        if not self.excited and not out:
            out.append("turns on the spot and straights (the wheels turned in one ratio)")
        return out

    def _side(self) -> str:
        return "left" if self.n_right == 0 else "right"

    def problem(self) -> str | None:
        """Why the intervals cannot be calibrated from, or None."""
        if self.excited:
            return None
        return (
            f"the motion does not excite the parameters (condition number "
            f"{self.condition:.3g} > {MAX_CONDITION:g} of the wheel-rotation fit): drive "
            f"more {' and '.join(self.missing())} "
            f"(held: {self.n_spot} turns on the spot, {self.n_straight} straights, "
            f"{self.n_arc} arcs; {self.n_left} turning left, {self.n_right} right)"
        )

    def warnings(self) -> list[str]:
        """Doubts about a calibration that is well conditioned."""
        turning = self.n_spot + self.n_arc
        if self.excited and turning and (self.n_left == 0 or self.n_right == 0):
            return [
                f"every turn is to the {self._side()}: a scan matcher's or the wheels' "
                "direction-dependent bias goes unnoticed; drive turns in both directions"
            ]
        return []


def excitation(phi_left: FloatArray, phi_right: FloatArray) -> Excitation:
    """What motion the intervals hold (``(n,)`` wheel rotations [rad] over each)."""
    f = 0.5 * (phi_left + phi_right)
    t = 0.5 * (phi_right - phi_left)
    still = np.maximum(np.abs(phi_left), np.abs(phi_right)) < _STILL
    spot = ~still & (np.abs(f) <= _SHARE * np.abs(t))
    straight = ~still & (np.abs(t) <= _SHARE * np.abs(f))
    arc = ~still & ~spot & ~straight
    turning = spot | arc
    return Excitation(
        n_spot=int(spot.sum()),
        n_straight=int(straight.sum()),
        n_arc=int(arc.sum()),
        n_left=int((turning & (t > 0)).sum()),
        n_right=int((turning & (t < 0)).sum()),
        n_still=int(still.sum()),
        condition=wheel_condition(phi_left, phi_right),
    )

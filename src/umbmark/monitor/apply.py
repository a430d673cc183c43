"""What to apply from the robot's present state, and whether its verdict lets it be
applied: the fleet's rules (:mod:`umbmark.fleets.present`: the three multipliers from the
robot's present ``E_d``, ``E_b``, ``E_s``, absolute, what the controller should hold
whatever it holds now) and the calibration's verdict
(:func:`umbmark.calibration.verdict.judge`, on the errors relative to the parameters the
controller runs with, on the standard 4 m square), as for any calibration.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from umbmark.calibration.verdict import Evidence, Verdict, judge
from umbmark.estimators.base import ErrorEstimate, SquareTest
from umbmark.estimators.registry import SCAN_MATCHING
from umbmark.model.systematic import alpha_from_E_b, beta_from_E_d
from umbmark.robot.base import DriveParams

__all__ = ["STANDARD_SIDE", "Offer", "offer"]

#: The square the verdict judges on [m] (the paper's).
STANDARD_SIDE = 4.0


@dataclass(frozen=True)
class Offer:
    """The parameters the robot's present state asks for, and the verdict on them."""

    params: DriveParams
    verdict: Verdict

    def line(self) -> str:
        """One line for people."""
        p = self.params
        return (
            f"wheel_separation_multiplier {p.wheel_separation_multiplier:.6f}, "
            f"left_wheel_radius_multiplier {p.left_wheel_radius_multiplier:.6f}, "
            f"right_wheel_radius_multiplier {p.right_wheel_radius_multiplier:.6f} "
            f"({self.verdict.words})"
        )


def offer(
    present: Mapping[str, tuple[float, float]], active: DriveParams, warnings: tuple[str, ...] = ()
) -> Offer | None:
    """The parameters the robot's present ``E_d``, ``E_b`` (and ``E_s``) ask for, with
    the verdict on the errors they correct; None without ``E_d`` and ``E_b``."""
    if "E_d" not in present or "E_b" not in present:
        return None
    (E_d, se_d), (E_b, se_b) = present["E_d"], present["E_b"]
    E_s, se_s = present.get("E_s", (1.0, 0.0))
    new = DriveParams(
        active.wheel_separation, active.wheel_radius, E_b,
        2.0 * E_s / (E_d + 1.0), 2.0 * E_s * E_d / (E_d + 1.0),
    )  # fmt: skip
    c_l, c_r = active.left_wheel_radius_multiplier, active.right_wheel_radius_multiplier
    rel_d = E_d * c_l / c_r
    rel_b = E_b / active.wheel_separation_multiplier
    rel_s = E_s / (0.5 * (c_l * 2.0 / (rel_d + 1.0) + c_r * 2.0 * rel_d / (rel_d + 1.0)))
    errors = {"E_d": se_d * c_l / c_r, "E_b": se_b / active.wheel_separation_multiplier}
    if "E_s" in present:
        errors["E_s"] = se_s
    estimate = ErrorEstimate(
        method=SCAN_MATCHING.name,
        alpha=float(alpha_from_E_b(rel_b, rel_s)),
        beta=float(beta_from_E_d(rel_d, STANDARD_SIDE, active.wheelbase)),
        E_d=rel_d, E_b=rel_b, E_s=rel_s if "E_s" in present else None,
        standard_errors=errors, warnings=warnings,
    )  # fmt: skip
    test = SquareTest(STANDARD_SIDE, active.wheelbase)
    verdict = judge(estimate, test, Evidence(warnings=warnings,
                                             wheel_diameter=2.0 * active.wheel_radius))  # fmt: skip
    return Offer(new, verdict)

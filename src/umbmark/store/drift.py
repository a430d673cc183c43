"""Whether a robot's errors drift between its recorded calibrations.

A pass measures ``E_d`` and ``E_b`` relative to the odometry parameters active during it:
a pass on odometry already corrected by an earlier calibration measures what is left
after the correction (``E_b`` near 1), not the robot. What the robot *is* comes from
composing the measured errors with those parameters, the composition ``umbmark
calibrate`` makes for the new parameters (:class:`umbmark.calibration.compose.Calibration`):

- ``robot E_d = c_R,new / c_L,new = E_d c_R,active / c_L,active`` (Eqs. 4.31-4.32), the
  robot's ``D_R / D_L``;
- ``robot E_b = wheel_separation_multiplier,new = E_b x multiplier,active`` (Eq. 4.26),
  its effective wheelbase over the configured (nominal) one.

:func:`drift_verdict` compares those of the first and the last calibration
(:attr:`CalibrationRecord.robot_E_d <umbmark.store.records.CalibrationRecord.robot_E_d>`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from umbmark.store.records import CalibrationRecord

__all__ = ["DEFINITIONS", "DRIFT_MIN_CALIBRATIONS", "DRIFT_SIGMAS", "drift_verdict"]

#: Fewest calibrations the drift check needs.
DRIFT_MIN_CALIBRATIONS = 3
#: The change that counts as drift, in standard errors of the change.
DRIFT_SIGMAS = 3.0

#: What a calibration's figures in the history mean (``history --json`` prints them).
DEFINITIONS = {
    "E_d": "measured by the pass: D_R / D_L relative to the odometry parameters active during it",
    "E_b": "measured by the pass: b_actual / b_effective relative to the odometry "
    "parameters active during it",
    "robot_E_d": "what the robot is: the pass's E_d composed with the active c_L, c_R "
    "(E_d c_R / c_L = the new c_R / c_L), the robot's D_R / D_L",
    "robot_E_b": "what the robot is: the pass's E_b composed with the active "
    "wheel_separation_multiplier (E_b x multiplier = the new multiplier), the robot's "
    "effective wheelbase over the nominal one",
    "robot_wheelbase": "the robot's effective wheelbase [m]: robot_E_b x nominal wheelbase",
    "drift": f"robot_E_d and robot_E_b of the first and the last calibration compared (E_b on "
    f"the last one's nominal wheelbase); a change over {DRIFT_SIGMAS:g} standard errors of it "
    "is drift",
}


def drift_verdict(calibrations: Sequence[CalibrationRecord]) -> str | None:
    """Whether the robot's ``E_d`` or ``E_b`` drifted between the first and the last
    calibration.

    It compares what the robot is, :attr:`~umbmark.store.history.CalibrationRecord.robot_E_d`
    and ``robot_E_b`` (each pass's measured errors composed with the parameters active
    during it), not what the passes measured: passes on corrected odometry measure what
    the correction left. A change counts as drift when it exceeds :data:`DRIFT_SIGMAS`
    times its standard error, ``sqrt(se_first^2 + se_last^2)`` from the two calibrations'
    standard errors (the active parameters are exact). ``E_b`` of a robot whose nominal
    wheelbase was changed between the two (a fleet's) is compared on the last nominal.

    Parameters
    ----------
    calibrations : sequence of CalibrationRecord
        A robot's calibrations, oldest first.

    Returns
    -------
    str or None
        One line for people; None with fewer than :data:`DRIFT_MIN_CALIBRATIONS`.
    """
    if len(calibrations) < DRIFT_MIN_CALIBRATIONS:
        return None
    first, last = calibrations[0], calibrations[-1]
    drifted: list[str] = []
    steady: list[str] = []
    unknown: list[str] = []
    for name in ("E_d", "E_b"):
        a, b = float(getattr(first, f"robot_{name}")), float(getattr(last, f"robot_{name}"))
        se_a = first.robot_standard_errors.get(name)
        se_b = last.robot_standard_errors.get(name)
        if name == "E_b":  # on the last one's nominal wheelbase, where it was changed
            scale = float(first.active["wheelbase"]) / float(last.active["wheelbase"])
            a, se_a = a * scale, None if se_a is None else se_a * scale
        if se_a is None or se_b is None or not math.isfinite(se_a + se_b):
            unknown.append(f"robot {name}")
            continue
        se = math.hypot(se_a, se_b)
        change = b - a
        text = f"robot {name} {a:.6f} -> {b:.6f} ({change:+.2e}, {DRIFT_SIGMAS:g} x se = "
        text += f"{DRIFT_SIGMAS * se:.2e})"
        (drifted if abs(change) > DRIFT_SIGMAS * se else steady).append(text)
    span = f"between calibrations {first.id} and {last.id}"
    parts = []
    if drifted:
        parts.append(f"drift {span}: {'; '.join(drifted)}")
    if steady:
        parts.append(f"{'no drift' if not drifted else 'within noise'} {span}: {'; '.join(steady)}")
    if unknown:
        parts.append(f"no standard errors to judge {', '.join(unknown)}")
    return ". ".join(parts)

"""A robot's present state, and what to apply from it: one story for the figures, the
E_max,syst, the overlay and the verdict.

The fleet follows what each robot *is*, not what each recording measured against the
parameters active while it was made: a recording made after a correction was applied
measures what the correction left (errors near 1), so its figures are composed with the
parameters active during it (:func:`robot_terms`, the composition ``umbmark history``
compares, :mod:`umbmark.store.drift`), and ``E_b`` and ``E_s`` are put on the latest
nominal wheelbase and wheel diameter:

- ``E_d`` of the robot: ``E_d c_R,active / c_L,active`` (its ``D_R / D_L``);
- ``E_b``: ``E_b x wheel_separation_multiplier,active x b / b_latest``;
- ``E_s``: the mean of its two new wheel factors, ``E_s (c_L 2 / (E_d + 1) + c_R 2 E_d /
  (E_d + 1)) / 2 x D / D_latest`` (Eqs. 4.31 and 4.32 with the active factors).

From the robot's present figures (each figure's course since its last change,
:class:`umbmark.calibration.changes.Change`), :func:`to_apply` gives the three multipliers
to set: ``wheel_separation_multiplier = E_b``, ``left = 2 E_s / (E_d + 1)``, ``right = 2
E_s E_d / (E_d + 1)`` (absolute: what the controller should hold, whatever it holds now),
the overlay keyed by the robot's controller, and the verdict: the worst of the verdicts
of the recordings the present state rests on, and no better than "apply with care" where
that state is the latest recording alone (a change still to be confirmed).
:func:`present_e_max_syst` is the E_max,syst the present errors make with the parameters
active in the latest recording, on the standard 4 m square.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from umbmark.fleets.outcome import RecordingOutcome, e_max_on_standard_square

__all__ = ["LEVELS", "UNCONFIRMED", "ToApply", "present_e_max_syst", "robot_terms", "to_apply"]

#: The verdicts, best first.
LEVELS = ("apply", "care", "do-not-apply")
#: Why a change in the latest recording is offered with care only.
UNCONFIRMED = (
    "the change is in the latest recording alone: confirm it with the next recording "
    "before relying on it"
)


@dataclass(frozen=True)
class ToApply:
    """What to put into a robot's controller from its present state.

    Attributes
    ----------
    multipliers : (float, float, float)
        ``wheel_separation_multiplier``, ``left_wheel_radius_multiplier`` and
        ``right_wheel_radius_multiplier`` to set.
    verdict : str
        ``apply``, ``care`` or ``do-not-apply``.
    reasons : tuple of str
        Why not plainly ``apply``.
    basis : str
        What the values rest on, for people.
    overlay : str or None
        The ros2_control overlay (YAML text) keyed by the robot's controller; None where
        the verdict is do not apply.
    """

    multipliers: tuple[float, float, float]
    verdict: str
    reasons: tuple[str, ...]
    basis: str
    overlay: str | None

    @property
    def offered(self) -> bool:
        """Whether the overlay is offered (the verdict lets it be applied)."""
        return self.overlay is not None

    def line(self) -> str:
        """One line: the values, or why none are offered."""
        if not self.offered:
            return f"nothing offered: do not apply ({'; '.join(self.reasons)})"
        sep, left, right = self.multipliers
        care = f"; apply with care: {'; '.join(self.reasons)}" if self.verdict == "care" else ""
        return (
            f"wheel_separation_multiplier {sep:.6f}, left_wheel_radius_multiplier {left:.6f}, "
            f"right_wheel_radius_multiplier {right:.6f} ({self.basis}{care})"
        )

    def to_dict(self) -> dict[str, Any]:
        sep, left, right = self.multipliers
        return {
            "wheel_separation_multiplier": sep,
            "left_wheel_radius_multiplier": left,
            "right_wheel_radius_multiplier": right,
            "verdict": self.verdict,
            "reasons": list(self.reasons),
            "basis": self.basis,
            "overlay": self.overlay,
        }


@dataclass(frozen=True)
class _Active:
    """The odometry parameters a recording was calibrated against."""

    c_left: float = 1.0
    c_right: float = 1.0
    separation: float = 1.0
    wheelbase: float | None = None
    diameter: float | None = None

    @classmethod
    def of(cls, outcome: RecordingOutcome) -> _Active:
        active: Mapping[str, Any] = outcome.record.get("active") or {}
        diameter = outcome.record.get("wheel_diameter")

        def factor(key: str) -> float:
            value = active.get(key)
            if isinstance(value, (int, float)) and math.isfinite(value) and value > 0:
                return float(value)
            return 1.0

        return cls(
            factor("c_L"),
            factor("c_R"),
            factor("wheel_separation_multiplier"),
            outcome.wheelbase or None,
            float(diameter) if isinstance(diameter, (int, float)) and diameter > 0 else None,
        )

    def scale_of(self, E_d: float) -> float:
        """The mean of the two wheel factors a correction of ``E_d`` composes to, over
        ``E_s`` (Eqs. 4.31, 4.32)."""
        return (self.c_left * 2.0 / (E_d + 1.0) + self.c_right * 2.0 * E_d / (E_d + 1.0)) / 2.0


def _ratio(ours: float | None, theirs: float | None) -> float:
    return ours / theirs if ours and theirs else 1.0


def robot_terms(outcome: RecordingOutcome, latest: RecordingOutcome) -> RecordingOutcome:
    """``outcome``'s figures as what the robot is (see the module), ``E_b`` (and ``E_b``
    relative to the gyro) and ``E_s`` on ``latest``'s nominal geometry; the laser's and
    the gyro's own figures as they are."""
    mine, last = _Active.of(outcome), _Active.of(latest)
    E_d = outcome.figures.get("E_d", (1.0, None))[0]
    E_b = mine.separation * _ratio(mine.wheelbase, last.wheelbase)
    scale = {
        "E_d": mine.c_right / mine.c_left,
        "E_b": E_b,
        "E_b_gyro": E_b,  # E_b k_g: the wheelbase's factor alike, the gyro's as it is
        "E_s": mine.scale_of(E_d) * _ratio(mine.diameter, last.diameter),
    }
    if all(v == 1.0 for v in scale.values()):
        return outcome
    figures = {
        name: (v * scale.get(name, 1.0), None if se is None else se * scale.get(name, 1.0))
        for name, (v, se) in outcome.figures.items()
    }
    return replace(outcome, figures=figures)


def _relative(present: Mapping[str, float], latest: RecordingOutcome) -> tuple[float, float, float]:
    """The robot's present ``E_d``, ``E_b``, ``E_s`` relative to the parameters active in
    ``latest`` (what its odometry now makes of them); ``E_s`` 1 where not measured."""
    active = _Active.of(latest)
    E_d = present["E_d"] * active.c_left / active.c_right
    E_b = present["E_b"] / active.separation
    E_s = present["E_s"] / active.scale_of(E_d) if "E_s" in present else 1.0
    return E_d, E_b, E_s


def present_e_max_syst(present: Mapping[str, float], latest: RecordingOutcome) -> float | None:
    """E_max,syst [m] the robot's present errors make on the standard 4 m square, driven
    with the parameters active in its latest recording (both directions, the worse)."""
    if "E_d" not in present or "E_b" not in present or not latest.wheelbase:
        return None
    return e_max_on_standard_square(*_relative(present, latest), latest.wheelbase)


def to_apply(
    present: Mapping[str, float],
    rests_on: Sequence[RecordingOutcome],
    latest: RecordingOutcome,
    *,
    basis: str,
    cautions: Sequence[str] = (),
) -> ToApply | None:
    """What to set from the robot's present figures (see the module).

    Parameters
    ----------
    present : mapping of str to float
        The robot's present ``E_d``, ``E_b`` and, where measured, ``E_s`` (what it is).
    rests_on : sequence of RecordingOutcome
        The recordings the present state rests on.
    latest : RecordingOutcome
        The robot's latest calibrated recording (its controller, its active parameters).
    basis : str
        What the values rest on, for people.
    cautions : sequence of str
        Why it is to be applied with care at best, whatever the recordings' verdicts (the
        present state is the latest recording alone, :data:`UNCONFIRMED`; the newest
        calibration failed its checks).

    Returns
    -------
    ToApply or None
        None without ``E_d`` and ``E_b``.
    """
    from umbmark.calibration.result import unnamed_controller
    from umbmark.sources.params.writer import ros2_control_overlay

    if "E_d" not in present or "E_b" not in present:
        return None
    E_d, E_b = present["E_d"], present["E_b"]
    E_s = present.get("E_s", _Active.of(latest).scale_of(_relative(present, latest)[0]))
    multipliers = (E_b, 2.0 * E_s / (E_d + 1.0), 2.0 * E_s * E_d / (E_d + 1.0))
    verdicts = [o.verdict for o in rests_on if o.verdict in LEVELS] or ["apply"]
    level = max(verdicts, key=LEVELS.index)
    reasons: list[str] = []
    for o in rests_on:
        for reason in (o.record.get("verdict") or {}).get("reasons") or []:
            if reason not in reasons:
                reasons.append(str(reason))
    if level == "apply":
        reasons = []
    if cautions and level == "apply":
        level = "care"
    reasons += [c for c in cautions if c not in reasons]
    overlay = None
    if level != "do-not-apply":
        controller = latest.record.get("controller") or {}
        keys = tuple(controller.get("key_path") or ()) or None
        comments = [
            f"Written by umbmark fleet for {latest.robot}: its present E_d = {E_d:.6f}, "
            f"E_b = {E_b:.6f}, E_s = {E_s:.6f} ({basis}).",
            "The values to set: what the controller should hold, whatever it holds now.",
            "diff_drive_controller reads these on configure: reload or restart the controller.",
            *([] if level == "apply" else [f"apply with care: {'; '.join(reasons)}"]),
            *([] if controller.get("named") else [unnamed_controller()]),
        ]
        reorder = (multipliers[1], multipliers[2], multipliers[0])
        overlay = (
            ros2_control_overlay(reorder, comments, keys)
            if keys
            else ros2_control_overlay(reorder, comments)
        )
    return ToApply(multipliers, level, tuple(reasons), basis, overlay)

"""Reading a calibration result (``umbmark calibrate -o result.json``) back."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from ..kinematics import WheelParams
from .ros_params import ActiveMultipliers
from .runs_table import read_text

__all__ = [
    "CalibratedParams",
    "is_result_file",
    "read_active_from_result",
    "read_calibrated_params",
]


@dataclass(frozen=True)
class CalibratedParams:
    """The odometry parameters a calibration result asks for.

    Attributes
    ----------
    wheelbase : float
        New effective wheelbase [m].
    c_left, c_right : float
        New absolute wheel factors.
    wheel_diameter_left, wheel_diameter_right : float or None
        New effective diameters [m], when the result knew the nominal diameter.
    source : str
        The file.
    """

    wheelbase: float
    c_left: float
    c_right: float
    wheel_diameter_left: float | None = None
    wheel_diameter_right: float | None = None
    separation_multiplier: float = 1.0
    configured_wheelbase: float | None = None
    wheel_diameter: float | None = None
    source: str = ""

    def applied_to(self, nominal: WheelParams) -> WheelParams:
        """``nominal`` with this result's wheelbase and wheel factors.

        Where the result knows the absolute diameters, they carry over even to a robot
        description with another nominal diameter.
        """
        c_left, c_right = self.c_left, self.c_right
        if self.wheel_diameter_left is not None and self.wheel_diameter_right is not None:
            c_left = self.wheel_diameter_left / nominal.wheel_diameter
            c_right = self.wheel_diameter_right / nominal.wheel_diameter
        return nominal.with_corrections(c_left=c_left, c_right=c_right, wheelbase=self.wheelbase)


def read_calibrated_params(path: str | Path) -> CalibratedParams:
    """Read the new parameters from a result JSON written by ``umbmark calibrate -o``.

    Raises
    ------
    InputError
        If the file is not such a result.
    """
    try:
        data = json.loads(read_text(path))
    except json.JSONDecodeError as exc:
        raise InputError(f"is not JSON ({exc.msg})", source=path, row=exc.lineno) from None
    if not isinstance(data, dict) or not isinstance(data.get("new"), dict):
        raise InputError(
            "is not an umbmark calibration result (no 'new' parameters; write one with "
            "umbmark calibrate -o FILE)",
            source=path,
        )
    new = data["new"]

    def number(container: dict[str, object], key: str, where: str) -> float:
        value = container.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(f"{where}{key} is missing or not a number", source=path)
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"{where}{key} is {value!r}, not a positive number", source=path)
        return float(value)

    def optional(key: str) -> float | None:
        return None if data.get(key) is None else number(data, key, "")

    active = data.get("active")
    if not isinstance(active, dict):
        active = {}
    return CalibratedParams(
        wheelbase=number(new, "wheelbase", "new."),
        c_left=number(new, "c_L", "new."),
        c_right=number(new, "c_R", "new."),
        wheel_diameter_left=optional("wheel_diameter_left"),
        wheel_diameter_right=optional("wheel_diameter_right"),
        separation_multiplier=number(new, "wheel_separation_multiplier", "new.")
        if "wheel_separation_multiplier" in new
        else 1.0,
        configured_wheelbase=number(active, "wheelbase", "active.")
        if active.get("wheelbase") is not None
        else None,
        wheel_diameter=number(active, "wheel_diameter", "active.")
        if active.get("wheel_diameter") is not None
        else None,
        source=str(path),
    )


def is_result_file(path: str | Path) -> bool:
    """Whether ``path`` looks like a calibration result (JSON with new parameters)."""
    try:
        data = json.loads(read_text(path))
    except (json.JSONDecodeError, InputError):
        return False
    return isinstance(data, dict) and isinstance(data.get("new"), dict)


def read_active_from_result(path: str | Path) -> ActiveMultipliers:
    """What was active on runs driven with a calibration result applied.

    The configured wheelbase stays; the separation multiplier and the wheel factors are
    the result's new ones.
    """
    new = read_calibrated_params(path)
    return ActiveMultipliers(
        wheel_separation_multiplier=new.separation_multiplier,
        left_wheel_radius_multiplier=new.c_left,
        right_wheel_radius_multiplier=new.c_right,
        wheel_separation=new.configured_wheelbase,
        wheel_radius=None if new.wheel_diameter is None else 0.5 * new.wheel_diameter,
    )

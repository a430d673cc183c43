"""Reading odometry parameters from files: controller parameter YAML and umbmark results.

Two questions are asked of such files:

- **What was active during the runs?** (:func:`read_parameter_file`) A ros2_control or
  ROS 1 ``diff_drive_controller`` parameter file gives its multipliers and, where it has
  them, ``wheel_separation`` and ``wheel_radius``; a previous result
  (``umbmark calibrate -o result.json``) whose new values were applied gives those.
- **What does a calibration ask for?** (:func:`read_calibrated_params`) The new
  wheelbase and wheel factors of a result, to replay or simulate with.

ros2_control's ``diff_drive_controller`` scales its configured geometry by three
multipliers: effective separation ``wheel_separation_multiplier * wheel_separation`` and
effective radii ``left/right_wheel_radius_multiplier * wheel_radius``. ROS 1's has
parameters of the same names, without the ``ros__parameters`` level. Writing them is
:mod:`umbmark.outputs.controller_params`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import yaml

from ..errors import InputError
from ..kinematics import WheelParams
from .text import read_text

__all__ = [
    "DEFAULT_CONTROLLER",
    "CalibratedParams",
    "ControllerParams",
    "is_result_file",
    "read_calibrated_params",
    "read_controller_params",
    "read_parameter_file",
]

DEFAULT_CONTROLLER = "diff_drive_controller"
MULTIPLIER_KEYS = (
    "wheel_separation_multiplier",
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
)
GEOMETRY_KEYS = ("wheel_separation", "wheel_radius")


@dataclass(frozen=True)
class ControllerParams:
    """The ``diff_drive_controller`` parameters a file says were active during the runs.

    Attributes
    ----------
    wheel_separation_multiplier, left_wheel_radius_multiplier, right_wheel_radius_multiplier : float
        The multipliers (1.0 where the file does not set them).
    wheel_separation, wheel_radius : float or None
        Configured geometry [m], where the file has it.
    controller : str
        The controller's node name (its last part, without namespaces).
    """

    wheel_separation_multiplier: float = 1.0
    left_wheel_radius_multiplier: float = 1.0
    right_wheel_radius_multiplier: float = 1.0
    wheel_separation: float | None = None
    wheel_radius: float | None = None
    controller: str = DEFAULT_CONTROLLER


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
    separation_multiplier : float
        New ``wheel_separation_multiplier``.
    configured_wheelbase : float or None
        The configured wheelbase [m] the multiplier scales (``wheel_separation``).
    wheel_diameter : float or None
        The nominal diameter ``D_n`` [m] the result knew.
    spot_wheelbase : float or None
        For a model whose wheelbase depends on turning (``trajectory-scrub``): the
        wheelbase of turns on the spot [m]; ``wheelbase`` is then the arcs' (see
        :class:`umbmark.kinematics.WheelParams`).
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
    spot_wheelbase: float | None = None
    source: str = ""

    def applied_to(self, nominal: WheelParams) -> WheelParams:
        """``nominal`` with this result's wheelbase(s) and wheel factors.

        Where the result knows the absolute diameters, they carry over even to a robot
        description with another nominal diameter.
        """
        c_left, c_right = self.c_left, self.c_right
        if self.wheel_diameter_left is not None and self.wheel_diameter_right is not None:
            c_left = self.wheel_diameter_left / nominal.wheel_diameter
            c_right = self.wheel_diameter_right / nominal.wheel_diameter
        corrected = nominal.with_corrections(
            c_left=c_left, c_right=c_right, wheelbase=self.wheelbase
        )
        return replace(corrected, spot_wheelbase=self.spot_wheelbase)


# --- results ---------------------------------------------------------------------------


def _result_data(path: str | Path) -> dict[str, Any]:
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
    return data


def read_calibrated_params(path: str | Path) -> CalibratedParams:
    """Read the new parameters from a result JSON written by ``umbmark calibrate -o``.

    Raises
    ------
    InputError
        If the file is not such a result.
    """
    data = _result_data(path)
    new = data["new"]

    def number(container: dict[str, object], key: str, where: str) -> float:
        value = container.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(f"{where}{key} is missing or not a number", source=path)
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"{where}{key} is {value!r}, not a positive number", source=path)
        return float(value)

    def optional(container: dict[str, object], key: str, where: str) -> float | None:
        return None if container.get(key) is None else number(container, key, where)

    active = data.get("active")
    if not isinstance(active, dict):
        active = {}
    model = data.get("model")
    if isinstance(model, dict):
        # The fitted model replays as fitted; "new" holds the single set for controllers.
        return CalibratedParams(
            wheelbase=number(model, "wheelbase", "model."),
            c_left=number(new, "c_L", "new."),
            c_right=number(new, "c_R", "new."),
            wheel_diameter_left=number(model, "wheel_diameter_left", "model."),
            wheel_diameter_right=number(model, "wheel_diameter_right", "model."),
            spot_wheelbase=optional(model, "spot_wheelbase", "model."),
            source=str(path),
        )
    return CalibratedParams(
        wheelbase=number(new, "wheelbase", "new."),
        c_left=number(new, "c_L", "new."),
        c_right=number(new, "c_R", "new."),
        wheel_diameter_left=optional(data, "wheel_diameter_left", ""),
        wheel_diameter_right=optional(data, "wheel_diameter_right", ""),
        separation_multiplier=optional(new, "wheel_separation_multiplier", "new.") or 1.0,
        configured_wheelbase=optional(active, "wheelbase", "active."),
        wheel_diameter=optional(active, "wheel_diameter", "active."),
        source=str(path),
    )


def is_result_file(path: str | Path) -> bool:
    """Whether ``path`` looks like a calibration result (JSON with new parameters)."""
    try:
        _result_data(path)
    except InputError:
        return False
    return True


# --- controller parameter files --------------------------------------------------------


def read_parameter_file(path: str | Path, controller: str | None = None) -> ControllerParams:
    """What was active during the runs, from a controller parameter YAML or a result JSON.

    A result's new values count as applied: the configured wheelbase stays, the
    separation multiplier and the wheel factors are the result's new ones.

    Raises
    ------
    InputError
        If the file is neither, or names no such controller.
    """
    if not is_result_file(path):
        return read_controller_params(path, controller)
    new = read_calibrated_params(path)
    return ControllerParams(
        wheel_separation_multiplier=new.separation_multiplier,
        left_wheel_radius_multiplier=new.c_left,
        right_wheel_radius_multiplier=new.c_right,
        wheel_separation=new.configured_wheelbase,
        wheel_radius=None if new.wheel_diameter is None else 0.5 * new.wheel_diameter,
        controller=controller or DEFAULT_CONTROLLER,
    )


def read_controller_params(path: str | Path, controller: str | None = None) -> ControllerParams:
    """Read the multipliers (and geometry) a ros2_control or ROS 1 parameter file sets.

    Parameters
    ----------
    path : path
        A YAML parameter file.
    controller : str, optional
        The controller's node name; by default the one node that has diff-drive
        parameters.

    Raises
    ------
    InputError
        If the file is not YAML, or names no such controller.
    """
    try:
        data = yaml.safe_load(read_text(path))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise InputError(
            f"is not valid YAML ({getattr(exc, 'problem', None) or exc})",
            source=path,
            row=None if mark is None else mark.line + 1,
        ) from None
    candidates = dict(_parameter_blocks(data))
    if controller is not None:
        # A namespaced node matches by its last part as well.
        matches = [n for n in candidates if controller in (n, n.rsplit("/", 1)[-1])]
        if len(matches) == 1:
            controller = matches[0]
        if controller not in candidates:
            found = ", ".join(sorted(candidates)) or "none"
            raise InputError(
                f"has no diff-drive parameters for controller {controller!r} "
                f"(controllers with them: {found})",
                source=path,
            )
        name = controller
    elif len(candidates) == 1:
        name = next(iter(candidates))
    elif not candidates:
        raise InputError(
            "has no diff_drive_controller parameters (wheel_separation, *_multiplier)",
            source=path,
        )
    else:
        raise InputError(
            f"has several controllers ({', '.join(sorted(candidates))}); "
            "name one with --controller",
            source=path,
        )
    params = candidates[name]
    values: dict[str, float] = {}
    for key in (*MULTIPLIER_KEYS, *GEOMETRY_KEYS):
        if key in params:
            value = params[key]
            if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
                raise InputError(f"{key} is {value!r}, not a positive number", source=path)
            values[key] = float(value)
    return ControllerParams(**values, controller=name.rsplit("/", 1)[-1])


def _parameter_blocks(data: object, prefix: str = "") -> list[tuple[str, dict[str, Any]]]:
    """Every mapping that holds diff-drive keys, named by its node (``ros__parameters``
    levels and namespaces skipped)."""
    found: list[tuple[str, dict[str, Any]]] = []
    if not isinstance(data, dict):
        return found
    keys = set(MULTIPLIER_KEYS) | set(GEOMETRY_KEYS)
    for name, value in data.items():
        if not isinstance(value, dict):
            continue
        inner = value.get("ros__parameters", value)
        if isinstance(inner, dict) and keys & set(inner):
            found.append((str(name) if not prefix else f"{prefix}/{name}", inner))
        else:
            found.extend(_parameter_blocks(value, str(name)))
    return found

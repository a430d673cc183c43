"""Controller parameter files: ros2_control overlays and ROS 1 parameters, read and written.

ros2_control's ``diff_drive_controller`` scales its configured geometry by three
multipliers: effective separation ``wheel_separation_multiplier * wheel_separation`` and
effective radii ``left/right_wheel_radius_multiplier * wheel_radius``. UMBmark's
correction maps onto them one to one: left by ``c_L``, right by ``c_R``, separation by
``E_b``, multiplied into the values that were active during the runs
(:mod:`umbmark.calibration`). The controller reads them only on configure, and its
parameters are doubles, so every value is written with a decimal point (``1.0``, not ``1``).
ROS 1's ``diff_drive_controller`` has parameters of the same names, without the
``ros__parameters`` level.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from ..calibration import Calibration
from ..errors import InputError
from .runs_table import read_text

__all__ = [
    "DEFAULT_CONTROLLER",
    "ActiveMultipliers",
    "read_active_multipliers",
    "ros1_params",
    "ros2_control_overlay",
]

DEFAULT_CONTROLLER = "diff_drive_controller"
_MULTIPLIER_KEYS = (
    "wheel_separation_multiplier",
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
)
_GEOMETRY_KEYS = ("wheel_separation", "wheel_radius")


@dataclass(frozen=True)
class ActiveMultipliers:
    """What a controller parameter file says was active during the runs."""

    wheel_separation_multiplier: float = 1.0
    left_wheel_radius_multiplier: float = 1.0
    right_wheel_radius_multiplier: float = 1.0
    wheel_separation: float | None = None
    wheel_radius: float | None = None
    controller: str = "diff_drive_controller"


def _multipliers(calibration: Calibration) -> dict[str, float]:
    return {
        "wheel_separation_multiplier": _tidy(calibration.new_separation_multiplier),
        "left_wheel_radius_multiplier": _tidy(calibration.new_c_left),
        "right_wheel_radius_multiplier": _tidy(calibration.new_c_right),
    }


def _tidy(value: float) -> float:
    """Round to 10 significant digits: beyond any calibration's precision, easy to read."""
    return float(f"{value:.10g}")


def _document(body: Mapping[str, Any], comments: Sequence[str]) -> str:
    header = "".join(f"# {line}\n" for line in comments)
    text = yaml.safe_dump(dict(body), sort_keys=False, default_flow_style=False)
    return header + text


def ros2_control_overlay(
    calibration: Calibration, comments: Sequence[str] = (), controller: str = DEFAULT_CONTROLLER
) -> str:
    """A ros2_control parameter overlay with the new multipliers (YAML text)."""
    return _document({controller: {"ros__parameters": _multipliers(calibration)}}, comments)


def ros1_params(
    calibration: Calibration, comments: Sequence[str] = (), controller: str = DEFAULT_CONTROLLER
) -> str:
    """ROS 1 ``diff_drive_controller`` parameters with the new multipliers (YAML text)."""
    return _document({controller: _multipliers(calibration)}, comments)


def read_active_multipliers(path: str | Path, controller: str | None = None) -> ActiveMultipliers:
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
    for key in (*_MULTIPLIER_KEYS, *_GEOMETRY_KEYS):
        if key in params:
            value = params[key]
            if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
                raise InputError(f"{key} is {value!r}, not a positive number", source=path)
            values[key] = float(value)
    return ActiveMultipliers(**values, controller=name.rsplit("/", 1)[-1])


def _parameter_blocks(data: object, prefix: str = "") -> list[tuple[str, dict[str, Any]]]:
    """Every mapping that holds diff-drive keys, named by its node (``ros__parameters``
    levels and namespaces skipped)."""
    found: list[tuple[str, dict[str, Any]]] = []
    if not isinstance(data, dict):
        return found
    keys = set(_MULTIPLIER_KEYS) | set(_GEOMETRY_KEYS)
    for name, value in data.items():
        if not isinstance(value, dict):
            continue
        inner = value.get("ros__parameters", value)
        if isinstance(inner, dict) and keys & set(inner):
            found.append((str(name) if not prefix else f"{prefix}/{name}", inner))
        else:
            found.extend(_parameter_blocks(value, str(name)))
    return found

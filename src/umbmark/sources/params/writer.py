"""Writing controller parameters: ros2_control overlays and ROS 1 parameter files.

ros2_control's ``diff_drive_controller`` scales its configured geometry by three
multipliers: effective separation ``wheel_separation_multiplier * wheel_separation`` and
effective radii ``left/right_wheel_radius_multiplier * wheel_radius``. UMBmark's
correction maps onto them one to one: left by ``c_L``, right by ``c_R``, separation by
``E_b``, multiplied into the values that were active during the runs
(:mod:`umbmark.calibration.compose`). The controller reads them only on configure, and its
parameters are doubles, so every value is written with a decimal point (``1.0``, not ``1``).
ROS 1's ``diff_drive_controller`` has parameters of the same names, without the
``ros__parameters`` level. Reading such files is :mod:`umbmark.sources.params.reader`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import yaml

from umbmark.sources.params.reader import DEFAULT_CONTROLLER

__all__ = ["multiplier_values", "parameter_document", "ros1_params", "ros2_control_overlay"]


def multiplier_values(separation: float, left: float, right: float) -> dict[str, float]:
    """The three multipliers by their parameter names, as the controller's doubles."""
    return {
        "wheel_separation_multiplier": _tidy(separation),
        "left_wheel_radius_multiplier": _tidy(left),
        "right_wheel_radius_multiplier": _tidy(right),
    }


def _multipliers(c_left: float, c_right: float, separation: float) -> dict[str, float]:
    return multiplier_values(separation, c_left, c_right)


def _tidy(value: float) -> float:
    """Round to 10 significant digits: beyond any calibration's precision, easy to read."""
    return float(f"{value:.10g}")


def parameter_document(body: Mapping[str, Any], comments: Sequence[str] = ()) -> str:
    """A parameter file's text: ``comments`` as ``#`` lines, then ``body`` as block YAML,
    keys in their order (floats keep their point: ``1.0``)."""
    return _document(body, comments)


def _document(body: Mapping[str, Any], comments: Sequence[str]) -> str:
    header = "".join(f"# {line}\n" for line in comments)
    text = yaml.safe_dump(dict(body), sort_keys=False, default_flow_style=False)
    return header + text


def _nested(keys: Sequence[str], leaf: Mapping[str, Any]) -> dict[str, Any]:
    """``leaf`` under the keys ``keys`` (outermost first)."""
    out: dict[str, Any] = dict(leaf)
    for key in reversed(keys):
        out = {key: out}
    return out


def ros2_control_overlay(
    new: tuple[float, float, float],
    comments: Sequence[str] = (),
    key_path: Sequence[str] = (DEFAULT_CONTROLLER,),
) -> str:
    """A ros2_control parameter overlay with the new multipliers ``new``: ``c_L``, ``c_R``
    and ``wheel_separation_multiplier`` (YAML text).

    ``key_path`` are the keys of the controller in the user's file (``("robot1",
    "diff_cont")``, ``("/robot1/diff_cont",)``, ``("/**",)``): the overlay is keyed the
    same way, so that the parameter server applies it to the same node.
    """
    return _document(_nested(key_path, {"ros__parameters": _multipliers(*new)}), comments)


def ros1_params(
    new: tuple[float, float, float],
    comments: Sequence[str] = (),
    key_path: Sequence[str] = (DEFAULT_CONTROLLER,),
) -> str:
    """ROS 1 ``diff_drive_controller`` parameters with the new multipliers ``new``:
    ``c_L``, ``c_R`` and ``wheel_separation_multiplier`` (YAML text).

    ROS 1's controller takes ``wheel_radius_multiplier``, when it is set, for both wheels
    and ignores the left and right ones: these left and right values work only once it is
    deleted (the caller says so in ``comments``).
    """
    return _document(_nested(key_path, _multipliers(*new)), comments)

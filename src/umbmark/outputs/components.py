"""What the figures of an estimate mean, for people.

An estimator reports figures of its own besides ``alpha``, ``beta``, ``E_d``, ``E_b``
(:attr:`umbmark.estimators.base.ErrorEstimate.components`, SI units: metres, radians,
seconds). :data:`COMPONENTS` names each one for people: a label, the unit it is shown in
(lengths in mm, angles in deg, times in ms) and what it means. The terminal and the HTML
page show them from here; the JSON keeps the SI values.

Angles a person reads are in degrees everywhere (alpha, beta and the heading figures);
:data:`ANGLE_UNIT` names that unit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

__all__ = ["ANGLE_UNIT", "COMPONENTS", "Component", "component", "to_shown"]

#: The unit of every angle a person reads (terminal, HTML page); JSON stays in radians.
ANGLE_UNIT = "deg"
#: Factor from the SI value to the unit shown.
_SCALE = {
    "mm": 1000.0,
    "ms": 1000.0,
    ANGLE_UNIT: 180.0 / math.pi,
    f"{ANGLE_UNIT}/s": 180.0 / math.pi,
}


def to_shown(value: float, unit: str) -> float:
    """``value`` (SI: m, rad, s) in ``unit`` (``mm``, ``deg``, ``ms``; else unchanged)."""
    return value * _SCALE.get(unit, 1.0)


@dataclass(frozen=True)
class Component:
    """One figure of an estimate, for people.

    Attributes
    ----------
    label : str
        Its name (without the unit).
    unit : str
        The unit it is shown in (``mm``, ``deg``, ``ms``), or empty (a ratio, a count, a
        probability).
    meaning : str
        What it says, in one phrase.
    digits : str
        Its format.
    """

    label: str
    unit: str = ""
    meaning: str = ""
    digits: str = ".6g"

    @property
    def heading(self) -> str:
        """The label with its unit: ``left wheel radius [mm]``."""
        return f"{self.label} [{self.unit}]" if self.unit else self.label

    def show(self, value: float) -> str:
        """``value`` (SI) formatted in the unit shown."""
        return format(to_shown(value, self.unit), self.digits)


_RESIDUALS = "between the ground truth and the fitted odometry"
COMPONENTS: Mapping[str, Component] = {
    # paper: Eqs. 4.20-4.27 on each axis
    "alpha_x": Component("alpha from the x coordinates", ANGLE_UNIT, "Eq. 4.24a", ".4f"),
    "alpha_y": Component("alpha from the y coordinates", ANGLE_UNIT, "Eq. 4.24b", ".4f"),
    "beta_x": Component("beta from the x coordinates", ANGLE_UNIT, "Eq. 4.20a", ".4f"),
    "beta_y": Component("beta from the y coordinates", ANGLE_UNIT, "Eq. 4.20b", ".4f"),
    "E_b_x": Component("E_b from alpha_x", "", "Eq. 4.27", ".6f"),
    "E_b_y": Component("E_b from alpha_y", "", "Eq. 4.27", ".6f"),
    "E_d_x": Component("E_d from beta_x", "", "Eq. 4.22", ".6f"),
    "E_d_y": Component("E_d from beta_y", "", "Eq. 4.22", ".6f"),
    # exact
    "residual_rms": Component(
        "misfit of the exact geometry (rms)",
        "mm",
        "how far the four coordinates of the two centres of gravity lie from the end "
        "points of the fitted alpha and beta, root mean square: near 0 when one robot of "
        "the model explains both clusters",
        ".3f",
    ),
    # endpose
    "model_check_statistic": Component(
        "model check statistic",
        "",
        "the centres' misfit to the best robot of the model, in units of their scatter (Hotelling)",
        ".3g",
    ),
    "model_check_p": Component(
        "model check p-value",
        "",
        "probability of runs this far from every robot of the model by scatter alone; "
        "below 0.001 a warning says so",
        ".3g",
    ),
    "headings_used": Component(
        "end headings used", "", "1: fitted with the end positions, 0: positions only", ".0f"
    ),
    # heading
    "eps_theta_cw": Component(
        "mean heading error of the cw runs", ANGLE_UNIT, "true minus odometry", ".4f"
    ),
    "eps_theta_ccw": Component(
        "mean heading error of the ccw runs", ANGLE_UNIT, "true minus odometry", ".4f"
    ),
    # straight
    "n_straight": Component("straight runs", "", "runs against a tape that measured E_s", ".0f"),
    # endpoints, trajectory, trajectory-scrub
    "r_left": Component("left wheel radius", "mm", "fitted", ".3f"),
    "r_right": Component("right wheel radius", "mm", "fitted", ".3f"),
    "wheelbase": Component("wheelbase", "mm", "fitted", ".3f"),
    "arc_wheelbase": Component(
        "wheelbase on straights and arcs", "mm", "scrub model: fitted", ".3f"
    ),
    "spot_wheelbase": Component(
        "wheelbase turning on the spot", "mm", "scrub model: fitted", ".3f"
    ),
    "time_offset": Component("time offset", "ms", "> 0: the ground truth lags the wheels", ".1f"),
    "truth_offset_x": Component(
        "tracked point forward", "mm", "fitted: the ground truth's point ahead of the axle", ".1f"
    ),
    "truth_offset_y": Component(
        "tracked point left", "mm", "fitted: the ground truth's point left of the axle", ".1f"
    ),
    "rms_position": Component("position residual (rms)", "mm", _RESIDUALS, ".2f"),
    "rms_heading": Component("heading residual (rms)", ANGLE_UNIT, _RESIDUALS, ".3f"),
    "runs": Component("runs fitted", "", "", ".0f"),
    "samples": Component("samples fitted", "", "", ".0f"),
    "scale_fitted": Component("scale E_s fitted", "", "1: fitted, 0: held at 1", ".0f"),
    "scrub_r_left": Component("left wheel radius, scrub model", "mm", "fitted", ".3f"),
    "scrub_r_right": Component("right wheel radius, scrub model", "mm", "fitted", ".3f"),
    "scrub_rms_position": Component(
        "position residual of the scrub model (rms)", "mm", _RESIDUALS, ".2f"
    ),
    "scrub_rms_heading": Component(
        "heading residual of the scrub model (rms)", ANGLE_UNIT, _RESIDUALS, ".3f"
    ),
    # scan-matching: wheels and laser mounting from motion intervals
    "wheel_diameter_left": Component("left wheel diameter", "mm", "scan matching", ".3f"),
    "wheel_diameter_right": Component("right wheel diameter", "mm", "scan matching", ".3f"),
    "laser_x": Component("laser position, forward", "mm", "on the robot", ".2f"),
    "laser_y": Component("laser position, left", "mm", "on the robot", ".2f"),
    "laser_yaw": Component("laser yaw", ANGLE_UNIT, "on the robot", ".3f"),
    "n_intervals": Component("motion intervals", "", "in the sources", ".0f"),
    "n_used": Component("motion intervals used", "", "the others: outliers", ".0f"),
    # gyro: the wheels against a gyro
    "gyro_scale": Component(
        "gyro scale k_g",
        "",
        "omega_true = k_g (omega_read - bias): a driver's scale times it",
        ".5f",
    ),
    "gyro_bias": Component(
        "gyro bias (yaw)", f"{ANGLE_UNIT}/s", "its mean over the recording: subtract it", ".4f"
    ),
    "E_b_gyro": Component(
        "E_b k_g / E_s", "", "the wheelbase relative to the gyro (wheels and gyro alone)", ".6f"
    ),
    "gyro_tilt": Component("IMU tilt from its turns", ANGLE_UNIT, "off the base's z", ".3f"),
    "n_rests": Component("rests", "", "the gyro's bias alone over them", ".0f"),
    "n_reference": Component("reference stretches", "", "an absolute heading's", ".0f"),
}


def component(name: str) -> Component:
    """The description of component ``name`` (an unknown one: its name, no unit)."""
    return COMPONENTS.get(name) or Component(name)

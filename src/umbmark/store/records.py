"""The records of the calibration history (:mod:`umbmark.store.history`): a robot, and
one calibration of it with what the robot is according to it."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from umbmark.model.active import ActiveParams

__all__ = ["CalibrationRecord", "NewCalibration", "RobotRecord"]


@dataclass(frozen=True)
class NewCalibration:
    """A calibration to record (:meth:`umbmark.store.history.History.record`), as the job
    that made it says it (``calibrate --json``'s figures and blocks).

    Attributes
    ----------
    time : datetime
        When it was made.
    method : str
    E_d, E_b : float
    E_s : float or None
    e_max_syst : float or None
        ``E_max,syst`` [m] of its runs.
    standard_errors : dict of str to float
    active : dict of str to object
        The parameters active during the runs (the ``active`` block).
    new : dict of str to object
        The new parameters (the ``new`` block).
    verdict : dict of str to object
        Whether to apply it (the ``apply`` block).
    wheelbase : float
        Nominal wheelbase [m]: the active one, as configured.
    wheel_diameter : float or None
        Nominal wheel diameter [m], when known.
    controller : str or None
        The controller it is for, with its namespace (``/robot1/diff_cont``; None where
        nothing named it).
    """

    time: dt.datetime
    method: str
    E_d: float
    E_b: float
    E_s: float | None
    e_max_syst: float | None
    standard_errors: dict[str, float]
    active: dict[str, Any]
    new: dict[str, Any]
    verdict: dict[str, Any]
    wheelbase: float
    wheel_diameter: float | None
    controller: str | None = None


@dataclass(frozen=True)
class RobotRecord:
    """A robot of the history.

    Attributes
    ----------
    name : str
    wheelbase : float
        Nominal wheelbase [m].
    wheel_diameter : float or None
        Nominal wheel diameter [m], when known.
    created : str
        When it was first recorded (UTC, ISO 8601): the day the history learnt of it (a
        fleet's robot: the day the fleet first ran), not when it was calibrated.
    calibrations : int
        How many calibrations it has.
    first, last : str or None
        Its first and last calibration's time (UTC, ISO 8601: a fleet's are its
        recordings' times); None without calibrations.
    """

    name: str
    wheelbase: float
    wheel_diameter: float | None
    created: str
    calibrations: int = 0
    first: str | None = None
    last: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres)."""
        return {
            "name": self.name,
            "wheelbase": self.wheelbase,
            "wheel_diameter": self.wheel_diameter,
            "created": self.created,
            "calibrations": self.calibrations,
            "first_calibration": self.first,
            "last_calibration": self.last,
        }


@dataclass(frozen=True)
class CalibrationRecord:
    """One recorded calibration.

    Attributes
    ----------
    id : int
    robot : str
    time : str
        When it was made (UTC, ISO 8601).
    method : str
    inputs : list of dict
        ``{"name": ..., "sha256": ...}`` per input (``sha256`` None for runs in memory).
    E_d, E_b : float
        What the pass measured, relative to the parameters active during it
        (:attr:`robot_E_d`, :attr:`robot_E_b`: what the robot is).
    E_s : float or None
    e_max_syst : float or None
        [m]
    standard_errors : dict
        The report's standard errors (``E_d``, ``E_b``, ...).
    active, new : dict
        The parameters active during the runs and the new ones (as ``calibrate --json``).
    applied : bool
    verdict : dict or None
        The calibration's verdict, ``{"level", "reasons", "instead"}`` (``calibrate
        --json``'s ``apply``); None for calibrations recorded before umbmark judged them.
    controller : str or None
        The controller it is for (``/robot1/diff_cont``); None where nothing named it, and
        for calibrations recorded before umbmark kept it.
    """

    id: int
    robot: str
    time: str
    method: str
    inputs: list[dict[str, Any]]
    E_d: float
    E_b: float
    E_s: float | None
    e_max_syst: float | None
    standard_errors: dict[str, float]
    active: dict[str, Any]
    new: dict[str, Any]
    applied: bool
    verdict: dict[str, Any] | None = None
    controller: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres)."""
        return {
            "id": self.id,
            "time": self.time,
            "method": self.method,
            "controller": self.controller,
            "E_d": self.E_d,
            "E_b": self.E_b,
            "E_s": self.E_s,
            "e_max_syst": self.e_max_syst,
            "standard_errors": self.standard_errors,
            "inputs": self.inputs,
            "active": self.active,
            "new": self.new,
            "applied": self.applied,
            "verdict": self.verdict,
            "robot_E_d": self.robot_E_d,
            "robot_E_b": self.robot_E_b,
            "robot_standard_errors": self.robot_standard_errors,
            "robot_wheelbase": self.robot_wheelbase,
            "E_b_relative_to_gyro": self.relative_to_gyro,
            "k_g": self.k_g,
        }

    @property
    def relative_to_gyro(self) -> bool:
        """Its ``E_b`` is relative to the gyro (``E_b k_g``: wheels and gyro alone, no
        absolute heading), not the wheelbase itself: never compared with one that is."""
        from umbmark.estimators.registry import GYROS

        return self.method in GYROS and "gyro_scale" not in self.standard_errors

    @property
    def k_g(self) -> float | None:
        """The gyro's scale it found (``new``'s ``gyro_scale_multiplier``), where it did."""
        value = self.new.get("gyro_scale_multiplier")
        return float(value) if isinstance(value, int | float) else None

    @property
    def active_params(self) -> ActiveParams:
        """The parameters active during the pass."""
        from umbmark.model.active import ActiveParams

        a = self.active
        return ActiveParams(
            wheelbase=float(a["wheelbase"]),
            c_left=float(a["c_L"]),
            c_right=float(a["c_R"]),
            separation_multiplier=float(a["wheel_separation_multiplier"]),
            wheel_diameter=None if a.get("wheel_diameter") is None else float(a["wheel_diameter"]),
        )

    @property
    def robot_E_d(self) -> float:
        """What the robot is: its ``D_R / D_L``, the pass's ``E_d`` composed with the active
        ``c_L``, ``c_R`` as calibrate composes them (:meth:`ActiveParams.robot_errors
        <umbmark.model.active.ActiveParams.robot_errors>`:
        ``E_d c_R,active / c_L,active``)."""
        return self.active_params.robot_errors(self.E_d, self.E_b)[0]

    @property
    def robot_E_b(self) -> float:
        """What the robot is: its effective wheelbase over the nominal one, the pass's
        ``E_b`` composed with the active ``wheel_separation_multiplier`` as calibrate
        composes them (``E_b x multiplier,active``, the new multiplier)."""
        return self.active_params.robot_errors(self.E_d, self.E_b)[1]

    @property
    def robot_wheelbase(self) -> float:
        """The robot's effective wheelbase [m]: :attr:`robot_E_b` x the nominal one."""
        return self.robot_E_b * float(self.active["wheelbase"])

    @property
    def robot_standard_errors(self) -> dict[str, float]:
        """Standard errors of :attr:`robot_E_d` and :attr:`robot_E_b` (keys ``E_d``,
        ``E_b``, where the pass has them): the pass's, scaled as the composition scales
        the value (the active parameters are exact)."""
        out = {}
        for name, robot in (("E_d", self.robot_E_d), ("E_b", self.robot_E_b)):
            se = self.standard_errors.get(name)
            if se is not None:
                out[name] = float(se) * abs(robot / float(getattr(self, name)))
        return out

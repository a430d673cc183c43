"""What a self-calibration reports (:func:`umbmark.jobs.selfcal.selfcal`): each pass, and
the whole routine with what the controller holds at the end. Metres and radians."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from umbmark.calibration.passes import Holds, e_b_words
from umbmark.core.jsontext import JsonText
from umbmark.robot.base import ApplyResult, DriveParams
from umbmark.routines.coarse import CoarseTurning

if TYPE_CHECKING:
    from umbmark.outputs.calibration import CalibrationReport

__all__ = ["PassResult", "SelfCalReport"]


@dataclass(frozen=True)
class PassResult:
    """One UMBmark pass of the self-calibration.

    Attributes
    ----------
    label : str
        ``pass 1``, ``pass 2``, ..., ``verification``.
    folder : Path or None
        Its run log (None: not kept, the self-calibration was given no ``out``).
    report : CalibrationReport
        Its calibration (composed with the parameters active during it).
    params : DriveParams
        The parameters the controller ran with during the pass.
    applied : ApplyResult or None
        What applying its correction did (None: not applied).
    warnings : tuple of str
        Runs whose odometry did not end where it was sent (the benchmark assumes the
        robot follows the square by its odometry).
    """

    label: str
    folder: Path | None
    report: CalibrationReport
    params: DriveParams
    applied: ApplyResult | None = None
    warnings: tuple[str, ...] = ()

    def summary(self, coarse: float | None = None) -> str:
        """One line: E_max,syst, the estimate, the verdict and whether it was applied;
        ``coarse``: the factor of a coarse turning correction this pass was measured
        after (its E_b the residual, :func:`umbmark.calibration.passes.e_b_words`)."""
        r = self.report
        e = "-" if r.e_max_syst is None else f"{r.e_max_syst * 1000:.1f} mm"
        if self.applied is None:
            applied = "not applied"
        elif self.applied.active:
            applied = f"applied by {self.applied.method}"
        else:
            applied = f"not active: {self.applied.message}"
        return (
            f"{self.label}: E_max,syst {e}, E_d {r.estimate.E_d:.6f}, E_b "
            f"{e_b_words(r.estimate.E_b, coarse)}; {r.verdict.words}; {applied}"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (metres, radians)."""
        estimate = self.report.estimate
        return {
            "label": self.label,
            "folder": None if self.folder is None else str(self.folder),
            "e_max_syst": self.report.e_max_syst,
            "E_d": estimate.E_d,
            "E_b": estimate.E_b,
            "verdict": self.report.verdict.words,
            "active": _multipliers(self.params),
            "applied": None if self.applied is None else self.applied.active,
            "apply_method": None if self.applied is None else self.applied.method,
            "apply_message": None if self.applied is None else self.applied.message,
            "warnings": list(self.warnings),
        }


@dataclass(frozen=True)
class SelfCalReport(JsonText):
    """What a self-calibration did and found.

    Attributes
    ----------
    robot : str
        The robot's name.
    side_length : float
        The square's side [m].
    measurement : str
        ``lidar``, ``ranges``, ``truth`` or ``tape``.
    coarse : CoarseTurning or None
        The coarse turning check (None: not made).
    coarse_applied : ApplyResult or None
    passes : tuple of PassResult
        The UMBmark passes, the verification last.
    final : DriveParams
        The parameters the controller holds at the end, as it reports them.
    holds : Holds
        What the controller holds: the pass whose correction (the last applied) and the
        multipliers of ``final``; the terminal, the JSON, ``overlay.yaml`` and the HTML
        page all say this one thing.
    fix_errors : array, shape (k, 3), or None
        Each fix's error against the truth (a virtual robot): ``x, y`` [m], heading [rad].
    checks : tuple of str
        What the checks before moving found.
    files : tuple of Path
        Files written.
    restart : str or None
        The routine stopped for a controller restart: what to do, and how to go on
        (``umbmark selfcal --resume DIR``).
    """

    robot: str
    side_length: float
    measurement: str
    coarse: CoarseTurning | None
    coarse_applied: ApplyResult | None
    passes: tuple[PassResult, ...]
    final: DriveParams
    holds: Holds
    fix_errors: np.ndarray | None = None
    checks: tuple[str, ...] = ()
    files: tuple[Path, ...] = field(default=(), compare=False)
    restart: str | None = None

    @property
    def e_max_syst_before(self) -> float | None:
        """E_max,syst of the first pass [m]."""
        return self.passes[0].report.e_max_syst if self.passes else None

    @property
    def e_max_syst_after(self) -> float | None:
        """E_max,syst of the last pass (the verification, if driven) [m]; None when only
        one pass was driven (nothing after a correction)."""
        return self.passes[-1].report.e_max_syst if len(self.passes) > 1 else None

    def measurement_errors(self) -> tuple[float, float] | None:
        """RMS position [m] and heading [rad] error of the fixes against the truth."""
        if self.fix_errors is None or self.fix_errors.size == 0:
            return None
        e = self.fix_errors
        position = float(np.sqrt(np.mean(e[:, 0] ** 2 + e[:, 1] ** 2)))
        return position, float(np.sqrt(np.mean(e[:, 2] ** 2)))

    def to_dict(self) -> dict[str, Any]:
        """What ``umbmark selfcal --json`` prints (metres, radians)."""
        measurement: dict[str, Any] = {"method": self.measurement}
        errors = self.measurement_errors()
        if errors is not None:
            measurement["rms_position_error"] = errors[0]
            measurement["rms_heading_error"] = errors[1]
            measurement["fixes"] = int(self.fix_errors.shape[0])  # type: ignore[union-attr]
        return {
            "robot": self.robot,
            "side_length": self.side_length,
            "checks": list(self.checks),
            "coarse": None if self.coarse is None else self.coarse.to_dict(),
            "passes": [p.to_dict() for p in self.passes],
            "e_max_syst_before": self.e_max_syst_before,
            "e_max_syst_after": self.e_max_syst_after,
            "applied": self.holds.multipliers(),
            "holds": self.holds.to_dict(),
            "measurement": measurement,
            "files": [str(f) for f in self.files],
            "restart": self.restart,
        }


def _multipliers(params: DriveParams) -> dict[str, float]:
    return {
        "wheel_separation_multiplier": params.wheel_separation_multiplier,
        "left_wheel_radius_multiplier": params.left_wheel_radius_multiplier,
        "right_wheel_radius_multiplier": params.right_wheel_radius_multiplier,
    }

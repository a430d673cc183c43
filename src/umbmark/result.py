"""The calibration result: one object that the CLI prints, serializes and later reads back.

The JSON form always holds lengths in metres and angles in radians, whatever units the
input came in.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import __version__
from .benchmark import Benchmark, Cluster
from .calibration import Calibration
from .estimators.base import SquareTest
from .io.atomic import atomic_write_text
from .runs import Run

__all__ = ["CalibrationReport"]


@dataclass(frozen=True)
class CalibrationReport:
    """Everything ``umbmark calibrate`` found.

    Attributes
    ----------
    source : str
        Where the runs came from (a path).
    runs : sequence of Run
    benchmark : Benchmark or None
        None when the runs are not in both directions (trajectory fits of other paths).
    test : SquareTest
    calibration : Calibration
    extra : mapping
        Source-specific facts to carry into the JSON (for example time matching).
    """

    source: str
    runs: Sequence[Run]
    benchmark: Benchmark | None
    test: SquareTest
    calibration: Calibration
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def warnings(self) -> tuple[str, ...]:
        """Everything that makes the result valid but shaky."""
        return self.calibration.estimate.warnings

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres, radians)."""
        bench, cal = self.benchmark, self.calibration
        est, active = cal.estimate, cal.active
        out: dict[str, Any] = {
            "umbmark_version": __version__,
            "source": self.source,
            "method": est.method,
            "units": {"length": "m", "angle": "rad"},
            "side_length": self.test.side_length,
            "n_runs": len(self.runs),
        }
        if bench is not None:
            out.update(
                {
                    "n_cw": bench.cw.n,
                    "n_ccw": bench.ccw.n,
                    "e_max_syst": bench.e_max_syst,
                    "worst_direction": bench.worst.direction.value,
                }
            )
            for cluster in bench.clusters:
                out.update(_cluster_dict(cluster))
            out.update(
                {
                    "sem": bench.sem,
                    "second_pass_threshold": bench.second_pass_threshold,
                    "second_pass_recommended": bench.second_pass_recommended,
                }
            )
        else:
            out.update({"e_max_syst": None, "second_pass_recommended": None})
        out.update(
            {
                "alpha": est.alpha,
                "beta": est.beta,
                "E_d": est.E_d,
                "E_b": est.E_b,
                "E_s": est.E_s,
                "standard_errors": dict(est.standard_errors),
                "components": dict(est.components),
                "c_L": cal.c_L,
                "c_R": cal.c_R,
                "wheelbase_corrected": cal.wheelbase_corrected,
                "wheelbase": cal.wheelbase_corrected,
                "wheel_diameter_left": cal.wheel_diameter_left,
                "wheel_diameter_right": cal.wheel_diameter_right,
                "active": {
                    "wheelbase": active.wheelbase,
                    "wheel_separation_multiplier": active.separation_multiplier,
                    "effective_wheelbase": active.effective_wheelbase,
                    "c_L": active.c_left,
                    "c_R": active.c_right,
                    "wheel_diameter": active.wheel_diameter,
                },
                "new": {
                    "c_L": cal.new_c_left,
                    "c_R": cal.new_c_right,
                    "wheel_separation_multiplier": cal.new_separation_multiplier,
                    "left_wheel_radius_multiplier": cal.new_c_left,
                    "right_wheel_radius_multiplier": cal.new_c_right,
                    "wheelbase": cal.wheelbase_corrected,
                },
                "warnings": list(self.warnings),
                "runs": [_run_dict(run) for run in self.runs],
            }
        )
        out.update(self.extra)
        return out

    def to_json(self) -> str:
        """The JSON text of :meth:`to_dict`."""
        return json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n"

    def write_json(self, path: str | Path) -> None:
        """Write the JSON atomically."""
        atomic_write_text(path, self.to_json())


def _cluster_dict(cluster: Cluster) -> dict[str, Any]:
    d = cluster.direction.value
    std = cluster.std_xy
    return {
        f"cg_{d}": [float(cluster.cg[0]), float(cluster.cg[1])],
        f"r_cg_{d}": cluster.r_cg,
        f"std_{d}": [float(std[0]), float(std[1])],
        f"sigma_{d}": cluster.sigma,
        f"sem_{d}": cluster.sem,
    }


def _run_dict(run: Run) -> dict[str, Any]:
    eps_x, eps_y = run.return_error
    return {
        "label": run.label,
        "direction": run.direction.value,
        "eps_x": eps_x,
        "eps_y": eps_y,
        "eps_theta": run.heading_error,
    }

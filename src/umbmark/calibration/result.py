"""What a calibration found (:class:`CalibrationResult`), and its serialisation.

The result's :meth:`~CalibrationResult.to_dict` is exactly what ``umbmark calibrate
--json`` prints (metres and radians, whatever units the input came in); its texts are what
the command writes with ``--yaml`` and ``--ros1-yaml``. A calibration to replay or
simulate with is a result file, the parameters it holds, or a result (:data:`Calibrated`).
"""

from __future__ import annotations

import datetime as dt
import os
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

from umbmark.calibration.compose import Calibration
from umbmark.calibration.result_parts import cluster_dict, run_dict, sensor_dict
from umbmark.core.jsontext import JsonText
from umbmark.core.version import __version__
from umbmark.estimators.base import ErrorEstimate, SquareTest
from umbmark.estimators.registry import LOGGED
from umbmark.model.kinematics import WheelParams
from umbmark.model.run import Run
from umbmark.returns.clusters import Benchmark, sem_verdict
from umbmark.runs.association import Association
from umbmark.sources.params.reader import (
    DEFAULT_CONTROLLER,
    CalibratedParams,
    ControllerParams,
    key_path_of,
    read_calibrated_params,
    result_nominal,
)

if TYPE_CHECKING:
    from umbmark.calibration.verdict import Evidence, Verdict
    from umbmark.estimators.gyro_result import GyroCalibration
    from umbmark.estimators.scan_matching import ScanCalibration
    from umbmark.estimators.trajectory_fit import TrajectoryFit
    from umbmark.model.scans import LaserMounting

__all__ = [
    "ABSOLUTE_FIGURES",
    "Calibrated",
    "CalibrationResult",
    "Without",
    "calibrated_name",
    "calibrated_nominal",
    "calibrated_params",
    "unnamed_controller",
]


def unnamed_controller() -> str:
    """What is said where nothing named the controller (its file, ``--controller``, a
    result or the history): the overlays are keyed by the default."""
    return (
        f"no controller named: keyed {DEFAULT_CONTROLLER}; give --controller NAME (with its "
        "namespace, e.g. /robot1/diff_cont) or --current-params with its parameter file"
    )


PathLike = str | os.PathLike[str]


@dataclass(frozen=True)
class Without:
    """The result without the rows far outside their cluster (shown beside the result).

    Attributes
    ----------
    rows : tuple of str
        The rows left out (``row 13``: the file's line).
    e_max_syst : float or None
        E_max,syst [m] of the other runs.
    E_d, E_b : float
        The estimate of the other runs.
    verdict : str
        Its verdict's level (``apply``, ``care``, ``do-not-apply``).
    """

    rows: tuple[str, ...]
    e_max_syst: float | None
    E_d: float
    E_b: float
    verdict: str

    def to_dict(self) -> dict[str, Any]:
        """``{"rows": [...], "e_max_syst": ..., "E_d": ..., "E_b": ..., "verdict": ...}``."""
        return {
            "rows": list(self.rows),
            "e_max_syst": self.e_max_syst,
            "E_d": self.E_d,
            "E_b": self.E_b,
            "verdict": self.verdict,
        }


@dataclass(frozen=True, repr=False)
class CalibrationResult(JsonText):
    """Everything a calibration found (the job's :class:`umbmark.jobs.calibrate.CalibrationReport`
    adds the files it writes).

    Attributes
    ----------
    sources : tuple of str
        What the runs came from (paths, or ``"runs"`` for runs given in memory).
    format : str
        The sources' format (``table``, ``log``, ``optiodom``, ``bag``).
    runs : tuple of Run
        Every run, in the sources' order.
    benchmark : Benchmark or None
        The UMBmark figures (Eqs. 3.1-3.4); None when the runs are not in both
        directions (trajectory fits of other paths).
    test : SquareTest
        Side [m] and wheelbase [m] the estimate assumed.
    calibration : Calibration
        The error estimate and the correction, composed with the active parameters.
    params : WheelParams or None
        What logged runs were integrated with (None for end points only).
    controller : ControllerParams
        The controller the parameters are for, as its file says (name, keys, flavour,
        ``open_loop``...); a default one when no file was given.
    associations : tuple of (str, Association)
        Time matching of each recording.
    notes : tuple of str
        What was done and chosen while reading, for people (information).
    input_warnings : tuple of str
        What makes the input doubtful (a unit that looks wrong, runs left out, sources
        that disagree): with the estimate's own, :attr:`warnings`.
    nominal_best : bool
        ``method="auto"`` found no estimator that predicts held-out runs better than the
        nominal parameters (the verdict is then "do not apply").
    forced : bool
        ``override_verdict=True``: the overlay is written even when the verdict is "do not
        apply" (``force`` only replaces files and does not set it).
    withheld : tuple of str
        The outputs asked for and not written because of the verdict (``yaml``,
        ``ros1_yaml``).
    model_fit : TrajectoryFit or None
        The trajectory methods' fit of the odometry model (the richer model of
        ``trajectory-scrub``), which replays use.
    created : datetime
        When the calibration was made (UTC); stamped into the parameter files' comments,
        not into :meth:`to_dict`.
    recorded : str or None
        Where the calibration was recorded in the history (``robot``), for people.
    sensor : ScanCalibration or None
        A calibration from motion intervals (``format="tuples"``, no runs): the wheels
        and the sensor's mounting it found, with their covariance.
    without : Without or None
        The result without a table's rows far outside their cluster
        (:func:`umbmark.estimators.rows.far_rows`), None when there are none.
    stated_mounting : LaserMounting or None
        The laser's mounting as the robot states it (TF, ``/tf_static``, the URDF), which
        the fitted one is compared with (None: not known).
    nominal : bool
        False for a calibration from motion intervals given no nominal geometry (no
        wheelbase, no wheel diameter): its figures are absolute (the wheel diameters, the
        wheelbase, the mounting, ``E_d = D_R / D_L``); the calibration is then made
        against the measured geometry itself, so ``E_b``, ``E_s``, ``alpha`` and the
        multipliers say nothing and the JSON gives them as null, and no parameter file
        is written.
    gyro : GyroCalibration or None
        A calibration with a gyro (``method="gyro"``): the gyro's own scale and bias,
        what the motion did not determine, the IMU's mounting as its readings show it
        (the JSON's ``gyro_calibration``).
    """

    sources: tuple[str, ...]
    format: str
    runs: tuple[Run, ...]
    benchmark: Benchmark | None
    test: SquareTest
    calibration: Calibration
    params: WheelParams | None = None
    controller: ControllerParams = field(default_factory=ControllerParams)
    associations: tuple[tuple[str, Association], ...] = ()
    notes: tuple[str, ...] = ()
    input_warnings: tuple[str, ...] = ()
    nominal_best: bool = False
    forced: bool = False
    withheld: tuple[str, ...] = ()
    model_fit: TrajectoryFit | None = field(default=None, compare=False)
    created: dt.datetime = field(default_factory=lambda: dt.datetime.now(dt.timezone.utc))
    robot: str | None = None
    command: str | None = field(default=None, compare=False)
    recorded: str | None = field(default=None, compare=False)
    sensor: ScanCalibration | None = field(default=None, compare=False)
    without: Without | None = None
    stated_mounting: LaserMounting | None = field(default=None, compare=False)
    nominal: bool = True
    gyro: GyroCalibration | None = field(default=None, compare=False)

    def __repr__(self) -> str:
        est = self.estimate
        e_max = "None" if self.e_max_syst is None else f"{self.e_max_syst:.6g} m"
        return (
            f"{type(self).__name__}(source={self.source!r}, method={est.method!r}, "
            f"runs={len(self.runs)}, e_max_syst={e_max}, E_d={est.E_d:.6f}, "
            f"E_b={est.E_b:.6f}, warnings={len(self.warnings)})"
        )

    @property
    def source(self) -> str:
        """The sources, comma-separated."""
        return ", ".join(self.sources)

    @property
    def estimate(self) -> ErrorEstimate:
        """The error estimate (``alpha``, ``beta``, ``E_d``, ``E_b``, ...)."""
        return self.calibration.estimate

    @property
    def e_max_syst(self) -> float | None:
        """``E_max,syst`` [m] of the runs (Eq. 3.4), None without both directions."""
        return None if self.benchmark is None else self.benchmark.e_max_syst

    @property
    def warnings(self) -> tuple[str, ...]:
        """Everything that makes the result valid but shaky: the input's doubts, the
        estimate's, and the outputs withheld."""
        withheld: tuple[str, ...] = ()
        if self.withheld:
            flags = ", ".join("--" + key.replace("_", "-") for key in self.withheld)
            them = "them" if len(self.withheld) > 1 else "it"
            withheld = (
                f"{flags} not written: the verdict is do not apply (--override-verdict writes "
                f"{them}; --force only replaces files that exist)",
            )
        return (*self.input_warnings, *self.calibration.estimate.warnings, *withheld)

    @cached_property
    def verdict(self) -> Verdict:
        """Whether to apply the correction, why, and what to record instead
        (:func:`umbmark.calibration.verdict.judge`)."""
        from umbmark.calibration.verdict import judge

        return judge(self.estimate, self.test, self._evidence())

    @property
    def second_pass(self) -> str | None:
        """The paper's 3 x SEM rule said in a sentence: whether another pass (apply the
        correction, run UMBmark again) is worth it; None without end points (JSON
        ``second_pass``)."""
        return None if self.benchmark is None else sem_verdict(self.benchmark)

    def _evidence(self) -> Evidence:
        from umbmark.calibration.verdict import Evidence, mean_path

        logs = [run.log for run in self.runs if run.log is not None]
        logged = self.estimate.method in LOGGED
        bench = self.benchmark
        return Evidence(
            runs_per_direction=None if logged or bench is None else (bench.cw.n, bench.ccw.n),
            recorded_runs=len(logs) if logged else None,
            path_length=mean_path(logs, self.params) if logged and self.params else None,
            warnings=(*self.input_warnings, *self.estimate.warnings),
            nominal_best=self.nominal_best,
            wheel_diameter=(self.params or self.calibration.active).wheel_diameter,
            returns=None if bench is None else (bench.e_max_syst, bench.second_pass_threshold),
        )

    @property
    def overlay_withheld(self) -> bool:
        """The parameter files are withheld: the verdict is "do not apply" and
        ``override_verdict`` was not given."""
        return not self.verdict.applies and not self.forced

    @property
    def calibrated_params(self) -> WheelParams | None:
        """The odometry parameters of logged runs with the correction applied."""
        if self.params is None:
            return None
        cal = self.calibration
        return self.params.with_corrections(
            c_left=cal.new_c_left, c_right=cal.new_c_right, wheelbase=cal.wheelbase_corrected
        )

    def new_params(self) -> CalibratedParams:
        """The new parameters, as :func:`umbmark.replay` and :func:`umbmark.simulate`
        take them (the same that reading this report's JSON back gives): the fitted model
        where the method fits a richer one than controllers take."""
        cal = self.calibration
        model = self._model()
        if model is not None:
            return CalibratedParams(
                wheelbase=model["wheelbase"],
                c_left=cal.new_c_left,
                c_right=cal.new_c_right,
                wheel_diameter_left=model["wheel_diameter_left"],
                wheel_diameter_right=model["wheel_diameter_right"],
                spot_wheelbase=model["spot_wheelbase"],
                source=self.source,
                controller=self._controller_name,
            )
        return CalibratedParams(
            wheelbase=cal.wheelbase_corrected,
            c_left=cal.new_c_left,
            c_right=cal.new_c_right,
            wheel_diameter_left=cal.wheel_diameter_left,
            wheel_diameter_right=cal.wheel_diameter_right,
            separation_multiplier=cal.new_separation_multiplier,
            configured_wheelbase=cal.active.wheelbase,
            wheel_diameter=cal.active.wheel_diameter,
            source=self.source,
            controller=self._controller_name,
            gyro_scale=None if self.gyro is None else self.gyro.values.get("k_g"),
            gyro_bias=None if self.gyro is None else self.gyro.values.get("bias"),
        )

    @property
    def _controller_name(self) -> str | None:
        return self.controller.name if self.controller.named else None

    def _model(self) -> dict[str, float] | None:
        """The richer model a method fitted (absolute values [m]), if any."""
        fit = self.model_fit
        if fit is None or fit.spot_wheelbase is None:
            return None
        return {
            "wheel_diameter_left": 2.0 * fit.r_left,
            "wheel_diameter_right": 2.0 * fit.r_right,
            "wheelbase": fit.wheelbase,
            "spot_wheelbase": fit.spot_wheelbase,
        }

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres, radians): what ``calibrate --json`` prints."""
        bench, cal = self.benchmark, self.calibration
        est, active = cal.estimate, cal.active
        out: dict[str, Any] = {
            "verdict": self.verdict.to_dict(),
            "umbmark_version": __version__,
            "source": self.source,
            "sources": list(self.sources),
            "method": est.method,
            "controller": self.controller.name if self.controller.named else None,
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
                out.update(cluster_dict(cluster))
            out.update(
                {
                    "sem": bench.sem,
                    "second_pass_threshold": bench.second_pass_threshold,
                    "second_pass_recommended": bench.second_pass_recommended,
                    "second_pass": sem_verdict(bench),
                }
            )
        else:
            out.update({"e_max_syst": None, "second_pass_recommended": None, "second_pass": None})
        out.update(
            {
                "alpha": est.alpha,
                "beta": est.beta,
                "E_d": est.E_d,
                "E_b": est.E_b,
                "E_s": est.E_s,
                "standard_errors": dict(est.standard_errors),
                "intervals_95": _intervals(est),
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
                "runs": [run_dict(run) for run in self.runs],
                "format": self.format,
            }
        )
        model = self._model()
        if model is not None:
            out["model"] = {"kind": "scrub", **model}
        if self.sensor is not None:
            out.update(sensor_dict(self.sensor))
            nominal = {"wheelbase": active.wheelbase, "wheel_diameter": active.wheel_diameter}
            out["nominal"] = nominal if self.nominal else None
        if not self.nominal:
            _without_nominal(out)
        logs = [run.log for run in self.runs if run.log is not None]
        if self.params is not None and logs:
            from umbmark.estimators.motions import motion_coverage

            out["motions"] = motion_coverage(logs, self.params).to_dict()
        if self.associations:
            out["time_association"] = {name: a.to_dict() for name, a in self.associations}
        if self.without is not None:
            out["without_rows"] = self.without.to_dict()
        if self.gyro is not None:  # the gyro's new scale and bias beside the wheels'
            out["gyro_calibration"] = self.gyro.to_dict()
            out["new"]["gyro_scale_multiplier"] = self.gyro.values.get("k_g")
            out["new"]["gyro_bias"] = self.gyro.values.get("bias")
        if self.notes:
            out["notes"] = list(self.notes)
        return out

    def provenance(self, *, ros1: bool = False) -> list[str]:
        """Comment lines saying where a parameter file came from (``ros1``: a ROS 1
        parameter file, which the controller reads when it is loaded)."""
        cal = self.calibration
        active = cal.active
        stamp = self.created.strftime("%Y-%m-%dT%H:%M:%SZ")
        e_max = (
            ""
            if self.benchmark is None
            else f"; E_max,syst of these runs = {self.benchmark.e_max_syst * 1000:.1f} mm"
        )
        return [
            f"Written by umbmark {__version__} on {stamp} from {self.source} "
            f"(method {cal.estimate.method}).",
            f"E_d = {cal.estimate.E_d:.6f}, E_b = {cal.estimate.E_b:.6f}{e_max}.",
            "Multiplied into the values active during the runs: separation "
            f"{active.separation_multiplier:g}, left {active.c_left:g}, right {active.c_right:g}.",
            "diff_drive_controller reads these when it is loaded: load them (rosparam load) and "
            "restart the controller (controller_manager)."
            if ros1
            else "diff_drive_controller reads these on configure: reload or restart the "
            "controller.",
            *([] if self.verdict.level == "apply" else [self.verdict.line()]),
            *([] if self.controller.named else [unnamed_controller()]),
            *(
                [
                    "open_loop is true: the controller's odometry integrates its commands, "
                    "so these change its wheel speeds, not its odometry; set it false."
                ]
                if self.controller.open_loop
                else []
            ),
        ]

    def overlay_yaml(self) -> str:
        """The ros2_control parameter overlay with the new multipliers (what ``--yaml`` writes)."""
        from umbmark.sources.params.writer import ros2_control_overlay

        new = self._new_multipliers()
        return ros2_control_overlay(new, self.provenance(), self.controller.key_path)

    def _new_multipliers(self) -> tuple[float, float, float]:
        """The new ``c_L``, ``c_R`` and ``wheel_separation_multiplier``."""
        cal = self.calibration
        return cal.new_c_left, cal.new_c_right, cal.new_separation_multiplier

    def ros1_yaml(self) -> str:
        """ROS 1 ``diff_drive_controller`` parameters (what ``--ros1-yaml`` writes)."""
        from umbmark.sources.params.writer import ros1_params

        controller = self.controller
        comments = self.provenance(ros1=True)
        if controller.radius_multiplier is not None:
            comments.append(
                f"Delete wheel_radius_multiplier ({controller.radius_multiplier:g}) from the "
                "controller's parameters: ROS 1's diff_drive_controller uses it instead of "
                "the left and right ones, which here include it."
            )
        keys = (
            key_path_of(controller.name) if "*" not in controller.name else (controller.controller,)
        )
        return ros1_params(self._new_multipliers(), comments, keys)


#: A calibration to replay or simulate with: a result file, or what it holds.
Calibrated: TypeAlias = "PathLike | CalibratedParams | CalibrationResult"


def calibrated_params(params: Calibrated) -> CalibratedParams:
    """The new parameters of a calibration: read from a result file, or taken from a report."""
    if isinstance(params, CalibratedParams):
        return params
    if isinstance(params, CalibrationResult):
        return params.new_params()
    return read_calibrated_params(Path(params))


def calibrated_nominal(params: Calibrated) -> tuple[float | None, float | None]:
    """The nominal wheelbase and wheel diameter [m] a calibration was computed for."""
    if isinstance(params, CalibratedParams):
        return params.configured_wheelbase, params.wheel_diameter
    if isinstance(params, CalibrationResult):
        active = params.calibration.active
        return active.wheelbase, active.wheel_diameter
    return result_nominal(Path(params))


def calibrated_name(params: Calibrated) -> str:
    """How a calibration is named in messages."""
    if isinstance(params, CalibratedParams):
        return params.source or "the calibration"
    if isinstance(params, str | os.PathLike):
        return os.fspath(params)
    return "the calibration"


#: The absolute figures an estimator may give as components, with a standard error
#: (scan matching): the JSON's intervals, the summary and the HTML page list them.
ABSOLUTE_FIGURES = (
    "wheel_diameter_left",
    "wheel_diameter_right",
    "wheelbase",
    "laser_x",
    "laser_y",
    "laser_yaw",
)


def _intervals(estimate: ErrorEstimate) -> dict[str, list[float]]:
    """95 % confidence intervals of the estimate's figures that have a standard error."""
    named: tuple[str, ...] = ("E_d", "E_b", "E_s", "alpha", "beta")
    named += tuple(n for n in ABSOLUTE_FIGURES if n in estimate.components)
    pairs = ((name, estimate.interval(name)) for name in named)
    return {name: [pair[0], pair[1]] for name, pair in pairs if pair is not None}


#: What a calibration is against a nominal geometry: null in the JSON without one.
_AGAINST_NOMINAL = ("alpha", "E_b", "E_s", "c_L", "c_R", "wheelbase_corrected", "active", "new")


def _without_nominal(out: dict[str, Any]) -> None:
    """``out`` (a result's JSON) with what needs a nominal geometry set null."""
    out.update(dict.fromkeys(_AGAINST_NOMINAL))
    for key in ("standard_errors", "intervals_95"):
        out[key] = {k: v for k, v in out[key].items() if k not in _AGAINST_NOMINAL}

"""The replay job: integrate recorded runs again with other parameters, and compare.

Each run's end-pose error (odometry end against ground truth) and its whole-trajectory
RMSE (odometry against ground truth over every matched sample) are computed with the
source's nominal parameters and, given a calibration, with the calibrated ones. Use it to
check a calibration on runs that were not used to compute it: calibrate on one session,
replay another (a circle, another day).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from umbmark.calibration.result import (
    Calibrated,
    calibrated_name,
    calibrated_nominal,
    calibrated_params,
)
from umbmark.core.errors import InputError, python_api
from umbmark.core.jsontext import JsonText
from umbmark.core.messages import split_messages
from umbmark.model.kinematics import IntegrationMethod, WheelParams
from umbmark.model.recording import RunLog
from umbmark.model.run import Run, end_errors
from umbmark.outputs.files import OutputPlan
from umbmark.runs.active import check_same_robot, read_runs
from umbmark.runs.association import Association
from umbmark.runs.read import PathLike, is_table, source_name
from umbmark.runs.read_options import ReadOptions, SourceOptions

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from typing_extensions import Unpack

    from umbmark.outputs.tum import TumTime
    from umbmark.sources.params.reader import CalibratedParams

__all__ = ["ReplayReport", "replay", "trajectory_rmse"]


def trajectory_rmse(log: RunLog, params: WheelParams, method: IntegrationMethod = "arc") -> float:
    """Root-mean-square position error [m] of the odometry over a whole run.

    ``sqrt(mean((x_odo - x_true)^2 + (y_odo - y_true)^2))`` over the samples with ground
    truth (``log.matched``), both in the run's start frame: what ``evo_ape`` reports as
    the RMSE of the translation without alignment, given the TUM files of the run.

    Parameters
    ----------
    log : RunLog
        The run's time series: ``wheel_angles`` shape (n, 2) [rad], ``truth`` shape
        (n, 3) (``x, y`` [m], ``theta`` [rad]; NaN rows where no ground truth matched).
    params : WheelParams
        The odometry parameters to integrate the wheels with.
    method : {"arc", ...}
        The integration (:func:`umbmark.model.kinematics.integrate_odometry`).

    Returns
    -------
    float
        The RMSE [m]; NaN if no sample has ground truth.
    """
    odometry = log.odometry(params, method)
    matched = log.matched
    if not np.any(matched):
        return float("nan")
    diff = odometry[matched, :2] - log.truth[matched, :2]
    return float(np.sqrt(np.mean(np.sum(diff * diff, axis=1))))


@dataclass(frozen=True, repr=False)
class ReplayReport(JsonText):
    """Recorded runs integrated again with one or more parameter sets.

    Attributes
    ----------
    source : str
        The recording.
    format : str
        Its format (``log``, ``optiodom``, ``bag``).
    params_file : str or None
        The calibration result replayed, if any.
    runs : tuple of Run
        The runs as integrated with the nominal parameters, with their time series.
    parameter_sets : mapping of str to WheelParams
        ``nominal`` and, with a calibration, ``calibrated``.
    end_errors : mapping of str to array, shape (n,)
        Each run's end-position error [m] under each parameter set.
    heading_errors : mapping of str to tuple of (float or None)
        Each run's end-heading error [rad] (true minus odometry) under each set.
    rmse : mapping of str to array, shape (n,)
        Each run's whole-trajectory RMSE [m] under each set: the root-mean-square
        distance between odometry and ground-truth positions over the run's matched
        samples (:func:`trajectory_rmse`).
    associations : tuple of (str, Association)
        Time matching of each recording.
    notes : tuple of str
        What was done and chosen while reading, for people (information).
    warnings : tuple of str
        What makes the input doubtful (runs left out, samples unmatched, ...).
    gyro_heading_errors : mapping of str to tuple of (float or None)
        With ``imu_topic``: each run's true heading change less the gyro's [rad], ``as
        read`` and, with a calibration that holds the gyro's scale and bias,
        ``calibrated`` (:func:`umbmark.calibration.gyro_bag.gyro_heading_errors`).
    """

    source: str
    format: str
    params_file: str | None
    runs: tuple[Run, ...]
    parameter_sets: Mapping[str, WheelParams]
    end_errors: Mapping[str, NDArray[np.float64]]
    heading_errors: Mapping[str, tuple[float | None, ...]]
    rmse: Mapping[str, NDArray[np.float64]]
    associations: tuple[tuple[str, Association], ...] = ()
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    gyro_heading_errors: Mapping[str, tuple[float | None, ...]] = field(default_factory=dict)

    def __repr__(self) -> str:
        means = ", ".join(
            f"{name}={float(errors.mean()):.6g} m" for name, errors in self.end_errors.items()
        )
        rmse = ", ".join(f"{name}={float(v.mean()):.6g} m" for name, v in self.rmse.items())
        return (
            f"ReplayReport(source={self.source!r}, runs={len(self.runs)}, mean_end_error: "
            f"{means}; mean_rmse: {rmse})"
        )

    @property
    def final(self) -> str:
        """The parameter set the replay is about: ``calibrated`` if given, else ``nominal``."""
        return "calibrated" if "calibrated" in self.parameter_sets else "nominal"

    @property
    def mean_end_error(self) -> float:
        """Mean end-position error [m] with the calibrated (else nominal) parameters."""
        return float(self.end_errors[self.final].mean())

    @property
    def mean_end_error_nominal(self) -> float:
        """Mean end-position error [m] with the nominal parameters."""
        return float(self.end_errors["nominal"].mean())

    @property
    def mean_rmse(self) -> float:
        """Mean over runs of the whole-trajectory RMSE [m], calibrated (else nominal)."""
        return float(self.rmse[self.final].mean())

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres, radians): what ``replay --json`` prints."""
        sets = self.parameter_sets
        out: dict[str, Any] = {
            "source": self.source,
            "format": self.format,
            "params": self.params_file,
            "runs": [
                {
                    "label": run.label,
                    "direction": run.direction.value,
                    **{f"end_error_{name}": float(self.end_errors[name][i]) for name in sets},
                    **{f"heading_error_{name}": self.heading_errors[name][i] for name in sets},
                    **{f"rmse_{name}": float(self.rmse[name][i]) for name in sets},
                    **{
                        f"gyro_heading_error_{name.replace(' ', '_')}": errors[i]
                        for name, errors in self.gyro_heading_errors.items()
                    },
                }
                for i, run in enumerate(self.runs)
            ],
            "mean_end_error": self.mean_end_error,
            "mean_end_error_nominal": self.mean_end_error_nominal,
            **{f"mean_rmse_{name}": float(self.rmse[name].mean()) for name in sets},
            "parameters": {
                name: {
                    "wheelbase": p.wheelbase,
                    "wheel_diameter_left": p.diameter_left,
                    "wheel_diameter_right": p.diameter_right,
                }
                for name, p in sets.items()
            },
            "time_association": {name: a.to_dict() for name, a in self.associations},
        }
        if "calibrated" in sets:
            out["mean_end_error_calibrated"] = float(self.end_errors["calibrated"].mean())
        return out

    def figure(self) -> Figure:
        """Every run's true path against its odometry paths (what ``--plot`` draws)."""
        from umbmark.outputs.plotting import replay_figure

        return replay_figure(self.runs, self.parameter_sets, title=f"Replay of {self.source}")

    @python_api
    def write(
        self,
        *,
        plot: str | os.PathLike[str] | None = None,
        tum: str | os.PathLike[str] | None = None,
        tum_time: TumTime = "recording",
        force: bool = False,
    ) -> list[Path]:
        """Write the figure and the TUM trajectories, each checked before any is written.

        Parameters
        ----------
        plot : path, optional
            The figure (.png, .svg, .pdf).
        tum : path, optional
            A folder for TUM trajectories of every run (truth and each parameter set).
        tum_time : {"recording", "run"}
            Timestamps of the TUM files: the recording's own clock [s] (default), or
            seconds from each run's start.
        force : bool
            Replace files that exist, write into a ``tum`` folder that holds files.

        Returns
        -------
        list of Path
            The files written.
        """
        from umbmark.outputs.tum import check_tum_time

        time = check_tum_time(tum_time)
        plan = OutputPlan.of(force=force, inputs=[self.source], plot=plot, tum=tum)
        written: list[Path] = []
        if plan.tum is not None:
            from umbmark.outputs.tum import write_tum_runs

            written += write_tum_runs(plan.tum, self.runs, self.parameter_sets, time=time)
        if plan.plot is not None:
            from umbmark.outputs.plotting import save_figure

            save_figure(self.figure(), plan.plot)
            written.append(plan.plot)
        return written


def replay(
    source: PathLike,
    params: Calibrated | None = None,
    *,
    wheelbase: float | None = None,
    plot: str | os.PathLike[str] | None = None,
    tum: str | os.PathLike[str] | None = None,
    tum_time: TumTime = "recording",
    force: bool = False,
    override_verdict: bool = False,
    **options: Unpack[SourceOptions],
) -> ReplayReport:
    """Replay recorded runs: integrate their wheel data again and compare with the truth.

    What ``umbmark replay`` does, with the same options as keywords.

    Parameters
    ----------
    source : path
        A run log, an OptiOdom session or a ROS bag (recorded wheel data and ground truth).
    params : path, CalibrationReport or CalibratedParams, optional
        A calibration to replay with: a result file (``calibrate -o result.json``) or a
        report from :func:`umbmark.calibrate`; without it, only the source's nominal
        parameters are replayed.
    wheelbase : float, optional
        Wheelbase [m] of the nominal parameters; overrides the source's.
    plot : path, optional
        Draw every run's true path and odometry paths (.png, .svg, .pdf).
    tum : path, optional
        A folder for TUM trajectories of every run (truth, nominal, calibrated).
    tum_time : {"recording", "run"}
        Timestamps of the TUM files: the recording's own clock [s] (default, so that evo
        can match them with other trajectories of the same recording), or seconds from
        each run's start.
    force : bool
        Replace ``plot`` if it exists and write into a ``tum`` folder that holds files;
        nothing else.
    override_verdict : bool
        Replay ``params`` (or take ``current_params``) even when it is a result for other
        nominal parameters (wheelbase, wheel diameter) than the source's own.
    **options
        How to read the source: see :class:`umbmark.runs.read_options.ReadOptions`.

    Raises
    ------
    InputError
        Bad input: one line naming the file and the problem.
    """
    read_options = ReadOptions.of(options)
    from umbmark.outputs.tum import check_tum_time

    check_tum_time(tum_time)
    OutputPlan.of(force=force, inputs=[source_name(source)], plot=plot, tum=tum)
    if is_table(source, read_options):
        raise InputError(
            "replay needs recorded wheel data (a run log, an OptiOdom session or a bag), "
            "not a runs table",
            source=source_name(source),
        )
    calibrated = None if params is None else calibrated_params(params)
    read = read_runs([source], read_options, wheelbase=wheelbase, override_verdict=override_verdict)
    nominal = read.params
    if nominal is None:  # pragma: no cover - is_table() refused end points above
        raise InputError("has no recorded wheel data", source=read.sources[0])
    if params is not None and read.nominal is not None and not override_verdict:
        check_same_robot(
            calibrated_name(params),
            calibrated_nominal(params),
            read.sources[0],
            (read.nominal.wheelbase, read.nominal.wheel_diameter),
        )
    sets = {"nominal": nominal}
    if calibrated is not None:
        sets["calibrated"] = calibrated.applied_to(nominal)
    results = {name: [run.reintegrated(p) for run in read.runs] for name, p in sets.items()}
    report = ReplayReport(
        source=read.sources[0],
        format=read.format,
        params_file=None if calibrated is None else calibrated.source or None,
        runs=read.runs,
        parameter_sets=sets,
        end_errors={name: end_errors(r) for name, r in results.items()},
        heading_errors={name: tuple(run.heading_error for run in r) for name, r in results.items()},
        rmse={
            name: np.array([_run_rmse(run, p) for run in read.runs], dtype=np.float64)
            for name, p in sets.items()
        },
        associations=read.associations,
        notes=split_messages(read.notes)[0],
        warnings=split_messages(read.notes)[1],
        gyro_heading_errors=_gyro(source, read_options, read.runs, calibrated),
    )
    report.write(plot=plot, tum=tum, tum_time=tum_time, force=force)
    return report


def _gyro(
    source: PathLike, options: ReadOptions, runs: tuple[Run, ...], params: CalibratedParams | None
) -> dict[str, tuple[float | None, ...]]:
    """The gyro's heading over each run against the truth's (with ``imu_topic``)."""
    if options.imu_topic is None:
        return {}
    from umbmark.calibration.gyro_bag import gyro_figures, gyro_heading_errors

    spans = [None if run.log is None else run.log.truth_turn() for run in runs]
    figures = None if params is None else gyro_figures(params)
    return gyro_heading_errors(source, options, spans, figures)


def _run_rmse(run: Run, params: WheelParams) -> float:
    if run.log is None:  # pragma: no cover - logged sources always attach their series
        raise InputError(f"{run.label} has no recorded wheel data to replay")
    return trajectory_rmse(run.log, params)

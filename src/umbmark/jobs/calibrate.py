"""The calibration job: runs in, UMBmark figures, error estimate and correction out.

:func:`calibrate` is what ``umbmark calibrate`` does; :class:`CalibrationReport` is
everything it found (:class:`umbmark.calibration.result.CalibrationResult`: its
:meth:`~umbmark.calibration.result.CalibrationResult.to_dict` is exactly what ``umbmark
calibrate --json`` prints) and the files it writes with ``--yaml``, ``--ros1-yaml``,
``--plot``, ``--tum`` and ``--report``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

from umbmark.calibration.result import CalibrationResult
from umbmark.calibration.sources import calibrate_sources
from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError, python_api
from umbmark.outputs.files import OutputPlan
from umbmark.runs.options import ReadOptions, SourceOptions
from umbmark.runs.read import RunSource, source_name

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from typing_extensions import Unpack

    from umbmark.outputs.tum import TumTime

__all__ = ["CalibrationReport", "calibrate"]


@dataclass(frozen=True, repr=False)
class CalibrationReport(CalibrationResult):
    """Everything a calibration found (:class:`~umbmark.calibration.result.CalibrationResult`),
    and the files it writes: the figure, the HTML page and :meth:`write`."""

    @classmethod
    def of(cls, result: CalibrationResult) -> CalibrationReport:
        """The report of ``result``."""
        return cls(**{f.name: getattr(result, f.name) for f in fields(result)})

    def figure(self) -> Figure:
        """The Fig. 6 view of the return errors (what ``--plot`` draws).

        Raises
        ------
        InputError
            Without runs in both directions.
        """
        if self.benchmark is None:
            raise InputError("--plot needs runs in both directions (cw and ccw)")
        from umbmark.outputs.plotting import cluster_figure

        title = "UMBmark return errors" + (f": {self.robot}" if self.robot else "")
        return cluster_figure([(self.benchmark, self.source)], title=title)

    def html(self) -> str:
        """One self-contained HTML page of the calibration (what ``--report`` writes)."""
        from umbmark.outputs.html_report import calibration_html

        return calibration_html(self)

    @python_api
    def write(
        self,
        *,
        output: str | os.PathLike[str] | None = None,
        yaml: str | os.PathLike[str] | None = None,
        ros1_yaml: str | os.PathLike[str] | None = None,
        plot: str | os.PathLike[str] | None = None,
        tum: str | os.PathLike[str] | None = None,
        tum_time: TumTime = "recording",
        report: str | os.PathLike[str] | None = None,
        force: bool = False,
        override_verdict: bool = False,
    ) -> list[Path]:
        """Write the requested files: every one checked before any is written.

        Parameters
        ----------
        output : path, optional
            The JSON result (:meth:`to_json`).
        yaml, ros1_yaml : path, optional
            The ros2_control overlay and the ROS 1 parameters.
        plot : path, optional
            The Fig. 6 view (.png, .svg or .pdf).
        tum : path, optional
            A folder for TUM trajectories of logged runs (truth, nominal, calibrated).
        tum_time : {"recording", "run"}
            Timestamps of the TUM files: the recording's own clock [s] (default), or
            seconds from each run's start.
        report : path, optional
            One self-contained HTML page of the calibration (:meth:`html`).
        force : bool
            Replace files that exist (and write into a ``tum`` folder that holds files);
            nothing else.
        override_verdict : bool
            Write ``yaml`` and ``ros1_yaml`` even when the verdict is "do not apply" (as
            does a report made with ``override_verdict``: :attr:`forced`).

        Returns
        -------
        list of Path
            The files written.

        Raises
        ------
        InputError
            For a file that cannot be written, an output this report cannot give, or
            a file that exists (without ``force``), or parameter files of a calibration
            not to apply (without ``override_verdict``).
        """
        from umbmark.outputs.tum import check_tum_time

        time = check_tum_time(tum_time)
        plan = _plan(
            self.sources,
            output=output,
            yaml=yaml,
            ros1_yaml=ros1_yaml,
            plot=plot,
            tum=tum,
            report=report,
            force=force,
        )
        return self._write(plan, time, override_verdict=override_verdict)

    def _write(self, plan: OutputPlan, time: TumTime, *, override_verdict: bool) -> list[Path]:
        """Write what ``plan`` (checked) names."""
        if plan.plot is not None and self.benchmark is None:
            raise InputError(
                "--plot needs runs in both directions (cw and ccw)", source=self.source
            )
        asked = [f for f, p in (("--yaml", plan.yaml), ("--ros1-yaml", plan.ros1_yaml)) if p]
        if asked and self.overlay_withheld and not override_verdict:
            raise InputError(
                f"{', '.join(asked)}: {self.verdict.line()} (--override-verdict writes it all "
                "the same; --force only replaces files that exist)",
                source=self.source,
            )
        calibrated = self.calibrated_params
        if plan.tum is not None and (self.params is None or calibrated is None):
            raise InputError("--tum needs logged runs with time series", source=self.source)
        written: list[Path] = []
        if plan.output is not None:
            atomic_write_text(plan.output, self.to_json())
            written.append(plan.output)
        if plan.yaml is not None:
            atomic_write_text(plan.yaml, self.overlay_yaml())
            written.append(plan.yaml)
        if plan.ros1_yaml is not None:
            atomic_write_text(plan.ros1_yaml, self.ros1_yaml())
            written.append(plan.ros1_yaml)
        if plan.plot is not None:
            from umbmark.outputs.plotting import save_figure

            save_figure(self.figure(), plan.plot)
            written.append(plan.plot)
        if plan.report is not None:
            atomic_write_text(plan.report, self.html())
            written.append(plan.report)
        if plan.tum is not None and self.params is not None and calibrated is not None:
            from umbmark.outputs.tum import write_tum_runs

            sets = {"nominal": self.params, "calibrated": calibrated}
            written += write_tum_runs(plan.tum, self.runs, sets, time=time)
        return written


def _plan(
    sources: Sequence[str], *, force: bool, **paths: str | os.PathLike[str] | None
) -> OutputPlan:
    return OutputPlan.of(force=force, inputs=sources, **paths)


def calibrate(
    source: RunSource,
    *more_sources: RunSource,
    side_length: float | None = None,
    wheelbase: float | None = None,
    method: str | None = None,
    fit_truth_offset: bool = False,
    output: str | os.PathLike[str] | None = None,
    yaml: str | os.PathLike[str] | None = None,
    ros1_yaml: str | os.PathLike[str] | None = None,
    plot: str | os.PathLike[str] | None = None,
    tum: str | os.PathLike[str] | None = None,
    tum_time: TumTime = "recording",
    report: str | os.PathLike[str] | None = None,
    force: bool = False,
    override_verdict: bool = False,
    robot: str | None = None,
    history: str | os.PathLike[str] | None = None,
    command: str | None = None,
    **options: Unpack[SourceOptions],
) -> CalibrationReport:
    """Benchmark runs around a square (UMBmark) and compute the correction.

    What ``umbmark calibrate`` does, with the same options as keywords (lengths in
    metres, angles in radians, times in seconds).

    Parameters
    ----------
    source, *more_sources : path or sequence of Run
        A runs table (CSV of end points), a run-log folder, an OptiOdom session folder or
        a ROS bag; or runs already in memory. Several sources are pooled; they must agree
        on the square and the parameters active during the runs.
    side_length : float, optional
        Side ``L`` of the square [m]. Logged sources may know it.
    wheelbase : float, optional
        Wheelbase ``b`` the odometry used during the runs [m] (ros2_control
        ``wheel_separation``); required for runs tables unless ``current_params`` has it.
    method : str, optional
        An estimator's name in :mod:`umbmark.estimators.registry` (``docs/estimators.md``
        says what each needs and finds), or ``auto``: the one that predicts held-out
        recorded runs best (:mod:`umbmark.calibration.auto`; runs tables take the
        default). Default: ``exact``, or ``scan-matching`` for motion intervals (tuple
        files, or a bag with ``scan_topic``).
    fit_truth_offset : bool
        ``trajectory`` and ``trajectory-scrub`` only: fit where the ground truth's tracked
        point (a motion-capture marker) sits in the robot frame, the components
        ``truth_offset_x``, ``truth_offset_y`` [m] (``docs/conventions.md``, "Tracked
        point"), instead of taking the ground truth as the axle centre's.
    output, yaml, ros1_yaml, plot, tum, report : path, optional
        Files to write (see :meth:`CalibrationReport.write`); checked before any is written.
    tum_time : {"recording", "run"}
        Timestamps of the TUM files: the recording's own clock [s] (default, so that evo
        can match them with other trajectories of the same recording), or seconds from
        each run's start.
    force : bool
        Replace output files that exist (and write into a ``tum`` folder that holds
        files); nothing else.
    override_verdict : bool
        Write ``yaml`` and ``ros1_yaml`` even when the verdict
        (:attr:`CalibrationReport.verdict`) is "do not apply" (without it they are not
        written, and the report's warnings say so); take ``current_params`` even when it
        is a result for other nominal parameters (wheelbase, wheel diameter) than the
        sources' own.
    robot : str, optional
        Record the calibration in the history under this robot's name
        (:class:`umbmark.store.history.History`); refused when the robot is known with another
        nominal wheelbase or wheel diameter. Without ``current_params`` and the
        ``current_*`` multipliers, the robot's last applied calibration's new parameters
        are taken as those active during the runs (a second pass; a note says so).
    history : path, optional
        The history file (default: ``$UMBMARK_HISTORY``, else the per-user file).
    command : str, optional
        The command line (or call) to state in the ``report`` page's provenance.
    **options
        How to read the sources: see :class:`umbmark.runs.options.ReadOptions`
        (``unit="mm"``, ``current_params="controllers.yaml"``, ``truth_topic=...``).

    Returns
    -------
    CalibrationReport

    Raises
    ------
    InputError
        Bad input: one line naming the file (and row) and the problem.

    Examples
    --------
    >>> report = umbmark.calibrate("runs.csv", side_length=4, wheelbase=0.34, unit="mm")
    >>> report.e_max_syst, report.estimate.E_d, report.calibration.new_c_left
    """
    store, composed = None, None
    if robot is not None:
        from umbmark.store.calibrations import recorded, same_robot
        from umbmark.store.history import History, compose_last_applied

        store = History(history)
        options, composed = compose_last_applied(store, robot, options)
    read_options = ReadOptions.of(options)
    time = _tum_time(tum_time)
    sources = (source, *more_sources)
    plan = _plan([source_name(s) for s in sources], output=output, yaml=yaml,
                 ros1_yaml=ros1_yaml, plot=plot, tum=tum, report=report, force=force)  # fmt: skip
    found = calibrate_sources(
        sources, read_options, method=method, wheelbase=wheelbase, side_length=side_length,
        override_verdict=override_verdict, fit_truth_offset=fit_truth_offset,
    )  # fmt: skip
    result = replace(CalibrationReport.of(found), robot=robot, command=command)
    if store is not None and robot is not None:
        result = same_robot(result, store, robot, composed)
    if result.overlay_withheld:  # the verdict says what to do instead
        files = {"yaml": plan.yaml, "ros1_yaml": plan.ros1_yaml}
        result = replace(result, withheld=tuple(k for k, v in files.items() if v is not None))
        plan = replace(plan, yaml=None, ros1_yaml=None)
    result._write(plan, time, override_verdict=override_verdict)
    if store is not None and robot is not None:
        result = recorded(result, store, robot, sources, override_verdict)
    return result


def _tum_time(tum_time: str) -> TumTime:
    from umbmark.outputs.tum import check_tum_time  # off start-up

    return check_tum_time(tum_time)

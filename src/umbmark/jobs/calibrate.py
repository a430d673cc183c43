"""The calibration job: runs in, UMBmark figures, error estimate and correction out.

:func:`calibrate` is what ``umbmark calibrate`` does; :class:`CalibrationReport` is
everything it found (:class:`umbmark.calibration.result.CalibrationResult`: its
:meth:`~umbmark.calibration.result.CalibrationResult.to_dict` is exactly what ``umbmark
calibrate --json`` prints) and the files it writes with ``--yaml``, ``--ros1-yaml``,
``--plot``, ``--tum`` and ``--report``.
"""

from __future__ import annotations

import os
from dataclasses import replace
from typing import TYPE_CHECKING

from umbmark.calibration.sources import calibrate_sources
from umbmark.outputs.calibration import CalibrationReport, plan_outputs
from umbmark.runs.read import RunSource, source_name
from umbmark.runs.read_options import ReadOptions, SourceOptions

if TYPE_CHECKING:
    from typing_extensions import Unpack

    from umbmark.outputs.files import OutputPlan
    from umbmark.outputs.tum import TumTime

__all__ = ["calibrate"]


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
        How to read the sources: see :class:`umbmark.runs.read_options.ReadOptions`
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
    plan = plan_outputs([source_name(s) for s in sources], output=output, yaml=yaml,
                 ros1_yaml=ros1_yaml, plot=plot, tum=tum, report=report, force=force)  # fmt: skip
    found = calibrate_sources(
        sources, read_options, method=method, wheelbase=wheelbase, side_length=side_length,
        override_verdict=override_verdict, fit_truth_offset=fit_truth_offset,
    )  # fmt: skip
    result = replace(CalibrationReport.of(found), robot=robot, command=command)
    result.check_nominal(plan, robot if store is not None else None)
    if store is not None and robot is not None:
        result = same_robot(result, store, robot, composed)
    if result.overlay_withheld:  # the verdict says what to do instead
        files = {"yaml": plan.yaml, "ros1_yaml": plan.ros1_yaml}
        result = replace(result, withheld=tuple(k for k, v in files.items() if v is not None))
        plan = replace(plan, yaml=None, ros1_yaml=None)
    result = _said_keyed(result, plan)
    result.write_planned(plan, time, override_verdict=override_verdict)
    if store is not None and robot is not None:
        result = recorded(result, store, robot, sources, override_verdict)
    return result


def _said_keyed(result: CalibrationReport, plan: OutputPlan) -> CalibrationReport:
    """``result`` with a note where it writes an overlay keyed by the default controller
    (nothing named it)."""
    if result.controller.named or not any((plan.yaml, plan.ros1_yaml, plan.report)):
        return result
    from umbmark.calibration.result import unnamed_controller

    return replace(result, notes=(*result.notes, unnamed_controller()))


def _tum_time(tum_time: str) -> TumTime:
    from umbmark.outputs.tum import check_tum_time  # off start-up

    return check_tum_time(tum_time)

"""A calibration's result and the files it writes (:class:`CalibrationReport`): the Fig. 6
view, the HTML page, the JSON, the controller parameter files and the TUM trajectories,
every one checked before any is written (:func:`plan_outputs`). What ``umbmark
calibrate`` returns, and each pass of the self-calibration."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from umbmark.calibration.result import CalibrationResult
from umbmark.core.atomic import atomic_write_text
from umbmark.core.errors import InputError, option, python_api
from umbmark.outputs.files import OutputPlan

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from umbmark.outputs.tum import TumTime

__all__ = ["CalibrationReport", "plan_outputs"]


@dataclass(frozen=True, repr=False)
class CalibrationReport(CalibrationResult):
    """Everything a calibration found (:class:`~umbmark.calibration.result.CalibrationResult`),
    and the files it writes: the figure, the HTML page and :meth:`write`."""

    @classmethod
    def of(cls, result: CalibrationResult) -> CalibrationReport:
        """The report of ``result``."""
        return cls(**{f.name: getattr(result, f.name) for f in fields(result)})

    def to_dict(self) -> dict[str, Any]:
        """The result's JSON (:meth:`CalibrationResult.to_dict`), and for a calibration
        from motion intervals the laser's mounting in the forms a user applies
        (``laser_mounting``: :mod:`umbmark.outputs.mounting`)."""
        from umbmark.outputs.mounting import mounting_forms

        out = super().to_dict()
        forms = mounting_forms(self)
        if forms is not None:
            out["laser_mounting"] = forms.to_dict()
        return out

    def figure(self) -> Figure:
        """The Fig. 6 view of the return errors (what ``--plot`` draws).

        Raises
        ------
        InputError
            Without runs in both directions.
        """
        if self.benchmark is None:
            raise InputError(f"{option('plot')} needs runs in both directions (cw and ccw)")
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
        plan = plan_outputs(
            self.sources,
            output=output,
            yaml=yaml,
            ros1_yaml=ros1_yaml,
            plot=plot,
            tum=tum,
            report=report,
            force=force,
        )
        return self.write_planned(plan, time, override_verdict=override_verdict)

    def check_nominal(self, plan: OutputPlan, robot: str | None = None) -> None:
        """Refuse the parameter files (and a history's record) of a calibration given no
        nominal geometry: they are multipliers of a nominal nobody gave.

        Raises
        ------
        InputError
            Naming the options asked for.
        """
        files = (("yaml", plan.yaml), ("ros1_yaml", plan.ros1_yaml), ("robot", robot))
        asked = [option(f) for f, p in files if p]
        if asked and not self.nominal:
            raise InputError(
                f"{', '.join(asked)} needs the nominal geometry the odometry uses "
                f"({option('wheelbase')} and {option('wheel_diameter')}, or "
                f"{option('current_params')}): without it the calibration gives absolute "
                "figures, no multipliers",
                source=self.source,
            )

    def write_planned(
        self, plan: OutputPlan, time: TumTime, *, override_verdict: bool
    ) -> list[Path]:
        """Write what ``plan`` (checked) names."""
        if plan.plot is not None and self.benchmark is None:
            raise InputError(
                f"{option('plot')} needs runs in both directions (cw and ccw)", source=self.source
            )
        asked = [option(f) for f, p in (("yaml", plan.yaml), ("ros1_yaml", plan.ros1_yaml)) if p]
        self.check_nominal(plan)
        if asked and self.overlay_withheld and not override_verdict:
            raise InputError(
                f"{', '.join(asked)}: {self.verdict.line()} ({option('override_verdict')} "
                f"writes it all the same; {option('force')} only replaces files that exist)",
                source=self.source,
            )
        calibrated = self.calibrated_params
        if plan.tum is not None and (self.params is None or calibrated is None):
            raise InputError(
                f"{option('tum')} needs logged runs with time series", source=self.source
            )
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


def plan_outputs(
    sources: Sequence[str], *, force: bool, **paths: str | os.PathLike[str] | None
) -> OutputPlan:
    return OutputPlan.of(force=force, inputs=sources, **paths)

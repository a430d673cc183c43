"""The history job: a robot's recorded calibrations and whether its errors drift.

:func:`history` is what ``umbmark history`` does; its report's
:meth:`~HistoryReport.to_dict` is what ``umbmark history --json`` prints.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from umbmark.core.errors import InputError, option, python_api, with_flags
from umbmark.core.jsontext import JsonText
from umbmark.outputs.files import OutputPlan
from umbmark.store.history import (
    DEFINITIONS,
    CalibrationRecord,
    History,
    RobotRecord,
    default_history_path,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: The command's words and the library's: the option renders itself, the example call
#: (the command line's syntax, or Python's) does not, so Python keeps its own text.
_PLOT_NEEDS_NAME = f"{option('plot')} needs the robot's NAME (umbmark history NAME --plot FILE)"
_PLOT_NEEDS_NAME_PY = "plot needs the robot's name (umbmark.history(name, plot=file))"
#: What a history that does not exist yet means, and how to record one.
_NOTHING_YET = (
    "nothing is recorded yet: umbmark calibrate SOURCE {robot} (or umbmark selfcal {robot}) "
    "records each calibration in this file"
)
_NOTHING_YET_PY = (
    "nothing is recorded yet: umbmark.calibrate(source, robot=name) (or umbmark.selfcal(..., "
    "robot=name)) records each calibration in this file"
)

#: Where the default history holds no robot: a fleet's (or any) history given its own file
#: is read by naming it.
_ELSEWHERE = (
    "a history written elsewhere (umbmark fleet ... --history FILE, calibrate --history "
    "FILE) is read with umbmark history --history FILE"
)
_ELSEWHERE_PY = (
    "a history written elsewhere (umbmark.fleet(..., history=file)) is read with "
    "umbmark.history(history=file)"
)

__all__ = ["HistoryReport", "history"]


@dataclass(frozen=True)
class HistoryReport(JsonText):
    """The robots of a history file, or one robot's calibrations.

    Attributes
    ----------
    path : str
        The history file.
    robot : str or None
        The robot asked for; None to list the robots.
    robots : tuple of RobotRecord
        Every robot (when ``robot`` is None).
    calibrations : tuple of CalibrationRecord
        The robot's calibrations, oldest first.
    drift : str or None
        The drift verdict (3 calibrations or more) on what the robot is, each pass's
        errors composed with the parameters active during it
        (:func:`umbmark.store.history.drift_verdict`).
    notes : tuple of str
        What was done, for people (a calibration marked applied).
    nominal : RobotRecord or None
        The robot asked for, with its nominal wheelbase and wheel diameter.
    """

    path: str
    robot: str | None = None
    robots: tuple[RobotRecord, ...] = ()
    calibrations: tuple[CalibrationRecord, ...] = ()
    drift: str | None = None
    notes: tuple[str, ...] = ()
    nominal: RobotRecord | None = None

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (metres): what ``history --json`` prints."""
        if self.robot is None:
            listing: dict[str, Any] = {
                "history": self.path,
                "robots": [r.to_dict() for r in self.robots],
            }
            if self.notes:
                listing["notes"] = list(self.notes)
            return listing
        out: dict[str, Any] = {
            "robot": self.robot,
            "history": self.path,
            "calibrations": [c.to_dict() for c in self.calibrations],
            "drift": self.drift,
            "definitions": dict(DEFINITIONS),
        }
        if self.notes:
            out["notes"] = list(self.notes)
        return out

    def figure(self) -> Figure:
        """The robot's E_d, E_b (composed with the active parameters, and as each pass
        measured them) and E_max,syst over time (what ``--plot`` draws).

        Raises
        ------
        InputError
            For a report that lists the robots instead of one robot's calibrations.
        """
        if self.nominal is None or not self.calibrations:
            raise InputError(_PLOT_NEEDS_NAME, python=_PLOT_NEEDS_NAME_PY)
        from umbmark.outputs.plotting import history_figure

        return history_figure(self.nominal, self.calibrations)

    @python_api
    def write(
        self, *, plot: str | os.PathLike[str] | None = None, force: bool = False
    ) -> list[Path]:
        """Write the trend figure (.png, .svg, .pdf), checked before it is drawn; a file
        that exists is replaced only with ``force``.

        Returns
        -------
        list of Path
            The files written.

        Raises
        ------
        InputError
            For a bad or unwritable name, one that is the history file itself, or a file
            that exists (without ``force``).
        """
        plan = OutputPlan.of(force=force, inputs=[self.path], plot=plot)
        written: list[Path] = []
        if plan.plot is not None:
            from umbmark.outputs.plotting import save_figure

            save_figure(self.figure(), plan.plot)
            written.append(plan.plot)
        return written


def history(
    robot: str | None = None,
    *,
    history: str | os.PathLike[str] | None = None,
    applied: int | None = None,
    force: bool = False,
    override_verdict: bool = False,
    plot: str | os.PathLike[str] | None = None,
) -> HistoryReport:
    """The robots of a history file, or one robot's calibrations and drift verdict.

    Parameters
    ----------
    robot : str, optional
        The robot; None lists the robots.
    history : path, optional
        The history file (default: ``$UMBMARK_HISTORY``, else the per-user file); read
        only, never created: where it does not exist yet, the list of robots is empty with
        a note saying how to record one, and a robot asked for is refused saying so.
    applied : int, optional
        Mark this calibration of ``robot`` as applied first (refused for a calibration
        whose verdict was "do not apply").
    force : bool
        Replace ``plot`` if it exists; nothing else.
    override_verdict : bool
        Mark ``applied`` even when its verdict was "do not apply".
    plot : path, optional
        Draw the robot's E_d, E_b and the passes' E_max,syst over time
        (:meth:`HistoryReport.figure`)
        to a .png, .svg or .pdf file (written atomically, never onto the history file).

    Returns
    -------
    HistoryReport

    Raises
    ------
    InputError
        For an unknown robot or calibration, a calibration not to apply (without
        ``override_verdict``), a plot that exists (without ``force``), or a file that is
        not a history.
    """
    if plot is not None and robot is None:
        raise InputError(_PLOT_NEEDS_NAME, python=_PLOT_NEEDS_NAME_PY)
    where = Path(history) if history is not None else default_history_path()
    if not where.exists() and not where.is_symlink():  # a read never creates the file
        nothing, python = _nothing_yet(default=history is None)
        if robot is None and applied is None:  # a fresh install: an empty list, said so
            return HistoryReport(path=str(where), notes=(f"{where}: {with_flags(nothing)}",))
        raise InputError(nothing, source=where, python=python)
    store = History(history, read_only=True)  # a read never creates the file
    path = str(store.path)
    if plot is not None:  # the output is checked before a calibration is marked applied
        OutputPlan.of(force=force, inputs=[store.path], plot=plot)
    if robot is None:
        if applied is not None:
            raise InputError(f"{option('applied')} needs the robot's NAME")
        return _listing(store, default=history is None)
    nominal = store.robot(robot)
    if nominal is None:
        known = ", ".join(r.name for r in store.robots()) or "none yet"
        unknown = f"no robot {robot!r} in the history (robots: {known})"
        if history is None:
            raise InputError(f"{unknown}; {_ELSEWHERE}", source=path,
                             python=f"{unknown}; {_ELSEWHERE_PY}")  # fmt: skip
        raise InputError(unknown, source=path)
    notes: tuple[str, ...] = ()
    if applied is not None:
        from umbmark.core.bounds import check_int_option

        number = check_int_option(option("applied"), applied, 1, 2**63 - 1)
        History(store.path).mark_applied(robot, number, override_verdict=override_verdict)
        notes = (f"calibration {applied} of {robot} marked applied",)
    calibrations = tuple(store.calibrations(robot))
    report = HistoryReport(
        path=path,
        robot=robot,
        calibrations=calibrations,
        drift=store.drift(robot),
        notes=notes,
        nominal=nominal,
    )
    if plot is not None:
        report.write(plot=plot, force=force)
    return report


def _nothing_yet(*, default: bool) -> tuple[str, str]:
    """That a history holds nothing yet and how to record, as the command line and as
    Python say it; of the default history, also where another is read from (a fleet's
    records are in the file its ``--history FILE`` named)."""
    nothing, python = _NOTHING_YET.format(robot=option("robot", "NAME")), _NOTHING_YET_PY
    if default:
        return f"{nothing}; {_ELSEWHERE}", f"{python}; {_ELSEWHERE_PY}"
    return nothing, python


def _listing(store: History, *, default: bool) -> HistoryReport:
    """The robots of ``store``; the default history holding none says so, and where
    another history is read from."""
    robots = tuple(store.robots())
    notes: tuple[str, ...] = ()
    if not robots and default:
        notes = (f"{store.path}: {with_flags(_nothing_yet(default=True)[0])}",)
    return HistoryReport(path=str(store.path), robots=robots, notes=notes)

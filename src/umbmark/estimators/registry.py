"""The estimators, in one table: each one's name, what it needs, and where it lives.

Everything that names an estimator reads it here: the dispatch
(:mod:`umbmark.estimators.dispatch`), ``validate`` and ``--method auto``, the commands'
``--method`` choices and help, the summaries. Adding an estimator is a module with its
function and one :class:`Estimator` in :data:`ESTIMATORS`.

The functions are named as ``"module:function"`` and imported on first use
(:meth:`Estimator.load`), so that reading the table costs nothing: the command line
builds its options from it before numpy is imported. Two calling conventions, by what
an estimator needs (:attr:`Estimator.needs`):

- ``"square"``, the end points of a bi-directional square test (runs tables, or the ends
  of recorded squares): ``function(bench, runs=runs, test=test)`` returns the
  :class:`~umbmark.estimators.base.ErrorEstimate`, with ``E_s=E_s`` and ``fit=fit`` too
  where :attr:`Estimator.fits_end_poses`. The dispatch refuses runs beyond what the
  method takes and adds the model check's warnings (:mod:`umbmark.estimators.diagnostics`).
- ``"logs"``, recorded runs of any shape: ``function(logs, params, side_length,
  **options)`` (``fit_truth_offset=...`` too where :attr:`Estimator.trajectories`)
  returns the estimate and the fit.
- ``"intervals"``, motion intervals of the wheels against a sensor's own motion
  (:class:`~umbmark.model.motion_intervals.MotionIntervals`: tuple files, scan matching
  of a bag's laser): ``function(intervals, params, side_length, **options)`` returns the
  estimate and the calibration (wheels and sensor mounting). No runs: the dispatch of
  runs, ``validate`` and ``--method auto`` leave these estimators out (:data:`RUNS`).
- ``"imu"``, a recording's wheels against its gyro
  (:class:`~umbmark.scans.gyro_intervals.GyroIntervals`, with an absolute heading
  reference or not): ``function(intervals, params, side_length, *, reference=None,
  scale_tolerance=..., **options)`` returns the estimate and the gyro's calibration
  (:class:`~umbmark.estimators.gyro.GyroCalibration`). No runs either: ``validate`` and
  ``--method auto`` leave them out (:data:`GYROS`).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

__all__ = [
    "AUTO",
    "CHOICES",
    "DEFAULT",
    "ENDPOINTS",
    "ENDPOSE",
    "ESTIMATORS",
    "EXACT",
    "GYRO",
    "GYROS",
    "HEADING",
    "INTERVALS",
    "LOGGED",
    "NAMES",
    "PAPER",
    "RUNS",
    "SCAN_MATCHING",
    "SQUARE",
    "STRAIGHT",
    "TRAJECTORY",
    "TRAJECTORY_SCRUB",
    "Estimator",
    "Method",
    "Needs",
    "Reach",
    "estimator",
    "find",
    "method_help",
    "method_label",
    "names",
]

#: The estimators' names, as a type (:data:`NAMES` in the table's order; a test keeps
#: them equal).
Method = Literal[
    "paper",
    "exact",
    "heading",
    "endpose",
    "endpoints",
    "trajectory",
    "trajectory-scrub",
    "scan-matching",
    "gyro",
]
Needs = Literal["square", "logs", "intervals", "imu"]
Reach = Literal["side", "path"]
#: How ``--help`` introduces the estimators of each kind.
_KINDS: dict[Needs, str] = {
    "square": "Square tests",
    "logs": "Recorded runs of any shape",
    "intervals": "Wheels against a laser's scan matching (tuple files)",
    "imu": "Wheels against a gyro (a recording's IMU)",
}


@dataclass(frozen=True)
class Estimator:
    """One estimator of the systematic errors.

    Attributes
    ----------
    name : str
        What ``--method`` and ``ErrorEstimate.method`` call it.
    label : str
        What it is, for people (the title of the summary's table of errors).
    summary : str
        What it does, in a phrase, for ``--help``.
    needs : {"square", "logs", "intervals", "imu"}
        A square test's end points (runs tables too; the square's side is required),
        recorded runs (time series: run logs, OptiOdom sessions, bags), motion
        intervals (the wheels against a sensor's scan-matched motion), or a recording's
        wheels and gyro.
    function : str
        ``"module:function"``, called as the module's documentation says.
    headings : bool
        It needs headings: a ground truth that measures them (not a GNSS fix or a
        tracked point alone).
    reach : {"side", "path"} or None
        A square estimator's farthest return error: within the square's side (the
        paper's small-angle formulas mean nothing beyond), within the whole path's length
        (the exact geometry: farther is no robot, a unit slip), or any (None).
    fits_end_poses : bool
        A square estimator whose estimate is the end-pose fit itself
        (:func:`~umbmark.estimators.endpose.fit_end_poses`): it holds ``E_s`` measured by
        straight runs fixed (the others' ``E_b`` is scaled by it afterwards,
        :meth:`~umbmark.estimators.base.ErrorEstimate.with_scale`), and the dispatch makes
        the fit once, for the estimate and for the model check.
    trajectories : bool
        It fits whole recorded trajectories: it takes ``--fit-truth-offset``, can take
        minutes, and pooled sources are fitted one by one as well to see whether they
        disagree.
    turn_rate : bool
        It fits the scrub model's turn-rate term, which only recordings that hold arcs
        and turns on the spot, with a fit that pins the term, identify
        (:mod:`umbmark.estimators.motions`): ``validate`` and ``--method auto`` leave it
        out elsewhere.
    options : tuple of (str, str)
        Keyword arguments of ``function`` that make this estimator of it.
    """

    name: Method
    label: str
    summary: str
    needs: Needs
    function: str
    headings: bool = False
    reach: Reach | None = None
    fits_end_poses: bool = False
    trajectories: bool = False
    turn_rate: bool = False
    options: tuple[tuple[str, str], ...] = ()

    @property
    def side_required(self) -> bool:
        """Whether the square's side must be known (for every square estimator)."""
        return self.needs == "square"

    def load(self) -> Callable[..., Any]:
        """The estimator's function, imported now."""
        module, _, function = self.function.partition(":")
        found: Callable[..., Any] = getattr(importlib.import_module(module), function)
        return found


PAPER = Estimator(
    name="paper",
    label="the paper's equations (Eqs. 4.20-4.27, x and y averaged)",
    summary="Eqs. 4.20-4.27 as printed",
    needs="square",
    function="umbmark.estimators.paper:paper_estimate",
    reach="side",
)

EXACT = Estimator(
    name="exact",
    label="exact square geometry, inverted numerically",
    summary="the exact square geometry inverted, no small-angle approximation",
    needs="square",
    function="umbmark.estimators.exact:exact_estimate",
    reach="path",
)

HEADING = Estimator(
    name="heading",
    label="final heading errors (Jung & Chung 2011)",
    summary="final headings, Jung & Chung 2011",
    needs="square",
    function="umbmark.estimators.heading:heading_estimate",
    headings=True,
)

ENDPOSE = Estimator(
    name="endpose",
    label="maximum likelihood on the runs' end poses, exact geometry",
    summary="maximum likelihood on every run's end pose",
    needs="square",
    function="umbmark.estimators.endpose:endpose_estimate",
    reach="path",
    fits_end_poses=True,
)

ENDPOINTS = Estimator(
    name="endpoints",
    label="least squares on where the recorded runs end",
    summary="least squares on where they end",
    needs="logs",
    function="umbmark.estimators.endpoints:endpoints_estimate",
    headings=True,
)

TRAJECTORY = Estimator(
    name="trajectory",
    label="least squares on whole recorded trajectories",
    summary="on whole trajectories; finds E_s too",
    needs="logs",
    function="umbmark.estimators.trajectory:trajectory_estimate",
    headings=True,
    trajectories=True,
)

TRAJECTORY_SCRUB = Estimator(
    name="trajectory-scrub",
    label="least squares on whole trajectories, turn-dependent wheelbase",
    summary="with a turn-dependent wheelbase; exports the single-wheelbase set",
    needs="logs",
    function="umbmark.estimators.trajectory:trajectory_estimate",
    headings=True,
    trajectories=True,
    turn_rate=True,
    options=(("model", "scrub"),),
)

SCAN_MATCHING = Estimator(
    name="scan-matching",
    label="wheels and laser mounting from scan matching (Censi et al. 2013)",
    summary="both wheel radii, the wheelbase and the laser's mounting, Censi et al. 2013",
    needs="intervals",
    function="umbmark.estimators.scan_matching:scan_matching_estimate",
)

GYRO = Estimator(
    name="gyro",
    label="wheels and gyro together (the gyro's scale and bias, E_d, E_b)",
    summary="E_d, and E_b relative to the gyro; with a heading reference, the gyro's scale "
    "and bias too",
    needs="imu",
    function="umbmark.estimators.gyro:gyro_estimate",
)

#: Every estimator, in the order the documentation and ``--help`` list them.
ESTIMATORS: tuple[Estimator, ...] = (
    PAPER,
    EXACT,
    HEADING,
    ENDPOSE,
    ENDPOINTS,
    TRAJECTORY,
    TRAJECTORY_SCRUB,
    SCAN_MATCHING,
    GYRO,
)

_BY_NAME: dict[str, Estimator] = {e.name: e for e in ESTIMATORS}
#: Every estimator's name.
NAMES: tuple[Method, ...] = tuple(e.name for e in ESTIMATORS)
#: The estimators of square tests' end points ...
SQUARE: tuple[Method, ...] = tuple(e.name for e in ESTIMATORS if e.needs == "square")
#: ... and of recorded runs.
LOGGED: tuple[Method, ...] = tuple(e.name for e in ESTIMATORS if e.needs == "logs")
#: ... of motion intervals (the wheels against a sensor's own motion) ...
INTERVALS: tuple[Method, ...] = tuple(e.name for e in ESTIMATORS if e.needs == "intervals")
#: ... of a recording's wheels against its gyro ...
GYROS: tuple[Method, ...] = tuple(e.name for e in ESTIMATORS if e.needs == "imu")
#: ... and of runs, square tests or recordings (what ``validate`` and ``auto`` compare).
RUNS: tuple[Method, ...] = SQUARE + LOGGED
#: The estimator used unless another is asked for: chosen by the evidence of
#: ``umbmark study`` and ``umbmark validate`` (``docs/estimators.md``).
DEFAULT: Estimator = EXACT
#: The meta-estimator: the estimator that predicts held-out recorded runs best
#: (:func:`umbmark.validate`), else :data:`DEFAULT`.
AUTO = "auto"
_AUTO_SUMMARY = "the one that predicts held-out recorded runs best (umbmark validate)"
#: What ``--method`` takes.
CHOICES: tuple[str, ...] = (*NAMES, AUTO)
#: The method of an estimate from straight runs alone (:mod:`umbmark.estimators.scale`),
#: what a square estimator gives without squares; and its label.
STRAIGHT = "straight"
_STRAIGHT_LABEL = "straight runs against a tape (scale only)"


def find(name: str) -> Estimator | None:
    """The estimator called ``name``, or None."""
    return _BY_NAME.get(name)


def estimator(name: str) -> Estimator:
    """The estimator called ``name``.

    Raises
    ------
    ValueError
        For an unknown name.
    """
    found = _BY_NAME.get(name)
    if found is None:
        raise ValueError(f"unknown method {name!r}; use one of {', '.join(NAMES)}")
    return found


def names(**flags: object) -> tuple[Method, ...]:
    """The names of the estimators whose attributes have these values, in table order:
    ``names(needs="square", headings=False)``."""
    return tuple(e.name for e in ESTIMATORS if all(getattr(e, k) == v for k, v in flags.items()))


def method_label(method: str) -> str:
    """An estimate's method for people (``ErrorEstimate.method``; unknown: as given)."""
    found = _BY_NAME.get(method)
    if found is not None:
        return found.label
    return _STRAIGHT_LABEL if method == STRAIGHT else method


def method_help() -> str:
    """The help of ``--method``: every estimator by kind, then ``auto``."""
    parts = [
        f"{_KINDS[kind]}: "
        + ", ".join(f"{e.name} ({e.summary})" for e in ESTIMATORS if e.needs == kind)
        for kind in _KINDS
    ]
    return f"Estimator. {'. '.join(parts)}. {AUTO}: {_AUTO_SUMMARY}."

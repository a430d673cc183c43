"""Whether a runs table's numbers are what a robot driving the square makes.

A robot driving UMBmark's square steers by its own odometry (Sec. 3.3): its odometry
believes it came back, so the **odometry end points lie near the start** (within the
controller's tolerance: millimetres to a few centimetres). Its **true end points**, and
so the return errors, gather in two clusters (cw, ccw) about the systematic errors'
centres: a few millimetres to tens of centimetres off for a robot near calibration
(the paper's uncalibrated LabMates: 7 % of the side), metres for one whose wheelbase or
wheels are far off. The clusters **scatter** by the floor and the wheels' slip (the
paper: 25 mm on a 4 m square), more than a tape measure resolves and far less than the
side. And **one robot of the square's exact geometry** explains both clusters
(:func:`umbmark.estimators.endpose.fit_end_poses`: legs as arcs, no small angles).

A table read in another unit than it was written in, or with its measured and odometry
columns swapped, breaks these:

- :func:`check_columns`: odometry end points far from the start, and farther than the
  measured ones: the columns are swapped (refused; a warning where it is less clear).
- :func:`unit_hints`: the table read in each unit (m, cm, mm) is judged as above. The
  unit asked for stands if its reach is typical (a quarter of the side at most). Else
  every other unit that makes the table plausible is named with the E_max,syst it gives;
  large return errors that one robot of the exact geometry explains, and no other unit
  does, stand (the exact inversion takes them); return errors beyond the side that
  neither explains are refused naming the real cause (errors beyond what the square test
  identifies) and the remedy (a coarse turning calibration first).
- Single rows in another unit, and headings in radians given as degrees.
"""

from __future__ import annotations

import contextlib
import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Literal

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, option, with_flags
from umbmark.core.messages import Blocking, blocking
from umbmark.model.run import EndPose, Run

if TYPE_CHECKING:
    from umbmark.runs.read import SourceRuns

__all__ = ["UNITS", "check_columns", "judge_table", "unit_hints"]

#: Length units a table may be in, in metres.
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}
#: End points and return errors within this fraction of the side are typical of a robot
#: near calibration (the paper's uncalibrated robot: 7 %): the unit asked for stands.
_PLAUSIBLE_REACH = 0.25
#: Below this fraction (0.4 mm on a 4 m square) no tape measure resolves them.
_TINY_REACH = 1e-4
#: Another unit is named only if it puts them beyond this fraction (4 mm on a 4 m
#: square) ...
_SMALLEST_REACH = 1e-3
#: ... and its return errors within this many sides: farther, they are farther from the
#: start than the whole path is long.
_REACHABLE = 4.0
#: A robot steering by its odometry ends with its odometry within this fraction of the
#: side from the start (20 cm on a 4 m square; a controller's tolerance is centimetres).
_NEAR_START = 0.05
#: The runs' scatter about their centres [m] is at least what a tape measure resolves ...
_LEAST_SCATTER = 0.0005
#: ... and at most this fraction of the side (20 cm on a 4 m square; the paper: 25 mm).
_MOST_SCATTER = 0.05
#: Odometry end points this many times farther from the start than the measured ones,
#: and at least :data:`_FAR_ODOMETRY` of the side away, are the measured ones: refused.
_SWAPPED_RATIO = 10.0
_FAR_ODOMETRY = 0.02
#: ... this many times and :data:`_NEAR_ODOMETRY` of the side: a warning.
_DOUBTFUL_RATIO = 4.0
_NEAR_ODOMETRY = 0.005

Fit = Literal["fits", "misfit", "fails", "unknown"]


@dataclass(frozen=True)
class _Reading:
    """A table's square runs read in one unit.

    Attributes
    ----------
    unit : str
    runs : tuple of Run
        The runs in metres, as this unit makes them.
    error : float
        The largest return error [m].
    reach : float
        The farthest end point or return error from the start [m].
    odometry : float
        The farthest odometry end point [m].
    scatter : float or None
        The runs' pooled standard deviation about their direction's centre [m] (None
        with fewer than two runs in every direction).
    e_max : float or None
        E_max,syst [m] (Eq. 3.4; None without two runs in each direction).
    """

    unit: str
    runs: tuple[Run, ...]
    error: float
    reach: float
    odometry: float
    scatter: float | None
    e_max: float | None

    def typical(self, side: float) -> bool:
        """Within a quarter of the side: the unit asked for stands."""
        return self.reach <= _PLAUSIBLE_REACH * side and self.odometry <= _NEAR_START * side

    def sound(self, side: float) -> bool:
        """Every magnitude is what a robot driving the square makes (see the module)."""
        scatter_ok = self.scatter is None or (
            _LEAST_SCATTER <= self.scatter <= _MOST_SCATTER * side
        )
        return (
            _SMALLEST_REACH * side <= self.reach
            and self.error <= _REACHABLE * side
            and self.odometry <= _NEAR_START * side
            and scatter_ok
        )

    def shown(self) -> str:
        """``they would reach 0.3246 m, E_max,syst 307.2 mm``."""
        text = f"they would reach {self.reach:.4g} m"
        if self.e_max is not None:
            text += f", E_max,syst {1000 * self.e_max:.4g} mm"
        return text


def _scaled(run: Run, factor: float) -> Run:
    def scaled(pose: EndPose) -> EndPose:
        return EndPose(pose.x * factor, pose.y * factor, pose.theta)

    return Run(run.direction, scaled(run.true_end), scaled(run.odometry_end), run.label)


def _read_as(squares: Sequence[Run], given: str, unit: str) -> _Reading | None:
    """The table's runs, written in ``given``, read as ``unit`` (None where a number
    overflows: far beyond any robot)."""
    from umbmark.returns.clusters import umbmark_benchmark

    factor = UNITS[unit] / UNITS[given]
    try:
        runs = tuple(_scaled(run, factor) for run in squares) if factor != 1.0 else tuple(squares)
    except ValueError:
        return None
    errors = [math.hypot(*run.return_error) for run in runs]
    odometry = max(math.hypot(r.odometry_end.x, r.odometry_end.y) for r in runs)
    truth = max(math.hypot(r.true_end.x, r.true_end.y) for r in runs)
    e_max = None
    # Numbers near the float range (a hostile table) overflow to inf: implausible anyway.
    with np.errstate(all="ignore"):
        with contextlib.suppress(ValueError):  # fewer than two runs in a direction
            e_max = umbmark_benchmark(runs).e_max_syst
        scatter = _scatter(runs)
    return _Reading(
        unit=unit,
        runs=runs,
        error=max(errors),
        reach=max(*errors, odometry, truth),
        odometry=odometry,
        scatter=scatter,
        e_max=e_max,
    )


def _scatter(runs: Sequence[Run]) -> float | None:
    """Pooled standard deviation [m] of the return errors about their direction's centre."""
    squares, dof = 0.0, 0
    for direction in Direction:
        errors = np.array([r.return_error for r in runs if r.direction is direction])
        if len(errors) >= 2:
            squares += float(np.sum((errors - errors.mean(axis=0)) ** 2))
            dof += len(errors) - 1
    return math.sqrt(squares / dof) if dof else None


def _fit(reading: _Reading, side: float, wheelbase: float | None) -> Fit:
    """Whether one robot of the square's exact geometry explains the reading: ``fits``
    (the model check passes), ``misfit`` (it fails), ``fails`` (no robot ends near the
    centres), ``unknown`` (too few runs, or no wheelbase, to tell)."""
    from umbmark.estimators.base import SquareTest
    from umbmark.estimators.endpose import fit_end_poses
    from umbmark.estimators.exact import check_identified, exact_components
    from umbmark.returns.clusters import umbmark_benchmark

    if wheelbase is None or reading.e_max is None:
        return "unknown"
    bench = umbmark_benchmark(reading.runs)
    test = SquareTest(side, wheelbase)
    with np.errstate(all="ignore"):
        try:
            centres = np.concatenate([bench.cw.cg, bench.ccw.cg])
            check_identified(exact_components(centres, test), bench, test)
            fit = fit_end_poses(bench, reading.runs, test)
        except (ValueError, np.linalg.LinAlgError):
            return "fails"
    return "misfit" if fit.check.failed else "fits"


def unit_hints(
    runs: Sequence[Run],
    unit: str,
    angle_unit: str,
    side: float | None,
    wheelbase: float | None,
    name: str,
) -> list[str]:
    """Warnings where a table's runs look like other units than it says: the whole table
    (see the module), single rows (:func:`_mixed_unit_rows`) or the headings
    (:func:`_heading_unit_hints`).

    Parameters
    ----------
    runs : sequence of Run
        The table's runs, read in ``unit`` and ``angle_unit``.
    side : float or None
        The square's side [m]; None: the table is not judged as a whole.
    wheelbase : float or None
        The odometry's wheelbase [m] (for the exact geometry).
    name : str
        The table, for messages.

    Raises
    ------
    InputError
        Where a return error is larger than the side (or than the whole path) and another
        unit explains it, or nothing does.
    """
    squares = [run for run in runs if run.kind == "square"]
    if not squares or unit not in UNITS:
        return []
    return [
        *_table_unit_hints(squares, unit, side, wheelbase, name),
        *_mixed_unit_rows(squares, unit),
        *_heading_unit_hints(squares, angle_unit),
    ]


def _table_unit_hints(
    squares: Sequence[Run], unit: str, side: float | None, wheelbase: float | None, name: str
) -> list[str]:
    """The judgement of the whole table (see the module)."""
    if side is None:
        return []
    given = _read_as(squares, unit, unit)
    if given is None:
        return []
    tiny = given.reach < _TINY_REACH * side
    still = given.scatter is not None and 0.0 < given.scatter < _LEAST_SCATTER
    if given.reach == 0.0 or (given.typical(side) and not tiny and not still):
        return []
    readings = [_read_as(squares, unit, other) for other in UNITS if other != unit]
    sound = [r for r in readings if r is not None and r.sound(side)]
    fits = {r.unit: _fit(r, side, wheelbase) for r in sound}
    # Units one robot explains; where none does, the magnitudes alone.
    named = [r for r in sound if fits[r.unit] != "misfit" and fits[r.unit] != "fails"] or [
        r for r in sound if given.error > _REACHABLE * side or tiny or still
    ]
    if tiny or still:
        return [] if not named else [_unit_mistake(given, named, unit, side, tiny=tiny)]
    worst = max(range(len(squares)), key=lambda k: math.hypot(*given.runs[k].return_error))
    label = squares[worst].label or "a run"
    if given.error > _REACHABLE * side:
        if not named:
            return []  # the estimators refuse it (farther than the path is long)
        raise InputError(
            f"the return error of {label} ({given.error:.4g} m) is larger than the square's "
            f"side ({side:g} m), farther from the start than the whole "
            f"{_REACHABLE * side:g} m path is long: are the lengths in the right unit? "
            f"{_choice(named, unit, capital=True)}",
            source=name,
        )
    # Large return errors: a robot far off, or another unit.
    fit = _fit(given, side, wheelbase)
    explained = fit in ("fits", "unknown") and given.sound(side)
    beyond = given.error > side
    if named and not explained:
        if beyond:
            raise InputError(
                f"the return error of {label} ({given.error:.4g} m) is larger than the "
                f"square's side ({side:g} m), and no robot driving the square explains the "
                f"runs in {unit}: are the lengths in the right unit? "
                f"{_choice(named, unit, capital=True)}",
                source=name,
            )
        said = (
            f"the end points and return errors reach {given.reach:.4g} m, "
            f"{100 * given.reach / side:.0f} % of the {side:g} m side, and no robot driving "
            f"the square explains them in {unit}; {_choice(named, unit)}"
        )
        if fit == "fails":  # the exact geometry cannot take them: refused
            raise InputError(said, source=name)
        return [with_flags(said)]
    if named:
        shown = f", E_max,syst {1000 * given.e_max:.4g} mm" if given.e_max is not None else ""
        return [
            f"the end points and return errors reach {given.reach:.4g} m, "
            f"{100 * given.reach / side:.0f} % of the {side:g} m side{shown}: a robot whose "
            f"wheelbase or wheels are far off, or a table in another unit than {unit}: "
            f"{with_flags(_choice(named, unit, question=False))}; say which with --unit"
        ]
    if beyond and fit == "fails":
        raise InputError(_too_large(label, given, side), source=name)
    return []


def _unit_mistake(
    given: _Reading, named: Sequence[_Reading], unit: str, side: float, *, tiny: bool
) -> Blocking:
    """The warning (and the verdict's reason) where the table's numbers are far smaller
    than any robot's in the unit given and another unit makes them a robot's."""
    said = []
    square = f" on a {side:g} m square"
    if tiny:
        said.append(f"the end points and return errors reach only {1000 * given.reach:.3g} mm")
    if given.scatter is not None and given.scatter < _LEAST_SCATTER:
        said.append(f"the runs scatter by only {1000 * given.scatter:.3g} mm about their centres")
    said[0] += square
    why = (
        f"{' and '.join(said)}, less than a tape measure resolves (no robot driving a "
        f"square comes back within {1000 * _LEAST_SCATTER:g} mm of where it came back "
        "before: slip alone scatters the returns by millimetres)"
    )
    others = " or ".join(r.unit for r in named)
    options = " or ".join(option("unit", r.unit) for r in named)
    return blocking(
        with_flags(f"{why}; {_choice(named, unit)}"),
        f"the table is likely in another unit than {unit} ({others}): {' and '.join(said)}, "
        "less than a tape measure resolves; the correction is no robot's",
        f"calibrate again with the table's unit ({options})",
    )


def _choice(
    named: Sequence[_Reading], unit: str, *, capital: bool = False, question: bool = True
) -> str:
    """``read as mm, they would reach ...: are these mm, not m? (--unit mm)``, or every
    reading named and the user asked to choose (naming the option by
    :func:`~umbmark.core.errors.option`: a warning passes through
    :func:`~umbmark.core.errors.with_flags`)."""
    read = "Read" if capital else "read"
    if len(named) == 1 and question:
        other = named[0].unit
        shown = named[0].shown()
        return (
            f"{read} as {other}, {shown}: are these {other}, not {unit}? ({option('unit', other)})"
        )
    parts = [f"as {r.unit}, {r.shown()} ({option('unit', r.unit)})" for r in named]
    listed = f"{read} " + "; ".join(parts)
    return f"{listed}: which unit is the table in?" if question else listed


def _too_large(label: str, given: _Reading, side: float) -> str:
    """The refusal of return errors beyond the side that no robot of the exact geometry
    and no other unit explains: its real cause and the remedy."""
    from umbmark.estimators.exact import beyond_square_test

    why = (
        f"no robot driving the square ends where these runs end (the return error of {label} "
        f"is {given.error:.4g} m), in this unit or another"
    )
    return beyond_square_test(why, given.e_max or given.error, side)


def check_columns(runs: Sequence[Run], side: float | None, name: str) -> list[str]:
    """Refuse (or warn of) a table whose measured and odometry columns look swapped.

    A robot steering by its odometry ends where its odometry says it started: the
    odometry end points are the ones near the start. Refused where they lie
    :data:`_SWAPPED_RATIO` times farther from the start than the measured ones (medians)
    and at least :data:`_FAR_ODOMETRY` of the side away; warned of from
    :data:`_DOUBTFUL_RATIO` times and :data:`_NEAR_ODOMETRY` of the side. Without the
    side, a 4 m square is assumed for these bounds.

    Raises
    ------
    InputError
        Naming the table and the columns.
    """
    squares = [run for run in runs if run.kind == "square"]
    if not squares:
        return []
    scale = 4.0 if side is None else side
    _check_odometry_frame(squares, scale, name)
    odometry = statistics.median(math.hypot(r.odometry_end.x, r.odometry_end.y) for r in squares)
    truth = statistics.median(math.hypot(r.true_end.x, r.true_end.y) for r in squares)
    if odometry < _NEAR_ODOMETRY * scale or odometry < _DOUBTFUL_RATIO * truth:
        return []
    said = (
        f"x_odo, y_odo put the robot's end {1000 * odometry:.4g} mm from the start (median), "
        f"x_abs, y_abs only {1000 * truth:.4g} mm; but a robot steering by its odometry "
        "ends where its odometry says it started, so the odometry's end points are the ones "
        "near the start"
    )
    if odometry >= _FAR_ODOMETRY * scale and odometry >= _SWAPPED_RATIO * truth:
        raise InputError(
            f"{said}: the measured and odometry columns are swapped (x_abs, y_abs are where "
            "the robot truly stopped, x_odo, y_odo where its odometry says), or the "
            "odometry's end points are not in the run's start frame",
            source=name,
        )
    return [f"{said}: are the measured and odometry columns swapped?"]


def _check_odometry_frame(squares: Sequence[Run], scale: float, name: str) -> None:
    """Refuse odometry end points that are all one offset from the start: the odom frame.

    A robot steering by its odometry ends where its odometry says it started, so in each
    run's start frame the odometry's end points lie near (0, 0). Odometry read in the odom
    frame (where the robot started its first run, or was switched on) puts them all near
    the run's start pose in that frame instead: one point, off the start by more than a
    controller's tolerance (:data:`_NEAR_START` of the side), gathered more tightly there
    than the measured end points gather (they scatter by the runs' errors), while the
    measured end points lie nearer the start than that point. Columns swapped put the
    measured end points, in their two clusters, in the odometry's columns: they do not
    gather tightly (:func:`check_columns` names those).

    Raises
    ------
    InputError
        Naming the offset and the remedy.
    """
    ox = statistics.median(r.odometry_end.x for r in squares)
    oy = statistics.median(r.odometry_end.y for r in squares)
    tx = statistics.median(r.true_end.x for r in squares)
    ty = statistics.median(r.true_end.y for r in squares)
    odometry = [math.hypot(r.odometry_end.x - ox, r.odometry_end.y - oy) for r in squares]
    truth = [math.hypot(r.true_end.x - tx, r.true_end.y - ty) for r in squares]
    near = statistics.median(math.hypot(r.true_end.x, r.true_end.y) for r in squares)
    there = statistics.median(math.hypot(r.true_end.x - ox, r.true_end.y - oy) for r in squares)
    offset = math.hypot(ox, oy)
    spread = statistics.median(odometry)
    if offset < _NEAR_START * scale or spread > statistics.median(truth) or near >= there:
        return
    raise InputError(
        f"x_odo, y_odo put every run's end near ({1000 * ox:.4g}, {1000 * oy:.4g}) mm "
        f"(median; half of them within {1000 * spread:.3g} mm of it), {1000 * offset:.4g} mm "
        "from the start, while x_abs, y_abs end near the start; a robot steering by its "
        "odometry ends where its odometry says it started, so the odometry's end points are "
        "in another frame, offset by that much (the odom frame, not each run's start frame): "
        "give x_odo, y_odo relative to each run's start (subtract the start pose the "
        "odometry gave at the run's start)",
        source=name,
    )


def _heading_unit_hints(squares: Sequence[Run], angle_unit: str) -> list[str]:
    """A warning where unwrapped headings given as degrees are a full loop in radians.

    A square driven once round turns the robot by 360 degrees; odometry headings of about
    6.28 "degrees" in every run are radians. (Degrees given as radians are refused by the
    table reader: 360 rad is no heading.)
    """
    if angle_unit != "deg":
        return []
    loops = [abs(run.odometry_end.theta) for run in squares if run.odometry_end.theta is not None]
    if not loops or len(loops) < len(squares):
        return []
    full_turn = math.radians(2.0 * math.pi)  # 6.28 read as degrees, in radians
    if all(0.97 * full_turn < loop < 1.03 * full_turn for loop in loops):
        shown = statistics.median(math.degrees(loop) for loop in loops)
        return [
            f"theta_odo is about {shown:.2f} deg in every run, where a square driven once "
            "round turns the robot by 360 deg: are the headings in radians? "
            "(--angle-unit rad)"
        ]
    return []


#: A run's return error this many times smaller or larger than the median of the others'
#: is taken for a row in another unit, if a unit's factor brings it near them.
_ROW_FACTOR = 100.0


def _mixed_unit_rows(squares: Sequence[Run], unit: str) -> list[str]:
    """Rows whose return error is some hundred times off the others' and that another
    unit's factor brings back among them (one row typed in metres in a mm table).

    A return error scatters about its cluster, so one 100 times smaller than the median of
    the other runs' of its direction (or larger) is rare by chance; only factors of the
    units read here count, and the row must land within 3 times of the median when
    rescaled.
    """
    hints = []
    for direction in ("cw", "ccw"):
        runs = [run for run in squares if run.direction.value == direction]
        if len(runs) < 3:
            continue
        errors = [math.hypot(*run.return_error) for run in runs]
        for k, error in enumerate(errors):
            typical = statistics.median(errors[:k] + errors[k + 1 :])
            if typical == 0.0 or error == 0.0:
                continue
            ratio = typical / error
            if 1.0 / _ROW_FACTOR < ratio < _ROW_FACTOR:
                continue
            for other, scale in UNITS.items():
                factor = scale / UNITS[unit]  # this row's numbers, read as ``other``
                if other != unit and 1.0 / 3.0 < error * factor / typical < 3.0:
                    hints.append(
                        f"{runs[k].label or f'{direction} run {k + 1}'}: its return error "
                        f"({1000 * error:.3g} mm) is {max(ratio, 1 / ratio):.0f} times "
                        f"{'smaller' if ratio > 1 else 'larger'} than the other {direction} "
                        f"runs' (median {1000 * typical:.3g} mm): is this row in {other}, not "
                        f"{unit}? (a table has one unit: --unit)"
                    )
                    break
    return hints


def judge_table(read: SourceRuns, unit: str, angle_unit: str, side: float | None) -> SourceRuns:
    """A runs table as read, judged as a robot driving the square makes it: refused where
    its columns look swapped (:func:`check_columns`), with warnings where its numbers look
    like other units than it says (:func:`unit_hints`) added to its notes."""
    name, runs = read.sources[0], list(read.runs)
    wheelbase = read.active.effective_wheelbase
    if _beyond_the_side(runs, side):  # the unit first: the frame's premise does not hold
        units = unit_hints(runs, unit, angle_unit, side, wheelbase, name)
        hints = [*check_columns(runs, side, name), *units]
    else:
        hints = [
            *check_columns(runs, side, name),
            *unit_hints(runs, unit, angle_unit, side, wheelbase, name),
        ]
    return replace(read, notes=(*read.notes, *hints))


def _beyond_the_side(runs: Sequence[Run], side: float | None) -> bool:
    """Whether the measured end points lie farther than the side from the start (median):
    no robot comes back from the square that far, so the odometry's columns are not
    judged (in another frame, swapped) before the table's unit is: a tape-measure table in
    mm read as m puts the ends tens of metres out, and its odometry, within a millimetre of
    the start, some hundreds of millimetres off it, which the frame's check would take for
    the odom frame."""
    squares = [run for run in runs if run.kind == "square"]
    if side is None or not squares:
        return False
    return statistics.median(math.hypot(r.true_end.x, r.true_end.y) for r in squares) > side

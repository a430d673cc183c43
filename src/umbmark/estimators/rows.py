"""Rows of a runs table far outside their own cluster: a number typed wrong.

A runs table is typed by hand; one character wrong in one row (a minus dropped, two digits
swapped) moves that run's return error far from the other runs of its direction, and the
cluster's centre, E_max,syst and the estimate with it. :func:`far_rows` finds such rows
and what likely went wrong with each.

How far a row lies is judged robustly, as :func:`umbmark.estimators.plausibility.unit_hints`
judges rows in another unit (against the median of the other runs), so that the row
itself does not hide in the scatter it inflates:

- each run's **deviation** is its return error minus the median of the other runs of its
  direction, per coordinate (x, y);
- the **scale** is 1.4826 times the median of the absolute deviations of every run of the
  table (both directions and both coordinates pooled: with the paper's five runs a
  direction, twenty numbers), and at least :data:`SCALE_FLOOR` (what a tape measure
  resolves); for Gaussian runs it is about the runs' standard deviation;
- a run's **distance** is its largest deviation over the scale, in standard deviations.

A row is named when it lies :data:`FAR` standard deviations out whatever the cause, or
:data:`TYPO` out where one character changed in one of its numbers (a sign, two adjacent
digits swapped) or its direction label brings it within :data:`FITS` of its cluster. The
thresholds are chosen against Gaussian runs (the scale pooled over unequal clusters) and
the real runs of the OptiOdom sessions (``docs/reading-results.md``, "A row far from its
cluster").
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import dataclass

from umbmark.core.conventions import Direction
from umbmark.core.messages import Blocking, blocking
from umbmark.model.run import Run

__all__ = ["FAR", "FITS", "SCALE_FLOOR", "TYPO", "FarRow", "Judged", "far_rows", "judge_rows"]

#: A row this many (robust) standard deviations from its cluster is named whatever the
#: cause, and from :data:`TYPO` on where one character or its label brings it back.
#: ``tools/far_rows_thresholds.py`` (20 000 Gaussian tables a setting, like the bundled
#: one): with both axes and clusters scattering alike, 1 table in 10 000 of 5 runs a
#: direction has a row named (1 in 2 900 of 3 runs, none of 10 or 20); with one axis
#: twice the other, 1 in 2 000; and the ccw cluster twice as wide besides, 1 in 540 (5
#: runs), 1 in 900 (10). The real OptiOdom sessions' farthest rows lie 1.7 and 1.5 out, the
#: bundled table's 2.1; a sign flipped in its ccw rows puts the row 12 to 15 out.
FAR = 15.0
#: See :data:`FAR`.
TYPO = 8.0
#: ... back: within this many standard deviations of its cluster's median.
FITS = 3.0
#: The scale is at least this [m]: rows nearer than what a tape measure resolves are not
#: far, however still the other runs are.
SCALE_FLOOR = 0.0005
#: The median absolute deviation of a Gaussian over its standard deviation.
_MAD = 1.4826
#: The table's columns of a run's end points, as :class:`Run` holds them.
_COLUMNS = ("x_abs", "y_abs", "x_odo", "y_odo")
_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}


@dataclass(frozen=True)
class FarRow:
    """A run far outside its cluster.

    Attributes
    ----------
    run : Run
        The run as read (its label names the row: ``row 13`` is the file's line 13).
    sigmas : float
        How far out, in robust standard deviations.
    axis : str
        ``x`` or ``y``: the coordinate of the return error that is farthest out.
    cause : str or None
        What likely went wrong (``a sign: y_abs 217.1 (-217.1 fits)``), None when no
        one-character change explains it.
    """

    run: Run
    sigmas: float
    axis: str
    cause: str | None

    @property
    def label(self) -> str:
        """The row (``row 13``)."""
        return self.run.label or f"a {self.run.direction.value} run"

    def warning(self) -> Blocking:
        """The warning, which makes the verdict "do not apply"."""
        direction = self.run.direction.value
        likely = (
            f"likely {self.cause}"
            if self.cause
            else "no sign or digit explains it: a typo, or a run that went wrong (a bump, "
            "a wheel slipping); check the row"
        )
        text = (
            f"{self.label} lies {self.sigmas:.0f} standard deviations from the other "
            f"{direction} runs in {self.axis} (robust: their median, and the runs' median "
            f"absolute deviation): {likely}; the result without it is shown beside"
        )
        return blocking(
            text,
            f"{self.label} lies {self.sigmas:.0f} standard deviations outside its cluster, "
            f"likely {self.cause or 'a typo or a run gone wrong'}: the result rests on it",
            f"correct {self.label} (or delete it) and calibrate again; the result without "
            "it is shown beside",
        )


def _typed(value: float) -> str:
    """A number as it was likely typed (``217.1``, ``-393``)."""
    text = f"{value:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _fields(run: Run) -> list[float]:
    return [run.true_end.x, run.true_end.y, run.odometry_end.x, run.odometry_end.y]


def _with_field(run: Run, k: int, value: float) -> tuple[float, float]:
    """The return error of ``run`` with its ``k``-th column (:data:`_COLUMNS`) ``value``."""
    values = _fields(run)
    values[k] = value
    return (values[0] - values[2], values[1] - values[3])


def _changes(run: Run, unit: str) -> list[tuple[str, tuple[float, float]]]:
    """One character changed in one number: its sign, or two adjacent digits swapped;
    each with the return error it gives."""
    found = []
    scale = _UNITS.get(unit, 1.0)
    for k, value in enumerate(_fields(run)):
        typed = _typed(value / scale)
        if value != 0.0:
            flipped = typed[1:] if typed.startswith("-") else "-" + typed
            found.append(
                (f"a sign: {_COLUMNS[k]} {typed} ({flipped} fits)", _with_field(run, k, -value))
            )
        for i in range(len(typed) - 1):
            a, b = typed[i], typed[i + 1]
            if a.isdigit() and b.isdigit() and a != b:
                swapped = typed[:i] + b + a + typed[i + 2 :]
                found.append(
                    (
                        f"swapped digits: {_COLUMNS[k]} {typed} ({swapped} fits)",
                        _with_field(run, k, float(swapped) * scale),
                    )
                )
    return found


def _median(points: Sequence[tuple[float, float]]) -> tuple[float, float]:
    return (statistics.median(p[0] for p in points), statistics.median(p[1] for p in points))


def _distance(error: tuple[float, float], centre: tuple[float, float], scale: float) -> float:
    return max(abs(error[0] - centre[0]), abs(error[1] - centre[1])) / scale


@dataclass(frozen=True)
class Judged:
    """Every judged run's distance from its cluster (see the module).

    Attributes
    ----------
    groups : dict of Direction to list of Run
        The square runs of each direction with three or more.
    centres : dict of int to (float, float)
        The median of the other runs of its direction [m], by ``id`` of each run.
    scale : float
        The robust standard deviation [m].
    """

    groups: dict[Direction, list[Run]]
    centres: dict[int, tuple[float, float]]
    scale: float

    def sigmas(self, run: Run) -> float:
        """How far ``run`` lies from its cluster, in standard deviations."""
        return _distance(run.return_error, self.centres[id(run)], self.scale)


def judge_rows(runs: Sequence[Run]) -> Judged | None:
    """The runs' distances from their clusters (None with no direction of three runs)."""
    groups: dict[Direction, list[Run]] = {}
    for run in runs:
        if run.kind == "square":
            groups.setdefault(run.direction, []).append(run)
    groups = {d: g for d, g in groups.items() if len(g) >= 3}
    centres: dict[int, tuple[float, float]] = {}
    deviations: list[float] = []
    for group in groups.values():
        for k, run in enumerate(group):
            centre = _median([r.return_error for j, r in enumerate(group) if j != k])
            centres[id(run)] = centre
            deviations += [abs(run.return_error[i] - centre[i]) for i in (0, 1)]
    if not deviations:
        return None
    return Judged(groups, centres, max(_MAD * statistics.median(deviations), SCALE_FLOOR))


def far_rows(runs: Sequence[Run], unit: str = "m") -> list[FarRow]:
    """The square runs far outside their cluster (see the module), in the table's order.

    Parameters
    ----------
    runs : sequence of Run
        A table's runs (only the square runs are judged; a direction needs three).
    unit : str
        The table's length unit (``m``, ``cm``, ``mm``), to name the numbers as typed.

    Returns
    -------
    list of FarRow
    """
    judged = judge_rows(runs)
    if judged is None:
        return []
    scale, found = judged.scale, []
    for direction, group in judged.groups.items():
        others = [r for d, g in judged.groups.items() if d is not direction for r in g]
        for run in group:
            error, centre = run.return_error, judged.centres[id(run)]
            sigmas = judged.sigmas(run)
            if sigmas < TYPO or _another_unit(error, centre, scale):
                continue
            axis = "x" if abs(error[0] - centre[0]) >= abs(error[1] - centre[1]) else "y"
            cause = _cause(run, unit, centre, others, scale)
            if sigmas >= FAR or cause is not None:
                found.append(FarRow(run, sigmas, axis, cause))
    order = {id(run): k for k, run in enumerate(runs)}
    return sorted(found, key=lambda row: order[id(row.run)])


def _another_unit(error: tuple[float, float], centre: tuple[float, float], scale: float) -> bool:
    """A factor of 10, 100 or 1000 brings the row back: a row in another unit, which
    :func:`umbmark.estimators.plausibility.unit_hints` names."""
    for factor in (10.0, 100.0, 1000.0):
        for f in (factor, 1.0 / factor):
            if _distance((error[0] * f, error[1] * f), centre, scale) <= FITS:
                return True
    return False


def _cause(
    run: Run,
    unit: str,
    centre: tuple[float, float],
    others: Sequence[Run],
    scale: float,
) -> str | None:
    """The one-character change that brings ``run`` within :data:`FITS` of ``centre``
    (the median of the other runs of its direction; the nearest, if several), or its
    direction label (it fits the ``others``, the other direction's runs)."""
    best: tuple[float, str] | None = None
    for said, error in _changes(run, unit):
        d = _distance(error, centre, scale)
        if d <= FITS and (best is None or d < best[0]):
            best = (d, said)
    if best is not None:
        return best[1]
    if (
        len(others) >= 3
        and _distance(run.return_error, _median([r.return_error for r in others]), scale) <= FITS
    ):
        other = others[0].direction.value
        return f"its direction label: it fits the {other} runs"
    return None

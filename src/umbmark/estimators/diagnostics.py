"""What the dispatch checks of square runs besides estimating: refusals before, warnings after.

Called once per estimate by :mod:`umbmark.estimators.dispatch`, for whichever estimator
(the table of :mod:`umbmark.estimators.registry` says what each one needs and takes):

- :func:`require_headings`: an estimator that needs headings refuses runs whose ground
  truth measures positions only.
- :func:`check_reach`: the plausibility of the return errors belongs to the method. The
  paper's small-angle formulas mean nothing for errors larger than the square's side
  (``reach="side"``); the exact geometry inverts anything a robot driving the
  square can do, and only refuses errors farther from the start than the whole path is
  long (a unit slip, ``reach="path"``).
- :func:`check_model`: the model check of the end-pose fit
  (:mod:`umbmark.estimators.endpose`) tests whether one robot of the model explains both
  clusters (and the headings); it fires on one in a thousand sets of runs with Gaussian
  scatter. When it fires, the warning gives the numbers and looks for the usual causes: a
  run whose direction label contradicts its cluster, every cw and ccw label swapped (the
  runs fit with them swapped back), headings in other units. The failure's figures go
  with the estimate (``ErrorEstimate.model_failure``) for the verdict.

What an estimator cannot identify it refuses itself (the exact geometry's
:func:`umbmark.estimators.exact.check_identified`, a fit that does not converge).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, ProblemError, option
from umbmark.core.messages import join_names
from umbmark.estimators.base import ModelCheckFailure, SquareTest
from umbmark.estimators.endpose import FLOOR, LEVEL, EndPoseFit, fit_end_poses
from umbmark.estimators.registry import RUNS, Estimator, names
from umbmark.model.run import Run, split_by_direction
from umbmark.returns.clusters import Benchmark, umbmark_benchmark

__all__ = [
    "MODEL_CAUSES",
    "check_model",
    "check_reach",
    "require_headings",
    "runs_label",
    "swapped_words",
]

_MM = 1000.0
#: A run this many standard deviations from its own cluster but inside the other one is
#: taken for a swapped label.
_OUTLIER_SIGMA = 5.0
#: ... and at most this many from the other cluster's centre.
_INSIDE_SIGMA = 4.5
#: Heading and position estimates of alpha differing by about this factor: a unit slip.
_DEGREE = 180.0 / math.pi


def _farthest(runs: Sequence[Run]) -> tuple[Run, float]:
    errors = [math.hypot(*run.return_error) for run in runs]
    k = int(np.argmax(errors))
    return runs[k], errors[k]


def _check_within_side(runs: Sequence[Run], test: SquareTest) -> None:
    """Refuse return errors larger than the square's side: beyond the paper's formulas.

    Raises
    ------
    ProblemError
        Naming the run and the likely cause.
    """
    run, error = _farthest(runs)
    if error > test.side_length:
        raise ProblemError(
            f"the return error of {run.label or 'a run'} ({error:.4g} m) is larger than the "
            f"square's side ({test.side_length:g} m), beyond the paper's small-angle "
            f"formulas: use {option('method', join_names(names(reach='path'), 'or'))} (the "
            "exact geometry)"
        )


def _check_reachable(runs: Sequence[Run], test: SquareTest) -> None:
    """Refuse return errors no robot driving the square can make (a unit slip).

    Raises
    ------
    ProblemError
        Naming the run.
    """
    run, error = _farthest(runs)
    if error > 4.0 * test.side_length:
        raise ProblemError(
            f"the return error of {run.label or 'a run'} ({error:.4g} m) is farther from the "
            f"start than the whole {4 * test.side_length:g} m path is long: are the lengths "
            f"in the right unit ({option('unit')}) and the side length right?"
        )


def _misfit_text(fit: EndPoseFit) -> str:
    parts = []
    for direction, misfit in fit.check.misfit.items():
        shown = f"{misfit[0] * _MM:+.1f}, {misfit[1] * _MM:+.1f} mm"
        if len(misfit) > 2:
            shown += f", {math.degrees(misfit[2]):+.3f} deg"
        parts.append(f"{direction} ({shown})")
    return " and ".join(parts)


def _swapped_labels(runs: Sequence[Run]) -> list[str]:
    """Runs that sit far outside their own cluster and inside the other one.

    Each run is measured against its cluster without it (Mahalanobis distance with the
    pooled scatter of the other runs, positions only) and against the other cluster;
    the clusters must be well apart for a label to matter.
    """
    groups = {
        d: np.array([r.return_error for r in g], dtype=np.float64).reshape(len(g), -1)
        for d, g in split_by_direction(runs).items()
    }
    found = []
    for direction, other in ((Direction.CW, Direction.CCW), (Direction.CCW, Direction.CW)):
        own_group, other_group = groups[direction], groups[other]
        n, m = len(own_group), len(other_group)
        if n < 3 or m < 2:
            continue
        # Every run left out at once, in O(n): the mean of the rest and the scatter of the
        # rest about it follow from the sums over the cluster (centred, for precision).
        other_mean = other_group.mean(axis=0)
        other_dev = other_group - other_mean
        other_scatter = np.einsum("ki,kj->ij", other_dev, other_dev)
        centre = own_group.mean(axis=0)
        dev = own_group - centre  # (n, 2)
        rest_mean = (dev.sum(axis=0) - dev) / (n - 1)  # (n, 2), relative to centre
        rest_scatter = (
            np.einsum("ki,kj->ij", dev, dev)
            - np.einsum("ki,kj->kij", dev, dev)
            - (n - 1) * np.einsum("ki,kj->kij", rest_mean, rest_mean)
        )
        scatter = (rest_scatter + other_scatter) / (n - 1 + m - 2) + np.diag(np.square(FLOOR[:2]))
        inverse = np.linalg.inv(scatter)  # (n, 2, 2)
        d_own = dev - rest_mean
        d_other = own_group - other_mean
        d_centres = rest_mean + centre - other_mean
        owns, nears, aparts = (
            np.sqrt(np.einsum("ki,kij,kj->k", d, inverse, d)) for d in (d_own, d_other, d_centres)
        )
        for k in range(n):
            own, near, apart = float(owns[k]), float(nears[k]), float(aparts[k])
            # Near the other cluster: within a few of the pooled standard deviations
            # (the pooled scatter is round, the clusters need not be) and far nearer
            # than to its own.
            inside = near < min(_INSIDE_SIGMA, own / 3.0)
            if own > _OUTLIER_SIGMA and inside and apart > 2.0 * _OUTLIER_SIGMA:
                found.append(
                    f"{runs_label(runs, direction, k)}, labelled {direction.value}, sits in "
                    f"the {other.value} cluster ({own:.0f} standard deviations from its own): "
                    "check its direction label"
                )
    return found


def runs_label(runs: Sequence[Run], direction: Direction, k: int) -> str:
    """The label of the ``k``-th run of ``direction``."""
    return split_by_direction(runs)[direction][k].label or f"{direction.value} run {k + 1}"


def _heading_units(
    bench: Benchmark, runs: Sequence[Run], test: SquareTest, fit: EndPoseFit
) -> list[str]:
    """Headings whose alpha differs from the positions' by a degree/radian factor."""
    if not fit.headings:
        return []
    positions = fit_end_poses(bench, runs, test, headings=False)
    alpha_positions = 0.5 * math.pi * (1.0 - 1.0 / positions.E_b)
    groups = split_by_direction(runs)
    # Unwrapped: a heading in the wrong unit may be many turns large.
    mean = {
        d: float(np.mean([(r.true_end.theta or 0.0) - (r.odometry_end.theta or 0.0) for r in g]))
        for d, g in groups.items()
    }
    alpha_headings = (mean[Direction.CW] - mean[Direction.CCW]) / 8.0
    if min(abs(alpha_positions), abs(alpha_headings)) < 1e-6:
        return []
    ratio = abs(alpha_headings / alpha_positions)
    said = (
        f"the headings say alpha = {math.degrees(alpha_headings):.3g} deg, the positions "
        f"{math.degrees(alpha_positions):.3g} deg"
    )
    if 0.7 * _DEGREE < ratio < 1.3 * _DEGREE:
        return [f"{said}: are the headings in degrees? (--angle-unit deg)"]
    if 0.7 / _DEGREE < ratio < 1.3 / _DEGREE:
        return [f"{said}: are the headings in radians? (--angle-unit rad)"]
    return []


#: What to check when the model check fails and no cause is found in the runs.
MODEL_CAUSES = (
    "check the runs' direction labels, axes and signs, the heading units and the side "
    "length; if they are right, the robot has errors the model leaves out (slip on the "
    "turns, a marker off the axle centre, E_s)"
)


def check_model(
    bench: Benchmark,
    runs: Sequence[Run],
    test: SquareTest,
    fit: EndPoseFit | None = None,
    *,
    E_s: float = 1.0,
) -> tuple[list[str], ModelCheckFailure | None]:
    """The model check of the end poses: its warnings (see the module) and, when it
    fails, the failure (p, misfit, and whether the runs fit with cw and ccw swapped).

    ``fit`` is the end-pose fit of the runs with the scale error ``E_s``, made here when
    not given.
    """
    if fit is None:
        try:
            fit = fit_end_poses(bench, runs, test, E_s=E_s)
        except ValueError:
            return _swapped_labels(runs), None
    swapped = _swapped_labels(runs)
    check = fit.check
    if not check.failed:
        return swapped, None
    what = "positions and headings" if fit.headings else "positions"
    failure = _failure(fit, runs, test, E_s)
    causes = swapped + _heading_units(bench, runs, test, fit)
    if failure.swapped_fits:
        causes.insert(0, swapped_words(failure))
    likely = "; ".join(causes) if causes else MODEL_CAUSES
    warning = (
        f"the runs' {what} do not fit one robot of the model: the centres miss it by "
        f"{_misfit_text(fit)} (model check {check.statistic:.1f} on {check.dof} degrees of "
        f"freedom, p = {check.p_value:.2g} < {LEVEL:g}); {likely}"
    )
    return [warning], failure


def swapped_words(failure: ModelCheckFailure) -> str:
    """What a failed check whose runs fit with cw and ccw swapped says of the labels."""
    return (
        f"with every cw and ccw label swapped the runs fit one robot of the model (p = "
        f"{failure.swapped_p:.2g}): the direction labels are likely swapped (a cw run turns "
        "right, clockwise seen from above); swap them"
    )


def _failure(
    fit: EndPoseFit, runs: Sequence[Run], test: SquareTest, E_s: float
) -> ModelCheckFailure:
    """The failed check's figures, and the same check with every label swapped."""
    misfit = max(math.hypot(m[0], m[1]) for m in fit.check.misfit.values())
    other = {Direction.CW: Direction.CCW, Direction.CCW: Direction.CW}
    relabelled = [replace(run, direction=other[run.direction]) for run in runs]
    try:
        again = fit_end_poses(
            umbmark_benchmark(relabelled), relabelled, test, E_s=E_s, headings=fit.headings
        )
    except ValueError:
        return ModelCheckFailure(fit.check.p_value, misfit)
    p = again.check.p_value
    return ModelCheckFailure(fit.check.p_value, misfit, p, p >= LEVEL)


def check_reach(method: Estimator, runs: Sequence[Run], test: SquareTest) -> None:
    """Refuse return errors beyond what ``method`` takes
    (:attr:`~umbmark.estimators.registry.Estimator.reach`).

    Raises
    ------
    ProblemError
        Naming the run and the likely cause.
    """
    if method.reach == "side":
        _check_within_side(runs, test)
    elif method.reach == "path":
        _check_reachable(runs, test)


def require_headings(method: Estimator, runs: Sequence[Run], where: str | None) -> None:
    """Refuse ``method`` where it needs headings and a run's ground truth has positions
    only (a GNSS fix, a tracked point).

    Raises
    ------
    InputError
        Naming the run, the method and the methods that serve.
    """
    if not method.headings:
        return
    serve = join_names([n for n in names(headings=False) if n in RUNS], "or")
    for run in runs:
        if run.log is not None and not run.log.headings:
            raise InputError(
                f"the ground truth of {run.label or 'the runs'} has positions only (a "
                f"PointStamped or NavSatFix reference, no headings): the {method.name} method "
                f"needs headings; use {option('method', serve)}",
                source=where,
            )

"""``calibrate --method auto``: the estimator that predicts held-out recorded runs best.

The held-out validation (:func:`umbmark.calibration.heldout.validate_read`) ranks the
estimators by their held-out end error, on the sources as the calibration read them (each
is read once). The richer
estimators of a turn-rate term (``trajectory-scrub``) are taken only where the recordings
identify it (:mod:`umbmark.estimators.motions`), in the pool and with every source held
out: held-out runs that one cannot be calibrated for say nothing of it, and a pool
without arcs or without turns on the spot cannot see what it extrapolates to. Otherwise
the simpler estimators compete without it, and the note says why.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from umbmark.calibration.heldout import validate_read
from umbmark.core.messages import info
from umbmark.estimators.motions import motion_coverage
from umbmark.estimators.registry import AUTO, DEFAULT, names
from umbmark.runs.read import SourceRuns

__all__ = ["auto_method"]


def auto_method(each: Sequence[SourceRuns], read: SourceRuns) -> tuple[str, str, bool]:
    """The estimator that predicts held-out recorded runs best, a note saying so, and
    whether the nominal parameters predicted them better than every estimator (the
    calibration is then made with the default, and its verdict is "do not apply").

    ``each`` are the sources read one by one, ``read`` the same pooled
    (:func:`umbmark.runs.active.read_each`, :func:`~umbmark.runs.read.pool_runs`).
    """
    default = DEFAULT.name
    if read.params is None or any(run.log is None for run in read.runs):
        said = (
            f"method {AUTO}: runs tables cannot be replayed to compare estimators; "
            f"calibrated with the default, {default}"
        )
        return default, info(said), False
    checked = validate_read(each)
    ranking = checked.ranking
    logs = [run.log for run in read.runs if run.log is not None]
    problem = motion_coverage(logs, read.params).scrub_problem()
    why = ""
    for scrub in names(turn_rate=True):
        if problem is not None:
            ranking = [(name, error) for name, error in ranking if name != scrub]
            why += f"; {scrub} left out: {problem}"
        elif scrub in checked.candidates and scrub not in dict(ranking):
            refused = [
                f"{Path(f.held_out).name} held out ({f.refused[scrub]})"
                for f in checked.folds
                if scrub in f.refused
            ]
            if refused:
                why += f"; {scrub} left out: not calibrated with " + ", ".join(refused)
    covers = f"; {checked.coverage}"
    best = next(iter(ranking), ("nominal", 0.0))[0]
    if best == "nominal":
        ranked = any(name != "nominal" for name, _ in ranking)  # else none could be tried
        said = (
            f"method {AUTO}: no estimator predicted held-out runs better than the nominal "
            "parameters "
            if ranked
            else f"method {AUTO}: no estimator could be calibrated with a source held out "
        )
        said += f"({checked.scheme}); calibrated with the default, {default}{why}{covers}"
        return default, info(said), ranked
    listed = ", ".join(f"{name} {1000 * error:.1f} mm" for name, error in ranking)
    said = f"method {AUTO}: {best}, by held-out end error ({checked.scheme}): {listed}{why}{covers}"
    return best, info(said), False

"""Whether to apply a calibration: ``apply``, ``apply with care`` or ``do not apply``.

:func:`judge` weighs an estimate and its evidence, criterion by criterion, each with its
threshold here and the reason for it:

- **Nothing beats the nominal parameters** (``calibrate --method auto``): no estimator
  predicted held-out runs better than the parameters active during them. Do not apply:
  those parameters are the better ones.
- **The interval does not say which way to correct**: the 95 % interval of ``E_d``,
  ``E_b`` or ``E_s`` holds both 1 (no correction) and ``2 - estimate``, a robot with the
  opposite error of the same size, which this correction would make twice as wrong; and
  the correction is large enough to matter (:data:`NOTICEABLE_ANGLE`). Do not apply.
  Where the interval holds 1 but not ``2 - estimate``, or the correction is too small to
  matter but the interval is wide enough to hide an error that does
  (:data:`WIDE_INTERVAL` times what matters): apply with care.
- **The model does not hold**: a trajectory or end-point fit whose rms residual is far
  beyond what random wheel slip leaves (:data:`MISFIT_CARE`, :data:`MISFIT_REFUSE` of
  the runs' path, and :data:`MISFIT_FLOOR`; :data:`HEADING_CARE`, :data:`HEADING_REFUSE`
  in heading): slip, a wrong wheel geometry, a time offset, a tracked point off the axle,
  a ground truth that lost the robot. Do not apply (apply with care below the larger
  thresholds).
- **The model check fails strongly**: the end poses are this improbable under every robot
  of the model (p below :data:`MODEL_REFUSE`) and the clusters' centres miss the nearest
  one by more than the paper's scatter on the square: no robot of the model drove these
  runs, so the correction is no robot's. Do not apply, with the likely cause (every cw
  and ccw label swapped, when the runs fit with them swapped back). A marginal failure
  (p between :data:`MODEL_REFUSE` and the check's level) is a warning: apply with care.
- **No error and no scatter**: ``E_max,syst`` and ``3 x SEM`` both under
  :data:`umbmark.returns.clusters.NO_RETURN_ERROR` (``0.0 mm`` as printed): the runs came
  back exactly where the odometry says, which no measured reference shows: a ground truth
  that reproduces the odometry (refused where the runs are read when it does so exactly:
  :mod:`umbmark.runs.reproduced`), or a simulation without noise. Apply with care.
- **Too few runs** (:data:`MIN_RUNS`): apply with care.
- **Implausible errors** (:data:`PLAUSIBLE_E_D`, :data:`PLAUSIBLE_E_B`,
  :data:`PLAUSIBLE_E_S`): apply with care, and check the nominal geometry. An ``E_s``
  near a power of ten (:func:`umbmark.estimators.scale.unit_slip`: 10, 100, 0.1, 0.01)
  is a wheel diameter given in another unit or with its decimal point slipped, and its
  multipliers of about that factor no robot's: do not apply, naming the diameter meant.
- **The input is wrong as read**: a warning that the table's numbers are in another unit
  than it says (no robot scatters by less than a tape measure resolves) or that a row
  lies far outside its cluster (a typo) (:class:`umbmark.core.messages.Blocking`, from
  :mod:`umbmark.estimators.plausibility` and :mod:`umbmark.estimators.rows`): the result
  is no robot's. Do not apply, with the warning's reason and remedy.
- **Warnings**: a result that comes with warnings (the model check of the end poses, a
  run in the other cluster, the paper's small-angle formulas beyond their range, input
  read with doubts) is valid but shaky: apply with care.

What "matters" is measured on the test's square against the paper's own figure of the
runs' scatter, about 25 mm per cluster on its 4 m square (Sec. 5): an error whose return
error stays below that scatter cannot be told from it by UMBmark.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from umbmark.core.errors import option, with_flags
from umbmark.core.messages import Blocking
from umbmark.estimators.base import ErrorEstimate, SquareTest
from umbmark.estimators.registry import GYROS, INTERVALS
from umbmark.returns.clusters import NO_RETURN_ERROR
from umbmark.sources.bag.truth.independence import REFERENCES

if TYPE_CHECKING:
    from umbmark.model.kinematics import WheelParams
    from umbmark.model.recording import RunLog

__all__ = [
    "HEADING_CARE",
    "HEADING_REFUSE",
    "LEVELS",
    "MIN_RUNS",
    "MISFIT_CARE",
    "MISFIT_FLOOR",
    "MISFIT_REFUSE",
    "MODEL_REFUSE",
    "NOTICEABLE_ANGLE",
    "PAPER_SCATTER",
    "PLAUSIBLE_E_B",
    "PLAUSIBLE_E_D",
    "PLAUSIBLE_E_S",
    "WIDE_INTERVAL",
    "Evidence",
    "Level",
    "Verdict",
    "judge",
    "mean_path",
    "noticeable",
]

Level = Literal["apply", "care", "do-not-apply"]
#: The levels, from the best to the worst.
LEVELS: tuple[Level, ...] = ("apply", "care", "do-not-apply")
_WORDS = {"apply": "apply", "care": "apply with care", "do-not-apply": "do not apply"}

#: The paper's non-systematic scatter: about 25 mm standard deviation per cluster on its
#: 4 m square (Sec. 5), as a fraction of the side.
PAPER_SCATTER = 0.025 / 4.0
#: A heading error per turn (alpha) or per leg (beta) [rad] whose return error on the
#: square, ``2 sqrt(2) L`` times the angle to first order (Eqs. 4.17-4.24), equals that
#: scatter: 0.13 deg. Smaller errors cannot be told from the scatter; larger ones matter.
NOTICEABLE_ANGLE = PAPER_SCATTER / (2.0 * math.sqrt(2.0))
#: An interval whose half-width is this many times what matters hides an error that
#: matters, whatever the estimate.
WIDE_INTERVAL = 2.0
#: A fitted model whose rms position residual exceeds this fraction of a run's path is
#: doubtful: three times the paper's random scatter at a run's end (25 mm on its 16 m
#: path, 0.16 %) ...
MISFIT_CARE = 0.005
#: ... and does not hold beyond this one: the paper's uncalibrated LabMate's whole
#: systematic error (317 mm on its 16 m path, 2 %). The model then leaves unexplained as
#: much as calibrating would remove.
MISFIT_REFUSE = 0.02
#: Residuals [m] below these are what the ground truth, the robot's stops and random slip
#: leave on any run, however short: the paper's scatter (25 mm), and four times it.
MISFIT_FLOOR = (0.025, 0.1)
#: The same for the rms heading residual [rad]: the heading an uncalibrated LabMate
#: gains over one square (4 turns of alpha = 1 deg) ...
HEADING_CARE = math.radians(4.0)
#: ... and twice as much.
HEADING_REFUSE = math.radians(8.0)
#: The model check of the end poses warns below p = 0.001 (one in a thousand sets of
#: Gaussian runs about a robot of the model); below this, ten times rarer, and with
#: centres missed by more than the paper's scatter, the model is refused. The p of a
#: grossly wrong table saturates far above Gaussian tails (the scatter is estimated from
#: a few runs: Hotelling's F on 8 degrees of freedom for 5 runs each way puts cw and ccw
#: swapped on the bundled example at 3e-7), so a refusal level much smaller than this
#: would let such tables through.
MODEL_REFUSE = 1e-4
#: Fewer runs in a direction (square tests) or recorded runs (fits) than this: the
#: scatter is known poorly (the paper drove 5 each way).
MIN_RUNS = 3
#: ``E_d`` beyond ``1 -/+`` this: wheels whose diameters differ by more than tyres do
#: (per mille to a per cent).
PLAUSIBLE_E_D = 0.05
#: ``E_b`` beyond ``1 -/+`` this: an effective wheelbase 20 % off, as skid-steer and
#: tracked robots turn, not as a two-wheel differential drive does.
PLAUSIBLE_E_B = 0.20
#: ``E_s`` beyond ``1 -/+`` this: a mean wheel diameter 10 % off its nominal one.
PLAUSIBLE_E_S = 0.10

_MORE_RUNS = (
    "record more runs (the interval narrows with the square root of their number) or, for "
    "a square test, a larger square"
)
#: What narrows an interval of wheels calibrated against a laser's scan matching: the
#: driving it holds (no square is driven).
_MORE_DRIVING = (
    "record more driving, with turns both ways (the interval narrows with the square root "
    "of the number of motion intervals matched)"
)
#: What narrows ``E_b``'s interval where it is relative to the gyro (wheels and gyro
#: alone): not more driving, an absolute heading that calibrates the gyro's scale.
_GYRO_REFERENCE = (
    "calibrate the gyro's scale with an absolute heading in the same recording (its laser: "
    "--scan-topic; motion capture: --truth-topic), or state its scale tolerance from its "
    "datasheet (--gyro-scale-tolerance)"
)
_CHECK_MODEL = (
    "check the nominal wheelbase and wheel diameter, the time offset between wheels and "
    "ground truth, a tracked point off the axle (--fit-truth-offset) and slip (slower "
    "turns); record again with the ground truth tracking the robot all along"
)


@dataclass(frozen=True)
class Verdict:
    """Whether to apply a calibration.

    Attributes
    ----------
    level : {"apply", "care", "do-not-apply"}
        Apply; apply with care; do not apply.
    reasons : tuple of str
        Why not plainly "apply", the weightiest first.
    instead : str or None
        What to record or check instead (or, for "care", to be sure).
    """

    level: Level
    reasons: tuple[str, ...] = ()
    instead: str | None = None

    @property
    def applies(self) -> bool:
        """Whether the correction may be applied (``apply`` or ``care``)."""
        return self.level != "do-not-apply"

    @property
    def words(self) -> str:
        """``apply``, ``apply with care`` or ``do not apply``."""
        return _WORDS[self.level]

    def line(self) -> str:
        """One line for people: ``Verdict: apply with care: why; why. Instead: ...``."""
        text = f"Verdict: {self.words}"
        if self.reasons:
            text += ": " + "; ".join(self.reasons)
        text += "."
        if self.instead:
            lead = "Instead" if self.level == "do-not-apply" else "To be sure"
            text += f" {lead}: {self.instead}."
        return text

    def to_dict(self) -> dict[str, Any]:
        """``{"level": ..., "reasons": [...], "instead": ...}``."""
        return {"level": self.level, "reasons": list(self.reasons), "instead": self.instead}


@dataclass(frozen=True)
class Evidence:
    """What an estimate rests on, besides the estimate itself.

    Attributes
    ----------
    runs_per_direction : tuple of (int, int), optional
        Square runs cw and ccw (square tests).
    recorded_runs : int, optional
        Recorded runs the fit used (``endpoints``, ``trajectory``).
    path_length : float, optional
        Mean path of a recorded run [m] (the axle centre's).
    warnings : sequence of str
        The warnings that come with the result.
    nominal_best : bool
        ``--method auto`` found no estimator that predicts held-out runs better than the
        nominal parameters.
    wheel_diameter : float, optional
        The nominal wheel diameter [m] recorded runs were integrated with, or motion
        intervals calibrated against (a scale error of about 2 or 1/2 names it: a radius
        given for a diameter; of a power of ten, a unit slip).
    returns : tuple of (float, float), optional
        The runs' ``E_max,syst`` and ``3 x SEM`` [m] (squares driven both ways).
    """

    runs_per_direction: tuple[int, int] | None = None
    recorded_runs: int | None = None
    path_length: float | None = None
    warnings: Sequence[str] = ()
    nominal_best: bool = False
    wheel_diameter: float | None = None
    returns: tuple[float, float] | None = None


def noticeable(name: str, test: SquareTest) -> float:
    """How far from 1 ``E_d``, ``E_b`` or ``E_s`` must be to matter on ``test``'s square.

    ``E_b``: ``alpha = (pi/2)(1 - 1/E_b)``, so ``2/pi`` times :data:`NOTICEABLE_ANGLE`.
    ``E_d``: ``beta = (2L/b)(E_d - 1)/(E_d + 1)``, so ``b/L`` times it. ``E_s``: a scale
    error whose error over the square's ``4 L`` path is the paper's scatter.
    """
    if name == "E_b":
        return NOTICEABLE_ANGLE * 2.0 / math.pi
    if name == "E_d":
        return NOTICEABLE_ANGLE * test.wheelbase / test.side_length
    return PAPER_SCATTER / 4.0


def mean_path(logs: Sequence[RunLog], params: WheelParams) -> float | None:
    """How far the wheels of a recorded run rolled, on average over the runs [m]: the mean
    of the left and right wheels' travel, forward or back (what slip grows with; a turn
    on the spot counts); None without runs."""
    paths = []
    for log in logs:
        steps = np.abs(np.diff(np.asarray(log.wheel_angles, dtype=np.float64), axis=0))
        radius = 0.5 * params.wheel_diameter
        left, right = params.c_left * radius * steps[:, 0], params.c_right * radius * steps[:, 1]
        paths.append(0.5 * float(np.sum(left) + np.sum(right)))
    return float(np.mean(paths)) if paths else None


_Finding = tuple[Level, str, "str | None"]


def _intervals(estimate: ErrorEstimate, test: SquareTest) -> list[_Finding]:
    found: list[_Finding] = []
    scans = estimate.method in (*INTERVALS, *GYROS)  # ordinary driving: no square, no runs
    where = (
        f"over {test.side_length:g} m of driving"
        if scans
        else f"on the {test.side_length:g} m square"
    )
    comp = estimate.components
    for name in ("E_d", "E_b", "E_s"):
        interval = estimate.interval(name)
        value = getattr(estimate, name)
        if interval is None or value is None:
            continue
        low, high = interval
        correction, half, floor = abs(value - 1.0), 0.5 * (high - low), noticeable(name, test)
        shown = f"{name}'s 95 % interval, {low:.6f} to {high:.6f},"
        if name == "E_b" and "E_b_gyro" in comp and "gyro_scale" not in comp:
            shown = f"{name}'s 95 % interval, {low:.6f} to {high:.6f} (the gyro's scale tolerance),"
            more = _GYRO_REFERENCE
        else:
            more = _MORE_DRIVING if scans else _MORE_RUNS
        mirror = 2.0 - value
        if low <= min(1.0, mirror) and high >= max(1.0, mirror) and correction >= floor:
            found.append(
                (
                    "do-not-apply",
                    f"{shown} holds both 1 (no correction) and {mirror:.6f}, a robot this "
                    "correction would make twice as wrong: the runs do not say which way to "
                    "correct",
                    more,
                )
            )
        elif low <= 1.0 <= high and correction >= floor:
            found.append(("care", f"{shown} holds 1: the correction is barely resolved", more))
        elif half >= WIDE_INTERVAL * floor and low <= 1.0 <= high:
            found.append(
                (
                    "care",
                    f"{shown} is wide enough to hide an error that matters {where}",
                    more,
                )
            )
    return found


def _misfit(estimate: ErrorEstimate, evidence: Evidence) -> list[_Finding]:
    comp = estimate.components
    if "rms_position" not in comp or "rms_heading" not in comp:
        return []
    found: list[_Finding] = []
    path = evidence.path_length
    where = "along the runs" if "samples" in comp else "at the runs' ends"
    position, heading = comp["rms_position"], comp["rms_heading"]
    if path is not None and path > 0.0:
        share = position / path
        if position >= max(MISFIT_CARE * path, MISFIT_FLOOR[0]):
            refuse = position >= max(MISFIT_REFUSE * path, MISFIT_FLOOR[1])
            level: Level = "do-not-apply" if refuse else "care"
            found.append(
                (
                    level,
                    f"the fitted model misses the ground truth by {1000 * position:.0f} mm rms "
                    f"{where}, {100 * share:.1f} % of the {path:.2f} m a run's wheels roll "
                    "(random slip leaves a few per mille): the model does not hold",
                    _CHECK_MODEL,
                )
            )
    if heading >= HEADING_CARE:
        level = "do-not-apply" if heading >= HEADING_REFUSE else "care"
        found.append(
            (
                level,
                f"the fitted model misses the ground truth's heading by "
                f"{math.degrees(heading):.1f} deg rms {where}: the model does not hold",
                _CHECK_MODEL,
            )
        )
    return found


def _model_check(estimate: ErrorEstimate, test: SquareTest) -> list[_Finding]:
    from umbmark.estimators.diagnostics import MODEL_CAUSES, swapped_words

    failure = estimate.model_failure
    scatter = PAPER_SCATTER * test.side_length
    if failure is None or failure.p_value >= MODEL_REFUSE or failure.misfit < scatter:
        return []  # passed, or marginal: its warning makes it "apply with care"
    reason = (
        f"the model check fails strongly (p = {failure.p_value:.2g} < {MODEL_REFUSE:g}): a "
        f"cluster's centre lies {1000 * failure.misfit:.0f} mm from the nearest robot of the "
        f"model, more than the {1000 * scatter:.0f} mm runs scatter by on the "
        f"{test.side_length:g} m square, so the correction is no robot's"
    )
    if failure.swapped_fits:
        return [
            (
                "do-not-apply",
                f"{reason}; {swapped_words(failure)}",
                "swap the cw and ccw labels of the runs and calibrate again",
            )
        ]
    return [("do-not-apply", reason, MODEL_CAUSES)]


def _no_return_error(evidence: Evidence) -> list[_Finding]:
    if evidence.returns is None:
        return []
    e_max, three_sem = evidence.returns
    if max(e_max, three_sem) >= NO_RETURN_ERROR:
        return []
    return [
        (
            "care",
            f"E_max,syst = {1000 * e_max:.1f} mm and 3 x SEM = {1000 * three_sem:.1f} mm: the "
            "runs came back exactly where the odometry says, without any scatter, which no "
            "measured reference shows: a ground truth that reproduces the odometry, or a "
            "simulation without noise",
            REFERENCES,
        )
    ]


def _few_runs(evidence: Evidence) -> list[_Finding]:
    advice = f"drive at least {MIN_RUNS} runs each way (the paper drove 5)"
    if evidence.runs_per_direction is not None:
        cw, ccw = evidence.runs_per_direction
        if min(cw, ccw) < MIN_RUNS:
            return [
                ("care", f"only {cw} cw and {ccw} ccw runs: their scatter is known poorly", advice)
            ]
    elif evidence.recorded_runs is not None and evidence.recorded_runs < MIN_RUNS:
        n = evidence.recorded_runs
        return [
            (
                "care",
                f"only {n} recorded run{'s' if n != 1 else ''}: the scatter is known poorly",
                f"record at least {MIN_RUNS} runs",
            )
        ]
    return []


def _implausible(estimate: ErrorEstimate, diameter: float | None) -> list[_Finding]:
    from umbmark.estimators.scale import diameter_mixup, meant_diameter, slipped_words, unit_slip

    found: list[_Finding] = []
    check = "check the nominal wheelbase and wheel diameter, the encoder resolution and gear ratio"
    if abs(estimate.E_d - 1.0) > PLAUSIBLE_E_D:
        found.append(
            (
                "care",
                f"E_d = {estimate.E_d:.4f}: wheel diameters {100 * abs(estimate.E_d - 1):.0f} % "
                "apart, more than tyres differ",
                check,
            )
        )
    if abs(estimate.E_b - 1.0) > PLAUSIBLE_E_B:
        found.append(
            (
                "care",
                f"E_b = {estimate.E_b:.4f}: an effective wheelbase "
                f"{100 * abs(estimate.E_b - 1):.0f} % off the nominal one, as skid-steer and "
                "tracked robots turn, not a two-wheel differential drive",
                check,
            )
        )
    if estimate.E_s is not None and abs(estimate.E_s - 1.0) > PLAUSIBLE_E_S:
        said = f"E_s = {estimate.E_s:.4f}: the wheels' mean diameter over the one given"
        slip = unit_slip(estimate.E_s)
        if slip is not None and diameter is not None:  # a mistake: multipliers of 10, 100
            meant = option("wheel_diameter", meant_diameter(diameter, slip))
            why = f"{slipped_words(diameter, slip, said)}; multipliers so far off are no robot's"
            again = f"calibrate again with {meant}, the diameter in metres"
            found.append(("do-not-apply", with_flags(why), with_flags(again)))
            return found
        mixup = diameter_mixup(estimate.E_s, diameter, said)
        mixup = with_flags(mixup) if mixup is not None else None  # a reason, not an error
        found.append(
            (
                "care",
                mixup
                or f"E_s = {estimate.E_s:.4f}: a mean wheel diameter "
                f"{100 * abs(estimate.E_s - 1):.0f} % off the nominal one",
                check,
            )
        )
    return found


def judge(estimate: ErrorEstimate, test: SquareTest, evidence: Evidence) -> Verdict:
    """The verdict on applying ``estimate`` (see the module for the criteria).

    Parameters
    ----------
    estimate : ErrorEstimate
        The errors, their standard errors and the fit's figures (``components``).
    test : SquareTest
        The square the errors are judged on (side and wheelbase [m]).
    evidence : Evidence
        The runs, the fit's path, the warnings, ``auto``'s finding.

    Returns
    -------
    Verdict
        The worst level any criterion reaches, with every reason (the worst first) and
        what to do instead.
    """
    found: list[_Finding] = []
    if evidence.nominal_best:
        found.append(
            (
                "do-not-apply",
                "no estimator predicted held-out runs better than the nominal parameters: the "
                "parameters active during the runs are the better ones",
                "keep the active parameters; to find an error, record runs that show it: "
                "more runs, squares in both directions, longer paths",
            )
        )
    blocked = [w for w in evidence.warnings if isinstance(w, Blocking)]
    found += [("do-not-apply", w.reason, w.instead) for w in blocked]
    found += _no_return_error(evidence)
    found += _intervals(estimate, test)
    found += _misfit(estimate, evidence)
    found += _model_check(estimate, test)
    found += _few_runs(evidence)
    found += _implausible(estimate, evidence.wheel_diameter)
    if len(evidence.warnings) > len(blocked):
        n = len(evidence.warnings) - len(blocked)
        said = f"{n} warnings come" if n > 1 else "a warning comes"
        found.append(("care", f"{said} with the result (listed with it)", None))
    if not found:
        return Verdict("apply")
    rank = {level: k for k, level in enumerate(LEVELS)}
    found.sort(key=lambda f: -rank[f[0]])  # stable: the criteria's order within a level
    level = found[0][0]
    advice = [f[2] for f in found if f[0] == level and f[2] is not None]
    instead = "; ".join(dict.fromkeys(advice)) or None
    return Verdict(level, tuple(f[1] for f in found), instead)

"""What recorded runs hold (straight legs, arcs, turns on the spot), and whether they
identify the scrub model's turn-rate term.

The scrub model (:mod:`umbmark.estimators.trajectory`) gives every sampling interval the
wheelbase ``b_eff(w) = b_arc + (b_spot - b_arc) w`` of its turning share ``w = |dU_R -
dU_L| / (|dU_R| + |dU_L|)`` (0 straight, 1 on the spot). A wheelbase is seen only through
the heading it turns: a turn through ``Theta`` with the wrong wheelbase ``b + db`` ends
``Theta db / b`` off. So what the recordings tell of ``b_eff`` at a turning share is what
they turn at that share.

Coherent turns
--------------
Each run is cut into coherent turns: maximal stretches whose intervals turn the same way
(the sign of ``dU_R - dU_L``) and are of one kind (on the spot, ``w > SPOT_SHARE``, or
not); standing still continues the stretch. A turn through ``Theta_j = |sum (dU_R -
dU_L)| / b`` at the travel-weighted turning share ``w_j`` tells ``b_eff(w_j)`` with weight
``Theta_j^2`` (the heading it ends off, squared). A controller's weaving on a straight leg
is many small turns of alternating sign, and weighs accordingly little; a coherent turn
with ``w_j <= STRAIGHT_SHARE`` counts as a straight leg, one above as an arc.

The rule
--------
The turn-rate term is identified when both hold:

1. **The recordings turn both ways the model separates** (the wheel data alone, before any
   fit): arcs and turns on the spot each hold at least :data:`HELD_SHARE` of the
   turning's weight (:attr:`MotionCoverage.holds_both_turns`). Without one kind the
   model's straight line in ``w`` is checked at one end only and extrapolates to the other,
   and the fit cannot see it: on squares (straight legs, spot turns) ``b_arc`` rests on
   the weaving of the legs, with standard errors that are honest for the model and small
   (the OptiOdom square sessions give 195 +- 4 and 205 +- 3 mm, pooled 212 +- 2 mm, where
   the circles want 202 mm). Squares alone, circles alone and straights with spot turns
   are refused here, with what they lack.
2. **The fit pins the term**: the cluster-robust standard error of ``b_spot - b_arc`` is
   at most :data:`MAX_TERM_SE` of the wheelbase (:func:`term_problem`, applied by
   :func:`umbmark.estimators.trajectory_fit.scrub_term_problem`). How the turning's weight
   splits between the two kinds does not decide beyond that: the six OptiOdom circle
   sessions of day 2506 with the square session 0029 hold 9 % of the turning on the spot
   and 91 % on arcs, and pin the term to 0.12 mm (0.06 % of the wheelbase); with the
   spot-turn session 1636 instead, to 0.37 mm.

Before (commit 8f0b291) the rule was a spread of turning shares: a straight line through
the turns' points ``(w_j, b_eff)`` had to be at most 3 times less certain at every turning
share than a single wheelbase. That refused those 9 % (``k`` = 3.3): less certain than a
single wheelbase is no fault where the single wheelbase is the wrong model, and leaving one
session out the held-out squares ended 20 and 31 mm off with one wheelbase instead of 10
(``tools/scrub_identification.py --loso``, ``docs/turning-coverage.md``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.core.arrays import FloatArray
from umbmark.core.messages import join_names
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog

__all__ = [
    "HELD_SHARE",
    "KINDS",
    "MAX_TERM_SE",
    "SCRUB_ADVICE",
    "SCRUB_FALLBACK",
    "SCRUB_MORE",
    "MotionCoverage",
    "MotionKind",
    "motion_coverage",
    "term_problem",
]

MotionKind = Literal["straight", "arc", "spot"]
#: The kinds of motion, and how messages name them.
KINDS: dict[MotionKind, str] = {
    "straight": "straight legs",
    "arc": "arcs",
    "spot": "turns on the spot",
}
#: Turning share above which an interval turns on the spot.
SPOT_SHARE = 0.9
#: Turning share up to which a coherent turn is a straight leg (weaving or drifting): a
#: radius of five wheelbases or more.
STRAIGHT_SHARE = 0.1
#: Least share of the travel or of the turning's weight for the recordings to hold a kind.
HELD_SHARE = 0.05
#: Largest standard error of the fitted turn-rate term ``b_spot - b_arc``, as a share of
#: the wheelbase, for the fit to pin it (module documentation): 1 mm on a 0.2 m wheelbase.
#: Fits that pin it give 0.05 to 0.2 % on the OptiOdom sessions, squares fitted anyway 1
#: to 2 %.
MAX_TERM_SE = 0.005
#: What to record for the scrub model.
SCRUB_ADVICE = "record arcs (circles of several radii) as well as turns on the spot to fit it"
#: What to record where the fit does not pin the term.
SCRUB_MORE = "record more runs of arcs and of turns on the spot to fit it"
#: What the scrub estimator gives instead.
SCRUB_FALLBACK = "the result is the single-wheelbase fit, as --method trajectory"


def term_problem(b_arc: float, b_spot: float, se_term: float) -> str | None:
    """Why the fit does not pin the turn-rate term (None when it does): its standard error
    is over :data:`MAX_TERM_SE` of the wheelbase.

    Parameters
    ----------
    b_arc, b_spot : float
        The fitted wheelbases [m].
    se_term : float
        Standard error of ``b_spot - b_arc`` [m] (NaN: not known, not pinned).
    """
    limit = MAX_TERM_SE * b_arc
    if se_term <= limit:
        return None
    return (
        f"the fit does not pin the scrub model's turn-rate term: b_spot - b_arc = "
        f"{1000 * (b_spot - b_arc):.1f} ± {1000 * se_term:.1f} mm, a standard error over "
        f"{100 * MAX_TERM_SE:g} % of the wheelbase ({1000 * limit:.1f} mm)"
    )


@dataclass(frozen=True)
class MotionCoverage:
    """The motion of recorded runs, by kind.

    Attributes
    ----------
    travel : dict of kind to float
        Share of the travel (the wheels' mean travel) on straight legs, arcs and turns on
        the spot; sums to 1 (0 without motion).
    weight : dict of kind to float
        Share of the turning's weight ``sum Theta_j^2`` on each kind.
    turned : dict of kind to float
        Heading turned in the coherent turns of each kind [rad].
    """

    travel: dict[MotionKind, float]
    weight: dict[MotionKind, float]
    turned: dict[MotionKind, float]

    @property
    def held(self) -> tuple[MotionKind, ...]:
        """The kinds the recordings hold: straight legs with :data:`HELD_SHARE` of the
        travel, arcs and turns on the spot with as much of the turning's weight (a kind
        of turn that turns the robot by next to nothing tells nothing of it)."""
        return tuple(
            kind
            for kind in KINDS
            if (self.travel if kind == "straight" else self.weight)[kind] >= HELD_SHARE
        )

    @property
    def holds_both_turns(self) -> bool:
        """Whether the recordings hold arcs and turns on the spot, the first condition of
        the scrub model's turn-rate term (module documentation; the second is the fit's)."""
        return "arc" in self.held and "spot" in self.held

    def held_text(self, only: bool = False) -> str:
        """``straight legs and turns on the spot``: what the recordings hold (``only``:
        preceded by "only" when they do not hold every kind)."""
        text = join_names([KINDS[kind] for kind in self.held]) or "no motion"
        return f"only {text}" if only and 0 < len(self.held) < len(KINDS) else text

    def missing_text(self) -> str:
        """The kinds of turn not held, which the scrub model would extrapolate to
        (``arcs``, ``turns on the spot`` or both)."""
        return join_names([KINDS[k] for k in ("arc", "spot") if k not in self.held])

    def describe(self, only: bool = False) -> str:
        """The kinds held (see :meth:`held_text`), and how the turning's weight splits
        among them."""
        places: tuple[tuple[MotionKind, str], ...] = (
            ("spot", "on the spot"),
            ("arc", "on arcs"),
            ("straight", "on straight legs"),
        )
        split = ", ".join(f"{100 * self.weight[kind]:.0f} % {where}" for kind, where in places)
        return f"{self.held_text(only)} (of the turning, {split})"

    def scrub_problem(self) -> str | None:
        """Why the recordings cannot identify the scrub model's turn-rate term, whatever
        the fit (None when they hold both kinds of turn): what they hold, and what the
        model would extrapolate to."""
        if self.holds_both_turns:
            return None
        return (
            f"the recordings hold {self.describe(only=True)}; the scrub model's turn-rate term "
            f"is not identified: it would extrapolate to {self.missing_text()}, which they do "
            "not turn on"
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (shares, radians)."""
        return {
            "held": list(self.held),
            "travel_share": dict(self.travel),
            "turning_weight_share": dict(self.weight),
            "turned": dict(self.turned),
            "holds_both_turns": self.holds_both_turns,
        }


def _turns(d_left: FloatArray, d_right: FloatArray) -> tuple[FloatArray, ...]:
    """Coherent turns of one run's wheel travel per interval (n,) [m]: the turning
    ``|sum (dU_R - dU_L)|`` [m], the travel ``sum (|dU_L| + |dU_R|)`` [m] and whether each
    is on the spot (module documentation)."""
    turn = d_right - d_left
    travel = np.abs(d_left) + np.abs(d_right)
    share = np.divide(np.abs(turn), travel, out=np.zeros_like(turn), where=travel > 0.0)
    key = np.sign(turn) * np.where(share > SPOT_SHARE, 2.0, 1.0)
    moving = travel > 0.0
    # Standing still continues the stretch before it.
    carried = np.maximum.accumulate(np.where(moving, np.arange(key.size), 0))
    key = np.where(moving, key, key[carried])
    starts = np.flatnonzero(np.r_[True, np.diff(key) != 0.0])
    turning = np.abs(np.add.reduceat(turn, starts)) if key.size else np.zeros(0)
    travelled = np.add.reduceat(travel, starts) if key.size else np.zeros(0)
    return turning, travelled, np.abs(key[starts]) == 2.0 if key.size else np.zeros(0, bool)


def motion_coverage(logs: Sequence[RunLog], params: WheelParams) -> MotionCoverage:
    """Cut the runs into coherent turns and measure what they hold.

    Parameters
    ----------
    logs : sequence of RunLog
        The runs' wheel angles (n, 2) [rad].
    params : WheelParams
        Turn wheel rotation into travel [m] and turning into heading (the wheelbase).

    Returns
    -------
    MotionCoverage
    """
    parts = []
    for log in logs:
        step = np.diff(np.asarray(log.wheel_angles, dtype=np.float64), axis=0)
        d_left = 0.5 * params.diameter_left * step[:, 0]
        d_right = 0.5 * params.diameter_right * step[:, 1]
        parts.append(_turns(d_left, d_right))
    turning = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0)
    travel = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0)
    spot = np.concatenate([p[2] for p in parts]) if parts else np.zeros(0, bool)
    w = np.divide(turning, travel, out=np.zeros_like(turning), where=travel > 0.0)
    kinds: dict[MotionKind, NDArray[np.bool_]] = {
        "straight": ~spot & (w <= STRAIGHT_SHARE),
        "arc": ~spot & (w > STRAIGHT_SHARE),
        "spot": spot,
    }
    theta = turning / params.wheelbase
    weight = theta**2

    def shares(values: FloatArray) -> dict[MotionKind, float]:
        total = float(values.sum())
        return {k: float(values[m].sum()) / total if total > 0 else 0.0 for k, m in kinds.items()}

    return MotionCoverage(
        travel=shares(travel),
        weight=shares(weight),
        turned={k: float(theta[m].sum()) for k, m in kinds.items()},
    )

"""What recorded runs hold (straight legs, arcs, turns on the spot), and whether that
identifies the scrub model's turn-rate term.

The scrub model (:mod:`umbmark.estimators.trajectory`) gives every sampling interval the
wheelbase ``b_eff(w) = b_arc + (b_spot - b_arc) w`` of its turning share ``w = |dU_R -
dU_L| / (|dU_R| + |dU_L|)`` (0 straight, 1 on the spot). A wheelbase is seen only through
the heading it turns: a turn through ``Theta`` with the wrong wheelbase ``b + db`` ends
``Theta db / b`` off. So what the recordings tell of ``b_eff`` at a turning share is what
they turn at that share, and the turn-rate term (``b_spot - b_arc``, the slope of
``b_eff`` in ``w``) is identified only when they turn at turning shares far apart:
squares (straight legs, spot turns) turn almost only at ``w = 1``, circles of one radius
only at their own ``w``.

Coherent turns
--------------
Each run is cut into coherent turns: maximal stretches whose intervals turn the same way
(the sign of ``dU_R - dU_L``) and are of one kind (on the spot, ``w > SPOT_SHARE``, or
not); standing still continues the stretch. A turn through ``Theta_j = |sum (dU_R -
dU_L)| / b`` at the travel-weighted turning share ``w_j`` tells ``b_eff(w_j)`` with weight
``Theta_j^2`` (the heading it ends off, squared). A controller's weaving on a straight leg
is many small turns of alternating sign, and weighs accordingly little.

The criterion
-------------
The two wheelbases form a straight line in ``w`` fitted to the turns' points ``(w_j,
b_eff)`` with weights ``Theta_j^2``: its value at a turning share ``w`` is uncertain by
``k(w) = sqrt(1 + (w - w_bar)^2 / s_w^2)`` times a single wheelbase fitted to the same
turns (``w_bar``, ``s_w``: the weighted mean and standard deviation of the ``w_j``; the
variance of a prediction in linear regression, whatever the noise). The term is
identified when ``k`` stays within :data:`MAX_INFLATION` over all turning shares 0 to 1:
with turns at both ends, each end holding at least a ninth of the weight. Beyond, the
recorded turning sits at too narrow a range of ``w`` and the model extrapolates to the
rest: a fit of it rests on a sliver of the data (a square's weaving legs) and its
standard errors, honest for the model, do not see that the model's straight line is
not checked where it will be used. The criterion depends on the wheel data alone, not on
the noise. On the OptiOdom sessions squares give ``k`` = 5 to 12 and straights with spot
turns about 150, squares or straights with a session of circles 1.8 to 2; simulated
squares with weaving legs 5.8, with circles of three radii 2.0
(``tools/scrub_identification.py``, ``tests/test_motions.py``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.core.messages import join_names
from umbmark.model.kinematics import WheelParams
from umbmark.model.recording import RunLog

__all__ = [
    "KINDS",
    "MAX_INFLATION",
    "SCRUB_ADVICE",
    "SCRUB_FALLBACK",
    "MotionCoverage",
    "MotionKind",
    "motion_coverage",
]

FloatArray = NDArray[np.float64]
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
#: Most the scrub model may inflate the uncertainty of the wheelbase at any turning share
#: against a single wheelbase (module documentation).
MAX_INFLATION = 3.0
#: Least share of the travel or of the turning's weight for the recordings to hold a kind.
HELD_SHARE = 0.05
#: What to record for the scrub model.
SCRUB_ADVICE = "record arcs (circles of several radii) as well as turns on the spot to fit it"
#: What the scrub estimator gives instead.
SCRUB_FALLBACK = f"the result is the single-wheelbase fit, as --method trajectory; {SCRUB_ADVICE}"


@dataclass(frozen=True)
class MotionCoverage:
    """The motion of recorded runs, by kind, and what it identifies.

    Attributes
    ----------
    travel : dict of kind to float
        Share of the travel (the wheels' mean travel) on straight legs, arcs and turns on
        the spot; sums to 1 (0 without motion).
    weight : dict of kind to float
        Share of the turning's weight ``sum Theta_j^2`` on each kind.
    turned : dict of kind to float
        Heading turned in the coherent turns of each kind [rad].
    mean_share, share_spread : float
        ``w_bar`` and ``s_w`` of the turns (weighted by ``Theta_j^2``); NaN without turns.
    worst_share : float
        The turning share 0 or 1 farthest from ``w_bar``, where the scrub model is least
        certain.
    inflation : float
        ``k`` there: how many times less certain the scrub model's wheelbase is than a
        single wheelbase (inf when the turns sit at one turning share).
    """

    travel: dict[MotionKind, float]
    weight: dict[MotionKind, float]
    turned: dict[MotionKind, float]
    mean_share: float
    share_spread: float
    worst_share: float
    inflation: float

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
    def identifies_scrub(self) -> bool:
        """Whether the turning spreads over enough turning shares for the scrub model's
        turn-rate term (module documentation)."""
        return self.inflation <= MAX_INFLATION

    def held_text(self, only: bool = False) -> str:
        """``straight legs and turns on the spot``: what the recordings hold (``only``:
        preceded by "only" when they do not hold every kind)."""
        text = join_names([KINDS[kind] for kind in self.held]) or "no motion"
        return f"only {text}" if only and 0 < len(self.held) < len(KINDS) else text

    def missing_text(self) -> str:
        """What the scrub model would extrapolate to: the kinds of turn not held, else
        the kind at :attr:`worst_share` (arcs near 0, turns on the spot at 1)."""
        missing = [KINDS[k] for k in ("arc", "spot") if k not in self.held]
        return join_names(missing) or KINDS["arc" if self.worst_share < 0.5 else "spot"]

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
        """Why the recordings do not identify the scrub model's turn-rate term (None when
        they do): what they hold, and what the model would extrapolate to."""
        if self.identifies_scrub:
            return None
        certain = (
            f"{self.inflation:.0f} times less certain than a single wheelbase"
            if math.isfinite(self.inflation)
            else "not pinned at all"
        )
        return (
            f"the recordings hold {self.describe(only=True)}; the scrub model's turn-rate term "
            f"is not identified: it would extrapolate to {self.missing_text()} (its "
            f"wheelbase there {certain})"
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (shares, radians)."""
        return {
            "held": list(self.held),
            "travel_share": dict(self.travel),
            "turning_weight_share": dict(self.weight),
            "turned": dict(self.turned),
            "mean_turning_share": _finite(self.mean_share),
            "turning_share_spread": _finite(self.share_spread),
            "worst_turning_share": _finite(self.worst_share),
            "scrub_inflation": _finite(self.inflation),
            "identifies_scrub": self.identifies_scrub,
        }


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


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

    total = float(weight.sum())
    mean = spread = worst = math.nan
    inflation = math.inf
    if total > 0.0:
        mean = float(np.sum(weight * w) / total)
        spread = math.sqrt(float(np.sum(weight * (w - mean) ** 2) / total))
        worst = 0.0 if mean >= 0.5 else 1.0
        if spread > 0.0:
            inflation = math.sqrt(1.0 + ((worst - mean) / spread) ** 2)
    return MotionCoverage(
        travel=shares(travel),
        weight=shares(weight),
        turned={k: float(theta[m].sum()) for k, m in kinds.items()},
        mean_share=mean,
        share_spread=spread,
        worst_share=worst,
        inflation=inflation,
    )

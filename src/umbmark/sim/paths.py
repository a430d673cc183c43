"""Test paths as the robot's odometry knows them: straight legs and on-the-spot turns.

A path is a sequence of segments written for a ccw run; a cw run mirrors every turn.
The robot follows the path in its odometry frame: each straight leg runs from its ideal
start corner along its ideal heading, each turn ends at its ideal heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "Path",
    "Segment",
    "spot_turn",
    "square",
    "straight_line",
]


@dataclass(frozen=True)
class Segment:
    """A straight leg of ``amount`` metres, or a turn by ``amount`` radians (ccw positive)."""

    kind: Literal["straight", "turn"]
    amount: float

    def __post_init__(self) -> None:
        if not math.isfinite(self.amount) or (self.kind == "straight" and self.amount <= 0):
            raise ValueError(f"a {self.kind} segment needs a positive amount, got {self.amount}")


@dataclass(frozen=True)
class Path:
    """A named sequence of segments (written for ccw travel)."""

    name: str
    segments: tuple[Segment, ...]

    def references(self, turn_sign: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Ideal start point and heading of every segment.

        Parameters
        ----------
        turn_sign : {+1, -1}
            +1 for ccw travel, -1 for cw (every turn mirrored).

        Returns
        -------
        starts : array, shape (n_segments, 2)
            Ideal start point of each segment [m].
        headings : array, shape (n_segments, 2)
            Ideal heading at the start and at the end of each segment [rad], unwrapped.
        """
        x = y = heading = 0.0
        starts = np.zeros((len(self.segments), 2))
        headings = np.zeros((len(self.segments), 2))
        for k, seg in enumerate(self.segments):
            starts[k] = (x, y)
            headings[k, 0] = heading
            if seg.kind == "straight":
                x += seg.amount * math.cos(heading)
                y += seg.amount * math.sin(heading)
            else:
                heading += turn_sign * seg.amount
            headings[k, 1] = heading
        return starts, headings

    @property
    def length(self) -> float:
        """Total length of the straight legs [m]."""
        return sum(s.amount for s in self.segments if s.kind == "straight")


def square(side_length: float) -> Path:
    """The square path of Sec. 3: four legs, each followed by a 90 degree turn on the spot.

    The fourth turn is made after returning to the start, as in Sec. 5.
    """
    leg = Segment("straight", side_length)
    turn = Segment("turn", 0.5 * math.pi)
    return Path(f"square {side_length:g} m", (leg, turn) * 4)


def straight_line(length: float) -> Path:
    """One straight leg (for measuring the scale error ``E_s`` with a tape measure)."""
    return Path(f"straight {length:g} m", (Segment("straight", length),))


def spot_turn(angle: float) -> Path:
    """One on-the-spot turn by ``angle`` [rad] (ccw positive; cw runs mirror it)."""
    return Path(f"turn {math.degrees(angle):g} deg", (Segment("turn", angle),))

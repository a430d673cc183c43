"""The run matrix of the vectorized simulator: a row per per-run quantity (stacked ones
take several), a column per run (see :mod:`umbmark.sim.engine`), and the period loop's
work space."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import BoolArray, FloatArray
from umbmark.sim.robot import ControlConfig

__all__ = ["N_ROWS", "REFS", "ROW", "ROWS", "RUN", "SEGMENT", "Work"]


#: The rows of the run matrix: a name and how many rows it takes, in order.
ROWS: tuple[tuple[str, int], ...] = (
    # State.
    ("pose", 6),  # x (true, odometry), y (true, odometry), theta (true, odometry)
    ("phi", 2),  # wheel rotation [rad], left and right
    ("counts", 4),  # encoder counts (whole numbers), left and right; two buffers
    ("speed", 2),  # commanded v [m/s] and omega [rad/s]
    ("goal", 2),  # the controller's goals for v and omega
    ("limit", 2),  # this period's caps on |v| and |omega|
    ("neg_limit", 2),
    ("segment", 1),  # index of the current segment
    ("refs", 7),  # its start x, y, cos and sin of its start heading, amount, h0, h1
    # The robot's constants.
    ("half_b", 1),  # b / 2 of its own model
    ("wheel_rad", 2),  # wheel rotation per (m/s) commanded, over dt, left and right
    ("travel_per", 4),  # floor travel per wheel radian (D_L / 2, D_R / 2), c_L c_m, c_R c_m
    ("counts_per_rad", 2),  # (the same for both wheels)
    ("wheelbase", 2),  # true, own
    ("ramp", 2),  # largest change of v and omega per period
    ("neg_ramp", 2),
    ("omega_max", 1),
    ("turn_brake", 4),  # a dt / 2, (a dt / 2)^2 and 2 a of turns, their creep rate
    ("stop_distance", 1),
    ("stop_angle", 1),
    ("turn_cruise", 1),  # heading error from which the turn-rate goal is omega_max
    ("noise", 3),  # slip, bump rate, bump size
    ("table_row", 1),  # the run's first column in the segment table (ccw ones, then cw)
    ("run", 1),  # the run's index in the caller's order
)
ROW: dict[str, slice] = {}
for _name, _count in ROWS:
    _start = sum(s.stop - s.start for s in ROW.values())
    ROW[_name] = slice(_start, _start + _count)
N_ROWS = sum(count for _, count in ROWS)
REFS = ROW["refs"]
SEGMENT = ROW["segment"].start
RUN = ROW["run"].start


@dataclass(frozen=True)
class Work:
    """Work space of the period loop, for ``width`` columns (rows as commented)."""

    width: int
    constants: FloatArray  # dtheta's share of the heading (true, odometry), 1, 1/2
    gains: FloatArray  # heading and cross-track gains
    leg: FloatArray  # dx, dy, two temporaries, remaining, rest, braking speed
    turn: FloatArray  # error, |error|, a temporary, braking rate
    done: BoolArray  # runs at their target: on legs, in turns
    d_speed: FloatArray
    w_arm: FloatArray  # omega b / 2
    wheel: FloatArray  # wheel rotation (l, r), count increments (l, r)
    travel: FloatArray  # floor travel (l, r), odometry travel (l, r)
    sums: FloatArray  # ds, dtheta, h, chord, heading; each (true, odometry)
    h2: FloatArray
    terms: FloatArray
    half_sinc: FloatArray
    cs: FloatArray  # cos and sin of the heading (true, odometry), then times the chord
    normal: FloatArray  # the generator's draws, in the caller's order (l, r)
    uniform: FloatArray
    normal_here: FloatArray  # ... in the order of the columns
    uniform_here: FloatArray
    noise: FloatArray  # |travel|, a temporary, sign of the travel
    bumped: BoolArray

    @classmethod
    def make(cls, width: int, n_runs: int, control: ControlConfig) -> Work:
        e = np.empty
        share = [[0.5], [1.0 if control.method == "segment" else 0.5]]
        return cls(
            width=width,
            constants=np.array(
                [np.broadcast_to(share, (2, width)), np.ones((2, width)), np.full((2, width), 0.5)]
            ),
            gains=np.array(
                [np.full(width, control.heading_gain), np.full(width, control.cross_track_gain)]
            ),
            leg=e((7, width)),
            turn=e((4, width)),
            done=np.zeros((2, width), dtype=np.bool_),
            d_speed=e((2, width)),
            w_arm=e(width),
            wheel=e((2, 2, width)),
            travel=e((2, 2, width)),
            sums=e((5, 2, width)),
            h2=e((2, width)),
            terms=e((3, 2, width)),
            half_sinc=np.full((2, width), 0.5),
            cs=e((2, 2, width)),
            normal=e((2, n_runs)),
            uniform=e((2, n_runs)),
            normal_here=e((2, width)),
            uniform_here=e((2, width)),
            noise=e((3, 2, width)),
            bumped=np.zeros((2, width), dtype=np.bool_),
        )

"""The closed-loop simulator, vectorized over runs (and robots).

Every sampling period, for every run at once:

1. The controller reads the robot's **odometry** pose and commands a body speed ``v`` and
   turn rate ``omega``: on a leg it follows the ideal line from the leg's start corner and
   slows to stop where its odometry says the leg ends; in a turn it rotates on the spot
   until its odometry heading reaches the target, to within two encoder pulses. Speeds
   ramp with an acceleration limit, brake in time, creep at the end and never command a
   step past the target.
2. The commands become wheel rotations through the robot's **own** model (its ``D_n``,
   ``c_L``, ``c_R``, ``b``): as on a real robot, the wheel speed loops track them.
3. The wheels move the robot over the floor by their **true** diameters, less slip and
   bumps; the true pose advances by the exact arc.
4. The encoders quantize the wheel rotations; the odometry integrates the count
   increments (Eqs. 2.1, 2.2, 4.33) with the robot's own parameters.

Runs finish at different times; a finished run stands still.

How the pass is organised
-------------------------
Each run's numbers go through the model's floating-point operations in the model's order,
whatever else is in the batch (the arcs as in :func:`umbmark.model.kinematics.chord_step`,
whose sin(h)/h takes its series form when every run's ``|h|`` is below 0.01). What is
arranged for speed is the bookkeeping around them, since a period costs a few dozen numpy
calls whatever the number of runs:

* Every per-run quantity (state, the current segment's references, the robot's constants)
  is a row of one matrix whose columns are the runs: first the runs on a leg, then the
  runs turning, then the finished ones. The leg and the turn laws each work on their
  block of columns; the wheels, the encoders and both poses (the true and the odometry
  pose in one stacked update) on all columns. When a run changes segment its column moves
  to its new block; finished columns are dropped now and then.
* Far from a leg's end the speed goal is the cruise speed, and far from a turn's end the
  turn-rate goal is the largest one: as the odometry moves a bounded amount per period,
  one check tells for how many periods that holds, and the braking profiles are evaluated
  only when they may bind.
* Slip and bumps are drawn for every run in every period, in the caller's order of the
  runs, as the model's period draws them (seeded results repeat).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.sim.batch import Batch
from umbmark.sim.paths import Path
from umbmark.sim.result import SimResult
from umbmark.sim.robot import ControlConfig, SimRobot

__all__ = ["simulate"]


def simulate(
    robots: SimRobot | Sequence[SimRobot],
    path: Path,
    directions: Sequence[Direction],
    control: ControlConfig | None = None,
    rng: np.random.Generator | None = None,
    *,
    record: bool = False,
    progress: Callable[[float], None] | None = None,
) -> SimResult:
    """Drive ``path`` once per entry of ``directions``, all runs in one vectorized pass.

    Parameters
    ----------
    robots : SimRobot or sequence of SimRobot
        One robot for every run, or one per run (length R).
    path : Path
        The path, written for ccw travel; cw runs mirror its turns.
    directions : sequence of Direction, length R
    control : ControlConfig, optional
    rng : numpy.random.Generator, optional
        Source of the non-systematic errors (needed only when a robot has noise).
    record : bool
        Keep the time series (memory grows as R x samples).
    progress : callable, optional
        Called now and then with the fraction of runs finished.

    Returns
    -------
    SimResult
    """
    control = control or ControlConfig()
    n_runs = len(directions)
    if n_runs == 0:
        raise ValueError("no runs to simulate")
    fleet = [robots] * n_runs if isinstance(robots, SimRobot) else list(robots)
    if len(fleet) != n_runs:
        raise ValueError(f"{len(fleet)} robots for {n_runs} runs")
    batch = Batch(fleet, path, directions, control)
    if batch.noisy and rng is None:
        raise ValueError("a robot has non-systematic errors: pass a random generator")
    return batch.run(rng, record, progress)

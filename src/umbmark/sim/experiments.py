"""UMBmark on virtual robots: the test, the calibration, the test again.

Many robots (and many experiments) go through the simulator in one vectorized pass.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from umbmark.calibration.compose import Calibration
from umbmark.core.conventions import Direction
from umbmark.estimators.base import SquareTest
from umbmark.estimators.dispatch import estimate_errors
from umbmark.estimators.registry import PAPER, Method
from umbmark.model.active import ActiveParams
from umbmark.model.run import Run
from umbmark.returns.clusters import Benchmark, umbmark_benchmark
from umbmark.sim.engine import simulate
from umbmark.sim.paths import square
from umbmark.sim.robot import ControlConfig, SimRobot

__all__ = ["Trial", "calibrate_robot", "umbmark_trials"]


@dataclass(frozen=True)
class Trial:
    """One bi-directional square test of one robot."""

    robot: SimRobot
    runs: list[Run]

    @property
    def benchmark(self) -> Benchmark:
        """The UMBmark evaluation of the runs."""
        return umbmark_benchmark(self.runs)


def umbmark_trials(
    robots: Sequence[SimRobot],
    side_length: float,
    runs_per_direction: int = 5,
    control: ControlConfig | None = None,
    rng: np.random.Generator | None = None,
    progress: Callable[[float], None] | None = None,
) -> list[Trial]:
    """The bi-directional square test (``n`` cw runs, then ``n`` ccw) of every robot.

    All runs of all robots are simulated in one pass.
    """
    n = runs_per_direction
    directions = ([Direction.CW] * n + [Direction.CCW] * n) * len(robots)
    fleet = [robot for robot in robots for _ in range(2 * n)]
    result = simulate(fleet, square(side_length), directions, control, rng, progress=progress)
    runs = result.runs()
    trials = []
    for i, robot in enumerate(robots):
        chunk = runs[2 * n * i : 2 * n * (i + 1)]
        labelled = [
            replace(r, label=f"{r.direction.value} run {k % n + 1}") for k, r in enumerate(chunk)
        ]
        trials.append(Trial(robot=robot, runs=labelled))
    return trials


def calibrate_robot(
    trial: Trial, side_length: float, method: Method = PAPER.name
) -> tuple[Calibration, SimRobot]:
    """Calibrate a virtual robot from its test, as a user would a real one.

    Returns the calibration and the robot with its odometry parameters replaced by the
    calibrated ones (composed with those active during the test).
    """
    odometry = trial.robot.odometry
    bench = trial.benchmark
    estimate = estimate_errors(
        method, bench, trial.runs, SquareTest(side_length, odometry.wheelbase)
    )
    calibration = Calibration(
        estimate,
        ActiveParams(
            wheelbase=odometry.wheelbase,
            c_left=odometry.c_left,
            c_right=odometry.c_right,
            wheel_diameter=odometry.wheel_diameter,
        ),
    )
    robot = trial.robot.calibrated(
        calibration.new_c_left, calibration.new_c_right, calibration.wheelbase_corrected
    )
    return calibration, robot

"""Simulated runs as one continuous recording, the way a robot records a UMBmark test.

The simulator drives every run from its own start (true and odometry pose zero, encoder
counts zero). A robot recording a test keeps one clock, one odometry frame and one
encoder count for the whole session: it stands still near the start, drives a loop,
rests there while the experimenter notes the result, drives the next loop from where it
stopped, and so on (``docs/driving.md``). :func:`continuous_session` lays the runs out so:

* a rest of :data:`REST` seconds before the first run, between runs and after the last,
  sampled every sampling period with the robot still (what
  :func:`umbmark.runs.segmentation.split_by_rests` splits at);
* each run starts where the one before it stopped: its true poses are composed onto the
  previous run's true end pose, its odometry poses onto the previous odometry end pose,
  its encoder counts added to the previous counts. The simulated motion does not depend
  on where a run starts (the controller steers relative to the run's start as its
  odometry sees it), so every run is the same run as the simulator drove it;
* the first true pose is :data:`START_IN_WORLD` (a motion-capture frame whose origin is
  not the start corner); the odometry starts at zero.

Units: seconds, metres, radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.model.recording import PoseSeries, WheelSeries
from umbmark.sim.result import SimResult

__all__ = ["REST", "START_IN_WORLD", "SimulatedSession", "continuous_session"]


#: Rest before the first run, between runs and after the last [s].
REST = 2.0
#: The robot's first true pose in the world (motion-capture) frame: x, y [m], heading [rad].
START_IN_WORLD = (0.5, 0.5, 0.0)


@dataclass(frozen=True)
class SimulatedSession:
    """The runs of a simulation as one recording, on one clock.

    Attributes
    ----------
    wheels : WheelSeries
        Wheel rotation [rad] from the cumulative encoder counts (whole pulses).
    odometry : PoseSeries
        The robot's own odometry pose in its odometry frame (zero at the first sample).
    truth : PoseSeries
        The true pose of the axle centre in the world frame, headings unwrapped.
    windows : array, shape (R, 2)
        Each run's first and last sample time [s], in the simulation's order of runs.
    """

    wheels: WheelSeries
    odometry: PoseSeries
    truth: PoseSeries
    windows: FloatArray


def _compose(origin: FloatArray, poses: FloatArray) -> FloatArray:
    """``poses`` (n, 3), given in the frame of their first pose, placed at ``origin`` (3,)."""
    x0, y0, th0 = poses[0]
    c0, s0 = math.cos(th0), math.sin(th0)
    dx, dy = poses[:, 0] - x0, poses[:, 1] - y0
    local_x, local_y = c0 * dx + s0 * dy, -s0 * dx + c0 * dy  # in the run's start frame
    c, s = math.cos(origin[2]), math.sin(origin[2])
    return np.column_stack(
        [
            origin[0] + c * local_x - s * local_y,
            origin[1] + s * local_x + c * local_y,
            origin[2] + (poses[:, 2] - th0),
        ]
    )


def continuous_session(
    result: SimResult,
    radians_per_pulse: float,
    rest: float = REST,
    start: tuple[float, float, float] = START_IN_WORLD,
) -> SimulatedSession:
    """Lay the simulated runs end to end with rests between them (see the module notes).

    Parameters
    ----------
    result : SimResult
        A simulation recorded with its time series (``record=True``).
    radians_per_pulse : float
        Wheel rotation per encoder count [rad] (``WheelParams.radians_per_pulse``).
    rest : float
        Rest before, between and after the runs [s].
    start : (float, float, float)
        The first true pose in the world frame.

    Raises
    ------
    ValueError
        If the simulation kept no time series.
    """
    trace = result.trace
    if trace is None:
        raise ValueError("the simulation kept no time series: simulate with record=True")
    dt = float(trace.time[1] - trace.time[0])
    n_rest = max(1, round(rest / dt))
    still = np.arange(1, n_rest + 1) * dt  # the rest's times after its first sample

    true_at = np.array(start, dtype=np.float64)
    odo_at = np.zeros(3)
    counts_at = np.zeros(2, dtype=np.int64)
    times = [np.concatenate([[0.0], still])]
    truths = [np.tile(true_at, (n_rest + 1, 1))]
    odos = [np.tile(odo_at, (n_rest + 1, 1))]
    counts = [np.tile(counts_at, (n_rest + 1, 1))]
    clock = float(times[0][-1])
    windows = []
    for i in range(len(result.directions)):
        end = int(result.samples_used[i]) + 1
        truth = _compose(true_at, trace.true_pose[i, :end])[1:]
        odo = _compose(odo_at, trace.odometry_pose[i, :end])[1:]
        count = trace.counts[i, 1:end] - trace.counts[i, 0] + counts_at
        run_time = clock + (trace.time[1:end] - trace.time[0])
        windows.append((clock, float(run_time[-1])))
        true_at, odo_at, counts_at = truth[-1], odo[-1], count[-1]
        clock = float(run_time[-1])
        rest_time = clock + still
        clock = float(rest_time[-1])
        times += [run_time, rest_time]
        truths += [truth, np.tile(true_at, (n_rest, 1))]
        odos += [odo, np.tile(odo_at, (n_rest, 1))]
        counts += [count, np.tile(counts_at, (n_rest, 1))]
    time = np.concatenate(times)
    return SimulatedSession(
        wheels=WheelSeries(time, np.concatenate(counts).astype(np.float64) * radians_per_pulse),
        odometry=PoseSeries(time, np.concatenate(odos)),
        truth=PoseSeries(time, np.concatenate(truths)),
        windows=np.array(windows, dtype=np.float64),
    )

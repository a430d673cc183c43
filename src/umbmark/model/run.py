"""The ``Run``: what every source produces and every estimator consumes.

A run is one trip around a closed path. What the benchmark needs of it is where the robot
really stopped (``true_end``) and where its odometry thinks it stopped (``odometry_end``),
both in the run's start frame (see :mod:`umbmark.core.conventions`). Sources that recorded the
whole trip attach the time series as well (``log``), so that the odometry can be
re-integrated with other wheel parameters.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from umbmark.core.conventions import Direction, wrap_angle
from umbmark.model.kinematics import IntegrationMethod, WheelParams
from umbmark.model.recording import RunLog

__all__ = ["EndPose", "Run", "end_errors", "return_errors", "split_by_direction"]


@dataclass(frozen=True)
class EndPose:
    """A planar pose: ``x``, ``y`` [m] and optionally the heading ``theta`` [rad]."""

    x: float
    y: float
    theta: float | None = None

    def __post_init__(self) -> None:
        values = (self.x, self.y) if self.theta is None else (self.x, self.y, self.theta)
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"pose has a value that is not a finite number: {self}")


@dataclass(frozen=True)
class Run:
    """One run around the test path.

    Attributes
    ----------
    direction : Direction
        ``cw`` or ``ccw``.
    true_end : EndPose
        Absolute (true) end pose, in the run's start frame (``x_abs``, ``y_abs``).
    odometry_end : EndPose
        End pose as the robot's odometry computed it (``x_calc``, ``y_calc``).
    label : str
        Where the run came from, for messages (``runs.csv row 3``, ``run-04``).
    log : RunLog or None
        The recorded time series, for logged runs.
    kind : {"square", "straight"}
        A run around the square (UMBmark), or a straight run whose odometry distance is
        compared with the distance measured (the scale error ``E_s``); a straight run's
        ``direction`` means nothing.
    """

    direction: Direction
    true_end: EndPose
    odometry_end: EndPose
    label: str = ""
    log: RunLog | None = field(default=None, repr=False, compare=False)
    kind: Literal["square", "straight"] = "square"

    @property
    def return_error(self) -> tuple[float, float]:
        """``(eps_x, eps_y)`` [m], Eq. 3.1: absolute minus calculated."""
        return (self.true_end.x - self.odometry_end.x, self.true_end.y - self.odometry_end.y)

    @property
    def heading_error(self) -> float | None:
        """``eps_theta`` [rad], Eq. 3.1, wrapped into ``[-pi, pi)``; None without headings."""
        if self.true_end.theta is None or self.odometry_end.theta is None:
            return None
        return float(wrap_angle(self.true_end.theta - self.odometry_end.theta))

    def reintegrated(self, params: WheelParams, method: IntegrationMethod = "arc") -> Run:
        """The same run with its odometry integrated anew with ``params`` (replay).

        Raises
        ------
        ValueError
            If the run has no recorded wheel data.
        """
        if self.log is None:
            raise ValueError(f"{self.label or 'a run'} has no recorded wheel data to replay")
        odo = self.log.odometry(params, method)
        return replace(self, odometry_end=EndPose(*(float(v) for v in odo[-1])))


def return_errors(runs: Sequence[Run]) -> NDArray[np.float64]:
    """Return errors of ``runs`` as an array of shape (n, 2): ``eps_x, eps_y`` [m]."""
    return np.array([run.return_error for run in runs], dtype=np.float64).reshape(-1, 2)


def end_errors(runs: Sequence[Run]) -> NDArray[np.float64]:
    """Distance between true and odometry end position of every run [m], shape (n,)."""
    return np.array([math.hypot(*run.return_error) for run in runs], dtype=np.float64)


def split_by_direction(runs: Sequence[Run]) -> dict[Direction, list[Run]]:
    """The square runs of each direction, in their original order (straight runs left out)."""
    groups: dict[Direction, list[Run]] = {Direction.CW: [], Direction.CCW: []}
    for run in runs:
        if run.kind == "square":
            groups[run.direction].append(run)
    return groups

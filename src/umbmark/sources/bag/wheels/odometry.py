"""Wheel rotation from a controller's odometry: its update, inverted.

Many robots record no wheel joint states, only the odometry their base controller
publishes (``nav_msgs/Odometry`` on ``/odom``, or the ``odom -> base_link`` transform).
That odometry is a known function of the wheel rotation, so the rotation can be
recovered from it, and every estimator then works as on encoder data.

What the controllers do
-----------------------
ros2_controllers' ``diff_drive_controller`` (``odometry.cpp``; Humble ``update`` /
``integrateExact``, Jazzy and later ``update_from_pos`` / ``integrate``) and ROS 1's
(``diff_drive_controller/src/odometry.cpp``) do the same on every control cycle: the
wheel positions (several wheels per side averaged) times the effective radii
``left/right_wheel_radius_multiplier * wheel_radius`` give each side's travel ``dU_L,
dU_R`` since the last cycle; ``linear = (dU_R + dU_L) / 2``, ``angular = (dU_R - dU_L) /
(wheel_separation_multiplier * wheel_separation)``; and the pose moves along the circular
arc of that length and turn (a second-order Runge-Kutta step, the same to first order, or
a straight Euler step in Jazzy, when ``|angular| < 1e-6``). The published pose is that
state, at the controller's publish rate.

The inverse
-----------
Between two published poses the robot moved along one arc if its curvature did not change
in between, and then :func:`umbmark.model.kinematics.wheel_travel_from_poses` gives ``dU_L,
dU_R`` exactly; dividing their running sums by the effective radii gives the wheel angles
the controller read. When the curvature did change between two messages (the start of a
spot turn), the motion is several arcs, and the single-arc inverse errs by about
``dU dtheta^2 / 12``: negligible at the 20-100 Hz controllers publish at, not for sparse
messages. Two measures of that are computed and refused beyond their bounds:

- the largest turn between messages: above :data:`MAX_STEP_TURN` the messages are too
  sparse to separate turning from driving;
- the displacement across the mid-step heading, which no single arc has, summed over the
  recording and divided by the distance driven: above :data:`MAX_LATERAL_SHARE` the poses
  do not come from a differential drive's odometry at this rate (a filtered odometry,
  a holonomic base, or too few messages).

Both leave out the steps across gaps in the messages
(:func:`umbmark.model.recording.gap_mask`; :mod:`umbmark.runs.gaps`): a
second without a message says nothing of the rate or of the odometry; whether a run can
cross it is decided where the runs are found.

An ``open_loop`` controller integrates its velocity commands instead of the wheels: its
odometry says nothing about the wheels, and the readers refuse it (see
:class:`umbmark.sources.params.reader.ControllerParams`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from umbmark.core.errors import InputError
from umbmark.model.kinematics import OdometryGeometry, wheel_travel_from_poses
from umbmark.model.recording import PoseSeries, WheelSeries, gap_mask

__all__ = ["MAX_LATERAL_SHARE", "MAX_STEP_TURN", "OdometryInversion", "wheels_from_odometry"]


#: Largest turn [rad] between two odometry messages (99th percentile) that is inverted.
MAX_STEP_TURN = 0.35
#: Largest sideways displacement, summed over the recording, per metre driven.
MAX_LATERAL_SHARE = 0.02


@dataclass(frozen=True)
class OdometryInversion:
    """Wheel rotation recovered from an odometry, and how well one arc explains each step.

    Attributes
    ----------
    wheels : WheelSeries
        ``time`` shape (n,) [s]; ``angles`` shape (n, 2) [rad], left and right, 0 at the
        first message.
    largest_turn : float
        99th percentile of the turn between messages [rad].
    lateral_share : float
        Sideways displacement no arc explains, summed, per metre driven.
    """

    wheels: WheelSeries
    largest_turn: float
    lateral_share: float


def wheels_from_odometry(
    odometry: PoseSeries, geometry: OdometryGeometry, what: str, source: str
) -> OdometryInversion:
    """The wheel angles that made a controller publish ``odometry``.

    Parameters
    ----------
    odometry : PoseSeries
        The controller's poses: ``time`` shape (n,) [s], ``poses`` shape (n, 3)
        ``x, y`` [m] and heading [rad] (wrapped or not).
    geometry : OdometryGeometry
        The effective radii and separation the controller used.
    what, source : str
        The topic or transform, and the file, for messages.

    Raises
    ------
    InputError
        The odometry has fewer than 2 poses, turns too far between messages, or moves
        sideways (see the module docstring).
    """
    poses = np.array(odometry.poses, dtype=np.float64)
    if poses.shape[0] < 2:
        raise InputError(f"{what} has fewer than 2 poses", source=source)
    poses[:, 2] = np.unwrap(poses[:, 2])
    d_left, d_right, lateral = wheel_travel_from_poses(poses, geometry.separation)
    # A gap in the messages is no sign of a sparse rate or a filtered odometry: its step
    # is judged where the runs are (umbmark.runs.gaps).
    steady = ~gap_mask(np.asarray(odometry.time, dtype=np.float64))
    if not steady.any():
        steady[:] = True
    turn = np.abs(np.diff(poses[:, 2]))[steady]
    largest = float(np.quantile(turn, 0.99))
    interval = float(np.median(np.diff(odometry.time)))
    if largest > MAX_STEP_TURN:
        raise InputError(
            f"{what} turns up to {largest:.2f} rad between messages ({1.0 / interval:.1f} Hz)"
            f": too sparse to separate turning from driving (at most {MAX_STEP_TURN} rad); "
            "record the controller's odometry at its publish rate",
            source=source,
        )
    driven = float(
        np.sum((0.5 * np.abs(d_left + d_right) + 0.25 * np.abs(d_right - d_left))[steady])
    )
    share = float(np.sum(np.abs(lateral[steady])) / driven) if driven > 0.0 else 0.0
    if share > MAX_LATERAL_SHARE:
        raise InputError(
            f"{what} moves sideways {1000.0 * share:.0f} mm per metre driven: not a "
            f"differential drive's odometry at this rate (at most {1000.0 * MAX_LATERAL_SHARE:.0f}"
            " mm/m); give the base controller's own odometry, not a filtered one",
            source=source,
        )
    angles = np.zeros((poses.shape[0], 2))
    angles[1:, 0] = np.cumsum(d_left) / geometry.left_radius
    angles[1:, 1] = np.cumsum(d_right) / geometry.right_radius
    wheels = WheelSeries(time=np.asarray(odometry.time, dtype=np.float64), angles=angles)
    return OdometryInversion(wheels=wheels, largest_turn=largest, lateral_share=share)

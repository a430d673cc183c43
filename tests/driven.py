"""Recordings written the way simulated and real robots write them: a TurtleBot3-like
robot in the package's simulator, its squares stitched as people drive them (put back at
the start between squares, wheels creeping and twitching in the pauses, messages that stop
for a while), written as real ROS bags with rosbags.

Nothing here calls the code under test: the truth is the simulator's, the controller
odometry the exact arc integration written out below.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from umbmark.core.conventions import Direction
from umbmark.model.kinematics import WheelParams
from umbmark.sim.engine import simulate
from umbmark.sim.paths import square
from umbmark.sim.robot import ControlConfig, SimRobot

#: A TurtleBot3 Burger: wheel radius 33 mm, separation 160 mm.
TB3 = WheelParams(wheelbase=0.160, wheel_diameter=0.066, encoder_resolution=4096, gear_ratio=1)
#: Faster than the real Burger (0.22 m/s), as simulated ones are driven.
CONTROL = ControlConfig(speed=0.35)
#: Every third simulator period (100 Hz) is published: 33 Hz, as Gazebo's plugins.
EVERY = 3


@dataclass(frozen=True)
class Session:
    """A recording at the simulator's 100 Hz.

    Attributes
    ----------
    time : array, shape (n,)
        [s] from 0.
    angles : array, shape (n, 2)
        Wheel angles [rad], left and right.
    truth : array, shape (n, 3)
        True pose in the world [m, rad].
    ends : list of (x, y, theta)
        Each square's true end in its start frame, from the simulator.
    starts, stops : list of float
        When each square's motion starts and ends [s].
    """

    time: np.ndarray
    angles: np.ndarray
    truth: np.ndarray
    ends: list[tuple[float, float, float]]
    starts: list[float]
    stops: list[float]


def squares(
    robot: SimRobot,
    directions: Sequence[str],
    *,
    side: float = 1.0,
    rest: float = 2.0,
    pauses: Sequence[float] | None = None,
    reset: bool = False,
    creep: float = 0.0,
    twitch: float = 0.0,
    seed: int = 0,
) -> Session:
    """Squares driven one after the other, ``rest`` seconds of standing before, between
    and after them (or ``pauses[k]`` seconds before square ``k``, the last after them).

    ``reset``: the robot is put back at the first start pose in the middle of each pause
    (the truth jumps while the wheels stand still); otherwise each square starts where
    the last one ended. ``creep``: the wheel angles jitter by this much [rad, standard
    deviation] in the pauses, and drift at a tenth of it per second. ``twitch``: the left
    wheel turns by this much [rad] in the 0.15 s before the middle of each pause between
    squares (before the reset, if any).
    """
    rng = np.random.default_rng(seed)
    result = simulate(
        robot,
        square(side),
        [Direction(d) for d in directions],
        CONTROL,
        np.random.default_rng(seed),
        record=True,
    )
    trace = result.trace
    assert trace is not None
    dt = float(trace.time[1] - trace.time[0])
    lengths = [round(p / dt) for p in (pauses or [rest] * (len(directions) + 1))]
    radians = robot.odometry.radians_per_pulse
    times: list[float] = []
    angles: list[np.ndarray] = []
    poses: list[tuple[float, float, float]] = []
    base = np.zeros(2)
    pose0 = (0.0, 0.0, 0.0)
    here = pose0
    starts, stops = [], []

    def pause(first: bool, last: bool) -> None:
        nonlocal here
        nonlocal base
        still = lengths[len(starts)]
        offsets = np.zeros((still, 2))
        if creep and not first:
            offsets += rng.normal(0.0, creep, size=(still, 2))
            offsets += 0.1 * creep * dt * np.arange(still)[:, None]
        if twitch and not first and not last:
            k0, k1 = still // 2 - round(0.15 / dt), still // 2
            offsets[k0:k1, 0] += np.linspace(0.0, twitch, k1 - k0)
            offsets[k1:, 0] += twitch
        for k in range(still):
            if reset and not first and k == still // 2:
                here = pose0
            times.append(len(times) * dt)
            angles.append(base + offsets[k])
            poses.append(here)
        base = base + offsets[-1]

    pause(True, False)
    for i in range(len(directions)):
        n = int(result.samples_used[i]) + 1
        x0, y0, th0 = here
        c, s = math.cos(th0), math.sin(th0)
        starts.append(len(times) * dt)
        for k in range(1, n):
            lx, ly, lth = trace.true_pose[i, k]
            times.append(len(times) * dt)
            angles.append(base + trace.counts[i, k] * radians)
            poses.append((x0 + c * lx - s * ly, y0 + s * lx + c * ly, th0 + lth))
        stops.append(times[-1])
        base = angles[-1].copy()
        here = poses[-1]
        pause(False, i == len(directions) - 1)
    ends = [tuple(float(v) for v in result.true_end[i]) for i in range(len(directions))]
    return Session(
        time=np.array(times),
        angles=np.array(angles),
        truth=np.array(poses),
        ends=ends,  # type: ignore[arg-type]
        starts=starts,
        stops=stops,
    )


def controller_odometry(angles: np.ndarray, params: WheelParams) -> np.ndarray:
    """The pose a diff_drive_controller publishes for ``angles`` (n, 2): the exact arc of
    each step's wheel travel (radius D/2, separation b), from (0, 0, 0); shape (n, 3)."""
    radius = 0.5 * params.wheel_diameter
    out = np.zeros((angles.shape[0], 3))
    x = y = heading = 0.0
    for k in range(1, angles.shape[0]):
        d_left = radius * float(angles[k, 0] - angles[k - 1, 0])
        d_right = radius * float(angles[k, 1] - angles[k - 1, 1])
        linear = 0.5 * (d_left + d_right)
        angular = (d_right - d_left) / params.wheelbase
        if abs(angular) < 1e-9:
            x += linear * math.cos(heading + 0.5 * angular)
            y += linear * math.sin(heading + 0.5 * angular)
        else:
            r = linear / angular
            x += r * (math.sin(heading + angular) - math.sin(heading))
            y -= r * (math.cos(heading + angular) - math.cos(heading))
        heading += angular
        out[k] = (x, y, heading)
    return out


def write_session_bag(
    path: Path,
    fmt: str,
    session: Session,
    *,
    wheels: str = "odom",
    drop: Sequence[tuple[float, float]] = (),
) -> Path:
    """Write ``session`` as a bag: the wheels as ``/odom`` (``nav_msgs/Odometry`` from
    :func:`controller_odometry` with :data:`TB3`) or ``/joint_states``, the truth as
    ``/ground_truth`` (``nav_msgs/Odometry``), both at :data:`EVERY` th simulator period;
    no wheel message inside the time ranges ``drop`` [s]."""
    from test_bag import JS, LEFT, ODOM, RIGHT, joint_state, ns, pose_msg, write_bag
    from test_bag import split as stamp

    keep = np.arange(0, session.time.size, EVERY)
    odom = controller_odometry(session.angles, TB3) if wheels == "odom" else None
    messages = []
    for k in keep:
        t = float(session.time[k])
        sec, nsec = stamp(t)
        if not any(a <= t <= b for a, b in drop):
            if odom is not None:
                msg = pose_msg(fmt, ODOM, sec, nsec, *odom[k])
                messages.append(("/odom", ns(t), msg))
            else:
                a_l, a_r = session.angles[k]
                msg = joint_state(fmt, sec, nsec, [LEFT, RIGHT], [a_l, a_r])
                messages.append(("/joint_states", ns(t), msg))
        truth = pose_msg(fmt, ODOM, sec, nsec, *session.truth[k])
        messages.append(("/ground_truth", ns(t + 0.001), truth))
    topic = "/odom" if wheels == "odom" else "/joint_states"
    typ = ODOM if wheels == "odom" else JS
    topics = {topic: typ, "/ground_truth": ODOM}
    return write_bag(path.parent, fmt, topics, messages, name=path.name)

"""The IMU of the simulated robot nodes (tests/ros1_robot_node.py, tests/ros2_robot_node.py):
their options, as a robot's driver is set up, and the virtual robot's IMU they make."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from umbmark.robot.base import Robot
from umbmark.sim.imu import ImuSetup


def imu_arguments(parser: argparse.ArgumentParser) -> None:
    """The IMU's options (and ``--no-laser``): simulate --imu's defaults, at 100 Hz (as a
    Kobuki's or a Create's), mounted rolled 1 deg."""
    parser.add_argument("--no-imu", action="store_true", help="publish no IMU")
    parser.add_argument("--imu-rate", type=float, default=100.0, help="readings a second")
    parser.add_argument("--gyro-scale", type=float, default=1.02, help="k_g")
    parser.add_argument("--gyro-bias", type=float, default=0.3, help="deg/s at the start")
    parser.add_argument("--gyro-bias-walk", type=float, default=2e-4, help="deg/s/sqrt(s)")
    parser.add_argument("--imu-roll", type=float, default=1.0, help="its mounting's roll [deg]")
    parser.add_argument("--imu-truth", default=None, help="write the IMU's truth here (JSON)")
    parser.add_argument("--no-laser", action="store_true", help="the robot has no laser")
    parser.add_argument(
        "--imu-frame",
        default="imu_link",
        help="the messages' frame (another than imu_link: none is mounted)",
    )


class ImuFault:
    """What the node publishes of its IMU's readings: all of them, until told on
    ``/sim/control`` (tests/ros1_robot_node.py): ``mute_imu``, none (a driver that died);
    ``freeze_imu``, the rates of its next reading in every later one, the stamps going on
    (a driver that lost its sensor); ``mend_imu``, all of them again."""

    def __init__(self) -> None:
        self.mode: str | None = None
        self.held: list[float] | None = None

    def control(self, command: str) -> None:
        """A ``/sim/control`` message (others are not the IMU's)."""
        if command in ("mute_imu", "freeze_imu", "mend_imu"):
            self.mode = None if command == "mend_imu" else command
            self.held = None

    def rows(self, time: list[float], rate: list[list[float]], accel: list[list[float]]
             ) -> list[tuple[float, list[float], list[float]]]:  # fmt: skip
        """The readings to publish, each (stamp, rates, accelerations)."""
        if self.mode == "mute_imu":
            return []
        if self.mode == "freeze_imu" and time:
            self.held = self.held or rate[0]
            rate = [self.held] * len(time)
        return list(zip(time, rate, accel, strict=True))


def imu_setup(args: argparse.Namespace) -> ImuSetup | None:
    """The IMU the node's options ask for (None: ``--no-imu``)."""
    if args.no_imu:
        return None
    return ImuSetup.of_options({
        "imu_rate": args.imu_rate, "gyro_scale": args.gyro_scale, "gyro_bias": args.gyro_bias,
        "gyro_bias_walk": args.gyro_bias_walk, "imu_roll": args.imu_roll,
    })  # fmt: skip


def imu_probe(robot: Robot, heading: Callable[[], float]) -> dict[str, object]:
    """What a ROS adapter's IMU gives (for tests/ros1_probe.py and tests/ros2_probe.py):
    the topic found, its frame's mounting, the readings over a rest, a turn on the spot
    (0.6 rad/s for 4 s) and a rest: their rate, the mean yaw rate at rest, the yaw rate's
    integral over it all, and the true turn (``heading``: the node's true heading)."""
    import numpy as np

    from umbmark.core.conventions import wrap_angle

    imu = robot.imu()
    if imu is None:
        return {"imu": None}

    def hold(linear: float, angular: float, seconds: float) -> None:
        end = robot.now() + seconds
        while robot.now() < end:
            robot.send_velocity(linear, angular)
            robot.wait(0.02)

    hold(0.0, 0.0, 1.0)
    start = robot.now()
    before = heading()
    hold(0.0, 0.0, 3.0)
    rested = robot.now()
    hold(0.0, 0.6, 4.0)
    hold(0.0, 0.0, 3.0)
    end = robot.now()
    after = heading()
    gyro = robot.gyro(start - 0.5)
    assert gyro is not None
    assert before is not None
    assert after is not None
    rest = (gyro.time > start + 0.5) & (gyro.time < rested - 0.2)
    inside = gyro.time[(gyro.time >= start) & (gyro.time <= end)]
    span = np.array([inside[0]]), np.array([inside[-1]])
    return {
        "imu": {
            "topic": imu.topic,
            "chosen": imu.chosen,
            "frame": imu.mounting.frame,
            "base": imu.mounting.base,
            "source": imu.mounting.source,
            "rotation": imu.mounting.rotation.tolist(),
        },
        "readings": len(gyro),
        "period": float(np.median(np.diff(gyro.time))),
        "rest_yaw_rate": float(np.mean(gyro.rate[rest, 2])),
        "rest_readings": int(rest.sum()),
        "integral": float(gyro.yaw_change(*span)[0]),
        "span": float(inside[-1] - inside[0]),
        "true_turn": float(wrap_angle(after - before)),
        "accel_z": None if gyro.accel is None else float(np.mean(gyro.accel[rest, 2])),
    }

"""Drives the simulated robot nodes (tests/ros1_robot_node.py, tests/ros2_robot_node.py,
``--world warehouse``) on ordinary warehouse missions, as a robot's navigation stack would:
a separate process publishing velocity commands, never a square.

``python tests/mission_driver.py --ros1|--ros2 [--seconds S] [--seed N] ...``

- The missions are :func:`umbmark.sim.missions.mission`'s on the aisles of
  :class:`umbmark.sim.missions.Warehouse` (corridors, quarter turns at crossings, a stop at
  a shelf, now and then a whole turn), one after the other from the crossing the last one
  ended at, the first from the node's start (crossing (0, 0), heading +x), with a rest of
  ``--rest`` seconds between them.
- Where the robot is: its odometry (ROS 1 ``/odom``; ROS 2 ``/diff_drive_controller/odom``)
  carried into the map by a localisation, the map -> odom offset taken from each true pose
  the node publishes (ROS 1 ``/sim/true_pose``, ROS 2 ``/ground_truth``, at its laser's
  rate), as AMCL's would: the robot stays on its aisles whatever its odometry's errors,
  while the odometry the monitor watches is the robot's own.
- The follower (:class:`Follower`, no ROS): turn on the spot to the next heading, then
  pure pursuit along the aisle (a point ``LOOKAHEAD`` ahead on the line), braking to stop
  at the segment's end; commands at 20 Hz of simulated time, stamped with it (ROS 1
  ``/cmd_vel`` Twist; ROS 2 ``/diff_drive_controller/cmd_vel`` TwistStamped), on the
  node's ``/clock``.
- Prints ``ready`` once the odometry and a true pose came; on SIGINT or SIGTERM (or after
  ``--seconds`` of simulated time) stops the robot and prints ``final {json}``: the
  segments done, the missions started, the true path (x, y every 0.5 s of simulated time,
  for a check of its clearance from the world's walls), how often the clock went back.
- The clock going back (a simulation reset) starts the missions again from the start.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import threading
import time
from dataclasses import dataclass

import numpy as np

from umbmark.robot.base import Pose2D
from umbmark.sim.missions import Warehouse, mission

#: How often a command is sent [s of simulated time] (Nav2's controller runs at 20 Hz).
COMMAND_PERIOD = 0.05
#: The pure pursuit's look-ahead [m] and the braking deceleration [m/s^2].
LOOKAHEAD, BRAKING = 0.6, 0.6
#: A turn is done within this [rad]; a straight this short of its end [m].
TURN_DONE, STRAIGHT_DONE = 0.01, 0.01
#: The slowest speeds the follower asks [m/s, rad/s] (a base does not creep slower).
CREEP, CREEP_TURN = 0.05, 0.06


@dataclass(frozen=True)
class Goal:
    """One segment in the map: a turn on the spot to ``heading`` (unwrapped [rad]), or a
    straight from ``start`` to ``end`` [m] along it."""

    kind: str
    heading: float
    start: tuple[float, float] = (0.0, 0.0)
    end: tuple[float, float] = (0.0, 0.0)


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class Follower:
    """The missions as goals in the map, and the velocity each pose asks for.

    Parameters
    ----------
    warehouse : Warehouse
    seed : int
        Seeds the missions.
    speed, turn_rate : float
        Cruise speed [m/s] and turn rate [rad/s].
    mission_seconds : float
        Each mission's length (:func:`mission`'s ``seconds``).
    rest : float
        The rest between missions [s].
    """

    def __init__(
        self, warehouse: Warehouse, seed: int, speed: float = 0.7, turn_rate: float = 0.8,
        mission_seconds: float = 60.0, rest: float = 2.0,
    ) -> None:  # fmt: skip
        self.warehouse, self.speed, self.turn_rate = warehouse, speed, turn_rate
        self.mission_seconds, self.rest = mission_seconds, rest
        self.rng = np.random.default_rng(seed)
        x, y, h = warehouse.start(0)
        self.plan = (x, y, h)  # where the last goal ends: a crossing, the heading unwrapped
        self.goals: list[Goal] = []
        self.done = 0
        self.missions = 0
        self.resting_until = -math.inf
        self._yaw: float | None = None  # the robot's heading, unwrapped
        self._next_mission(0.0)

    def _next_mission(self, now: float) -> None:
        x, y, h = self.plan
        xs, ys = self.warehouse.aisles_x, self.warehouse.aisles_y
        x, y = min(xs, key=lambda a: abs(a - x)), min(ys, key=lambda a: abs(a - y))
        quarter = round(h / (0.5 * math.pi))
        start = (x, y, _wrap(quarter * 0.5 * math.pi))
        path = mission(self.warehouse, start, self.rng, self.mission_seconds, self.speed)
        h = quarter * 0.5 * math.pi  # unwrapped, as the robot's yaw
        for seg in path.segments:
            if seg.kind == "turn":
                h += seg.amount
                self.goals.append(Goal("turn", h))
            else:
                end = (x + seg.amount * math.cos(h), y + seg.amount * math.sin(h))
                self.goals.append(Goal("straight", h, (x, y), end))
                x, y = end
        self.plan = (x, y, h)
        self.missions += 1
        self.resting_until = now + self.rest

    def command(self, pose: Pose2D, now: float) -> tuple[float, float]:
        """The velocity [m/s, rad/s] at the map pose ``pose`` at ``now`` [s]."""
        if self._yaw is None:
            self._yaw = pose.theta
        self._yaw += _wrap(pose.theta - _wrap(self._yaw))
        while True:
            if now < self.resting_until:
                return 0.0, 0.0
            if not self.goals:
                self._next_mission(now)
                continue
            goal = self.goals[0]
            asked = self._turn(goal) if goal.kind == "turn" else self._straight(goal, pose)
            if asked is not None:
                return asked
            self.goals.pop(0)
            self.done += 1

    def _turn(self, goal: Goal) -> tuple[float, float] | None:
        assert self._yaw is not None
        err = goal.heading - self._yaw
        if abs(err) < TURN_DONE:
            return None
        rate = max(CREEP_TURN, min(self.turn_rate, 2.0 * abs(err)))
        return 0.0, math.copysign(rate, err)

    def _straight(self, goal: Goal, pose: Pose2D) -> tuple[float, float] | None:
        (ax, ay), (bx, by) = goal.start, goal.end
        length = math.hypot(bx - ax, by - ay)
        ux, uy = (bx - ax) / length, (by - ay) / length
        along = (pose.x - ax) * ux + (pose.y - ay) * uy
        remaining = length - along
        if remaining < STRAIGHT_DONE:
            return None
        ahead = min(along + LOOKAHEAD, length + 0.05)
        tx, ty = ax + ahead * ux, ay + ahead * uy
        err = _wrap(math.atan2(ty - pose.y, tx - pose.x) - pose.theta)
        angular = max(-self.turn_rate, min(self.turn_rate, 2.5 * err))
        if abs(err) > 0.5:  # far off the line's heading: turn first
            return 0.0, angular
        linear = max(CREEP, min(self.speed, math.sqrt(2.0 * BRAKING * remaining)))
        return linear * math.cos(err), angular


class Localised:
    """The robot's pose in the map: its odometry carried by the map -> odom offset of the
    latest true pose (as a localisation gives it)."""

    def __init__(self) -> None:
        self.odom: Pose2D | None = None
        self.offset: Pose2D | None = None
        self.truth: Pose2D | None = None

    def odometry(self, pose: Pose2D) -> None:
        self.odom = pose

    def true_pose(self, pose: Pose2D) -> None:
        self.truth = pose
        if self.odom is not None:
            self.offset = pose.compose(self.odom.inverse())

    def pose(self) -> Pose2D | None:
        if self.odom is None or self.offset is None:
            return None
        return self.offset.compose(self.odom)


def _yaw(q: object) -> float:
    x, y, z, w = (float(getattr(q, k)) for k in "xyzw")
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class Driver:
    """What both ROS sides share: the follower fed, the commands paced, the path kept.
    The clock going back (a simulation reset: the robot back at its start) starts the
    missions again from the start, as a navigation stack started again would; the
    simulated time driven before counts towards ``--seconds``."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.follower = self._follower()
        self.where = Localised()
        self.lock = threading.Lock()
        self.last_sent = -math.inf
        self.first: float | None = None
        self.latest = -math.inf
        self.before = 0.0  # the simulated time driven before the clock last went back [s]
        self.resets = 0
        self.done_before = self.missions_before = 0  # the follower's before that
        self.seconds = args.seconds
        self.path: list[list[float]] = []
        self.last_kept = -math.inf
        self.ready = threading.Event()
        self.stop = threading.Event()

    def _follower(self) -> Follower:
        a = self.args
        return Follower(Warehouse(), a.seed, a.speed, a.turn_rate, a.mission_seconds, a.rest)

    def _clock_back(self, stamp: float) -> None:
        """A simulation reset: the missions again from the start, the localisation anew."""
        if self.first is not None:
            self.before += self.latest - self.first
        self.done_before += self.follower.done
        self.missions_before += self.follower.missions
        self.follower, self.where = self._follower(), Localised()
        self.first, self.last_sent, self.last_kept = stamp, -math.inf, -math.inf
        self.resets += 1

    def on_odometry(self, stamp: float, pose: Pose2D) -> tuple[float, float] | None:
        """The command to send now, if one is due."""
        with self.lock:
            if stamp < self.latest - 1.0:
                self._clock_back(stamp)
            self.latest = stamp
            self.where.odometry(pose)
            here = self.where.pose()
            if here is None:
                return None
            if self.first is None:
                self.first = stamp
                self.ready.set()
            if self.seconds is not None and self.before + stamp - self.first > self.seconds:
                self.stop.set()
                return None
            if stamp - self.last_sent < COMMAND_PERIOD - 1e-6:
                return None
            self.last_sent = stamp
            return self.follower.command(here, stamp - self.first)

    def on_truth(self, stamp: float, pose: Pose2D) -> None:
        with self.lock:
            self.where.true_pose(pose)
            if stamp - self.last_kept >= 0.5:
                self.last_kept = stamp
                self.path.append([round(pose.x, 4), round(pose.y, 4)])

    def final(self) -> str:
        with self.lock:
            f = self.follower
            return "final " + json.dumps(
                {
                    "segments": self.done_before + f.done,
                    "path": self.path,
                    "missions": self.missions_before + f.missions,
                    "resets": self.resets,
                }
            )


def _signals(stop: threading.Event) -> None:
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())


def run_ros1(args: argparse.Namespace) -> None:
    import rospy
    from geometry_msgs.msg import Pose2D as Pose2DMsg
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry

    driver = Driver(args)
    _signals(driver.stop)
    rospy.init_node("mission_driver", disable_signals=True)
    cmd = rospy.Publisher("/cmd_vel", Twist, queue_size=10, tcp_nodelay=True)
    latest = [0.0]

    def on_odom(msg: Odometry) -> None:
        stamp = msg.header.stamp.to_sec()
        latest[0] = stamp
        p = msg.pose.pose
        asked = driver.on_odometry(stamp, Pose2D(p.position.x, p.position.y, _yaw(p.orientation)))
        if asked is not None:
            twist = Twist()
            twist.linear.x, twist.angular.z = asked
            cmd.publish(twist)

    def on_truth(msg: Pose2DMsg) -> None:
        driver.on_truth(latest[0], Pose2D(msg.x, msg.y, msg.theta))

    rospy.Subscriber("/sim/true_pose", Pose2DMsg, on_truth, queue_size=10)
    rospy.Subscriber("/odom", Odometry, on_odom, queue_size=10, tcp_nodelay=True)
    _wait(driver)
    for _ in range(3):
        cmd.publish(Twist())
        time.sleep(0.05)
    print(driver.final(), flush=True)
    rospy.signal_shutdown("done")


def run_ros2(args: argparse.Namespace) -> None:
    import rclpy
    from geometry_msgs.msg import PoseStamped, TwistStamped
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    driver = Driver(args)
    _signals(driver.stop)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("mission_driver")
    controller = args.controller.rstrip("/")
    cmd = node.create_publisher(TwistStamped, f"{controller}/cmd_vel", 10)

    def send(stamp: object, linear: float, angular: float) -> None:
        msg = TwistStamped()
        msg.header.stamp = stamp
        msg.header.frame_id = "base_link"
        msg.twist.linear.x, msg.twist.angular.z = linear, angular
        cmd.publish(msg)

    latest: list[object] = [None]

    def on_odom(msg: Odometry) -> None:
        s = msg.header.stamp
        latest[0] = s
        p = msg.pose.pose
        pose = Pose2D(p.position.x, p.position.y, _yaw(p.orientation))
        asked = driver.on_odometry(s.sec + 1e-9 * s.nanosec, pose)
        if asked is not None:
            send(s, *asked)

    def on_truth(msg: PoseStamped) -> None:
        s, p = msg.header.stamp, msg.pose
        pose = Pose2D(p.position.x, p.position.y, _yaw(p.orientation))
        driver.on_truth(s.sec + 1e-9 * s.nanosec, pose)

    node.create_subscription(PoseStamped, "/ground_truth", on_truth, 10)
    node.create_subscription(Odometry, f"{controller}/odom", on_odom, 10)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spin = threading.Thread(target=_spin, args=(executor, driver.stop), daemon=True)
    spin.start()
    try:
        _wait(driver)
    finally:
        driver.stop.set()
        spin.join(2.0)
        if latest[0] is not None:
            send(latest[0], 0.0, 0.0)
        print(driver.final(), flush=True)
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown()


def _spin(executor: object, stop: threading.Event) -> None:
    while not stop.is_set():
        executor.spin_once(timeout_sec=0.05)  # type: ignore[attr-defined]


def _wait(driver: Driver) -> None:
    said = False
    while not driver.stop.is_set():
        if not said and driver.ready.is_set():
            print("ready", flush=True)
            said = True
        driver.stop.wait(0.05)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    side = parser.add_mutually_exclusive_group(required=True)
    side.add_argument("--ros1", action="store_true")
    side.add_argument("--ros2", action="store_true")
    parser.add_argument("--seed", type=int, default=1, help="seeds the missions")
    parser.add_argument("--seconds", type=float, default=None, help="simulated time to drive")
    parser.add_argument("--speed", type=float, default=0.7, help="cruise speed [m/s]")
    parser.add_argument("--turn-rate", type=float, default=0.8, help="turn rate [rad/s]")
    parser.add_argument("--mission-seconds", type=float, default=60.0)
    parser.add_argument("--rest", type=float, default=2.0, help="between missions [s]")
    parser.add_argument("--controller", default="/diff_drive_controller", help="ROS 2")
    args = parser.parse_args()
    run_ros1(args) if args.ros1 else run_ros2(args)


if __name__ == "__main__":
    sys.exit(main())

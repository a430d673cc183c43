"""The faults tests/ros2_robot_node.py makes on ``/sim/control``, as the real thing makes
them (for tests/test_monitor_ros2_faults.py), and what it keeps of them for its ``final``:

- ``reset_clock``: the simulation reset as Gazebo's ``/reset_simulation`` does it
  (:meth:`umbmark.robot.virtual.VirtualRobot.reset_simulation`): ``/clock`` back to the
  start (``T0``), the robot at its start and at rest, its wheels' joints back to 0 (the
  joint states say so), the laser and the IMU going on. gazebo_ros2_control's ``Reset()``
  only sets its last update time to 0, so the controller goes on updating, not told:
  ros2_controllers' master (``--distro rolling``: ``update_from_pos`` on the period) moves
  its odometry by the wheels' jump back to 0 and goes on publishing; Humble to Kilted
  (``Odometry::update`` returns while ``time - timestamp_ < 0.0001``, and
  ``previous_publish_timestamp_ + publish_period_ < time`` is false) publish no odometry
  until the clock has passed the time it was reset from (husky/husky#281 says the same of
  ROS 1's). The last velocity command stands (its age is negative) until the next comes.
- ``restart_controller``: the controller restarted as the controller manager restarts it
  (``ros2 control set_controller_state ... inactive``, then ``active`` after a configure,
  as a reload does): deactivated (``on_deactivate``: ``halt()``, no update, no odometry)
  for :data:`RESTART_GAP` of simulated time, cleaned up and configured (``reset()`` sets
  the odometry's pose to zero; ``on_configure`` reads the parameters), activated (the
  command cleared). Its odometry starts again from zero: ``final``'s ``restarts`` says
  where it was before and where it started.
- Every ``set_parameters`` on the controller's node, with the simulated time and how fast
  the robot truly moved then (``final``'s ``parameter_sets``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ros2_robot_node import SimNode

#: How long the controller stands deactivated in a restart [s of simulated time]: the
#: controller manager's service calls (switch, configure, switch) at a few update cycles.
RESTART_GAP = 0.2
#: The controls of /sim/control this module takes.
CONTROLS = ("reset_clock", "restart_controller")


class Faults:
    """The node's faults (module notes); call :meth:`step` after each simulated period
    under the node's lock."""

    def __init__(self, sim: SimNode) -> None:
        self.sim = sim
        self.resets: list[dict[str, Any]] = []
        self.restarts: list[dict[str, Any]] = []
        self.parameter_sets: list[dict[str, Any]] = []
        self._frozen_until = -math.inf  # Humble to Kilted: no odometry until this sim time
        self._timer: Any = None  # the restart's second half, in the executor's thread
        self._speed = (0.0, 0.0)
        self._last: tuple[float, float, float] | None = None

    def control(self, command: str) -> None:
        """A ``/sim/control`` message (others are not these), in the executor's thread
        under the node's lock: made at once."""
        if command == "reset_clock":
            self._reset()
        elif command == "restart_controller":
            self._deactivate()

    def watch(self, node: Any) -> None:
        """Keep every set_parameters on the controller's ``node``."""
        from rcl_interfaces.msg import SetParametersResult

        def on_set(parameters: list[Any]) -> Any:
            robot = self.sim.robot
            self.parameter_sets.append({
                "time": robot.now(), "values": {p.name: p.value for p in parameters},
                "linear": self._speed[0], "angular": self._speed[1],
            })  # fmt: skip
            return SetParametersResult(successful=True)

        node.add_on_set_parameters_callback(on_set)

    def odometry_silent(self) -> bool:
        """Whether the controller publishes no odometry now (after a reset, Humble to
        Kilted)."""
        return self.sim.robot.now() <= self._frozen_until

    def step(self) -> None:
        """After a period: the robot's true speed kept."""
        robot = self.sim.robot
        pose = robot.true_pose
        if self._last is not None:
            dt = robot.period
            self._speed = (
                math.hypot(pose.x - self._last[0], pose.y - self._last[1]) / dt,
                abs(math.remainder(pose.theta - self._last[2], math.tau)) / dt,
            )
        self._last = (pose.x, pose.y, pose.theta)

    def _reset(self) -> None:
        sim, robot = self.sim, self.sim.robot
        was = robot.now()
        odometry = robot.odometry()
        robot.reset_simulation()
        sim.imu_since = -1.0
        self._last = None
        if sim.args.distro != "rolling":
            self._frozen_until = odometry.time
        self.resets.append({"from": was, "odometry": list(_pose(odometry.pose))})
        print(f"event reset_clock at {was:.2f} s", flush=True)

    def _deactivate(self) -> None:
        controller = self.sim.controller
        if controller is None or controller.state != "active" or self._timer is not None:
            return
        controller.state = "inactive"  # on_deactivate: halt(); no update, no odometry
        robot = self.sim.robot
        self.restarts.append({"time": robot.now(), "before": list(_pose(robot.odometry().pose))})
        self._timer = self.sim.node.create_timer(RESTART_GAP / self.sim.rate, self._due)
        print(f"event restart_controller at {robot.now():.2f} s", flush=True)

    def _due(self) -> None:
        """The timer (the executor's thread): the restart's second half."""
        with self.sim.lock:
            if self._timer is None:
                return
            self.sim.node.destroy_timer(self._timer)
            self._timer = None
            self._activate()

    def _activate(self) -> None:
        sim, controller = self.sim, self.sim.controller
        if controller is None:
            return
        controller.reset()  # the manager cleans an inactive controller up first
        controller.state = "unconfigured"
        if not sim._configure():  # on_configure: reset() sets the odometry's pose to zero
            return
        controller.command, controller.command_time = (0.0, 0.0), -math.inf
        controller.state = "active"
        self.restarts[-1]["after"] = list(_pose(sim.robot.odometry().pose))

    def final(self) -> dict[str, Any]:
        """What the node prints of them at its end."""
        return {
            "resets": self.resets, "controller_restarts": self.restarts,
            "parameter_sets": self.parameter_sets,
        }  # fmt: skip


def _pose(pose: Any) -> tuple[float, float, float]:
    return (float(pose.x), float(pose.y), float(pose.theta))

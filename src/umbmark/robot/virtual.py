"""The virtual robot: a differential-drive robot with known errors behind the
:class:`~umbmark.robot.base.Robot` interface, simulated as fast as the computer allows.

Each control period (``period``, 20 ms by default: a 50 Hz ``diff_drive_controller``):

1. the commanded body velocity becomes wheel speeds through the controller's *current*
   parameters (``wheel_separation * wheel_separation_multiplier``, ``wheel_radius *
   {left,right}_wheel_radius_multiplier``), as diff_drive_controller's inverse kinematics;
   a command older than ``command_timeout`` is a stop (its ``cmd_vel_timeout``);
2. the true wheels (diameters ``D_L``, ``D_R`` from ``E_d`` and ``E_s``, wheelbase
   ``E_b b``: :meth:`umbmark.sim.robot.SimRobot.with_errors`, the batch simulator's
   definitions) roll that far over the floor, less the slip of the simulator's noise model
   (Gaussian, standard deviation ``slip * sqrt(travel)``), and move the robot along the
   arc they describe;
3. the encoders count whole pulses;
4. the odometry is updated exactly as ros_controllers' ``diff_drive_controller::Odometry``
   does: the wheel positions times the current radii, differenced with the previous ones
   *as stored in metres*, integrated as an exact arc. Changing a radius multiplier
   therefore makes the next update jump by ``angle * (r_new - r_old)`` (the real
   controller's behaviour): apply parameters while the robot stands and take the next
   run's start from the odometry after that.

The sensors (a planar laser, range sensors, motion capture) see a world of walls and
clutter (:mod:`umbmark.robot.world`) from the true pose. Where given an IMU
(:class:`umbmark.sim.imu.ImuSetup`: the simulator's MEMS model, its scale error, bias and
walk, noise, full scale, mounting and rate), it reads the true motion of every period
(:class:`umbmark.sim.imu.ImuStream`, its own random numbers: the rest of the simulation
is the same with or without it), and states its mounting as it is.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from umbmark.core.arrays import FloatArray
from umbmark.core.errors import InputError
from umbmark.model.kinematics import WheelParams
from umbmark.robot.base import (
    IMU_HELD,
    ApplyMethod,
    ApplyResult,
    DriveParams,
    ImuSource,
    Pose2D,
    RangeReading,
    ScanSweep,
    StampedPose,
)
from umbmark.sim.robot import NoiseModel
from umbmark.sim.robot import SimRobot as RobotTruth

if TYPE_CHECKING:
    from umbmark.model.gyro_series import GyroSeries
    from umbmark.robot.world import World
    from umbmark.sim.imu import ImuReadings, ImuSetup, ImuStream

__all__ = ["ERROR_RANGE", "MAX_SLIP", "VirtualRobot"]

#: The systematic errors a virtual robot may have (E_d, E_b, E_s).
ERROR_RANGE = (0.5, 2.0)
#: The largest wheel slip of a virtual robot [m^0.5].
MAX_SLIP = 0.01

#: The longest stretch of robot time one :meth:`VirtualRobot.wait` may simulate [s].
LONGEST_WAIT = 3600.0
#: The virtual robot's IMU: its topic and frame, as a robot's driver names them.
IMU_TOPIC, IMU_FRAME = "/imu", "imu_link"
#: The IMU's readings are made at least every this many control periods.
_IMU_BATCH = 250


class VirtualRobot:
    """A simulated differential-drive robot with systematic errors ``E_d``, ``E_b``, ``E_s``.

    Parameters
    ----------
    E_d, E_b, E_s : float
        The robot's true ``D_R / D_L``, wheelbase over the nominal one, and mean wheel
        diameter over the nominal one (Sec. 2.2).
    wheelbase, wheel_diameter : float
        The nominal wheelbase and wheel diameter [m]: what its controller is configured with
        (``wheel_separation``, ``2 * wheel_radius``).
    slip : float
        Wheel slip [m^(1/2)] (:class:`umbmark.sim.robot.NoiseModel`).
    seed : int, optional
        Seeds the slip and the sensors' noise.
    encoder_resolution, gear_ratio : float
        Encoder pulses per motor revolution, motor revolutions per wheel revolution.
    period : float
        The controller's period [s].
    world : World, optional
        What the sensors see (default: :func:`umbmark.robot.world.corner_world`, an
        L-shaped corner behind the start with some clutter).
    params : DriveParams, optional
        The controller's parameters at the start (default: nominal, multipliers 1).
    command_timeout : float
        A velocity command older than this [s] stops the wheels.
    laser_pose : (float, float, float), optional
        The laser's true mounting ``x, y, yaw`` [m, m, rad] in the base frame: the scans
        are cast from there (default: the world's laser as it is; a world without one gets
        the standard laser, :data:`umbmark.robot.world.DEFAULT_LIDAR`). The scans report
        this mounting, as TF would, unless ``stated_laser_pose`` says otherwise.
    stated_laser_pose : (float, float, float), optional
        The mounting ``x, y, yaw`` [m, m, rad] the robot states (its TF, its URDF) where
        it differs from the true one: the scans report it, the beams are cast from the
        true one (a robot whose description is off).
    stated_laser_lift : (float, float, float), optional
        The height and tilt ``z, roll, pitch`` [m, rad, rad] the robot states with the
        mounting (None: only the planar mounting). The planar world ignores them.
    acceleration, turn_acceleration : float
        How fast the base changes its speed [m/s^2] and turn rate [rad/s^2] at most, as a
        real base's motor controller does: a zero velocity brakes at this deceleration,
        it is not obeyed at once (default: a stiff base, 5 m/s^2 being the largest
        ``--acceleration``; give the acceleration limit to brake as the obstacle stop's
        formula assumes).
    imu : ImuSetup, optional
        The robot's IMU (None: it has none): :meth:`gyro` gives its readings.
    """

    name = "virtual robot"

    def __init__(
        self,
        E_d: float = 1.0,
        E_b: float = 1.0,
        E_s: float = 1.0,
        wheelbase: float = 0.34,
        wheel_diameter: float = 0.15,
        slip: float = 0.0,
        seed: int | None = None,
        *,
        encoder_resolution: float = 2000.0,
        gear_ratio: float = 20.0,
        period: float = 0.02,
        world: World | None = None,
        params: DriveParams | None = None,
        command_timeout: float = 0.5,
        laser_pose: tuple[float, float, float] | None = None,
        stated_laser_pose: tuple[float, float, float] | None = None,
        stated_laser_lift: tuple[float, float, float] | None = None,
        acceleration: float = 5.0,
        turn_acceleration: float = 20.0,
        imu: ImuSetup | None = None,
    ) -> None:
        _check_arguments(E_d, E_b, E_s, wheelbase, wheel_diameter, slip, command_timeout)
        nominal = WheelParams(
            wheelbase=wheelbase,
            wheel_diameter=wheel_diameter,
            encoder_resolution=encoder_resolution,
            gear_ratio=gear_ratio,
        )
        #: The robot's truth (its diameters, wheelbase and slip).
        self.truth = RobotTruth.with_errors(nominal, E_d, E_b, E_s, NoiseModel(slip=slip))
        if not (period > 0.0 and math.isfinite(period)):
            raise InputError(f"period must be a positive time, got {period!r} s")
        self.period = float(period)
        self.command_timeout = float(command_timeout)
        if not (acceleration > 0.0 and turn_acceleration > 0.0):
            raise InputError(
                f"acceleration {acceleration!r} m/s^2 and turn acceleration "
                f"{turn_acceleration!r} rad/s^2 must be positive"
            )
        self.acceleration = float(acceleration)
        self.turn_acceleration = float(turn_acceleration)
        self._velocity = (0.0, 0.0)  # the base's true linear, angular velocity
        if world is None:
            from umbmark.robot.world import corner_world

            world = corner_world()
        if laser_pose is not None:
            world = _with_laser(world, laser_pose)
        self.world = world
        stated = stated_laser_pose
        self._stated = None if stated is None else _laser_pose(stated, "stated_laser_pose")
        self._lift = None if stated_laser_lift is None else _lift(stated_laser_lift)
        self._rng = np.random.default_rng(seed)
        self._params = params or DriveParams(wheelbase, 0.5 * wheel_diameter)
        self._pulses = gear_ratio * encoder_resolution  # per wheel revolution
        self._time = 0.0
        self._pose = world.start  # true pose in the world
        self._angle = [0.0, 0.0]  # true wheel rotation [rad]
        self._counts = [0, 0]
        self._command = (0.0, 0.0, -math.inf)  # linear, angular, time sent
        self._odom = [0.0, 0.0, 0.0]
        self._old = [0.0, 0.0]  # the controller's previous wheel positions [m]
        self._odom_time = 0.0
        #: Every velocity command sent, with its time: ``(t, linear, angular)``.
        self.commands: list[tuple[float, float, float]] = []
        self._travel = 0.0  # the distance driven forward [m]
        self._seed = seed
        self._imu = None if imu is None else _imu_stream(imu, seed, self._pose.theta)
        self._held: deque[ImuReadings] = deque()

    # --- the Robot interface ------------------------------------------------------------

    def now(self) -> float:
        """The robot's clock [s]."""
        return self._time

    def wait(self, duration: float) -> None:
        """Simulate ``duration`` seconds, one controller period after the other."""
        if not (0.0 <= duration <= LONGEST_WAIT):
            raise InputError(f"wait {duration!r} s: give 0 to {LONGEST_WAIT:g} s")
        steps = round(duration / self.period)
        for _ in range(steps):
            self._step()

    def send_velocity(self, linear: float, angular: float) -> None:
        """Command a body velocity [m/s, rad/s] (held until the next, or the timeout)."""
        if not (math.isfinite(linear) and math.isfinite(angular)):
            raise InputError(f"velocity ({linear!r}, {angular!r}) is not finite")
        self._command = (float(linear), float(angular), self._time)
        self.commands.append((self._time, float(linear), float(angular)))

    def odometry(self) -> StampedPose:
        """The controller's odometry pose (frame ``odom``) at its last update."""
        return StampedPose(self._odom_time, Pose2D(*self._odom))

    def scan(self) -> ScanSweep | None:
        """A laser scan from the true pose, if the world has a laser on the robot, with
        the mounting the robot states (frames ``base_link`` and ``laser``)."""
        sweep = self.world.scan(self._pose, self._time, self._rng)
        if sweep is None:
            return None
        mount = sweep.mount if self._stated is None else self._stated
        return replace(sweep, mount=mount, lift=self._lift, frame="laser", base="base_link")

    def ranges(self) -> RangeReading | None:
        """The range sensors' readings from the true pose, if the robot has them."""
        return self.world.ranges(self._pose, self._time, self._rng)

    def ground_truth(self) -> StampedPose | None:
        """The true pose in the world's frame (as motion capture would give it)."""
        return self.world.truth(self._pose, self._time, self._rng)

    def imu(self) -> ImuSource | None:
        """The IMU (None: the robot has none), its mounting stated as it is."""
        if self._imu is None:
            return None
        from umbmark.sources.bag.imu_frames import ImuMounting

        mounting = ImuMounting(IMU_FRAME, "base_link", self._imu.setup.rotation, "as mounted")
        return ImuSource(IMU_TOPIC, mounting, "the virtual robot's IMU")

    def gyro(self, since: float) -> GyroSeries | None:
        """The IMU's readings after ``since`` (the last :data:`IMU_HELD` seconds), their
        rates in the base frame (None: no IMU)."""
        from umbmark.model.gyro_series import GyroSeries

        read = self.imu_readings(since)
        if read is None or self._imu is None:
            return None
        rotation = self._imu.setup.rotation
        return GyroSeries(
            time=read.time, rate=read.rate @ rotation.T, accel=read.accel @ rotation.T,
            frame=IMU_FRAME, source="the virtual robot's IMU",
        )  # fmt: skip

    def imu_readings(self, since: float) -> ImuReadings | None:
        """The IMU's readings after ``since`` as it gives them, in its own frame, with
        the true bias of each (for its publisher and for checks); None: no IMU."""
        if self._imu is None:
            return None
        from umbmark.sim.imu import ImuReadings

        self._pull()
        chunks = [c for c in self._held if c.time.size and c.time[-1] > since]
        if not chunks:
            return ImuReadings(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
        rows = np.concatenate([c.time for c in chunks]) > since

        def joined(name: str) -> FloatArray:
            return np.asarray(np.concatenate([getattr(c, name) for c in chunks])[rows])

        return ImuReadings(
            joined("time"), joined("rate"), joined("accel"), joined("bias"),
            clipped=sum(c.clipped for c in chunks),
        )  # fmt: skip

    def imu_truth(self) -> dict[str, object] | None:
        """The IMU's truth now, JSON-ready (None: no IMU): its scale ``k_g``, its bias
        [rad/s] on its own axes and about the base's z (``yaw_bias``, ``(R b)_z``), its
        walk, noise, rate, mounting (``rotation``, ``base <- imu``, and the quaternion
        ``x, y, z, w``), topic and frame."""
        if self._imu is None:
            return None
        s, bias = self._imu.setup, self._imu.bias
        return {
            "k_g": s.gyro_scale, "bias": bias.tolist(),
            "yaw_bias": float((s.rotation @ bias)[2]), "bias_walk": s.gyro_bias_walk,
            "noise_density": s.gyro_noise, "rate": s.imu_rate,
            "rotation": s.rotation.tolist(), "quaternion": list(s.quaternion),
            "topic": IMU_TOPIC, "frame": IMU_FRAME,
        }  # fmt: skip

    def _pull(self) -> None:
        """The readings the motion so far makes, held for :data:`IMU_HELD` seconds."""
        assert self._imu is not None
        read = self._imu.read()
        if read.time.size:
            self._held.append(read)
        while self._held and self._held[0].time[-1] < self._time - IMU_HELD:
            self._held.popleft()

    def wheel_angles(self) -> tuple[float, float, float]:
        """The wheels' encoder angles now: ``time`` [s], left, right [rad] (whole pulses;
        what a ``joint_states`` message of its controller would say)."""
        step = 2.0 * math.pi / self._pulses
        return self._time, self._counts[0] * step, self._counts[1] * step

    def drive_params(self) -> DriveParams:
        """The parameters the controller runs with now."""
        return self._params

    def apply(self, params: DriveParams, method: ApplyMethod) -> ApplyResult:
        """Run with ``params``: ``reconfigure`` changes them at once (as dynamic_reconfigure
        does, odometry jump included), ``yaml`` as a controller restarted on a new file
        (the odometry starts again at zero), ``none`` leaves them."""
        if method == "none":
            return ApplyResult("none", False, "parameters not applied (apply: none)")
        _check_multipliers(params)
        self._params = replace(params)
        if method == "yaml":
            self._odom = [0.0, 0.0, 0.0]
            self._old = self._wheel_positions()
            return ApplyResult("yaml", True, "controller restarted with the new parameters")
        return ApplyResult("reconfigure", True, "parameters reconfigured")

    def configure_controller(self, params: DriveParams, *, loaded: bool) -> None:
        """ros2_control's diff_drive_controller configured on ``params`` (its
        ``on_configure``: the new radii and separation, ``reset()`` sets the odometry's pose
        to zero). Its odometry keeps the wheel positions of its last update, in metres at
        the old radii (Humble to Kilted, position feedback): its first update then moves it
        by the wheels' whole rotation times the radius change. ``loaded``: a controller
        just loaded remembers zero, and its first update moves it by the wheels' whole
        travel (the hardware's positions are not reset with it)."""
        _check_multipliers(params)
        self._params = replace(params)
        self._odom = [0.0, 0.0, 0.0]
        if loaded:
            self._old = [0.0, 0.0]

    def reset_simulation(self) -> None:
        """The simulation reset as Gazebo's (``/reset_simulation``) does it: the clock back
        to 0, the robot at its start and at rest, its wheels' joints back to 0 (encoder
        counts 0), its IMU started again. The controller is a plugin the reset does not
        tell: its odometry keeps its pose and the wheel positions of its last update, so
        that its next update moves it by the wheels' jump (ros2_controllers' position
        feedback, ``update_from_pos``), and the last command stands."""
        self._time = 0.0
        self._pose = self.world.start
        self._velocity = (0.0, 0.0)
        self._angle = [0.0, 0.0]
        self._counts = [0, 0]
        self._odom_time = 0.0
        self._travel = 0.0
        if self._imu is not None:
            self._imu = _imu_stream(self._imu.setup, self._seed, self._pose.theta)
            self._held.clear()

    def close(self) -> None:
        """Stop: a zero velocity."""
        self.send_velocity(0.0, 0.0)

    # --- what is simulated --------------------------------------------------------------

    @property
    def true_pose(self) -> Pose2D:
        """The robot's true pose in the world [m, rad] (for checks against the truth)."""
        return self._pose

    def tape_marks(self) -> tuple[tuple[float, float], ...]:
        """Where a person measures from on this robot [m, base frame]: three marks at its
        back, where the paper's LabMate carried its sensors (x = -350 mm, y = +-250 mm);
        the first two to the wall behind, the third to the side wall (on the corner's
        side)."""
        marks = ((-0.35, 0.25), (-0.35, -0.25), (-0.35, -0.25))
        corner = self.world.corner
        if corner is not None and Pose2D(*corner.vertex, 0.0).relative_to(self.world.start).y > 0:
            return tuple((x, -y) for x, y in marks)  # the side wall on the left
        return marks

    def corner_truth(self) -> Pose2D | None:
        """The true pose in the corner frame (None: the world has no corner)."""
        corner = self.world.corner
        return None if corner is None else corner.in_corner(self._pose)

    def _wheel_positions(self) -> list[float]:
        """The controller's wheel positions [m]: encoder angles times the current radii."""
        p = self._params
        step = 2.0 * math.pi / self._pulses
        radius = p.wheel_radius
        return [
            self._counts[0] * step * radius * p.left_wheel_radius_multiplier,
            self._counts[1] * step * radius * p.right_wheel_radius_multiplier,
        ]

    def _step(self) -> None:
        dt = self.period
        linear, angular, sent = self._command
        if self._time - sent > self.command_timeout:
            linear = angular = 0.0
        was_linear, was_angular = self._velocity
        step, turn_step = self.acceleration * dt, self.turn_acceleration * dt
        linear = min(max(linear, was_linear - step), was_linear + step)
        angular = min(max(angular, was_angular - turn_step), was_angular + turn_step)
        self._velocity = (linear, angular)
        p = self._params
        separation = p.wheel_separation * p.wheel_separation_multiplier
        r_left = p.wheel_radius * p.left_wheel_radius_multiplier
        r_right = p.wheel_radius * p.right_wheel_radius_multiplier
        turn_left = (linear - 0.5 * angular * separation) / r_left * dt  # wheel rotation [rad]
        turn_right = (linear + 0.5 * angular * separation) / r_right * dt
        truth = self.truth
        travel_left = 0.5 * truth.diameter_left * turn_left
        travel_right = 0.5 * truth.diameter_right * turn_right
        slip = truth.noise.slip
        if slip > 0.0:
            noise = self._rng.standard_normal(2)
            travel_left += slip * math.sqrt(abs(travel_left)) * float(noise[0])
            travel_right += slip * math.sqrt(abs(travel_right)) * float(noise[1])
        x, y, theta = self._pose.x, self._pose.y, self._pose.theta
        x, y, theta = _arc(x, y, theta, travel_left, travel_right, truth.wheelbase)
        self._pose = Pose2D(x, y, theta)
        self._travel += 0.5 * (travel_left + travel_right)
        self._angle[0] += turn_left
        self._angle[1] += turn_right
        per_radian = self._pulses / (2.0 * math.pi)
        self._counts = [math.floor(a * per_radian) for a in self._angle]
        self._time += dt
        if self._imu is not None:
            self._imu.add(self._time, theta, self._travel)
            if self._imu.pending > _IMU_BATCH:
                self._pull()
        # diff_drive_controller::Odometry::update
        current = self._wheel_positions()
        moved_left, moved_right = current[0] - self._old[0], current[1] - self._old[1]
        self._old = current
        x, y, theta = self._odom
        self._odom = list(_arc(x, y, theta, moved_left, moved_right, separation))
        self._odom_time = self._time


def _imu_stream(setup: ImuSetup, seed: int | None, heading: float) -> ImuStream:
    """The IMU's reading of the motion from time 0, on random numbers of its own."""
    from umbmark.sim.imu import ImuStream

    rng = np.random.default_rng(None if seed is None else [seed, 3])
    stream = ImuStream(setup, rng, 0.0)
    stream.add(0.0, heading, 0.0)
    return stream


def _with_laser(world: World, pose: tuple[float, float, float]) -> World:
    """``world`` with its laser (the standard one where it has none) mounted at ``pose``."""
    from umbmark.robot.world import DEFAULT_LIDAR

    mount = _laser_pose(pose)
    return replace(world, lidar=replace(world.lidar or DEFAULT_LIDAR, mount=mount))


def _laser_pose(pose: tuple[float, float, float], name: str = "laser_pose") -> Pose2D:
    """A laser's mounting ``x, y, yaw`` checked: finite, within 2 m of the axle centre."""
    values = tuple(float(v) for v in pose)
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise InputError(f"{name}={pose!r}: give x, y [m] and yaw [rad]")
    if math.hypot(values[0], values[1]) > 2.0:
        raise InputError(f"{name}={pose!r}: the laser must sit within 2 m of the axle centre")
    return Pose2D(*values)


def _lift(lift: tuple[float, float, float]) -> tuple[float, float, float]:
    """A stated ``z, roll, pitch`` checked: finite, within 2 m and 180 degrees."""
    values = tuple(float(v) for v in lift)
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise InputError(f"stated_laser_lift={lift!r}: give z [m], roll and pitch [rad]")
    if abs(values[0]) > 2.0 or max(abs(values[1]), abs(values[2])) > math.pi:
        raise InputError(f"stated_laser_lift={lift!r}: z within 2 m, angles within pi rad")
    return values[0], values[1], values[2]


def _arc(
    x: float, y: float, theta: float, left: float, right: float, wheelbase: float
) -> tuple[float, float, float]:
    """The pose after the wheels travel ``left`` and ``right`` [m]: an exact arc
    (``integrateExact`` of diff_drive_controller; the midpoint rule below 1e-6 rad)."""
    linear = 0.5 * (left + right)
    angular = (right - left) / wheelbase
    if abs(angular) < 1e-6:
        heading = theta + 0.5 * angular
        return x + linear * math.cos(heading), y + linear * math.sin(heading), theta + angular
    radius = linear / angular
    after = theta + angular
    return (
        x + radius * (math.sin(after) - math.sin(theta)),
        y - radius * (math.cos(after) - math.cos(theta)),
        after,
    )


def _check_multipliers(params: DriveParams) -> None:
    """Refuse multipliers that are not positive numbers."""
    for name in (
        "wheel_separation_multiplier",
        "left_wheel_radius_multiplier",
        "right_wheel_radius_multiplier",
    ):
        value = getattr(params, name)
        if not (0.0 < value < math.inf):
            raise InputError(f"{name} {value!r} is not a positive number")


def _check_arguments(
    E_d: float,
    E_b: float,
    E_s: float,
    wheelbase: float,
    wheel_diameter: float,
    slip: float,
    command_timeout: float,
) -> None:
    """Refuse a virtual robot that the simulation cannot stand for (Python's names)."""
    low, high = ERROR_RANGE
    for name, value in (("E_d", E_d), ("E_b", E_b), ("E_s", E_s)):
        if not (low <= value <= high):
            raise InputError(f"{name}={value!r}: give {low:g} to {high:g}")
    for name, value, top in (
        ("wheelbase", wheelbase, 5.0),
        ("wheel_diameter", wheel_diameter, 2.0),
    ):
        if not (0.0 < value <= top):
            raise InputError(f"{name}={value!r} m: give more than 0 and at most {top:g} m")
    if not (0.0 <= slip <= MAX_SLIP):
        raise InputError(f"slip={slip!r} m^0.5: give 0 to {MAX_SLIP:g}")
    if not (0.0 < command_timeout <= 60.0):
        raise InputError(f"command_timeout={command_timeout!r} s: give more than 0, at most 60 s")

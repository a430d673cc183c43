"""What the ROS 1 and ROS 2 adapters share: their options, and everything that does not
need ``rospy`` or ``rclpy`` (so it is tested without them).

Defaults are what a ROS robot usually has: ``/cmd_vel``, ``/odom``, ``/scan``, the
controller at ``/diff_drive_controller``, frames from ``/tf`` and ``/tf_static``.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["RECONFIGURE_RANGE", "RosOptions"]

#: ros_controllers' ``DiffDriveController.cfg`` bounds the three multipliers to this; a
#: dynamic_reconfigure server clamps values outside it without a word.
RECONFIGURE_RANGE = (0.5, 1.5)


@dataclass(frozen=True)
class RosOptions:
    """How to reach a ROS robot.

    Attributes
    ----------
    cmd_vel, odom : str
        The velocity command topic (``geometry_msgs/Twist``) and the odometry topic
        (``nav_msgs/Odometry``).
    scan : str or None
        The laser scan topic (``sensor_msgs/LaserScan``); its mounting comes from TF.
    ranges : tuple of str
        Three ``sensor_msgs/Range`` topics (two facing one wall, one the other), their
        mountings from TF.
    truth : str or None
        A ground-truth pose topic (``geometry_msgs/PoseStamped``, motion capture).
    base_frame : str
        The robot's base frame (``base_link``).
    controller : str
        The diff_drive_controller's namespace (its parameters and its dynamic_reconfigure
        server).
    params_file : str or None
        The YAML file the controller loads its parameters from (``--apply yaml`` writes the
        new multipliers into it, atomically).
    wheel_separation, wheel_radius : float or None
        The controller's nominal geometry [m], where its parameters cannot be read.
    reload : bool
        ROS 2: reload the controller through the controller manager after writing its
        parameter file.
    timeout : float
        How long to wait for the first message of each topic and for services [s].
    """

    cmd_vel: str = "/cmd_vel"
    odom: str = "/odom"
    scan: str | None = "/scan"
    ranges: tuple[str, ...] = ()
    truth: str | None = None
    base_frame: str = "base_link"
    controller: str = "/diff_drive_controller"
    params_file: str | None = None
    wheel_separation: float | None = None
    wheel_radius: float | None = None
    reload: bool = False
    timeout: float = 5.0

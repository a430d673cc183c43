"""The reading options as Python types: :class:`SourceOptions`, the keywords of
``**options`` (:func:`umbmark.calibrate`, :func:`umbmark.replay`, :func:`umbmark.report`,
:func:`umbmark.validate`), and :class:`ReadFields`, the fields of
:class:`umbmark.runs.read_options.ReadOptions` (which checks them): one per entry of
:data:`umbmark.options.spec.READ_OPTIONS`, in its order, with its type
(``Spec.py_type``, else by its kind), default and help.

Generated from src/umbmark/options/spec.py by tools/gen_read_options.py; do not edit
(tests/runs/test_read_fields.py fails when it is not what the tool writes now).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, TypedDict

from umbmark.options.spec import READ

__all__ = ["PathLike", "ReadFields", "SourceOptions"]

#: A path as the library takes it.
PathLike = str | os.PathLike[str]


class SourceOptions(TypedDict, total=False):
    """How to read a source: the keywords of the reading functions beyond the square's
    geometry, typed for ``**options`` (what each means: :class:`ReadFields`)."""

    unit: Literal["m", "cm", "mm"]
    angle_unit: Literal["rad", "deg"]
    current_params: PathLike | None
    current_c_l: float | None
    current_c_r: float | None
    current_separation_multiplier: float | None
    wheel_diameter: float | None
    controller: str | None
    format: Literal["auto", "table", "log", "optiodom", "bag", "tuples"]
    split: Literal["rests", "none", "windows"]
    windows: str | Sequence[tuple[float, float]] | None
    max_gap: float
    min_rest: float
    wheel_topic: str
    left_joint: str | Sequence[str] | None
    right_joint: str | Sequence[str] | None
    odom_topic: str | None
    odom_tf: tuple[str, str] | None
    left_ticks_topic: str | None
    right_ticks_topic: str | None
    left_field: str | None
    right_field: str | None
    msg_dir: PathLike | None
    ticks_per_rev: float | None
    left_wheel_frame: str | None
    right_wheel_frame: str | None
    scan_topic: str | None
    imu_topic: str | None
    truth_topic: str | None
    truth_model: str | None
    tf_parent: str | None
    tf_child: str | None
    truth_offset: tuple[float, float] | None
    time_source: Literal["header", "bag"]
    gyro_scale_tolerance: float


@dataclass(frozen=True)
class ReadFields:
    """The reading options with their defaults, those of
    :data:`umbmark.options.spec.READ` (lengths in metres, times in seconds);
    :class:`umbmark.runs.read_options.ReadOptions` checks them.

    Attributes
    ----------
    unit : Literal["m", "cm", "mm"]
        Unit of the lengths in a runs table.
    angle_unit : Literal["rad", "deg"]
        Unit of the headings in a runs table.
    current_params : PathLike | None
        What was active during the runs: a ros2_control (or ROS 1) parameter YAML (its multipliers,
        wheel_separation, wheel_radius) or a previous result (calibrate -o) whose new values were
        applied. Options below override it.
    current_c_l : float | None
        Left wheel factor c_L active during the runs (ros2_control left_wheel_radius_multiplier)
        [default: 1.0, or from ``current_params``].
    current_c_r : float | None
        Right wheel factor c_R active during the runs [default: 1.0, or from ``current_params``].
    current_separation_multiplier : float | None
        wheel_separation_multiplier active during the runs [default: 1.0, or from
        ``current_params``].
    wheel_diameter : float | None
        Nominal wheel diameter D_n [m]; for logged runs, overrides the source's.
    controller : str | None
        The diff_drive_controller's name with its namespace (/robot1/diff_cont): parameter files are
        read under it, overlays and the history keyed by it [default: the one a parameter file
        names, else diff_drive_controller].
    format : Literal["auto", "table", "log", "optiodom", "bag", "tuples"]
        Source format (auto: by the path; tuples: motion intervals of the wheels against a laser's
        scan matching, for ``method`` scan-matching).
    split : Literal["rests", "none", "windows"]
        How to find runs in a recording: at rests near the start (rests), the whole recording cut
        only where its reference was reset (none), or ``windows``.
    windows : str | Sequence[tuple[float, float]] | None
        Runs as time windows, seconds from the recording's start: '0:95,100:190'.
    max_gap : float
        Longest ground-truth gap to interpolate across [s], at most 60.
    min_rest : float
        Shortest rest between runs [s] (for ``split`` rests), at most 600.
    wheel_topic : str
        sensor_msgs/JointState topic; with ``left_field``/``right_field``, a topic of any type.
    left_joint : str | Sequence[str] | None
        Left wheel joint, or several separated by commas (averaged, as ros2_control does) [default:
        left_wheel_names of ``current_params``, else left_wheel_joint, else the moving joints named
        left].
    right_joint : str | Sequence[str] | None
        Right wheel joint(s) [default: as for ``left_joint``].
    odom_topic : str | None
        No wheel data? The controller's odometry (nav_msgs/Odometry), turned back into wheel
        rotation with the controller's geometry (``current_params``, or ``wheelbase`` and
        ``wheel_diameter``).
    odom_tf : tuple[str, str] | None
        ... or the controller's odometry as a /tf chain, e.g. odom base_link.
    left_ticks_topic : str | None
        Cumulative left encoder counts (std_msgs Int*/UInt*/Float*), instead of JointState.
    right_ticks_topic : str | None
        Cumulative right encoder counts.
    left_field : str | None
        Wheel data in a message of any type on ``wheel_topic``: the field with the left wheel's
        angle [rad], or its encoder counts with ``ticks_per_rev``, e.g. left_ticks,
        wheels.left.position, positions[0].
    right_field : str | None
        ... and the right wheel's field.
    msg_dir : PathLike | None
        The .msg files of ``wheel_topic``'s type (<pkg>/msg/<Name>.msg, searched recursively), for
        bags that do not carry its definition (ROS 2 sqlite3 bags before Iron).
    ticks_per_rev : float | None
        Encoder counts per wheel revolution (with the ticks topics or fields).
    left_wheel_frame : str | None
        No wheel joint states? The left wheel's frame on /tf (its transform from the base, e.g.
        wheel_left_link from robot_state_publisher): its rotation.
    right_wheel_frame : str | None
        ... and the right.
    scan_topic : str | None
        A sensor_msgs/LaserScan topic (calibrate only): the wheels are calibrated against the
        laser's scan matching (``method`` scan-matching: both wheel diameters, the wheelbase and the
        laser's mounting from ordinary driving; no ground truth needed).
    imu_topic : str | None
        A sensor_msgs/Imu topic: the gyro, its rates put into the base frame by its frame's mounting
        (/tf_static, /tf or the robot description).
    truth_topic : str | None
        Ground truth: geometry_msgs/PoseStamped, PoseWithCovarianceStamped, nav_msgs/Odometry or
        gazebo_msgs/ModelStates; or positions only: geometry_msgs/PointStamped,
        sensor_msgs/NavSatFix (for paper, exact, endpose).
    truth_model : str | None
        With a gazebo_msgs/ModelStates ground truth: the robot's model [default: the one model that
        moves].
    tf_parent : str | None
        Ground truth from /tf and /tf_static instead: the parent frame (e.g. map); any chain of
        transforms to the child is followed and interpolated in time.
    tf_child : str | None
        ... and the child frame (e.g. base_link).
    truth_offset : tuple[float, float] | None
        The ground truth tracks a point X forward and Y left of the axle centre [m] (a marker, an
        antenna): move it to the axle centre. Left in place, it adds (R(dtheta) - I)(X, Y) to every
        return error.
    time_source : Literal["header", "bag"]
        Message header stamps (where they have them) or bag receive times.
    gyro_scale_tolerance : float
        With an IMU and no heading reference: how far the gyro's scale may be off, as a fraction
        (MEMS datasheets: 0.03 for +-3 % at 25 C); E_b is then relative to the gyro and its interval
        is widened by this.
    """

    unit: Literal["m", "cm", "mm"] = READ["unit"].default
    angle_unit: Literal["rad", "deg"] = READ["angle_unit"].default
    current_params: PathLike | None = None
    current_c_l: float | None = None
    current_c_r: float | None = None
    current_separation_multiplier: float | None = None
    wheel_diameter: float | None = None
    controller: str | None = None
    format: Literal["auto", "table", "log", "optiodom", "bag", "tuples"] = READ["format"].default
    split: Literal["rests", "none", "windows"] = READ["split"].default
    windows: str | Sequence[tuple[float, float]] | None = None
    max_gap: float = READ["max_gap"].default
    min_rest: float = READ["min_rest"].default
    wheel_topic: str = READ["wheel_topic"].default
    left_joint: str | Sequence[str] | None = None
    right_joint: str | Sequence[str] | None = None
    odom_topic: str | None = None
    odom_tf: tuple[str, str] | None = None
    left_ticks_topic: str | None = None
    right_ticks_topic: str | None = None
    left_field: str | None = None
    right_field: str | None = None
    msg_dir: PathLike | None = None
    ticks_per_rev: float | None = None
    left_wheel_frame: str | None = None
    right_wheel_frame: str | None = None
    scan_topic: str | None = None
    imu_topic: str | None = None
    truth_topic: str | None = None
    truth_model: str | None = None
    tf_parent: str | None = None
    tf_child: str | None = None
    truth_offset: tuple[float, float] | None = None
    time_source: Literal["header", "bag"] = READ["time_source"].default
    gyro_scale_tolerance: float = READ["gyro_scale_tolerance"].default

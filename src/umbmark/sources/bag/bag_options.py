"""What to read from a bag: :class:`BagOptions`, and the checks they pass before any
message is read (:func:`check_options`).

Wheels, one of:

- ``wheel_topic`` (``sensor_msgs/JointState``, default ``/joint_states``) with the joints
  ``left_joint`` and ``right_joint`` (:mod:`umbmark.sources.bag.wheels.joint_states`).
  Each message's ``name`` list is searched for them, so joint order may change between
  messages and other joints may be present; messages without both joints (another joint
  group published on the same topic) are skipped. The angle is ``position``; if
  ``position`` is empty and ``velocity`` is not, the velocity is integrated over time
  with the trapezoid rule (angle 0 at the first sample).
- ``left_ticks_topic`` and ``right_ticks_topic`` (``std_msgs`` ``Int16``, ``Int32``,
  ``Int64``, ``UInt16``, ``UInt32``, ``UInt64``, ``Float32`` or ``Float64``): cumulative
  encoder counts of each wheel, with ``ticks_per_rev`` counts per wheel
  revolution. 16- and 32-bit counters wrap around; a jump of more than half the type's
  range between two messages is taken as a wrap and unwrapped. Angle
  ``= counts * 2 pi / ticks_per_rev`` (:mod:`umbmark.sources.bag.wheels.encoders`).
- ``left_field`` and ``right_field``: two numbers in the messages of ``wheel_topic``, of
  any type (a vendor's ``my_robot_msgs/msg/WheelEncoders``), named by field paths
  (``left_ticks``, ``wheels.left.position``, ``positions[0]``; at most 8 names, one
  index each). Angles [rad]; or, with ``ticks_per_rev``, encoder counts, where
  8-, 16- and 32-bit integer fields are unwrapped as above. An integer field without
  ``ticks_per_rev`` is refused. The type's definition comes from the bag (ROS 1
  bags, MCAP, sqlite3 from rosbag2 Iron on) or from ``.msg`` files in ``msg_dir``; see
  :mod:`umbmark.sources.bag.custom`, which also checks the paths against the definition
  before any message is read (a field that is not there: the message lists the fields
  that are); :mod:`umbmark.sources.bag.wheels.encoders` reads them.
- ``odom_topic`` or ``odom_tf`` with ``odom_geometry``: the controller's odometry, turned
  back into wheel rotation (:mod:`umbmark.sources.bag.wheels.odometry`).
- ``left_wheel_frame`` and ``right_wheel_frame``: the wheels' frames on ``/tf``
  (``base_link -> wheel_left_link`` from ``robot_state_publisher``), their rotation
  about the parent's ``y`` axis (:mod:`umbmark.sources.bag.wheels.wheel_tf`).

Ground truth, optional: ``truth_topic`` (``geometry_msgs/PoseStamped``,
``geometry_msgs/PoseWithCovarianceStamped``, ``nav_msgs/Odometry``, Gazebo's
``gazebo_msgs/ModelStates`` with the model ``truth_model``, or the position-only
``geometry_msgs/PointStamped`` and ``sensor_msgs/NavSatFix``:
:mod:`umbmark.sources.bag.truth.references`), else the transform chain ``tf_parent ->
tf_child`` on ``/tf`` (``tf2_msgs/TFMessage``; leading slashes of frame names are
ignored). The pose is ``x, y`` of the position and the yaw of the orientation,
``atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))`` of the normalized quaternion
(:func:`umbmark.core.geometry.quaternion_yaw`). A ground truth
that is the odometry the wheels are read from is refused
(:mod:`umbmark.sources.bag.truth.independence`).

The gyro, optional: ``imu_topic`` (``sensor_msgs/Imu``), read on its own by
:func:`umbmark.sources.bag.imu.read_imu`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from umbmark.core.errors import InputError, option
from umbmark.model.kinematics import OdometryGeometry
from umbmark.options.spec import READ, check_pairs
from umbmark.sources.bag.fieldpath import parse_path

__all__ = ["DEFAULT_JOINTS", "BagOptions", "check_options", "check_wheel_fields"]

#: The wheel joints read when the options name none and the bag has them.
DEFAULT_JOINTS = ("left_wheel_joint", "right_wheel_joint")


@dataclass(frozen=True)
class BagOptions:
    """What to read from a bag; see the module docstring for the details. The defaults
    are those of the reading options (:data:`umbmark.options.spec.READ`).

    Attributes
    ----------
    wheel_topic : str
        ``sensor_msgs/JointState`` topic with the wheel joints.
    left_joint, right_joint : str, tuple of str or None
        The left and right wheel joints in it: a name, several (a tuple, or one string
        separated by commas) whose angles are averaged as ros2_control does for
        ``left_wheel_names``, or None to find them
        (:func:`umbmark.sources.bag.wheels.joint_states.wheel_joints`).
    left_ticks_topic, right_ticks_topic : str or None
        Instead of the joint states: ``std_msgs`` number topics with each wheel's
        cumulative encoder counts (both or neither).
    ticks_per_rev : float or None
        Encoder counts per wheel revolution; required with the ticks topics.
    truth_topic : str or None
        Ground truth: ``geometry_msgs/PoseStamped``,
        ``geometry_msgs/PoseWithCovarianceStamped``, ``nav_msgs/Odometry``,
        ``gazebo_msgs/ModelStates``, or (positions only) ``geometry_msgs/PointStamped``
        or ``sensor_msgs/NavSatFix``.
    truth_model : str or None
        With a ``gazebo_msgs/ModelStates`` ground truth: the robot's model (default: the
        one model that moves).
    tf_parent, tf_child : str or None
        Ground truth from the direct transform ``tf_parent -> tf_child`` on ``/tf``
        (used when ``truth_topic`` is not given).
    time_source : {"header", "bag"}
        Stamp samples with ``header.stamp`` (where messages have one) or with the time the
        bag recorded them.
    odom_topic : str or None
        Instead of wheel data: the controller's odometry (``nav_msgs/Odometry`` or a
        pose type), turned back into wheel rotation with ``odom_geometry``.
    odom_tf : (str, str) or None
        Instead of wheel data: the controller's odometry as the transform chain
        ``(parent, child)``, for example ``("odom", "base_link")``.
    odom_geometry : OdometryGeometry or None
        The effective radii and separation the controller used; required with
        ``odom_topic`` or ``odom_tf``.
    left_field, right_field : str or None
        Instead of joint states: field paths to each wheel's value in the messages of
        ``wheel_topic``, which may then have any type (``left_ticks``,
        ``wheels.left.position``, ``positions[0]``; both or neither). Angles [rad], or
        encoder counts when ``ticks_per_rev`` is given.
    msg_dir : Path or None
        A folder of ``.msg`` files defining ``wheel_topic``'s type, for bags that do not
        carry its definition (:mod:`umbmark.sources.bag.custom`); only with the fields.
    left_wheel_frame, right_wheel_frame : str or None
        Instead of joint states: the child frames of the wheels' transforms on ``/tf``
        (both or neither).
    imu_topic : str or None
        A ``sensor_msgs/Imu`` topic: the gyro (:mod:`umbmark.sources.bag.imu`); the
        wheels' readers leave it alone.
    """

    wheel_topic: str = READ["wheel_topic"].default
    left_joint: str | tuple[str, ...] | None = None
    right_joint: str | tuple[str, ...] | None = None
    left_ticks_topic: str | None = None
    right_ticks_topic: str | None = None
    ticks_per_rev: float | None = None
    truth_topic: str | None = None
    tf_parent: str | None = None
    tf_child: str | None = None
    time_source: Literal["header", "bag"] = READ["time_source"].default
    odom_topic: str | None = None
    odom_tf: tuple[str, str] | None = None
    odom_geometry: OdometryGeometry | None = None
    left_field: str | None = None
    right_field: str | None = None
    msg_dir: Path | None = None
    truth_model: str | None = None
    left_wheel_frame: str | None = None
    right_wheel_frame: str | None = None
    imu_topic: str | None = None

    @property
    def left_joints(self) -> tuple[str, ...]:
        """The left wheel joints asked for (empty: take them from the bag)."""
        return _joint_names(self.left_joint)

    @property
    def right_joints(self) -> tuple[str, ...]:
        """The right wheel joints asked for (empty: take them from the bag)."""
        return _joint_names(self.right_joint)


def _joint_names(value: str | tuple[str, ...] | None) -> tuple[str, ...]:
    if value is None:
        return ()
    names = value.split(",") if isinstance(value, str) else value
    return tuple(name.strip() for name in names if name.strip())


def check_options(options: BagOptions, src: str) -> None:
    """Refuse options that contradict each other or are malformed, before the bag is read.

    :func:`umbmark.sources.bag.truth.independence.check_distinct` checks next that the
    ground truth is not the odometry the wheels are read from.

    Raises
    ------
    InputError
        One line naming ``src`` and the problem.
    """

    def fail(problem: str) -> None:
        raise InputError(problem, source=src)

    if options.time_source not in READ["time_source"].choices:
        fail(f"time source must be 'header' or 'bag', not {options.time_source!r}")
    if (options.left_ticks_topic is None) != (options.right_ticks_topic is None):
        fail("the left and right ticks topics go together: give both or neither")
    if options.left_ticks_topic is not None:
        if options.ticks_per_rev is None:
            needs = option("ticks_per_rev")
            fail(f"reading ticks topics needs {needs} (counts per wheel revolution)")
        if options.left_ticks_topic == options.right_ticks_topic:
            fail(f"the left and right ticks topics are the same: {options.left_ticks_topic}")
    tpr = options.ticks_per_rev
    if tpr is not None and not (math.isfinite(tpr) and tpr > 0):
        fail(f"ticks_per_rev must be a positive number, not {tpr!r}")
    check_pairs(vars(options), src)
    check_wheel_fields(
        options.left_field,
        options.right_field,
        options.msg_dir,
        (
            ("left_ticks_topic", options.left_ticks_topic),
            ("right_ticks_topic", options.right_ticks_topic),
            ("odom_topic", options.odom_topic),
            ("odom_tf", options.odom_tf),
        ),
        src,
    )
    left_field, right_field = options.left_field, options.right_field
    if (
        left_field is not None
        and right_field is not None
        and (left_field.replace(" ", "") == right_field.replace(" ", ""))
    ):
        fail(f"the left and right fields are the same: {left_field!r}")
    for side, given, names in (
        ("left", options.left_joint, options.left_joints),
        ("right", options.right_joint, options.right_joints),
    ):
        if given is not None and not names:
            fail(
                f"the {side} wheel joint option ({option(f'{side}_joint')}) names no joint: "
                f"{given!r:.60}"
            )
    left = options.left_joints or DEFAULT_JOINTS[:1]
    right = options.right_joints or DEFAULT_JOINTS[1:]
    both = set(left) & set(right)
    if both and options.left_ticks_topic is None:
        fail(f"the left and right wheel joints are the same: {sorted(both)[0]!r}")
    if (options.odom_topic is not None or options.odom_tf is not None) and (
        options.odom_geometry is None
    ):
        fail(
            "turning odometry back into wheel rotation needs the controller's geometry "
            "(wheel radius and separation)"
        )
    if options.odom_topic is not None and options.odom_tf is not None:
        fail("give the odometry as a topic or as a transform, not both")
    if options.truth_topic is None and (options.tf_parent is None) != (options.tf_child is None):
        fail("a TF ground truth needs both tf_parent and tf_child")
    if options.truth_topic is not None and (
        options.tf_parent is not None or options.tf_child is not None
    ):
        fail(
            f"give the ground truth as a topic ({option('truth_topic')}) or as a TF pair "
            f"({option('tf_parent')}, {option('tf_child')}), not both"
        )
    if options.truth_model is not None and options.truth_topic is None:
        fail(
            f"{option('truth_model')} names a model of the ground-truth topic: give "
            f"{option('truth_topic')} too"
        )
    if options.left_wheel_frame is not None:
        other = (
            "ticks topics"
            if options.left_ticks_topic is not None
            else "fields"
            if options.left_field is not None
            else "controller odometry"
            if options.odom_topic is not None or options.odom_tf is not None
            else None
        )
        if other is not None:
            fail(f"give the wheels as wheel frames on /tf or as {other}, not both")


def check_wheel_fields(
    left_field: str | None,
    right_field: str | None,
    msg_dir: object,
    others: Sequence[tuple[str, object]],
    source: str | None = None,
) -> None:
    """Refuse ``msg_dir`` without the wheel fields, malformed field paths, and the fields
    given with other wheel data (``others``: ``(keyword, value)``, given when true). The one
    check of the field options, for :class:`umbmark.runs.read_options.ReadOptions` and
    :func:`check_options` (:func:`umbmark.options.spec.check_pairs` checks that both are
    given first).

    Raises
    ------
    InputError
        One line naming the options (:func:`umbmark.core.errors.option`) and ``source``.
    """
    if left_field is None or right_field is None:
        if msg_dir is not None:
            raise InputError(
                f"{option('msg_dir')} is for wheel data in a custom message type: give it "
                f"with {option('left_field')} and {option('right_field')}",
                source=source,
            )
        return
    for name, text in (("left_field", left_field), ("right_field", right_field)):
        try:
            parse_path(text, option(name))
        except InputError as err:
            raise InputError(err.problem, source=source) from None
    for name, value in others:
        if value:
            raise InputError(
                f"{option('left_field')}/{option('right_field')} read the wheels from "
                f"{option('wheel_topic')}: leave out {option(name)}",
                source=source,
            )

"""A :class:`~umbmark.monitor.status.MonitorStatus` as ``diagnostic_msgs/DiagnosticArray``,
laid out as ``diagnostic_updater`` writes it (ros/diagnostics, ``_diagnostic_updater.py``
of the ROS 2 branch and of ``noetic-devel``):

- one ``DiagnosticStatus`` per task, named ``<node>: <task>`` (ROS 2: the node's name,
  ``get_name()``; ROS 1: ``rospy.get_name()[1:]``): here ``umbmark_monitor: odometry``;
- ``hardware_id`` the robot; ``level`` OK 0, WARN 1, ERROR 2, STALE 3 (ROS 2 carries the
  byte as ``bytes``, ``b'\\x00'``; ROS 1 as an integer); ``message`` one line;
- ``values``: ``diagnostic_msgs/KeyValue`` pairs of strings, in order;
- the array's ``header.stamp`` the node's clock (sim time where ``/clock`` runs), published
  on ``/diagnostics`` (ROS 2 depth 1, ROS 1 queue 10, as the updater's publishers) once
  a period, 1 s by default.

The composition (:func:`compose`) needs no ROS and is tested without it;
:func:`fill_array` puts it into the message classes a node hands it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from umbmark.monitor.status import LEVELS, MonitorStatus

__all__ = ["NODE_NAME", "PERIOD", "STATUS_NAME", "TASK", "TOPIC", "Diagnostic", "compose"]
__all__ += ["fill_array", "level_value"]

#: The node's name (``umbmark_monitor``), its one diagnostic task, and the status name
#: diagnostic_updater makes of them.
NODE_NAME = "umbmark_monitor"
TASK = "odometry"
STATUS_NAME = f"{NODE_NAME}: {TASK}"
#: Where and how often the status is published [s].
TOPIC = "/diagnostics"
PERIOD = 1.0


@dataclass(frozen=True)
class Diagnostic:
    """One ``diagnostic_msgs/DiagnosticStatus`` as plain values.

    Attributes
    ----------
    name : str
        ``<node>: odometry``.
    level : int
        0 OK, 1 WARN, 2 ERROR, 3 STALE.
    message, hardware_id : str
        The line for people; the robot.
    values : tuple of (str, str)
        The key-values, in order.
    """

    name: str
    level: int
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...]


def compose(status: MonitorStatus, node_name: str = NODE_NAME) -> Diagnostic:
    """The status as diagnostic_updater would publish it from a node named ``node_name``
    (its namespace-less name, as the updater takes it by default)."""
    return Diagnostic(
        name=f"{node_name.strip('/')}: {TASK}",
        level=LEVELS.index(status.level),
        message=status.message,
        hardware_id=status.robot,
        values=tuple((str(k), str(v)) for k, v in status.key_values()),
    )


def level_value(level: int, *, ros2: bool) -> bytes | int:
    """The level as the message field takes it: ROS 2 ``bytes`` of one byte, ROS 1 an
    integer."""
    if not 0 <= level <= 3:
        raise ValueError(f"a diagnostic level is 0 to 3, not {level!r}")
    return bytes([level]) if ros2 else level


def fill_array(
    diagnostic: Diagnostic,
    array_type: Any,  # noqa: ANN401 (diagnostic_msgs DiagnosticArray)
    status_type: Any,  # noqa: ANN401 (DiagnosticStatus)
    key_value_type: Any,  # noqa: ANN401 (KeyValue)
    stamp: Any,  # noqa: ANN401 (builtin_interfaces Time, or rospy.Time)
    *,
    ros2: bool,
) -> Any:  # noqa: ANN401 (a DiagnosticArray)
    """A ``DiagnosticArray`` holding ``diagnostic`` alone, stamped ``stamp``."""
    array = array_type()
    array.header.stamp = stamp
    status = status_type()
    status.name = diagnostic.name
    status.level = level_value(diagnostic.level, ros2=ros2)
    status.message = diagnostic.message
    status.hardware_id = diagnostic.hardware_id
    values = []
    for key, value in diagnostic.values:
        pair = key_value_type()
        pair.key, pair.value = key, value
        values.append(pair)
    status.values = values
    array.status = [status]
    return array

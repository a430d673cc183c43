"""Which velocity topic the ROS 2 client drives on, from the graph's subscribers
(:func:`umbmark.robot.ros2.pick_velocity`; no ROS needed). The cases are the
diff_drive_controller's own subscriptions (its branches' ``diff_drive_controller.cpp``):
Humble and Iron with ``use_stamped_vel: false`` take ``geometry_msgs/Twist`` on
``~/cmd_vel_unstamped``; otherwise ``TwistStamped`` on ``~/cmd_vel``."""

from __future__ import annotations

from umbmark.robot.ros2 import pick_velocity

CONTROLLER = "/diff_drive_controller"
CMD_VEL = "/diff_drive_controller/cmd_vel"
UNSTAMPED = "/diff_drive_controller/cmd_vel_unstamped"
TOPICS = (CMD_VEL, UNSTAMPED)
TWIST, STAMPED = "geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"


def test_humbles_unstamped_subscription_is_found() -> None:
    endpoints = [(UNSTAMPED, CONTROLLER, TWIST)]
    assert pick_velocity(endpoints, TOPICS, CONTROLLER) == (UNSTAMPED, TWIST, CONTROLLER)


def test_jazzys_stamped_subscription_is_found() -> None:
    endpoints = [(CMD_VEL, CONTROLLER, STAMPED)]
    assert pick_velocity(endpoints, TOPICS, CONTROLLER) == (CMD_VEL, STAMPED, CONTROLLER)


def test_the_controllers_own_subscription_wins_over_a_monitor_on_cmd_vel() -> None:
    """A monitor subscribing ``~/cmd_vel`` (TwistStamped) beside a Humble controller on
    ``~/cmd_vel_unstamped``: commands on ``~/cmd_vel`` would drive nothing."""
    endpoints = [(CMD_VEL, "/umbmark_watch", STAMPED), (UNSTAMPED, CONTROLLER, TWIST)]
    assert pick_velocity(endpoints, TOPICS, CONTROLLER) == (UNSTAMPED, TWIST, CONTROLLER)


def test_another_node_is_taken_where_the_controller_has_no_subscription() -> None:
    """A relay (a twist_stamper, a mux) subscribing the topic: the first candidate topic's
    subscriber, TwistStamped before Twist on one topic."""
    endpoints = [(UNSTAMPED, "/relay_b", TWIST), (CMD_VEL, "/relay_a", TWIST),
                 (CMD_VEL, "/relay_c", STAMPED)]  # fmt: skip
    assert pick_velocity(endpoints, TOPICS, CONTROLLER) == (CMD_VEL, STAMPED, "/relay_c")


def test_no_twist_subscriber_is_none() -> None:
    assert pick_velocity([], TOPICS, CONTROLLER) is None
    endpoints = [(CMD_VEL, CONTROLLER, "std_msgs/msg/String")]
    assert pick_velocity(endpoints, TOPICS, CONTROLLER) is None
    other = [("/cmd_vel", CONTROLLER, TWIST)]  # not a candidate topic
    assert pick_velocity(other, TOPICS, CONTROLLER) is None

"""ROS bags: wheel rotation and ground truth from ROS 1 and ROS 2 recordings."""

from __future__ import annotations

from .series import BagOptions, bag_topics, read_bag

__all__ = ["BagOptions", "bag_topics", "read_bag"]

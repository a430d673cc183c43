"""ROS bags: wheel rotation and ground truth from ROS 1 and ROS 2 recordings."""

from __future__ import annotations

from umbmark.sources.bag.series import BagOptions, BagRead, bag_topics, read_bag, read_recording

__all__ = ["BagOptions", "BagRead", "bag_topics", "read_bag", "read_recording"]

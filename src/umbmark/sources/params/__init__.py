"""Odometry parameters in files: controller parameter YAML (ros2_control, ROS 1) and
umbmark results; their reader and their writer.
"""

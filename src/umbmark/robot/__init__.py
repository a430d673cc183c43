"""A robot as the self-calibration sees it: a small interface (send a velocity, read the
odometry, the sensors and the clock, read and apply the odometry's parameters) and its
implementations: the virtual robot, ROS 1 (rospy) and ROS 2 (rclpy).

The adapters know nothing of UMBmark; the routine (:mod:`umbmark.routines`) knows nothing of
ROS.
"""

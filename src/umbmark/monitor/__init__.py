"""The monitor: a robot watching its own odometry as it works (``umbmark monitor``).

:mod:`umbmark.monitor.status` is what the monitor says and what it is fed (the interface
between its ROS-free core and the nodes that feed it); the core matches the robot's motion
as it arrives, over a window measured in driving, and follows each figure's course with the
fleet's change model (:mod:`umbmark.calibration.changes`); the ROS 1 and ROS 2 nodes
subscribe, publish ``/diagnostics`` and the corrected odometry, and apply at rest.
"""

"""Wheel rotation from a bag, one module per kind of wheel data.

- :mod:`~umbmark.sources.bag.wheels.joint_states`: ``sensor_msgs/JointState``;
- :mod:`~umbmark.sources.bag.wheels.encoders`: cumulative counts on ``std_msgs`` topics,
  or two fields of a message of any type;
- :mod:`~umbmark.sources.bag.wheels.wheel_tf`: the wheels' frames on ``/tf``;
- :mod:`~umbmark.sources.bag.wheels.odometry`: the controller's odometry, its update
  inverted.

Each returns a :class:`umbmark.model.recording.WheelSeries`; none imports another, nor
the ground truth's modules.
"""

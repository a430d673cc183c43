"""Poses from a bag: the ground truth, and the controller's odometry read as poses.

- :mod:`~umbmark.sources.bag.truth.poses`: pose topics (``PoseStamped``,
  ``PoseWithCovarianceStamped``, ``Odometry``);
- :mod:`~umbmark.sources.bag.truth.transforms`: chains of transforms on ``/tf`` and
  ``/tf_static``;
- :mod:`~umbmark.sources.bag.truth.references`: Gazebo's model states, and the
  position-only ``PointStamped`` and ``NavSatFix``;
- :mod:`~umbmark.sources.bag.truth.independence`: a ground truth must not be the
  odometry it judges.
"""

"""Scan matching: a planar scanner's own motion, and the motion intervals of the
simultaneous calibration of odometry and sensor mounting (Censi et al. 2013).

- :mod:`.points`: a sweep as points, normals and a KD-tree;
- :mod:`.icp`: point-to-line ICP with covariance and degeneracy checks;
- :mod:`.intervals`: :func:`~.intervals.intervals_from_scans`, scans and wheels to
  :class:`umbmark.model.motion_intervals.MotionIntervals`.
"""

"""The routines the robot drives to calibrate itself (``umbmark selfcal``, the paper's
Sec. 6, and ``--routine anywhere``): driving by odometry with its safety stops, the
checks before moving, the fixes at the corner, a pass recorded as a run log, the pattern
calibrated anywhere, and what a person watching is told. The job that runs them is
:func:`umbmark.jobs.selfcal.selfcal`.
"""

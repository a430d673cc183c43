"""The robot and the test as values and physics: the systematic error model (E_d, E_b,
alpha, beta), the square's exact geometry, wheel kinematics and odometry, the ``Run``
every source produces, and recorded time series.
"""

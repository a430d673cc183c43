"""Poses from a bag: pose topics, transform chains, Gazebo's model states, position-only
references, and the checks that a ground truth is not the odometry it judges.
"""

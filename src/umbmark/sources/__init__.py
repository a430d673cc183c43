"""Readers of recorded runs: umbmark run logs, OptiOdom sessions, ROS bags.

Each produces :class:`umbmark.recording.Recording` values; nothing here knows of
estimators.
"""

"""From estimated errors to what the robot should run with: the correction composed
with the active parameters, and whether to apply it.
"""

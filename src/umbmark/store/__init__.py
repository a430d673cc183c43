"""The one stateful part: a robot's calibration history in an SQLite file, and whether
its errors drift.
"""

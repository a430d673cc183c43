"""The self-calibration (the paper's Sec. 6): the robot drives UMBmark by itself, measures
where it stopped against an L-shaped corner, calibrates, applies and verifies.
"""

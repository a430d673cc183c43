"""From recordings to runs: matching ground truth to wheel samples, gaps, rests and
resets, splitting a recording into runs, and the one entry point that reads any source
into runs.
"""

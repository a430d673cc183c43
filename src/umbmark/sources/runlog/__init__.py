"""The umbmark run log: recorded runs as CSV time series plus a small metadata file; its
reader and its writer.
"""

"""Wheel rotation from a bag, one module per kind of wheel data (see
:mod:`umbmark.sources.bag.bag_options`); each returns a
:class:`~umbmark.model.recording.WheelSeries` and imports neither another nor the truth's.
"""

"""The formats, reader beside writer: runs tables, run logs, OptiOdom sessions, tuple
files, controller parameter files and umbmark results, and ROS bags
(:mod:`~umbmark.sources.bag`).
Every text reader starts at :mod:`~umbmark.sources.text`. Turning recordings into runs is
:mod:`umbmark.runs`, the layer above; nothing here knows of estimators
(``docs/architecture.md``).
"""

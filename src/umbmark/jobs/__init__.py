"""The jobs: one function per command, each returning a report that serializes and draws.

``calibrate``, ``replay``, ``simulate``, ``demo``, ``reproduce_table1``, ``reproduce_fig4``
and ``example`` are importable from :mod:`umbmark` itself; the command of the same name
parses its options, calls the function and renders the report.
"""

"""Everything that turns input into runs.

- :mod:`~umbmark.sources.text`: reading text files (every text reader starts here).
- Formats: :mod:`~umbmark.sources.runs_table` (end points typed in),
  :mod:`~umbmark.sources.runlog`, :mod:`~umbmark.sources.optiodom`,
  :mod:`~umbmark.sources.bag` (recordings), :mod:`~umbmark.sources.params` (controller
  parameter files and previous results).
- Recordings to runs: :mod:`~umbmark.sources.association` (time matching),
  :mod:`~umbmark.sources.segmentation` (finding runs), :mod:`~umbmark.sources.logged`.
- :mod:`~umbmark.sources.load`: one entry point that detects the format and reads it.

Nothing here knows of estimators.
"""

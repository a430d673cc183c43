"""Everything that turns input into runs.

- :mod:`~umbmark.sources.text`: reading text files (every text reader starts here).
- Formats: :mod:`~umbmark.sources.runs_table.reader` (end points typed in),
  :mod:`~umbmark.sources.runlog.reader`, :mod:`~umbmark.sources.optiodom`,
  :mod:`~umbmark.sources.bag` (recordings), :mod:`~umbmark.sources.params.reader` (controller
  parameter files and previous results).
- Recordings to runs: :mod:`~umbmark.runs.association` (time matching),
  :mod:`~umbmark.runs.segmentation` (finding runs), :mod:`~umbmark.runs.logged`.
- :mod:`~umbmark.runs.load`: one entry point that detects the format and reads it.

Nothing here knows of estimators.
"""

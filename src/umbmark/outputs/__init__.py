"""Everything umbmark writes: runs tables, run logs, controller parameters, TUM
trajectories, figures; always whole or not at all (:mod:`umbmark.core.atomic`)."""

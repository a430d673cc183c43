"""The ``umbmark`` console script's first code: Ctrl-C while the command line's modules
load (click, rich, numpy: a few tenths of a second) ends with the same one line and
status as Ctrl-C later, not with Python's traceback."""

from __future__ import annotations

import sys

__all__ = ["main"]

#: Exit status after Ctrl-C, as shells report it (the same as :mod:`umbmark.cli.main`'s).
EXIT_INTERRUPTED = 130


def main() -> None:
    """Load the command line and run it (:func:`umbmark.cli.main.main`)."""
    try:
        from umbmark.cli.main import main as run
    except KeyboardInterrupt:
        sys.stderr.write("umbmark: interrupted\n")
        sys.exit(EXIT_INTERRUPTED)
    run()

"""The options, specified once: :mod:`umbmark.options.spec` (each option's keyword, flags,
kind, unit, default, bounds, help and ``--help`` section), from which the click options,
the library's checks and the bag reader's defaults are derived. Imports only
:mod:`umbmark.core`; cheap to import (no numpy)."""

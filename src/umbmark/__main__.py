"""``python -m umbmark``: the same as the ``umbmark`` command."""

from umbmark._entry import main

main()

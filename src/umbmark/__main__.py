"""``python -m umbmark``: the same as the ``umbmark`` command."""

from ._entry import main

main()

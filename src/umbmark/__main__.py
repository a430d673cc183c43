"""``python -m umbmark``: the same as the ``umbmark`` command."""

from .cli.main import main

main()

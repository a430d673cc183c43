"""The ``umbmark`` command: one module per command, each parsing its options, calling the
library function of the same name and rendering the report (``docs/architecture.md``)."""

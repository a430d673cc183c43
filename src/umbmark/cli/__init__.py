"""The ``umbmark`` command: a thin layer that wires sources, estimators and outputs."""

"""The jobs: one function per command, each returning a report (a frozen dataclass) that
serializes and draws. The facade :mod:`umbmark` exports them; the command of the same name
parses its options, calls the function and renders the report (``docs/architecture.md``).
"""

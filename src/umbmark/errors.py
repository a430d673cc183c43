"""The error users see: bad input, named by file (and row) and problem."""

from __future__ import annotations

from pathlib import Path

__all__ = ["InputError"]


class InputError(ValueError):
    """Input that umbmark cannot use.

    Its text is one line: ``FILE, row N: PROBLEM`` (file and row when known), the line
    the command prints before it exits with status 2. It is a ``ValueError``, so code
    that already catches those catches it too.
    """

    def __init__(
        self, problem: str, *, source: str | Path | None = None, row: int | None = None
    ) -> None:
        self.problem = problem
        self.source = None if source is None else str(source)
        self.row = row
        super().__init__(str(self))

    def __str__(self) -> str:
        where = self.source or ""
        if self.row is not None:
            where = f"{where}, row {self.row}" if where else f"row {self.row}"
        return f"{where}: {self.problem}" if where else self.problem

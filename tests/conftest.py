"""Fixtures shared by the tests."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import pytest

from helpers import write_table


@pytest.fixture
def table(tmp_path: Path):
    """Factory: ``table(rows, header=...)`` writes a runs table and returns its path."""

    def make(
        rows: Sequence[Sequence[object]],
        header: str = "direction,x_abs,y_abs,x_odo,y_odo",
        name: str = "runs.csv",
    ) -> Path:
        return write_table(tmp_path / name, rows, header)

    return make

"""Plain functions the fleet engine's tests hand to Dask workers (importable by a worker
process: ``tests/`` is on its path)."""

from __future__ import annotations

import os
import time
from pathlib import Path

from umbmark.core.errors import InputError


def square_or_refuse(n: int) -> int:
    """``n * n``; an InputError for a negative ``n`` (a recording that fails to read)."""
    if n < 0:
        raise InputError(f"item {n} cannot be read", source=f"rec-{n}.bag")
    return n * n


def slow_square(task: tuple[int, str, float]) -> tuple[int, int]:
    """``n * n`` after ``seconds``, leaving ``folder/started-n-PID`` behind; returns
    ``(n * n, the worker's PID)``."""
    n, folder, seconds = task
    Path(folder, f"started-{n}-{os.getpid()}").write_text("")
    time.sleep(seconds)
    return n * n, os.getpid()

"""Plain functions the fleet engine's tests hand to Dask workers (importable by a worker
process: ``tests/`` is on its path)."""

from __future__ import annotations

import os
import sqlite3
import time
from pathlib import Path

from umbmark.core.errors import InputError
from umbmark.fleets.outcome import RecordingOutcome


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


def executing(dask_worker) -> dict[str, str]:  # type: ignore[no-untyped-def]
    """What a worker is running right now, by its own state (``Client.run`` hands it the
    worker): each task it executes (in its thread, not waiting), its key and the path of
    the recording it calibrates."""
    return {
        str(ts.key): next((a.path for a in ts.run_spec.args if hasattr(a, "path")), "")
        for ts in dask_worker.state.executing
    }


def holders(n: int, dask_scheduler=None) -> list[str]:  # type: ignore[no-untyped-def]
    """The workers holding the finished result of :func:`slow_square`'s item ``n``, by the
    scheduler's own state (``Client.run_on_scheduler`` hands it the scheduler); none while
    it is not finished."""
    for ts in dask_scheduler.tasks.values():
        args = getattr(ts.run_spec, "args", ())
        if args and isinstance(args[0], tuple) and args[0][0] == n and ts.state == "memory":
            return sorted(ws.address for ws in ts.who_has)
    return []


DAY = 86400.0
T0 = 1_790_000_000.0
SE = {"E_d": 1e-4, "E_b": 3e-4, "E_s": 2e-4, "laser_x": 3e-4, "laser_y": 3e-4, "laser_yaw": 5e-4}


def daily_outcomes(robot, days, rng, step_day=None, figure=None, jump=0.0):  # type: ignore[no-untyped-def]
    """A robot's daily outcomes with known figures, ``figure`` stepped by ``jump`` from
    ``step_day`` on (scan matching, 8 h a day, a nominal wheelbase of 0.34 m, nothing
    active but the nominal)."""
    out = []
    truth = {"E_d": 1.003, "E_b": 0.98, "E_s": 1.0, "laser_x": 0.12, "laser_y": -0.04,
             "laser_yaw": 0.07}  # fmt: skip
    for day in range(days):
        figures = {}
        for name, value in truth.items():
            stepped = step_day is not None and name == figure and day >= step_day
            figures[name] = (value + jump * stepped + rng.normal(0.0, SE[name]), SE[name])
        out.append(
            RecordingOutcome(
                f"{robot}/day{day:02d}.mcap", robot, T0 + day * DAY, 8.0, "0" * 64,
                method="scan-matching", figures=figures, e_max_syst=0.1 + 0.001 * day,
                multipliers=(0.98, 0.9985, 1.0015), verdict="apply", wheelbase=0.34,
            )
        )  # fmt: skip
    return out


def recorded_rows(history: Path) -> int:
    """Rows in a history's recordings table (0 while it is being made)."""
    if not history.exists():
        return 0
    try:
        with sqlite3.connect(history) as db:
            return int(db.execute("SELECT count(*) FROM recordings").fetchone()[0])
    except sqlite3.OperationalError:  # the table is being made
        return 0

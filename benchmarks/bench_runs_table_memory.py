"""Runs-table reading: memory and time of umbmark's streaming reader against the old way.

Writes one runs table into a temporary folder (default 200 000 rows, with headings, the
way ``umbmark simulate -o`` writes them), then reads it two ways, each measured in the
same process:

(a) the old way: the whole text read at once, then ``csv.DictReader`` into a list of
    dicts (one per row), then the numbers converted: what umbmark did before it streamed
    (``read_text`` of the file, a list of its lines, a list of dicts);
(b) ``umbmark.read_runs_table``: line by line, keeping only the runs.

Peak memory is traced with ``tracemalloc`` (Python allocations, numpy's included) and
given per row; times are the best of ``--repeat`` runs without tracing. Both readings
are checked to give the same numbers.

Run: python benchmarks/bench_runs_table_memory.py [--rows N] [--repeat R]
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import sys
import tempfile
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from umbmark import read_runs_table

from _timing import best_of

COLUMNS = ("direction", "x_abs", "y_abs", "theta_abs", "x_odo", "y_odo", "theta_odo")


def generate(path: Path, rows: int) -> None:
    """A runs table of ``rows`` runs near the start of a 4 m square, metres and radians."""
    rng = np.random.default_rng(1)
    values = rng.normal(0.0, [0.1, 0.1, 0.02, 0.01, 0.01, 0.01], size=(rows, 6))
    with path.open("w", encoding="utf-8") as file:
        file.write("# a benchmark table\n" + ",".join(COLUMNS) + "\n")
        for k in range(rows):
            v = values[k]
            direction = "cw" if k % 2 else "ccw"
            file.write(
                f"{direction},{v[0]:.6f},{v[1]:.6f},{v[2]:.8f},{v[3]:.6f},{v[4]:.6f},{v[5]:.8f}\n"
            )


def old_way(path: Path) -> list[dict[str, Any]]:
    """(a) The whole text, its lines, a list of dicts, the numbers converted in place."""
    text = path.read_text(encoding="utf-8-sig")
    lines = [line for line in text.splitlines() if line.strip() and not line.startswith("#")]
    rows = list(csv.DictReader(io.StringIO("\n".join(lines))))
    for row in rows:
        for name in COLUMNS[1:]:
            row[name] = float(row[name])
    return rows


def peak(fn: Callable[[], Any]) -> tuple[int, Any]:
    """Peak traced memory [bytes] while ``fn`` runs and its result is alive."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    before = tracemalloc.get_traced_memory()[0]
    result = fn()
    top = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return top - before, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=200_000, help="runs in the table")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs of each (best)")
    args = parser.parse_args()
    n = args.rows
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "runs.csv"
        generate(path, n)
        size = path.stat().st_size
        print(f"runs table: {n:,} rows, {size / 1e6:.1f} MB ({size / n:.0f} bytes per row)")

        mem_old, rows = peak(lambda: old_way(path))
        del rows
        mem_new, runs = peak(lambda: read_runs_table(path))
        del runs
        t_old, rows = best_of(lambda: old_way(path), repeat=args.repeat)
        t_new, runs = best_of(lambda: read_runs_table(path), repeat=args.repeat)

        same = len(rows) == len(runs) and all(
            math.isclose(row["x_abs"], run.true_end.x)
            and math.isclose(row["theta_odo"], run.odometry_end.theta or 0.0)
            and row["direction"] == run.direction.value
            for row, run in zip(rows, runs, strict=True)
        )
        print("peak memory (tracemalloc), the result kept")
        print(
            f"  (a) read_text + csv.DictReader list of dicts: {mem_old / n:7.0f} bytes/row "
            f"({mem_old / 1e6:6.1f} MB)"
        )
        print(
            f"  (b) umbmark read_runs_table, streaming:       {mem_new / n:7.0f} bytes/row "
            f"({mem_new / 1e6:6.1f} MB)   {mem_old / mem_new:4.1f}x less"
        )
        print(f"time (best of {args.repeat})")
        print(f"  (a) old way:   {t_old:6.3f} s ({n / t_old:10,.0f} rows/s)")
        print(
            f"  (b) streaming: {t_new:6.3f} s ({n / t_new:10,.0f} rows/s)   "
            f"time ratio (b)/(a) = {t_new / t_old:4.2f}"
        )
        print(f"  same numbers: {'yes' if same else 'NO'}")
        if not same:
            sys.exit(1)


if __name__ == "__main__":
    main()

"""Reading a run log's CSV: rows parsed in blocks by numpy's parser against row by row.

Both read the same file through :func:`umbmark.sources.runlog.reader.read_runlog`; the
row-by-row reading is the reader with its block parser turned off (every block read as a
block that failed: what the reader did before, and still does for a block with an empty
cell, a quote or a word). The two give the same arrays, to the bit.

Run: python benchmarks/bench_runlog_read.py [--rows N]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np

from umbmark.sources.runlog import reader
from umbmark.sources.runlog.reader import LogMetadata, read_runlog
from umbmark.sources.runlog.writer import write_log_csv, write_metadata

from _timing import best_of


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=200_000)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    time = np.arange(args.rows) * 0.01
    truth = np.cumsum(rng.normal(size=(args.rows, 3)) * 1e-3, axis=0)
    angles = np.cumsum(rng.uniform(0.0, 0.2, size=(args.rows, 2)), axis=0)
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        meta = LogMetadata(wheel_diameter=0.15, wheelbase=0.34, wheel_data="angles")
        write_metadata(root, meta)
        write_log_csv(root / "run.csv", time, truth, angles)
        blocks, (fast, _) = best_of(lambda: read_runlog(root))
        with mock.patch.object(reader, "_whole_chunk", return_value=False):
            rows, (slow, _) = best_of(lambda: read_runlog(root))
    for a, b in zip(fast, slow, strict=True):
        assert np.array_equal(a.wheels.angles, b.wheels.angles)
        assert a.truth is not None
        assert b.truth is not None
        assert np.array_equal(a.truth.poses, b.truth.poses)
    print(f"{args.rows} rows: in blocks {blocks:.3f} s ({args.rows / blocks:,.0f} rows/s)")
    print(f"{args.rows} rows: row by row {rows:.3f} s ({args.rows / rows:,.0f} rows/s)")
    print(f"ratio {rows / blocks:.1f}x")


if __name__ == "__main__":
    main()

"""Start-up cost: ``umbmark calibrate`` on the bundled runs table against ``import numpy``.

A tape-measure calibration is microseconds of arithmetic; what a user waits for is the
interpreter starting and the modules loading. This script times, in one run and
interleaved (so that both see the same machine load), whole processes of

- ``python -c "import numpy"``: the floor any numpy program pays;
- ``umbmark calibrate RUNS -L 4 -b 0.34 --unit mm`` (the summary, rich tables) and the
  same with ``--json``, on the bundled example written to a temporary file;
- ``umbmark --help`` and ``python -c pass``, for reference,

and prints the median of each and the ratio to ``import numpy``. Target: calibrate costs
at most 3 times a bare numpy import.

Run: python benchmarks/bench_startup.py [--repeat N]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET = 3.0


def _umbmark() -> str:
    beside = Path(sys.executable).with_name("umbmark")
    found = str(beside) if beside.exists() else shutil.which("umbmark")
    if not found:
        sys.exit("the umbmark command is not installed: pip install -e .")
    return found


def _time(cmd: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15, help="runs of each command")
    args = parser.parse_args()
    umbmark = _umbmark()
    with tempfile.TemporaryDirectory() as tmp:
        runs = Path(tmp) / "runs.csv"
        subprocess.run([umbmark, "example", str(runs)], check=True, capture_output=True)
        calibrate = [umbmark, "calibrate", str(runs), "-L", "4", "-b", "0.34", "--unit", "mm"]
        commands = {
            "python -c pass": [sys.executable, "-c", "pass"],
            "python -c 'import numpy'": [sys.executable, "-c", "import numpy"],
            "umbmark --help": [umbmark, "--help"],
            "umbmark calibrate (summary)": calibrate,
            "umbmark calibrate --json": [*calibrate, "--json"],
        }
        for cmd in commands.values():  # warm the file cache
            _time(cmd)
        times: dict[str, list[float]] = {name: [] for name in commands}
        for _ in range(args.repeat):
            for name, cmd in commands.items():
                times[name].append(_time(cmd))
    median = {name: statistics.median(t) for name, t in times.items()}
    floor = median["python -c 'import numpy'"]
    print(f"start-up, median of {args.repeat} interleaved runs each")
    for name, value in median.items():
        print(f"  {name:<30} {1000 * value:7.0f} ms   {value / floor:4.2f}x import numpy")
    worst = max(median["umbmark calibrate (summary)"], median["umbmark calibrate --json"])
    verdict = "meets" if worst / floor <= TARGET else "MISSES"
    print(f"  calibrate / import numpy: {worst / floor:.2f}x ({verdict} the target of {TARGET:g}x)")


if __name__ == "__main__":
    main()

"""``umbmark info`` on a long bag against the least any tool must do: read every message.

Generates one hour of 100 Hz ``sensor_msgs/JointState`` (360 000 messages; the same bag
as ``bench_bag_ingest.py``) as a ROS 2 sqlite3 bag and as a ROS 1 bag, then times, on
each, in the same process:

(a) a bare rosbags loop: open the bag and iterate every connection's raw messages
    (``for conn, t, raw in reader.messages()``), deserializing nothing: the floor of any
    look into the whole bag;
(b) ``umbmark.info(path)``: topics, types, counts, rates, the wheel joints found and the
    options to pass to ``calibrate`` (it deserializes a sample of each topic).

Prints both times and the ratio (b) / (a): below 1, ``info`` is cheaper than reading the
bag once.

Run: python benchmarks/bench_info.py [--seconds S] [--rate HZ] [--repeat R]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

import umbmark
from bench_bag_ingest import generate

from _timing import best_of


def bare_loop(path: Path) -> int:
    """(a) Every raw message of every connection, counted, none deserialized."""
    count = 0
    with AnyReader([path], default_typestore=get_typestore(Stores.LATEST)) as reader:
        for _conn, _t, _raw in reader.messages(connections=reader.connections):
            count += 1
    return count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3600.0, help="recording length [s]")
    parser.add_argument("--rate", type=float, default=100.0, help="messages per second")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs of each (best)")
    args = parser.parse_args()
    print(f"umbmark info, {args.seconds:g} s of {args.rate:g} Hz JointState")
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in ("sqlite3", "ros1"):
            folder = Path(tmp) / fmt
            folder.mkdir()
            path, n = generate(folder, fmt, args.seconds, args.rate)
            t_bare, count = best_of(lambda p=path: bare_loop(p), repeat=args.repeat)
            t_info, report = best_of(lambda p=path: umbmark.info(p), repeat=args.repeat)
            assert count == n, (count, n)
            suggested = report.suggested_options or ""
            print(f"{fmt}: {n:,} messages")
            print(f"  (a) rosbags: iterate the raw messages   {t_bare:7.3f} s")
            print(
                f"  (b) umbmark.info(path)                  {t_info:7.3f} s   "
                f"ratio (b)/(a) = {t_info / t_bare:5.3f}"
            )
            print(f"  suggested options: {suggested}")


if __name__ == "__main__":
    main()

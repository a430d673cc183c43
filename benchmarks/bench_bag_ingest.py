"""Bag ingestion: umbmark's ``read_bag`` against rosbags' own deserialize-every-message loop.

Generates one bag into a temporary folder (default: one hour of 100 Hz
``sensor_msgs/JointState`` with the two wheel joints, 360 000 messages, ROS 2 sqlite3),
then reads the wheel stamps and positions from it twice:

- rosbags' loop: ``for conn, t, raw in reader.messages(...)``, ``reader.deserialize``,
  then the stamp and the two joints' positions picked out of each message;
- ``umbmark.sources.bag.read_bag``, whose fast path reads fixed-layout messages with
  vectorized numpy views instead of deserializing them.

Both include opening the bag. Also checks that the two produced the same arrays.

Run: python benchmarks/bench_bag_ingest.py [--format ros1|sqlite3|mcap] [--seconds S]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_typestore

from umbmark.sources.bag import BagOptions, read_bag

from _timing import best_of

TOPIC = "/joint_states"
JOINT_STATE = "sensor_msgs/msg/JointState"
LEFT, RIGHT = "left_wheel_joint", "right_wheel_joint"
T0_NS = 1_700_000_000 * 1_000_000_000


def generate(path: Path, fmt: str, seconds: float, rate: float) -> tuple[Path, int]:
    """Write the bag message by message (streaming); return its path and message count."""
    ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
    n = round(seconds * rate)
    Time = ts.types["builtin_interfaces/msg/Time"]
    Header = ts.types["std_msgs/msg/Header"]
    JointState = ts.types[JOINT_STATE]
    if fmt == "ros1":
        path = path / "ingest.bag"
        writer: Writer1 | Writer2 = Writer1(path)
        serialize = ts.serialize_ros1
    else:
        path = path / "ingest"
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
        serialize = ts.serialize_cdr
    step_ns = round(1e9 / rate)
    with writer:
        conn = writer.add_connection(TOPIC, JOINT_STATE, typestore=ts)
        for k in range(n):
            t = k / rate
            stamp_ns = T0_NS + k * step_ns
            sec, nsec = divmod(stamp_ns, 1_000_000_000)
            stamp = Time(sec=sec, nanosec=nsec)
            header = (
                Header(seq=k, stamp=stamp, frame_id="")
                if fmt == "ros1"
                else Header(stamp=stamp, frame_id="")
            )
            msg = JointState(
                header=header,
                name=[LEFT, RIGHT],
                position=np.array([2.0 * t + 0.1 * math.sin(t), 1.9 * t]),
                velocity=np.array([2.0 + 0.1 * math.cos(t), 1.9]),
                effort=np.zeros(0),
            )
            writer.write(conn, stamp_ns + 2_000_000, serialize(msg, JOINT_STATE))
            if k % 20_000 == 0 or k == n - 1:
                print(f"\r  generating: {k + 1:>9,} / {n:,} messages", end="", flush=True)
    print()
    return path, n


def rosbags_loop(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Stamps [s] and wheel positions [rad] by deserializing every message."""
    times: list[float] = []
    angles: list[tuple[float, float]] = []
    with AnyReader([path], default_typestore=get_typestore(Stores.LATEST)) as reader:
        conns = [c for c in reader.connections if c.topic == TOPIC]
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            names = msg.name
            i, j = names.index(LEFT), names.index(RIGHT)
            stamp = msg.header.stamp
            times.append(stamp.sec + stamp.nanosec * 1e-9)
            position = msg.position
            angles.append((float(position[i]), float(position[j])))
    return np.array(times), np.array(angles)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--format", choices=["ros1", "sqlite3", "mcap"], default="sqlite3")
    parser.add_argument("--seconds", type=float, default=3600.0, help="recording length [s]")
    parser.add_argument("--rate", type=float, default=100.0, help="messages per second")
    parser.add_argument("--repeat", type=int, default=1, help="timed runs of each (best)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        print(f"bag ingestion, {args.format}, {args.seconds:g} s of {args.rate:g} Hz JointState")
        path, n = generate(Path(tmp), args.format, args.seconds, args.rate)

        t_loop, (ref_time, ref_angles) = best_of(lambda: rosbags_loop(path), repeat=args.repeat)
        t_read, (wheels, _) = best_of(lambda: read_bag(path, BagOptions()), repeat=args.repeat)

        same = np.array_equal(wheels.time, ref_time) and np.array_equal(wheels.angles, ref_angles)
        rate_loop, rate_read = n / t_loop, n / t_read
        print(f"  rosbags deserialize loop  {rate_loop:12,.0f} messages/s   ({t_loop:7.2f} s)")
        print(
            f"  umbmark read_bag          {rate_read:12,.0f} messages/s   ({t_read:7.2f} s)"
            f"   ratio {rate_read / rate_loop:5.1f}x"
        )
        print(f"  same arrays: {'yes' if same else 'NO'} ({wheels.time.size:,} samples)")
        if not same:
            sys.exit(1)


if __name__ == "__main__":
    main()

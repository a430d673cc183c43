"""Bag ingestion: umbmark's ``read_bag`` and its decoder against rosbags' deserializer.

Generates one bag into a temporary folder (default: one hour of 100 Hz
``sensor_msgs/JointState`` with the two wheel joints, 360 000 messages, ROS 2 sqlite3),
then reads the wheel stamps and positions from that same bag three ways:

(a) rosbags' loop: ``for conn, t, raw in reader.messages(...)``, ``reader.deserialize``,
    then the stamp and the two joints' positions picked out of each message; opening the
    bag included;
(b) ``umbmark.sources.bag.recording.read_bag``, whose fast path reads fixed-layout messages with
    vectorized numpy views instead of deserializing them; opening the bag included;
(c) the decoders alone, on the same list of raw messages already read from the bag:
    rosbags' ``reader.deserialize`` plus picking the fields, against
    ``umbmark.sources.bag.fastpath.decode_messages``. Its ratio is the part of the
    speed-up the decoder is responsible for; the rest of (a) and (b) is reading the bag.

Prints messages per second, the ratios, the share of (a) that deserialization takes,
and checks that (a) and (b), and the two decoders of (c), produced the same arrays.

Run: python benchmarks/bench_bag_ingest.py [--format ros1|sqlite3|mcap] [--seconds S]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_typestore

from umbmark.sources.bag import fastpath
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import read_bag

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


def pick(msg: Any) -> tuple[int, int, float, float]:
    """Stamp ``sec, nanosec`` and the two wheel joints' positions of a JointState."""
    names = msg.name
    i, j = names.index(LEFT), names.index(RIGHT)
    stamp = msg.header.stamp
    position = msg.position
    return stamp.sec, stamp.nanosec, float(position[i]), float(position[j])


def rosbags_loop(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(a) Stamps [s] and wheel positions [rad] by deserializing every message."""
    times: list[float] = []
    angles: list[tuple[float, float]] = []
    with AnyReader([path], default_typestore=get_typestore(Stores.LATEST)) as reader:
        conns = [c for c in reader.connections if c.topic == TOPIC]
        for conn, _, raw in reader.messages(connections=conns):
            sec, nsec, left, right = pick(reader.deserialize(raw, conn.msgtype))
            times.append(sec + nsec * 1e-9)
            angles.append((left, right))
    return np.array(times), np.array(angles)


def decoders_alone(path: Path, repeat: int) -> tuple[float, float, bool, int]:
    """(c) Time rosbags' deserializer and umbmark's decoder on the same raw messages.

    Returns the two times [s], whether they gave the same stamps and values, and how many
    messages the decoder deserialized (the first, to check its layout).
    """
    with AnyReader([path], default_typestore=get_typestore(Stores.LATEST)) as reader:
        conns = [c for c in reader.connections if c.topic == TOPIC]
        raws = [(t, raw) for _, t, raw in reader.messages(connections=conns)]

        def deserializer() -> np.ndarray:
            rows = [pick(reader.deserialize(raw, JOINT_STATE)) for _, raw in raws]
            return np.array(rows, dtype=np.float64)

        def decode(raw: bytes) -> list[fastpath.Sample]:
            sec, nsec, left, right = pick(reader.deserialize(raw, JOINT_STATE))
            return [(sec, nsec, (left, right), fastpath.POSITION)]

        def decoder() -> fastpath.Decoded:
            return fastpath.decode_messages(
                raws,
                ros2=bool(reader.is2),
                width=2,
                decode=decode,
                layout_of=fastpath.fast_layout(JOINT_STATE, (LEFT, RIGHT)),
            )

        t_deser, ref = best_of(deserializer, repeat=repeat)
        t_fast, got = best_of(decoder, repeat=repeat)
    same = (
        np.array_equal(got.sec, ref[:, 0].astype(np.int64))
        and np.array_equal(got.nsec, ref[:, 1].astype(np.int64))
        and np.array_equal(got.values, ref[:, 2:])
    )
    return t_deser, t_fast, same, got.deserialized


def rate_line(label: str, n: int, seconds: float, ratio: str = "") -> str:
    return f"  {label:<34}{n / seconds:12,.0f} messages/s  ({seconds:7.3f} s){ratio}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--format", choices=["ros1", "sqlite3", "mcap"], default="sqlite3")
    parser.add_argument("--seconds", type=float, default=3600.0, help="recording length [s]")
    parser.add_argument("--rate", type=float, default=100.0, help="messages per second")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs of each (best)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        print(f"bag ingestion, {args.format}, {args.seconds:g} s of {args.rate:g} Hz JointState")
        path, n = generate(Path(tmp), args.format, args.seconds, args.rate)

        t_loop, (ref_time, ref_angles) = best_of(lambda: rosbags_loop(path), repeat=args.repeat)
        t_read, (wheels, _) = best_of(lambda: read_bag(path, BagOptions()), repeat=args.repeat)
        t_deser, t_fast, same_decoded, deserialized = decoders_alone(path, args.repeat)

        same_read = np.array_equal(wheels.time, ref_time) and np.array_equal(
            wheels.angles, ref_angles
        )
        print("(a, b) end to end, opening the bag included")
        print(rate_line("rosbags read + deserialize loop", n, t_loop))
        print(rate_line("umbmark read_bag", n, t_read, f"   {t_loop / t_read:5.1f}x faster"))
        print("(c) decoding alone, the same raw messages in memory")
        print(rate_line("rosbags deserialize + pick", n, t_deser))
        ratio = f"   {t_deser / t_fast:5.1f}x faster"
        print(rate_line("umbmark fastpath.decode_messages", n, t_fast, ratio))
        print(
            f"  deserializing is {100 * t_deser / t_loop:.0f} % of the loop (a);"
            f" the decoder deserialized {deserialized:,} of {n:,} messages"
        )
        samples = wheels.time.size
        print(f"  same arrays (a) = (b): {'yes' if same_read else 'NO'} ({samples:,} samples)")
        print(f"  same arrays, decoders of (c): {'yes' if same_decoded else 'NO'}")
        if not (same_read and same_decoded):
            sys.exit(1)


if __name__ == "__main__":
    main()

"""Wheels in a custom message type: umbmark's ``read_bag`` against rosbags' deserializer.

Generates one ROS 2 sqlite3 bag (default 300 000 messages) of a vendor's wheel message,
``my_robot_msgs/msg/WheelEncoders`` (the type of ``tests/sources/test_bag_custom.py``: a header,
two int32 tick counts, a float64[] of positions, a fixed array of nested states, a
string), registered in the writer's typestore from its ``.msg`` text, then reads the
stamps and both wheels' positions from it two ways, in the same process:

(a) rosbags' loop: open the bag, ``reader.deserialize`` every message, pick the stamp and
    ``positions[0]``, ``positions[1]``;
(b) ``umbmark.sources.bag.recording.read_bag`` with ``--wheel-topic /wheels --left-field
    positions[0] --right-field positions[1]``: what ``calibrate`` runs for those options.

Prints messages per second and the time ratio (b) / (a) (above 1: umbmark is slower),
and checks that both gave the same arrays.

Run: python benchmarks/bench_custom_messages.py [--messages N] [--repeat R]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import read_bag

from _timing import best_of

ENCODERS = "my_robot_msgs/msg/WheelEncoders"
STATE = "my_robot_msgs/msg/WheelState"
MSG = {
    ENCODERS: (
        "std_msgs/Header header\n"
        "int32 left_ticks\n"
        "int32 right_ticks\n"
        "float64[] positions\n"
        "WheelState[2] wheels\n"
        "string note\n"
    ),
    STATE: "float64 position\nint16 counter\n",
}
TOPIC = "/wheels"
RATE = 100.0  # messages per second
T0_NS = 1_700_000_000 * 1_000_000_000
TICKS_PER_REV = 4096


def generate(path: Path, n: int) -> Path:
    """Write ``n`` WheelEncoders messages at 100 Hz, streaming."""
    ts = get_typestore(Stores.LATEST)
    for name in (STATE, ENCODERS):
        ts.register(get_types_from_msg(MSG[name], name))
    types = ts.types
    step_ns = round(1e9 / RATE)
    with Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
        conn = writer.add_connection(TOPIC, ENCODERS, typestore=ts)
        for k in range(n):
            t = k / RATE
            left, right = 0.8 * t + 0.3 * math.sin(t), 1.1 * t
            stamp_ns = T0_NS + k * step_ns
            sec, nsec = divmod(stamp_ns, 1_000_000_000)
            header = types["std_msgs/msg/Header"](
                stamp=types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec),
                frame_id="base_link",
            )
            ticks = [round(a * TICKS_PER_REV / (2 * math.pi)) for a in (left, right)]
            msg = types[ENCODERS](
                header=header,
                left_ticks=ticks[0],
                right_ticks=ticks[1],
                positions=np.array([left, right]),
                wheels=[
                    types[STATE](position=left, counter=ticks[0] % 32768),
                    types[STATE](position=right, counter=ticks[1] % 32768),
                ],
                note="ok",
            )
            writer.write(conn, stamp_ns + 2_000_000, ts.serialize_cdr(msg, ENCODERS))
            if k % 20_000 == 0 or k == n - 1:
                print(f"\r  generating: {k + 1:>9,} / {n:,} messages", end="", flush=True)
    print()
    return path


def rosbags_loop(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(a) Stamps [s] and the two positions [rad], deserializing every message."""
    times: list[float] = []
    angles: list[tuple[float, float]] = []
    with AnyReader([path]) as reader:  # the bag carries the type's definition
        conns = [c for c in reader.connections if c.topic == TOPIC]
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            stamp = msg.header.stamp
            times.append(stamp.sec + stamp.nanosec * 1e-9)
            angles.append((float(msg.positions[0]), float(msg.positions[1])))
    return np.array(times), np.array(angles)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=300_000, help="wheel messages")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs of each (best)")
    args = parser.parse_args()
    n = args.messages
    options = BagOptions(wheel_topic=TOPIC, left_field="positions[0]", right_field="positions[1]")
    with tempfile.TemporaryDirectory() as tmp:
        print(f"custom wheel messages ({ENCODERS}), ROS 2 sqlite3, {n:,} messages")
        path = generate(Path(tmp) / "custom", n)
        t_loop, (ref_time, ref_angles) = best_of(lambda: rosbags_loop(path), repeat=args.repeat)
        t_read, (wheels, _) = best_of(lambda: read_bag(path, options), repeat=args.repeat)
        same = np.array_equal(wheels.time, ref_time) and np.array_equal(wheels.angles, ref_angles)
        print(
            f"  (a) rosbags read + deserialize loop   {n / t_loop:10,.0f} messages/s"
            f"  ({t_loop:6.3f} s)"
        )
        print(
            f"  (b) umbmark read_bag --left-field     {n / t_read:10,.0f} messages/s"
            f"  ({t_read:6.3f} s)   time ratio (b)/(a) = {t_read / t_loop:4.2f}"
        )
        print(f"  same arrays: {'yes' if same else 'NO'} ({wheels.time.size:,} samples)")
        if not same:
            sys.exit(1)


if __name__ == "__main__":
    main()

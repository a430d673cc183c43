"""Reading an IMU from a bag: the time and the peak memory against the recording's length,
the whole recording at once against windows (``umbmark.sources.bag.imu.read_imu``).

Generates, into a temporary folder, one bag per length (default 10, 30 and 60 minutes)
with a 200 Hz ``sensor_msgs/Imu`` (``/imu`` in ``imu_link``, its mounting on
``/tf_static``) and 50 Hz ``sensor_msgs/JointState`` wheels (``/joint_states``), written
message by message with rosbags. Then, each in a fresh process (so that its peak resident
memory is its own), side by side on the same bag:

(a) the IMU read whole: ``read_imu(bag, BagOptions(imu_topic="/imu"))``;
(b) the IMU read in windows of ``--window`` seconds (default 300, ``scans.bag.WINDOW``),
    the bag opened once: ``read_imu_windows``, keeping only each window's yaw integral (as
    a calibration that matches intervals window by window does);
(c) the same windows, the bag opened again for each: ``time_windows`` and
    ``read_imu(..., window=w)`` (what opening a bag costs: it reads its index);
(d) the wheels read whole (``read_recording``), the other half of what the calibration
    reads.

The times leave out Python's start and the imports (rosbags' too), which a command pays
once.

Prints, per length: the IMU's messages, the seconds and the peak resident memory [MB] of
each (the process's ``ru_maxrss``, less the same process's after its imports), and the
ratios: windowed over whole (time, memory) and the IMU over the wheels (time).

Run: python benchmarks/bench_imu_read.py [--minutes 10,30,60] [--format mcap|sqlite3|ros1]
[--window 300]
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

IMU_RATE, WHEEL_RATE = 200.0, 50.0
T0_NS = 1_700_000_000 * 1_000_000_000


def generate(folder: Path, fmt: str, minutes: float) -> Path:
    """Write the bag (streaming, message by message); its path."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.rosbag2.enums import StoragePlugin
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
    if fmt == "ros1":
        from rosbags.typesys import get_types_from_msg

        ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms",
                                       "tf2_msgs/msg/TFMessage"))  # fmt: skip
    T = ts.types
    path = folder / (f"imu{minutes:g}.bag" if fmt == "ros1" else f"imu{minutes:g}")
    if fmt == "ros1":
        writer = Writer1(path)
        serialize = ts.serialize_ros1
    else:
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
        serialize = ts.serialize_cdr

    def header(ns: int, frame: str):
        sec, nsec = divmod(ns, 1_000_000_000)
        stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        if fmt == "ros1":
            return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    vector, quat = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    cov, none = np.zeros(9), np.r_[-1.0, np.zeros(8)]
    seconds = 60.0 * minutes
    n_imu, per_wheel = round(seconds * IMU_RATE), round(IMU_RATE / WHEEL_RATE)
    rng = np.random.default_rng(1)
    with writer:
        imu = writer.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=ts)
        js = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=ts)
        static = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        mount = T["geometry_msgs/msg/TransformStamped"](
            header=header(T0_NS, "base_link"), child_frame_id="imu_link",
            transform=T["geometry_msgs/msg/Transform"](
                translation=vector(x=0.0, y=0.0, z=0.1), rotation=quat(x=1.0, y=0.0, z=0.0, w=0.0)
            ),
        )  # fmt: skip
        writer.write(static, T0_NS, serialize(T["tf2_msgs/msg/TFMessage"](transforms=[mount]),
                                              "tf2_msgs/msg/TFMessage"))  # fmt: skip
        for start in range(0, n_imu, 20_000):
            k = np.arange(start, min(start + 20_000, n_imu))
            t = k / IMU_RATE
            w = np.column_stack([0.01 * np.sin(t), 0.01 * np.cos(t), 0.5 * np.sin(0.1 * t)])
            w += rng.normal(0.0, 1e-3, w.shape)
            for i, kk in enumerate(k.tolist()):
                ns = T0_NS + round(kk * 1e9 / IMU_RATE)
                msg = T["sensor_msgs/msg/Imu"](
                    header=header(ns, "imu_link"), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0),
                    orientation_covariance=none, angular_velocity=vector(x=w[i, 0], y=w[i, 1],
                    z=w[i, 2]), angular_velocity_covariance=cov,
                    linear_acceleration=vector(x=0.0, y=0.0, z=-9.81),
                    linear_acceleration_covariance=cov,
                )  # fmt: skip
                writer.write(imu, ns, serialize(msg, "sensor_msgs/msg/Imu"))
                if kk % per_wheel == 0:
                    angle = 2.0 * kk / IMU_RATE
                    state = T["sensor_msgs/msg/JointState"](
                        header=header(ns, ""), name=["left_wheel_joint", "right_wheel_joint"],
                        position=np.array([angle, 1.01 * angle]), velocity=np.zeros(0),
                        effort=np.zeros(0),
                    )  # fmt: skip
                    writer.write(js, ns, serialize(state, "sensor_msgs/msg/JointState"))
    return path


def child(mode: str, path: str, window: float) -> None:
    """One measurement in this process: prints seconds and peak memory [MB] as JSON."""
    import rosbags.highlevel
    import rosbags.typesys  # noqa: F401

    from umbmark.sources.bag.bag_options import BagOptions
    from umbmark.sources.bag.imu import read_imu, read_imu_windows
    from umbmark.sources.bag.reader import time_windows
    from umbmark.sources.bag.recording import read_recording

    options = BagOptions(imu_topic="/imu")
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    start = time.perf_counter()
    if mode == "whole":
        gyro = read_imu(path, options).gyro
        samples, total = len(gyro), float(gyro.yaw_change(gyro.time[:1], gyro.time[-1:])[0])
    elif mode == "windows":
        samples, total = 0, 0.0
        for read in read_imu_windows(path, options, window):
            gyro = read.gyro
            samples += len(gyro)
            total += float(gyro.yaw_change(gyro.time[:1], gyro.time[-1:])[0])
    elif mode == "reopened":
        samples, total = 0, 0.0
        for span in time_windows(Path(path), path, window):
            gyro = read_imu(path, options, window=span).gyro
            samples += len(gyro)
            total += float(gyro.yaw_change(gyro.time[:1], gyro.time[-1:])[0])
    else:
        samples, total = len(read_recording(path, BagOptions()).wheels.time), 0.0
    seconds = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"seconds": seconds, "peak": peak - before, "samples": samples,
                      "yaw": total}))  # fmt: skip


def measure(mode: str, path: Path, window: float) -> dict[str, float]:
    done = subprocess.run(
        [sys.executable, __file__, "--child", mode, str(path), "--window", str(window)],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    return dict(json.loads(done.stdout))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--minutes", default="10,30,60")
    parser.add_argument("--format", default="mcap", choices=["mcap", "sqlite3", "ros1"])
    parser.add_argument("--window", type=float, default=300.0)
    parser.add_argument("--child", nargs=2, metavar=("MODE", "BAG"))
    args = parser.parse_args()
    if args.child:
        child(args.child[0], args.child[1], args.window)
        return
    print(f"IMU {IMU_RATE:g} Hz and wheels {WHEEL_RATE:g} Hz, {args.format}, windows of "
          f"{args.window:g} s; each read in a fresh process, memory: peak RSS over its "
          "imports")  # fmt: skip
    print(f"{'min':>4} {'IMU msgs':>9} | {'whole s':>8} {'MB':>6} | {'windows s':>9} {'MB':>6} | "
          f"{'reopened s':>10} | {'wheels s':>8} | {'win/whole time':>14} {'win/whole MB':>12} "
          f"{'reopened/win':>12} {'IMU/wheels':>10}")  # fmt: skip
    with tempfile.TemporaryDirectory() as folder:
        for minutes in (float(m) for m in args.minutes.split(",")):
            path = generate(Path(folder), args.format, minutes)
            whole = measure("whole", path, args.window)
            windows = measure("windows", path, args.window)
            reopened = measure("reopened", path, args.window)
            wheels = measure("wheels", path, args.window)
            assert whole["samples"] == windows["samples"] == round(60 * minutes * IMU_RATE)
            assert reopened["samples"] == windows["samples"]
            assert math.isclose(whole["yaw"], windows["yaw"], rel_tol=1e-2, abs_tol=1e-2)
            print(
                f"{minutes:4g} {int(whole['samples']):9d} | {whole['seconds']:8.2f} "
                f"{whole['peak']:6.0f} | {windows['seconds']:9.2f} {windows['peak']:6.0f} | "
                f"{reopened['seconds']:10.2f} | {wheels['seconds']:8.2f} | "
                f"{windows['seconds'] / whole['seconds']:14.2f} "
                f"{windows['peak'] / max(whole['peak'], 1.0):12.2f} "
                f"{reopened['seconds'] / windows['seconds']:12.2f} "
                f"{whole['seconds'] / wheels['seconds']:10.2f}"
            )
            for p in sorted(path.glob("*")) if path.is_dir() else [path]:
                p.unlink()


if __name__ == "__main__":
    main()

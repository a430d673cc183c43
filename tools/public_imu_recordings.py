"""The gyro calibration on the public recordings of real wheeled robots with an IMU.

Each recording below is a ROS bag that a public repository ships as test data, read with
umbmark's readers (the wheels through the bag readers, the IMU through
``umbmark.sources.bag.imu.read_imu``) and calibrated with the gyro
(``umbmark.calibration.gyro.calibrate_gyro``); where a recording holds a laser
(``scan_topic``), also with scan matching alone and with both together (the scan
intervals as the gyro calibration's reference). It prints one table row per recording.

None of these files can be had from a package registry: get them from their repositories
(a clone, or ``git cat-file -p BLOB`` in one), into any folder outside this repository::

    git clone https://github.com/cra-ros-pkg/robot_localization
    git clone https://github.com/ros-planning/navigation
    python tools/public_imu_recordings.py robot_localization/test/test1.bag \\
        navigation/robot_pose_ekf/test/gps_data.bag

Each file is known by its git blob id (SHA-1 of ``blob SIZE\\0`` and its bytes), so a
changed copy is refused. Where the IMU's mounting is stated outside the bag (in the
repository's launch file), a copy of the bag with that mounting on ``/tf_static`` is
written into a temporary folder (``--work`` to keep it elsewhere), never next to the
original.
"""

from __future__ import annotations

import argparse
import hashlib
import math
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from umbmark.calibration.gyro import GyroResult, calibrate_gyro
from umbmark.core.errors import InputError
from umbmark.model.kinematics import OdometryGeometry
from umbmark.runs.read_options import ReadOptions
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.imu import ImuRead, read_imu
from umbmark.sources.bag.recording import read_recording

#: A Husky's wheel diameter [m] (13 in tyres: husky_description's wheel radius 0.1651 m)
#: and its wheel separation [m] (husky_description 0.555 m), and the separation
#: multiplier of Clearpath's husky_control (1.875: its odometry turns with 1.04 m).
HUSKY_DIAMETER = 0.3302
HUSKY_SEPARATION = 0.555
HUSKY_MULTIPLIER = 1.875


@dataclass(frozen=True)
class Mounting:
    """An IMU's mounting stated outside the bag: ``parent -> child``, translation [m]
    and roll, pitch, yaw [rad] (``static_transform_publisher``'s ``yaw pitch roll``)."""

    parent: str
    child: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    stated_in: str


@dataclass(frozen=True)
class Recording:
    """A public recording and how umbmark reads it."""

    name: str
    repository: str
    path: str
    blob: str
    robot: str
    bag: BagOptions
    wheel_diameter: float
    wheelbase: float
    mounting: Mounting | None = None
    scan_topic: str | None = None


RECORDINGS = (
    Recording(
        name="parking lot",
        repository="cra-ros-pkg/robot_localization",
        path="test/test1.bag",
        blob="565f14c8e555135ae5c7274fc6855675fb201dab",
        robot="Clearpath Husky, MicroStrain 3DM-GX2 IMU at 30 Hz, its controller's odometry "
        "at 10 Hz, GPS; 2015, 395 s, 359 m around a parking lot",
        bag=BagOptions(
            odom_topic="/husky_velocity_controller/odom",
            odom_geometry=OdometryGeometry(
                HUSKY_DIAMETER / 2, HUSKY_DIAMETER / 2, HUSKY_SEPARATION * HUSKY_MULTIPLIER
            ),
            imu_topic="/imu/data",
        ),
        wheel_diameter=HUSKY_DIAMETER,
        wheelbase=HUSKY_SEPARATION * HUSKY_MULTIPLIER,
        # test/test_ekf_localization_node_bag1.test: "0 -0.3 0.52 -1.570796327 0
        # 1.570796327 base_link imu_link" (x y z yaw pitch roll): "rotated +90 degrees about
        # the X axis, then (extrinsically) -90 degrees about the Z axis"
        mounting=Mounting(
            "base_link",
            "imu_link",
            (0.0, -0.3, 0.52),
            (math.pi / 2, 0.0, -math.pi / 2),
            "test/test_ekf_localization_node_bag1.test",
        ),
    ),
    Recording(
        name="circles",
        repository="ros-planning/navigation",
        path="robot_pose_ekf/test/gps_data.bag",
        blob="d35e6a8bb1727f1e5048ab4dbe00a25b8298c510",
        robot="Clearpath Husky, IMU at 8.3 Hz (mounting on /tf), each side's encoder travel "
        "at 10 Hz; 2013, 38 s of circles to the right",
        # clearpath_base/Encoders: travel [m] of the left, then the right side; read as
        # encoder counts of pi * D per revolution, the angle is travel / (D / 2)
        bag=BagOptions(
            wheel_topic="/husky/data/encoders",
            left_field="encoders[0].travel",
            right_field="encoders[1].travel",
            ticks_per_rev=math.pi * HUSKY_DIAMETER,
            imu_topic="/imu/data",
        ),
        wheel_diameter=HUSKY_DIAMETER,
        wheelbase=HUSKY_SEPARATION,
    ),
)


@dataclass(frozen=True)
class Calibrated:
    """What one recording gave."""

    recording: Recording
    imu: ImuRead
    gyro: GyroResult
    scan: dict[str, float] | None = None
    joint: GyroResult | None = None


def blob_id(path: Path) -> str:
    """The file's git blob id (what ``git hash-object`` prints)."""
    data = path.read_bytes()
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


def recording_of(path: Path) -> Recording:
    """The recording a file is, by its blob id; another file is one line."""
    found = blob_id(path)
    for rec in RECORDINGS:
        if rec.blob == found:
            return rec
    known = ", ".join(f"{r.repository} {r.path}" for r in RECORDINGS)
    raise InputError(
        f"not one of the recordings known here ({known}): blob {found}", source=str(path)
    )


def with_mounting(source: Path, target: Path, mounting: Mounting) -> Path:
    """A copy of the ROS 1 bag ``source`` at ``target`` with ``mounting`` on ``/tf_static``
    (one latched message at the bag's start); every other message as it was."""
    from rosbags.rosbag1 import Reader, Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from umbmark.sources.bag.msgtypes import TF_MESSAGE, TF_STATIC_TOPIC
    from umbmark.sources.bag.writer import TF_DEFINITION

    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg(TF_DEFINITION, TF_MESSAGE))
    t = store.types
    roll, pitch, yaw = (0.5 * a for a in mounting.rpy)
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    rotation = t["geometry_msgs/msg/Quaternion"](
        x=sr * cp * cy - cr * sp * sy,
        y=cr * sp * cy + sr * cp * sy,
        z=cr * cp * sy - sr * sp * cy,
        w=cr * cp * cy + sr * sp * sy,
    )
    with Reader(source) as reader, Writer(target) as writer:
        start = reader.start_time
        sec, nanosec = divmod(start, 1_000_000_000)
        header = t["std_msgs/msg/Header"](
            seq=0, stamp=t["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec),
            frame_id=mounting.parent,
        )  # fmt: skip
        x, y, z = mounting.xyz
        message = t[TF_MESSAGE](
            transforms=[
                t["geometry_msgs/msg/TransformStamped"](
                    header=header,
                    child_frame_id=mounting.child,
                    transform=t["geometry_msgs/msg/Transform"](
                        translation=t["geometry_msgs/msg/Vector3"](x=x, y=y, z=z),
                        rotation=rotation,
                    ),
                )
            ]
        )
        static = writer.add_connection(TF_STATIC_TOPIC, TF_MESSAGE, typestore=store, latching=1)
        writer.write(static, start, store.serialize_ros1(message, TF_MESSAGE))
        copies = {
            c.id: writer.add_connection(
                c.topic,
                c.msgtype,
                msgdef=c.msgdef.data,
                md5sum=c.digest,
                callerid=c.ext.callerid,
                latching=c.ext.latching,
            )
            for c in reader.connections
        }
        for conn, stamp, raw in reader.messages():
            writer.write(copies[conn.id], stamp, raw)
    return target


def prepared(path: Path, rec: Recording, work: Path) -> Path:
    """The bag to read: the file itself, or its copy with the stated mounting."""
    if rec.mounting is None:
        return path
    return with_mounting(path, work / f"{Path(rec.path).stem}-mounted.bag", rec.mounting)


def calibrate(path: Path, rec: Recording) -> Calibrated:
    """The recording read and calibrated with its gyro (and its laser, where it has one)."""
    read = read_recording(path, rec.bag)
    imu = read_imu(path, rec.bag)
    options = ReadOptions(wheel_diameter=rec.wheel_diameter)
    where = f"{rec.repository} {rec.path}"
    gyro = calibrate_gyro(
        read.wheels, imu.gyro, options, wheelbase=rec.wheelbase, source=where,
        notes=(*read.notes, *imu.notes),
    )  # fmt: skip
    if rec.scan_topic is None:
        return Calibrated(rec, imu, gyro)
    from umbmark.calibration.scan import calibrate_intervals
    from umbmark.scans.bag import intervals_from_bag
    from umbmark.scans.intervals import IntervalOptions, OdometryGuess

    radius = rec.wheel_diameter / 2
    guess = OdometryGuess(radius, radius, rec.wheelbase)
    intervals = intervals_from_bag(path, rec.scan_topic, rec.bag, IntervalOptions(guess=guess))
    scan = calibrate_intervals([intervals], options, "scan-matching", wheelbase=rec.wheelbase)
    data = scan.to_dict()
    figures = {k: data[k] for k in ("E_d", "E_b") if data.get(k) is not None}
    figures |= {f"se_{k}": v for k, v in data["standard_errors"].items() if k in ("E_d", "E_b")}
    joint = calibrate_gyro(
        read.wheels, imu.gyro, options, wheelbase=rec.wheelbase, reference=intervals,
        source=where,
    )  # fmt: skip
    return Calibrated(rec, imu, gyro, figures, joint)


def _figure(
    values: dict[str, float], errors: dict[str, float], name: str, scale: float = 1.0
) -> str:
    if name not in values:
        return "not determined"
    return f"{scale * values[name]:.4f} ± {scale * errors[name]:.4f}"


def row(done: Calibrated) -> list[str]:
    """The table's cells of one recording."""
    g = done.gyro.gyro
    v, se = g.values, g.standard_errors
    deg = math.degrees(1.0)
    data = done.gyro.gyro.to_dict()
    cells = [
        f"{done.recording.repository} `{done.recording.path}`",
        f"{data['n_intervals']} ({data['n_rests']} rests)",
        _figure(v, se, "E_d"),
        _figure(v, se, "E_b_k_g"),
        _figure(v, se, "k_g"),
        _figure(v, se, "bias", deg),
        done.gyro.verdict.level,
    ]
    if done.scan is not None and done.joint is not None:
        j = done.joint.gyro
        cells += [
            f"{done.scan.get('E_b', math.nan):.4f} ± {done.scan.get('se_E_b', math.nan):.4f}",
            _figure(j.values, j.standard_errors, "E_b"),
            _figure(j.values, j.standard_errors, "k_g"),
        ]
    else:
        cells += ["no laser", "", ""]
    return cells


HEAD = [
    "recording",
    "intervals",
    "E_d",
    "E_b k_g (gyro)",
    "k_g",
    "bias [deg/s]",
    "verdict",
    "E_b (scan matching)",
    "E_b (joint)",
    "k_g (joint)",
]


def table(rows: Sequence[list[str]]) -> str:
    """A Markdown table of the rows."""
    lines = ["| " + " | ".join(HEAD) + " |", "|" + "---|" * len(HEAD)]
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bags", type=Path, nargs="+", help="the recordings' files")
    parser.add_argument("--work", type=Path, help="where mounted copies go (a temporary folder)")
    args = parser.parse_args()
    rows, said = [], []
    with tempfile.TemporaryDirectory(prefix="umbmark-public-imu-") as temporary:
        work = args.work or Path(temporary)
        for path in args.bags:
            try:
                rec = recording_of(path)
                done = calibrate(prepared(path, rec, work), rec)
            except (InputError, OSError) as err:
                print(f"error: {err}", file=sys.stderr)
                return 2
            rows.append(row(done))
            said += [f"{rec.repository} {rec.path}: {rec.robot}"]
            said += [f"  {line}" for line in done.gyro.result.warnings]
            warned = " ".join(done.gyro.result.warnings)
            for name, why in done.gyro.gyro.undetermined.items():
                if f"{name} is not determined" not in warned:
                    said.append(f"  {name} not determined: {why}")
    print(table(rows))
    print()
    print("\n".join(said))
    return 0


if __name__ == "__main__":
    sys.exit(main())

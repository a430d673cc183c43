"""ROS bags: real bags written with rosbags' writers, read back with ``read_bag``.

Every expected value comes from what the test wrote (known trajectories, hand-built
quaternions), never from the code under test.
"""

from __future__ import annotations

import itertools
import math
import sys
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from umbmark.core.errors import InputError
from umbmark.sources.bag import fastpath
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import bag_topics, read_bag

TS2 = get_typestore(Stores.LATEST)
TS1 = get_typestore(Stores.ROS1_NOETIC)
# Noetic's store has no tf2_msgs; ROS 1 bags carry this definition.
TS1.register(
    get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
)

FORMATS = ["ros1", "sqlite3", "mcap"]
JS = "sensor_msgs/msg/JointState"
POSE = "geometry_msgs/msg/PoseStamped"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
ODOM = "nav_msgs/msg/Odometry"
TF = "tf2_msgs/msg/TFMessage"
LEFT, RIGHT = "left_wheel_joint", "right_wheel_joint"
T0 = 1_700_000_000  # epoch seconds of the first stamp


# --- writing bags ---------------------------------------------------------------------


def ts_for(fmt: str):
    return TS1 if fmt == "ros1" else TS2


def write_bag(
    tmp_path: Path,
    fmt: str,
    topics: dict[str, str],
    messages: Iterable[tuple[str, int, object]],
    name: str = "test",
) -> Path:
    """Write ``(topic, bag time [ns], message)`` (objects, or serialized bytes) to a bag."""
    ts = ts_for(fmt)
    if fmt == "ros1":
        path = tmp_path / f"{name}.bag"
        writer: Writer1 | Writer2 = Writer1(path)
    else:
        path = tmp_path / name
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    with writer:
        conns = {
            topic: writer.add_connection(topic, typ, typestore=ts) for topic, typ in topics.items()
        }
        for topic, bag_ns, msg in messages:
            if isinstance(msg, (bytes, memoryview)):
                raw = msg
            elif fmt == "ros1":
                raw = ts.serialize_ros1(msg, topics[topic])
            else:
                raw = ts.serialize_cdr(msg, topics[topic])
            writer.write(conns[topic], bag_ns, raw)
    return path


def header(fmt: str, sec: int, nsec: int, frame: str = "base_link"):
    ts = ts_for(fmt)
    stamp = ts.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
    if fmt == "ros1":
        return ts.types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
    return ts.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)


def joint_state(
    fmt: str,
    sec: int,
    nsec: int,
    names: Sequence[str],
    position: Sequence[float] = (),
    velocity: Sequence[float] = (),
    frame: str = "",
):
    return ts_for(fmt).types[JS](
        header=header(fmt, sec, nsec, frame),
        name=list(names),
        position=np.array(position, np.float64),
        velocity=np.array(velocity, np.float64),
        effort=np.array([], np.float64),
    )


def split(t: float) -> tuple[int, int]:
    """Stamp seconds and nanoseconds of ``T0 + t`` (``t`` [s] rounded to nanoseconds)."""
    sec, nsec = divmod(round(t * 1e9), 1_000_000_000)
    return T0 + sec, nsec


def stamp_seconds(sec: int, nsec: int) -> float:
    return sec + nsec * 1e-9


def ns(t: float) -> int:
    """Bag time [ns] of ``T0 + t``, in integers (float seconds since 1970 lose digits)."""
    return T0 * 1_000_000_000 + round(t * 1e9)


def quat_yaw_roll(yaw: float, roll: float = 0.0) -> tuple[float, float, float, float]:
    """``x, y, z, w`` of a rotation by ``yaw`` about z after ``roll`` about x (by hand)."""
    sz, cz = math.sin(yaw / 2), math.cos(yaw / 2)
    sr, cr = math.sin(roll / 2), math.cos(roll / 2)
    # q_yaw * q_roll, q_yaw = (0, 0, sz, cz), q_roll = (sr, 0, 0, cr)
    return cz * sr, sz * sr, sz * cr, cz * cr


def pose_msg(fmt: str, typ: str, sec: int, nsec: int, x: float, y: float, yaw: float):
    ts = ts_for(fmt)
    qx, qy, qz, qw = quat_yaw_roll(yaw, roll=0.1)
    pose = ts.types["geometry_msgs/msg/Pose"](
        position=ts.types["geometry_msgs/msg/Point"](x=x, y=y, z=0.25),
        orientation=ts.types["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
    )
    hdr = header(fmt, sec, nsec, "world")
    if typ == POSE:
        return ts.types[POSE](header=hdr, pose=pose)
    with_cov = ts.types["geometry_msgs/msg/PoseWithCovariance"](
        pose=pose, covariance=np.arange(36, dtype=np.float64)
    )
    if typ == POSE_COV:
        return ts.types[POSE_COV](header=hdr, pose=with_cov)
    twist = ts.types["geometry_msgs/msg/TwistWithCovariance"](
        twist=ts.types["geometry_msgs/msg/Twist"](
            linear=ts.types["geometry_msgs/msg/Vector3"](x=1.0, y=0.0, z=0.0),
            angular=ts.types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.5),
        ),
        covariance=np.zeros(36),
    )
    return ts.types[ODOM](header=hdr, child_frame_id="base_link", pose=with_cov, twist=twist)


def transform(fmt: str, sec: int, nsec: int, parent: str, child: str, x, y, yaw):
    ts = ts_for(fmt)
    qx, qy, qz, qw = quat_yaw_roll(yaw)
    return ts.types["geometry_msgs/msg/TransformStamped"](
        header=header(fmt, sec, nsec, parent),
        child_frame_id=child,
        transform=ts.types["geometry_msgs/msg/Transform"](
            translation=ts.types["geometry_msgs/msg/Vector3"](x=x, y=y, z=0.0),
            rotation=ts.types["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
        ),
    )


def wrap_angle(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def left_angle(t):
    return 2.0 * t + 0.3 * np.sin(t)


def right_angle(t):
    return 1.5 * t - 0.2 * np.cos(2 * t)


def wheel_bag(tmp_path: Path, fmt: str, n: int = 50) -> tuple[Path, dict]:
    """A bag with ``n`` joint states at 20 Hz; header stamps 30 ms before the bag time."""
    truth: dict[str, list] = {"header": [], "bag": [], "left": [], "right": []}
    messages = []
    for k in range(n):
        t = 0.05 * k
        sec, nsec = split(t)
        bag_t = t + 0.03
        a_l, a_r = left_angle(t), right_angle(t)
        messages.append(
            ("/joint_states", ns(bag_t), joint_state(fmt, sec, nsec, [LEFT, RIGHT], [a_l, a_r]))
        )
        truth["header"].append(stamp_seconds(sec, nsec))
        truth["bag"].append(T0 + bag_t)
        truth["left"].append(a_l)
        truth["right"].append(a_r)
    return write_bag(tmp_path, fmt, {"/joint_states": JS}, messages), truth


def assert_one_line(err: InputError, path: Path, *fragments: str) -> None:
    text = str(err)
    assert "\n" not in text
    assert text.startswith(f"{path}: ")
    for fragment in fragments:
        assert fragment in text, (fragment, text)


# --- wheels -----------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
def test_joint_state_positions(tmp_path, fmt):
    path, truth = wheel_bag(tmp_path, fmt)
    wheels, ground_truth = read_bag(path, BagOptions())
    assert ground_truth is None
    np.testing.assert_allclose(wheels.time, truth["header"], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(wheels.angles[:, 0], truth["left"])
    np.testing.assert_array_equal(wheels.angles[:, 1], truth["right"])

    wheels, _ = read_bag(path, BagOptions(time_source="bag"))
    np.testing.assert_allclose(wheels.time, truth["bag"], rtol=0, atol=1e-6)
    # the two clocks differ by the 30 ms the test put between them
    np.testing.assert_allclose(wheels.time - np.array(truth["header"]), 0.03, atol=1e-6)


@pytest.mark.parametrize("path_of", ["db3", "mcap", "metadata"])
def test_ros2_storage_file_means_its_folder(tmp_path, path_of):
    fmt = "mcap" if path_of == "mcap" else "sqlite3"
    folder, truth = wheel_bag(tmp_path, fmt)
    if path_of == "metadata":
        path = folder / "metadata.yaml"
    else:
        (path,) = folder.glob(f"*.{path_of}")
    wheels, _ = read_bag(path, BagOptions())
    np.testing.assert_array_equal(wheels.angles[:, 0], truth["left"])


@pytest.mark.parametrize("fmt", FORMATS)
def test_joint_order_differs_and_other_joint_groups(tmp_path, fmt):
    orders = [
        [LEFT, RIGHT],
        [RIGHT, "caster_joint", LEFT],
        ["arm_joint", LEFT, "head_joint", RIGHT],
    ]
    messages, want_t, want = [], [], []
    for k in range(60):
        t = 0.1 * k
        sec, nsec = split(t)
        if k % 4 == 3:  # another joint group on the same topic: skipped
            msg = joint_state(fmt, sec, nsec, ["arm_joint", "head_joint"], [9.0, 9.0])
        else:
            names = orders[k % 3]
            angles = {LEFT: left_angle(t), RIGHT: right_angle(t)}
            position = [angles.get(name, 100.0 + i) for i, name in enumerate(names)]
            msg = joint_state(fmt, sec, nsec, names, position)
            want_t.append(stamp_seconds(sec, nsec))
            want.append((left_angle(t), right_angle(t)))
        messages.append(("/joint_states", ns(t), msg))
    path = write_bag(tmp_path, fmt, {"/joint_states": JS}, messages)
    wheels, _ = read_bag(path, BagOptions())
    np.testing.assert_allclose(wheels.time, want_t, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(wheels.angles, np.array(want))


@pytest.mark.parametrize("fmt", FORMATS)
def test_velocity_only_joint_states_are_integrated(tmp_path, fmt):
    # velocity a*t at uneven steps: the trapezoid rule is exact for it
    a_left, a_right = 0.8, -0.3
    times = np.cumsum(np.r_[0.0, np.linspace(0.01, 0.05, 39)])
    messages = []
    for t in times:
        sec, nsec = split(t)
        vel = [a_right * t, 7.0, a_left * t]
        msg = joint_state(fmt, sec, nsec, [RIGHT, "caster", LEFT], velocity=vel)
        messages.append(("/joint_states", ns(t), msg))
    path = write_bag(tmp_path, fmt, {"/joint_states": JS}, messages)
    wheels, _ = read_bag(path, BagOptions(time_source="bag"))
    elapsed = wheels.time - wheels.time[0]
    np.testing.assert_allclose(elapsed, times, atol=1e-6)
    t = times
    np.testing.assert_allclose(wheels.angles[:, 0], a_left * t**2 / 2, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(wheels.angles[:, 1], a_right * t**2 / 2, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("fmt", ["ros1", "sqlite3"])
def test_unsorted_and_duplicate_stamps_are_sorted_and_dropped(tmp_path, fmt):
    stamps = [0.0, 0.2, 0.1, 0.3, 0.3, 0.5, 0.4]  # 0.3 twice: the second is dropped
    messages = []
    for k, t in enumerate(stamps):
        sec, nsec = split(t)
        extra = 1000.0 if k == 4 else 0.0
        msg = joint_state(fmt, sec, nsec, [LEFT, RIGHT], [10 * t + extra, -10 * t])
        messages.append(("/joint_states", ns(0.01 * k), msg))
    path = write_bag(tmp_path, fmt, {"/joint_states": JS}, messages)
    wheels, _ = read_bag(path, BagOptions())
    want_t = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    np.testing.assert_allclose(wheels.time - T0, want_t, atol=1e-6)
    np.testing.assert_allclose(wheels.angles[:, 0], 10 * want_t, atol=1e-12)
    np.testing.assert_allclose(wheels.angles[:, 1], -10 * want_t, atol=1e-12)


def test_stamps_closer_than_float_seconds_resolve_keep_the_first(tmp_path):
    # 1 ns apart: distinct stamps, but the same float seconds since 1970
    stamps = [(T0, 0), (T0, 1), (T0, 100_000_000), (T0, 100_000_001), (T0, 200_000_000)]
    messages = [
        ("/joint_states", ns(0.01 * k), joint_state("sqlite3", sec, nsec, [LEFT, RIGHT], [k, -k]))
        for k, (sec, nsec) in enumerate(stamps)
    ]
    path = write_bag(tmp_path, "sqlite3", {"/joint_states": JS}, messages)
    wheels, _ = read_bag(path, BagOptions())
    np.testing.assert_allclose(wheels.time - T0, [0.0, 0.1, 0.2], atol=1e-6)
    np.testing.assert_array_equal(wheels.angles, [[0, 0], [2, -2], [4, -4]])


def wrap_int(value: int, bits: int, signed: bool) -> int:
    value %= 2**bits
    if signed and value >= 2 ** (bits - 1):
        value -= 2**bits
    return value


@pytest.mark.parametrize(
    ("fmt", "typ", "bits", "signed", "start", "rate"),
    [
        ("ros1", "std_msgs/msg/Int32", 32, True, 2**31 - 3000, 997),  # wraps up past 2^31
        ("sqlite3", "std_msgs/msg/Int32", 32, True, -(2**31) + 3000, -997),  # down past -2^31
        ("mcap", "std_msgs/msg/UInt16", 16, False, 2000, -251),  # wraps below 0 downwards
    ],
)
def test_ticks_topics_unwrap_and_interpolate(
    tmp_path, fmt, typ, bits, signed, start, rate, monkeypatch
):
    tpr = 4096.0
    ts = ts_for(fmt)
    cls = ts.types[typ]
    messages = []
    # left at 50 Hz; right at 30 Hz from 0.013 s, counts linear in time (interpolation exact)
    t_left = 0.02 * np.arange(60)
    t_right = 0.013 + np.arange(38) / 30.0
    left_counts = [start + rate * k for k in range(t_left.size)]
    right_rate = 2 * rate / 0.02  # counts per second
    for t, c in zip(t_left, left_counts, strict=True):
        messages.append(("/left_ticks", ns(t), cls(data=wrap_int(c, bits, signed))))
    for t in t_right:
        c = round(start + right_rate * t)
        messages.append(("/right_ticks", ns(t), cls(data=wrap_int(c, bits, signed))))
    messages.sort(key=lambda m: m[1])
    path = write_bag(tmp_path, fmt, {"/left_ticks": typ, "/right_ticks": typ}, messages)
    options = BagOptions(
        left_ticks_topic="/left_ticks", right_ticks_topic="/right_ticks", ticks_per_rev=tpr
    )
    calls = count_deserialize(monkeypatch)
    wheels, _ = read_bag(path, options)
    assert calls[0] == 2  # the fast path read all but one message of each topic
    inside = (t_left >= t_right[0]) & (t_left <= t_right[-1])
    assert inside.sum() < t_left.size  # the overlap does cut samples
    np.testing.assert_allclose(wheels.time - T0, t_left[inside], atol=1e-6)
    want_left = np.array(left_counts, float)[inside] * 2 * np.pi / tpr
    # interpolate at the times as written: whole nanoseconds
    left_ns = np.array([ns(t) - ns(0.0) for t in t_left], float)
    right_ns = np.array([ns(t) - ns(0.0) for t in t_right], float)
    right_counts = [round(start + right_rate * s) for s in t_right]
    right_at_left = np.interp(left_ns, right_ns, right_counts)[inside]
    # angles of 2^31 counts are large: compare to 1e-13 of them
    np.testing.assert_allclose(wheels.angles[:, 0], want_left, rtol=1e-13)
    np.testing.assert_allclose(
        wheels.angles[:, 1], right_at_left * 2 * np.pi / tpr, rtol=1e-13, atol=1e-12
    )
    # the unwrapped count really crossed the type's limit
    wrapped = [wrap_int(c, bits, signed) for c in left_counts]
    assert any(abs(b - a) > 2 ** (bits - 1) for a, b in itertools.pairwise(wrapped))


def test_ticks_topics_that_do_not_overlap_are_refused(tmp_path):
    typ = "std_msgs/msg/Int32"
    cls = TS1.types[typ]
    # the left wheel from 0 to 0.18 s, the right one from 1 s on: no sample in common
    messages = [("/left_ticks", ns(0.02 * k), cls(data=k)) for k in range(10)]
    messages += [("/right_ticks", ns(1.0 + 0.02 * k), cls(data=k)) for k in range(10)]
    path = write_bag(tmp_path, "ros1", {"/left_ticks": typ, "/right_ticks": typ}, messages)
    options = BagOptions(
        left_ticks_topic="/left_ticks", right_ticks_topic="/right_ticks", ticks_per_rev=100
    )
    with pytest.raises(InputError) as err:
        read_bag(path, options)
    assert_one_line(
        err.value,
        path,
        "the ticks topics /left_ticks and /right_ticks overlap in time in fewer than 2 samples "
        "of the left wheel",
    )


# --- ground truth -----------------------------------------------------------------------


def truth_path(t):
    return 0.5 * t, 0.2 * t**2, 0.9 * t - 2.5  # yaw passes through -pi .. pi and beyond


@pytest.mark.parametrize(
    ("fmt", "typ"), [("sqlite3", POSE), ("ros1", POSE_COV), ("mcap", ODOM), ("ros1", ODOM)]
)
def test_ground_truth_topic(tmp_path, fmt, typ, monkeypatch):
    messages = []
    times = 0.01 + 0.1 * np.arange(80)
    for t in times:
        sec, nsec = split(t)
        x, y, yaw = truth_path(t)
        messages.append(("/truth", ns(t + 0.001), pose_msg(fmt, typ, sec, nsec, x, y, yaw)))
    js = [
        ("/joint_states", ns(0.05 * k), joint_state(fmt, T0, 5_000_000 * k, [LEFT, RIGHT], [k, k]))
        for k in range(3)
    ]
    path = write_bag(
        tmp_path,
        fmt,
        {"/joint_states": JS, "/truth": typ},
        sorted(js + messages, key=lambda m: m[1]),
        name="gt",
    )
    calls = count_deserialize(monkeypatch)
    _, truth = read_bag(path, BagOptions(truth_topic="/truth"))
    assert calls[0] == 2  # the fast path read all but one message of each topic
    assert truth is not None
    np.testing.assert_allclose(truth.time - T0, times, atol=1e-6)
    x, y, yaw = truth_path(times)
    np.testing.assert_allclose(truth.poses[:, 0], x, atol=1e-12)
    np.testing.assert_allclose(truth.poses[:, 1], y, atol=1e-12)
    np.testing.assert_allclose(wrap_angle(truth.poses[:, 2] - yaw), 0.0, atol=1e-12)
    _, truth_bag = read_bag(path, BagOptions(truth_topic="/truth", time_source="bag"))
    assert truth_bag is not None
    np.testing.assert_allclose(truth_bag.time - T0, times + 0.001, atol=1e-6)


@pytest.mark.parametrize("fmt", FORMATS)
def test_ground_truth_from_tf_pair(tmp_path, fmt):
    messages = []
    times = 0.1 * np.arange(40)
    slash = "/" if fmt == "ros1" else ""  # ROS 1 frame names often have a leading slash
    tf_cls = ts_for(fmt).types[TF]
    for t in times:
        sec, nsec = split(t)
        x, y, yaw = truth_path(t)
        transforms = [
            transform(fmt, sec, nsec, slash + "map", slash + "odom", 1.0, 2.0, 0.3),
            transform(fmt, sec, nsec, slash + "odom", slash + "base_link", x, y, yaw),
            transform(fmt, sec, nsec, slash + "base_link", slash + "laser", 0.1, 0.0, 0.0),
        ]
        messages.append(("/tf", ns(t + 0.002), tf_cls(transforms=transforms)))
        msg = joint_state(fmt, sec, nsec, [LEFT, RIGHT], [t, t])
        messages.append(("/joint_states", ns(t), msg))
    messages.sort(key=lambda m: m[1])
    path = write_bag(tmp_path, fmt, {"/joint_states": JS, "/tf": TF}, messages)
    _, truth = read_bag(path, BagOptions(tf_parent="odom", tf_child="base_link"))
    assert truth is not None
    np.testing.assert_allclose(truth.time - T0, times, atol=1e-6)
    x, y, yaw = truth_path(times)
    np.testing.assert_allclose(truth.poses[:, :2], np.column_stack([x, y]), atol=1e-12)
    np.testing.assert_allclose(wrap_angle(truth.poses[:, 2] - yaw), 0.0, atol=1e-12)

    # a chain: map -> odom (fixed at x 1, y 2, yaw 0.3) -> base_link, composed by hand
    _, chained = read_bag(path, BagOptions(tf_parent="map", tf_child="base_link"))
    assert chained is not None
    c, s_ = math.cos(0.3), math.sin(0.3)
    expected = np.column_stack([1.0 + c * x - s_ * y, 2.0 + s_ * x + c * y])
    np.testing.assert_allclose(chained.poses[:, :2], expected, atol=1e-12)
    np.testing.assert_allclose(wrap_angle(chained.poses[:, 2] - (yaw + 0.3)), 0.0, atol=1e-12)
    # walked backwards: base_link in laser's frame is 0.1 m behind it
    _, back = read_bag(path, BagOptions(tf_parent="laser", tf_child="base_link"))
    assert back is not None
    np.testing.assert_allclose(back.poses, np.tile([-0.1, 0.0, 0.0], (times.size, 1)), atol=1e-12)

    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(tf_parent="odom", tf_child="camera"))
    assert_one_line(
        err.value, path, "odom", "camera", "map->odom", "odom->base_link", "base_link->laser"
    )


# --- the fast path equals deserialization ---------------------------------------------


def reference_joint_states(path: Path, topic: str, left: str, right: str):
    """Times and positions by deserializing every message with rosbags (no sorting needed)."""
    times, angles = [], []
    with AnyReader([path], default_typestore=TS2) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            names = list(msg.name)
            if left not in names or right not in names:
                continue
            stamp = msg.header.stamp
            times.append(stamp.sec + stamp.nanosec * 1e-9)
            angles.append((msg.position[names.index(left)], msg.position[names.index(right)]))
    return np.array(times), np.array(angles)


def count_deserialize(monkeypatch) -> list[int]:
    calls = [0]
    original = AnyReader.deserialize

    def counting(self, rawdata, typ):
        calls[0] += 1
        return original(self, rawdata, typ)

    monkeypatch.setattr(AnyReader, "deserialize", counting)
    return calls


@pytest.mark.parametrize("fmt", FORMATS)
def test_fast_path_equals_deserialization(tmp_path, fmt, monkeypatch):
    n = 400
    messages, odd = [], 0
    for k in range(n):
        t = 0.01 * k
        sec, nsec = split(t)
        names, frame = [LEFT, RIGHT], ""
        if k % 50 == 7:  # other layouts in between: a longer frame_id, another order
            frame = "base"
            odd += 1
        elif k % 50 == 23:
            names = [RIGHT, LEFT]
            odd += 1
        angles = {LEFT: left_angle(t), RIGHT: right_angle(t)}
        msg = joint_state(fmt, sec, nsec, names, [angles[j] for j in names], frame=frame)
        if fmt != "ros1" and k % 50 == 41:  # a big-endian CDR message of the same length
            msg = TS2.serialize_cdr(msg, JS, little_endian=False)
            odd += 1
        messages.append(("/joint_states", ns(t), msg))
    path = write_bag(tmp_path, fmt, {"/joint_states": JS}, messages)

    calls = count_deserialize(monkeypatch)
    fast, _ = read_bag(path, BagOptions())
    fast_calls, calls[0] = calls[0], 0
    monkeypatch.setattr(fastpath, "_LAYOUT_ATTEMPTS", 0)  # deserialize every message
    slow, _ = read_bag(path, BagOptions())
    assert calls[0] == n
    assert fast_calls <= odd + 1  # the first message, and the ones that do not fit

    np.testing.assert_array_equal(fast.time, slow.time)
    np.testing.assert_array_equal(fast.angles, slow.angles)
    ref_t, ref_angles = reference_joint_states(path, "/joint_states", LEFT, RIGHT)
    np.testing.assert_array_equal(fast.time, ref_t)
    np.testing.assert_array_equal(fast.angles, ref_angles)
    t = 0.01 * np.arange(n)
    np.testing.assert_array_equal(fast.angles, np.column_stack([left_angle(t), right_angle(t)]))


@pytest.mark.parametrize("fmt", FORMATS)
def test_fast_path_equals_deserialization_for_velocities_and_poses(tmp_path, fmt, monkeypatch):
    n = 300
    messages = []
    for k in range(n):
        t = 0.01 * k
        sec, nsec = split(t)
        msg = joint_state(fmt, sec, nsec, [LEFT, RIGHT], velocity=[1.0 + t, 2.0 - t])
        messages.append(("/joint_states", ns(t), msg))
        x, y, yaw = truth_path(t)
        messages.append(("/odom", ns(t + 0.001), pose_msg(fmt, ODOM, sec, nsec, x, y, yaw)))
    path = write_bag(tmp_path, fmt, {"/joint_states": JS, "/odom": ODOM}, messages)
    options = BagOptions(truth_topic="/odom")
    calls = count_deserialize(monkeypatch)
    fast_wheels, fast_truth = read_bag(path, options)
    assert calls[0] == 2  # one per topic, to check the layout
    monkeypatch.setattr(fastpath, "_LAYOUT_ATTEMPTS", 0)
    slow_wheels, slow_truth = read_bag(path, options)
    assert calls[0] == 2 + 2 * n
    assert fast_truth is not None
    assert slow_truth is not None
    np.testing.assert_array_equal(fast_wheels.time, slow_wheels.time)
    np.testing.assert_array_equal(fast_wheels.angles, slow_wheels.angles)
    np.testing.assert_array_equal(fast_truth.time, slow_truth.time)
    np.testing.assert_array_equal(fast_truth.poses, slow_truth.poses)
    x, _, _ = truth_path(0.01 * np.arange(n))
    np.testing.assert_array_equal(fast_truth.poses[:, 0], x)


# --- which joints are the wheels -------------------------------------------------------


def joints_bag(tmp_path: Path, fmt: str, names: Sequence[str], rates: Sequence[float]) -> Path:
    """Joint states with ``names`` turning at ``rates`` [rad/s], 20 Hz for 5 s, shuffled
    order in every other message."""
    messages = []
    for k in range(100):
        t = 0.05 * k
        sec, nsec = split(t)
        order = list(range(len(names)))
        if k % 2:
            order.reverse()
        msg = joint_state(fmt, sec, nsec, [names[i] for i in order], [rates[i] * t for i in order])
        messages.append(("/joint_states", ns(t), msg))
    return write_bag(tmp_path, fmt, {"/joint_states": JS}, messages)


@pytest.mark.parametrize("fmt", ["ros1", "sqlite3"])
def test_wheel_joints_found_by_name_when_not_given(tmp_path, fmt):
    # TurtleBot names, a caster that turns little and a gripper that does not move
    path = joints_bag(
        tmp_path,
        fmt,
        ["caster_joint", "wheel_left_joint", "gripper", "wheel_right_joint"],
        [0.1, 2.0, 0.0, 3.0],
    )
    wheels, _ = read_bag(path, BagOptions())
    t = 0.05 * np.arange(100)
    np.testing.assert_allclose(wheels.angles, np.column_stack([2.0 * t, 3.0 * t]), atol=1e-12)


@pytest.mark.parametrize("fmt", ["ros1", "mcap"])
def test_several_wheels_per_side_are_averaged(tmp_path, fmt):
    # a skid-steer: front and rear wheels of a side slip differently
    names = ["front_left_wheel", "rear_left_wheel", "front_right_wheel", "rear_right_wheel"]
    path = joints_bag(tmp_path, fmt, names, [2.0, 2.2, 3.0, 3.4])
    t = 0.05 * np.arange(100)
    expected = np.column_stack([2.1 * t, 3.2 * t])
    found, _ = read_bag(path, BagOptions())  # found by their names
    np.testing.assert_allclose(found.angles, expected, atol=1e-12)
    given, _ = read_bag(
        path,
        BagOptions(
            left_joint="front_left_wheel, rear_left_wheel",
            right_joint=("front_right_wheel", "rear_right_wheel"),
        ),
    )
    np.testing.assert_allclose(given.angles, expected, atol=1e-12)
    one, _ = read_bag(
        path, BagOptions(left_joint="rear_left_wheel", right_joint="rear_right_wheel")
    )
    np.testing.assert_allclose(one.angles, np.column_stack([2.2 * t, 3.4 * t]), atol=1e-12)


def test_wheel_joints_that_cannot_be_told_apart_are_named(tmp_path):
    path = joints_bag(tmp_path, "sqlite3", ["wheel_a", "wheel_b", "lidar"], [2.0, 3.0, 10.0])
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions())
    assert_one_line(err.value, path, "--left-joint", "wheel_a", "wheel_b", "lidar")
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(left_joint="wheel_a", right_joint="wheel_c"))
    assert_one_line(err.value, path, "no joint 'wheel_c'", "lidar")


# --- bad input --------------------------------------------------------------------------


def test_missing_topic_names_the_topics_present(tmp_path):
    path, _ = wheel_bag(tmp_path, "sqlite3", n=3)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(wheel_topic="/wheels"))
    assert_one_line(err.value, path, "/wheels", "/joint_states (sensor_msgs/msg/JointState)")
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(truth_topic="/mocap"))
    assert_one_line(err.value, path, "/mocap", "ground truth", "/joint_states")
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(tf_parent="odom", tf_child="base_link"))
    assert_one_line(err.value, path, "/tf", "/joint_states")


@pytest.mark.parametrize("fmt", ["ros1", "mcap"])
def test_topic_of_the_wrong_type(tmp_path, fmt):
    sec, nsec = split(0.0)
    messages = [("/odom", ns(k), pose_msg(fmt, ODOM, sec + k, nsec, 0, 0, 0)) for k in range(3)]
    path = write_bag(tmp_path, fmt, {"/odom": ODOM}, messages)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(wheel_topic="/odom"))
    assert_one_line(err.value, path, "/odom", "nav_msgs/msg/Odometry", JS)
    with pytest.raises(InputError) as err:
        read_bag(
            path,
            BagOptions(
                wheel_topic="/odom",
                left_ticks_topic="/odom",
                right_ticks_topic="/x",
                ticks_per_rev=100,
            ),
        )
    assert_one_line(err.value, path, "/odom", "std_msgs/msg/Int32")


@pytest.mark.parametrize("fmt", ["ros1", "mcap"])
def test_unknown_joint_names_the_joints_present(tmp_path, fmt):
    path, _ = wheel_bag(tmp_path, fmt, n=3)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(left_joint="wheel_l"))
    assert_one_line(err.value, path, "'wheel_l'", f"joints present: {LEFT}, {RIGHT}")


def test_empty_topic(tmp_path):
    for fmt in FORMATS:
        path = write_bag(tmp_path, fmt, {"/joint_states": JS}, [], name=f"empty_{fmt}")
        with pytest.raises(InputError) as err:
            read_bag(path, BagOptions())
        assert_one_line(err.value, path, "/joint_states", "no messages")


def test_a_single_sample_is_not_enough(tmp_path):
    path, _ = wheel_bag(tmp_path, "sqlite3", n=1)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions())
    assert_one_line(err.value, path, "/joint_states", "1 usable sample", "at least 2")


def test_equal_header_stamps_suggest_the_bag_time(tmp_path):
    messages = [
        ("/joint_states", ns(0.1 * k), joint_state("sqlite3", 0, 0, [LEFT, RIGHT], [k, k]))
        for k in range(5)
    ]
    path = write_bag(tmp_path, "sqlite3", {"/joint_states": JS}, messages)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions())
    assert_one_line(err.value, path, "bag time")
    wheels, _ = read_bag(path, BagOptions(time_source="bag"))
    np.testing.assert_array_equal(wheels.angles[:, 0], np.arange(5.0))


def test_joint_state_without_position_or_velocity(tmp_path):
    sec, nsec = split(0.0)
    messages = [("/joint_states", ns(0.0), joint_state("ros1", sec, nsec, [LEFT, RIGHT]))]
    path = write_bag(tmp_path, "ros1", {"/joint_states": JS}, messages)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions())
    assert_one_line(err.value, path, "neither position nor velocity")


def test_ticks_need_ticks_per_rev(tmp_path):
    path, _ = wheel_bag(tmp_path, "sqlite3", n=2)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(left_ticks_topic="/l", right_ticks_topic="/r"))
    assert_one_line(err.value, path, "ticks_per_rev")
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions(left_ticks_topic="/l", ticks_per_rev=10))
    assert_one_line(err.value, path, "left and right ticks topics")


@pytest.mark.parametrize(
    ("make", "fragment"),
    [
        (lambda p: p / "missing.bag", "does not exist"),
        (lambda p: (p / "notes.txt", (p / "notes.txt").write_text("hello"))[0], "not a bag"),
        (lambda p: (p / "junk.bag", (p / "junk.bag").write_text("hello"))[0], "cannot read"),
        (lambda p: (p / "junk.db3", (p / "junk.db3").write_bytes(b"x" * 5000))[0], "cannot read"),
        (lambda p: (p / "junk.mcap", (p / "junk.mcap").write_bytes(b"x" * 50))[0], "cannot read"),
        (lambda p: (p / "folder", (p / "folder").mkdir())[0], "metadata.yaml"),
    ],
)
def test_not_a_bag(tmp_path, make: Callable[[Path], Path], fragment):
    path = make(tmp_path)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions())
    assert_one_line(err.value, path, fragment)
    with pytest.raises(InputError):
        bag_topics(path)


def test_truncated_ros1_bag(tmp_path):
    path, _ = wheel_bag(tmp_path, "ros1", n=200)
    data = path.read_bytes()
    cut = tmp_path / "cut.bag"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError) as err:
        read_bag(cut, BagOptions())
    assert_one_line(err.value, cut, "cannot read")


def test_bad_options(tmp_path):
    path, _ = wheel_bag(tmp_path, "sqlite3", n=2)
    for options, fragment in [
        (BagOptions(tf_parent="odom"), "tf_child"),
        (BagOptions(right_joint=LEFT), "same"),
        (BagOptions(time_source="gps"), "time source"),  # type: ignore[arg-type]
        (
            BagOptions(left_ticks_topic="/a", right_ticks_topic="/b", ticks_per_rev=0),
            "positive",
        ),
    ]:
        with pytest.raises(InputError) as err:
            read_bag(path, options)
        assert_one_line(err.value, path, fragment)


def test_without_rosbags(tmp_path, monkeypatch):
    path, _ = wheel_bag(tmp_path, "sqlite3", n=2)
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)
    with pytest.raises(InputError) as err:
        read_bag(path, BagOptions())
    assert_one_line(err.value, path, "python -m pip install 'rosbags")


@pytest.mark.parametrize("fmt", FORMATS)
def test_bag_topics(tmp_path, fmt):
    path = write_bag(tmp_path, fmt, {"/joint_states": JS, "/odom": ODOM, "/tf": TF}, [])
    assert bag_topics(path) == {"/joint_states": JS, "/odom": ODOM, "/tf": TF}

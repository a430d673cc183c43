"""The byte-level decoder of ``umbmark.sources.bag.fastpath`` equals rosbags' deserializer.

Hypothesis draws batches of random messages of every type the decoder has a layout for
(``sensor_msgs/JointState``, the three pose types, ``sensor_msgs/Imu``, the eight
``std_msgs`` numbers),
serializes them with rosbags as ROS 1 (Noetic store) or as CDR (latest store; little- and
big-endian mixed in one batch), and reads them with ``fastpath.decode_messages``. The
stamps, values and kinds must equal, bit for bit (NaN equal to NaN), what this test picks
out of rosbags' ``deserialize_ros1`` / ``deserialize_cdr`` of each message by itself.

A batch starts with a template message whose layout the decoder derives (for joint
states after up to two messages without the wheel joints, which are skipped), followed,
in random order, by

- siblings: the template's structure (names, array lengths, string lengths) with other
  stamps, values and string texts; they must be read through the layout, never given to
  the deserializing callback, so the test fails if the fast path stops being used;
- variants: one structural change that keeps the raw length where the format allows
  (wheel joints swapped, ``frame_id`` one byte longer, strings moved between fields,
  the other CDR byte order); they must be deserialized;
- others: messages of random structure (wheel joints missing, position empty with
  velocity present, arrays shorter or longer than the names, ...), read either way.

The messages go through ``decode_messages`` in vectorized batches of 1, 2, 3 or 65 536,
so the fallback inside a batch and the reassembly of the bag's order are exercised.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any
from unittest import mock

import numpy as np
import pytest

pytest.importorskip("rosbags")

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

from umbmark.sources.bag import fastpath

TS1 = get_typestore(Stores.ROS1_NOETIC)
TS2 = get_typestore(Stores.LATEST)

JS = "sensor_msgs/msg/JointState"
POSE = "geometry_msgs/msg/PoseStamped"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
ODOM = "nav_msgs/msg/Odometry"
POSE_TYPES = [POSE, POSE_COV, ODOM]
IMU = "sensor_msgs/msg/Imu"
# std_msgs numbers: the range of ``data``
INTS = {
    "std_msgs/msg/Int16": (-(2**15), 2**15 - 1),
    "std_msgs/msg/Int32": (-(2**31), 2**31 - 1),
    "std_msgs/msg/Int64": (-(2**63), 2**63 - 1),
    "std_msgs/msg/UInt16": (0, 2**16 - 1),
    "std_msgs/msg/UInt32": (0, 2**32 - 1),
    "std_msgs/msg/UInt64": (0, 2**64 - 1),
}
FLOATS = {"std_msgs/msg/Float32": 32, "std_msgs/msg/Float64": 64}
TYPES = [JS, *POSE_TYPES, IMU, *INTS, *FLOATS]

# rosbags' Time has an int32 ``sec`` in both stores; ROS 1 sends an uint32: drawing every
# int32 draws every bit pattern, so ROS 1 seconds >= 2^31 are covered as their int32 bits.
SEC = st.integers(-(2**31), 2**31 - 1)
NSEC = st.integers(0, 2**32 - 1)  # the format does not limit nanosec to < 1e9
SEQ = st.integers(0, 2**32 - 1)
TEXT = st.text(max_size=10)  # empty, non-ASCII, control characters
F64 = st.floats(allow_nan=True, allow_infinity=True)

Sample = fastpath.Sample


@dataclass(frozen=True)
class Message:
    """A serialized message and what the batch expects of the decoder for it."""

    raw: bytes
    role: str  # "skipped", "template", "sibling", "variant" or "other"


def store(ros2: bool) -> Any:
    return TS2 if ros2 else TS1


def serialize(msg: object, typ: str, encoding: str) -> bytes:
    """``encoding``: ``"ros1"``, ``"le"`` or ``"be"`` (CDR byte order)."""
    if encoding == "ros1":
        return bytes(TS1.serialize_ros1(msg, typ))
    return bytes(TS2.serialize_cdr(msg, typ, little_endian=encoding == "le"))


def deserialize(raw: bytes, typ: str, ros2: bool) -> Any:
    return TS2.deserialize_cdr(raw, typ) if ros2 else TS1.deserialize_ros1(raw, typ)


def make_header(ros2: bool, seq: int, sec: int, nsec: int, frame: str) -> object:
    ts = store(ros2)
    stamp = ts.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
    if ros2:
        return ts.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)
    return ts.types["std_msgs/msg/Header"](seq=seq, stamp=stamp, frame_id=frame)


# --- what rosbags' deserialization says ------------------------------------------------


def reference(msg: Any, typ: str, joints: tuple[str, str]) -> list[Sample]:
    """The samples of a deserialized message, picked out without umbmark's code."""
    if typ == JS:
        names = list(msg.name)
        left, right = joints
        if left not in names or right not in names:
            return []
        i, j = names.index(left), names.index(right)
        stamp = msg.header.stamp
        for array, kind in ((msg.position, fastpath.POSITION), (msg.velocity, fastpath.VELOCITY)):
            if len(array) > max(i, j):
                values = (float(array[i]), float(array[j]))
                return [(int(stamp.sec), int(stamp.nanosec), values, kind)]
        return []
    if typ in POSE_TYPES:
        pose = msg.pose if typ == POSE else msg.pose.pose
        p, q = pose.position, pose.orientation
        stamp = msg.header.stamp
        values = (float(p.x), float(p.y), float(q.x), float(q.y), float(q.z), float(q.w))
        return [(int(stamp.sec), int(stamp.nanosec), values, fastpath.POSITION)]
    if typ == IMU:
        w, a, stamp = msg.angular_velocity, msg.linear_acceleration, msg.header.stamp
        values = (float(w.x), float(w.y), float(w.z), float(msg.angular_velocity_covariance[0]),
                  float(a.x), float(a.y), float(a.z), float(msg.linear_acceleration_covariance[0]),
                  float(msg.orientation_covariance[0]))  # fmt: skip
        return [(int(stamp.sec), int(stamp.nanosec), values, fastpath.POSITION)]
    return [(0, 0, (float(msg.data),), fastpath.POSITION)]


def width_of(typ: str) -> int:
    return 2 if typ == JS else 6 if typ in POSE_TYPES else 9 if typ == IMU else 1


# --- drawing messages ------------------------------------------------------------------


@dataclass(frozen=True)
class JointShape:
    """The structure of a joint state: what fixes its layout."""

    frame: str
    names: tuple[str, ...]
    lengths: tuple[int, int, int]  # of position, velocity, effort


@st.composite
def joint_shape(
    draw: st.DrawFn, joints: tuple[str, str], *, template: bool, wheels: str = "any"
) -> JointShape:
    """``wheels``: ``"both"`` joints, ``"missing"`` one or both, or ``"any"``."""
    left, right = joints
    extra = draw(st.lists(TEXT.filter(lambda s: s not in joints), max_size=4))
    if template or wheels == "both" or (wheels == "any" and draw(st.booleans())):
        present = [left, right]
    else:  # a joint group without one or both wheels
        present = draw(st.lists(st.sampled_from([left, right]), max_size=1))
    names = tuple(draw(st.permutations([*extra, *present])))
    n = len(names)
    any_length = st.integers(0, n + 1)
    if template:
        position = draw(st.sampled_from([n, 0]))
        velocity = n if position == 0 else draw(st.sampled_from([n, 0]))
    else:
        position = draw(st.one_of(st.just(n), st.just(0), any_length))
        velocity = draw(st.one_of(st.just(n), st.just(0), any_length))
    effort = draw(st.one_of(st.just(n), st.just(0), any_length))
    return JointShape(draw(TEXT), names, (position, velocity, effort))


@st.composite
def joint_state(draw: st.DrawFn, shape: JointShape, ros2: bool) -> object:
    arrays = [np.array(draw(st.lists(F64, min_size=k, max_size=k))) for k in shape.lengths]
    header = make_header(ros2, draw(SEQ), draw(SEC), draw(NSEC), shape.frame)
    return store(ros2).types[JS](
        header=header,
        name=list(shape.names),
        position=arrays[0],
        velocity=arrays[1],
        effort=arrays[2],
    )


@dataclass(frozen=True)
class PoseShape:
    frame: str
    child: str  # nav_msgs/Odometry's child_frame_id


@st.composite
def imu_message(draw: st.DrawFn, shape: PoseShape, ros2: bool) -> object:
    """``sensor_msgs/Imu``: every field drawn (the covariances' first elements -1 at times)."""
    ts = store(ros2)
    vector, quaternion = (
        ts.types["geometry_msgs/msg/Vector3"],
        ts.types["geometry_msgs/msg/Quaternion"],
    )
    w = draw(st.lists(F64, min_size=3, max_size=3))
    a = draw(st.lists(F64, min_size=3, max_size=3))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    covariances = [rng.standard_normal(9) for _ in range(3)]
    for cov in covariances:
        cov[0] = draw(st.sampled_from([-1.0, 0.0])) if draw(st.booleans()) else draw(F64)
    return ts.types[IMU](
        header=make_header(ros2, draw(SEQ), draw(SEC), draw(NSEC), shape.frame),
        orientation=quaternion(x=rng.standard_normal(), y=0.0, z=0.0, w=1.0),
        orientation_covariance=covariances[0],
        angular_velocity=vector(x=w[0], y=w[1], z=w[2]),
        angular_velocity_covariance=covariances[1],
        linear_acceleration=vector(x=a[0], y=a[1], z=a[2]),
        linear_acceleration_covariance=covariances[2],
    )


@st.composite
def pose_message(draw: st.DrawFn, typ: str, shape: PoseShape, ros2: bool) -> object:
    ts = store(ros2)
    if typ == IMU:
        return draw(imu_message(shape, ros2))
    x, y, z, qx, qy, qz, qw = draw(st.lists(F64, min_size=7, max_size=7))
    pose = ts.types["geometry_msgs/msg/Pose"](
        position=ts.types["geometry_msgs/msg/Point"](x=x, y=y, z=z),
        orientation=ts.types["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
    )
    header = make_header(ros2, draw(SEQ), draw(SEC), draw(NSEC), shape.frame)
    if typ == POSE:
        return ts.types[POSE](header=header, pose=pose)
    # values the decoder does not read: random, but not worth hypothesis' effort
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    with_cov = ts.types["geometry_msgs/msg/PoseWithCovariance"](
        pose=pose, covariance=rng.standard_normal(36)
    )
    if typ == POSE_COV:
        return ts.types[POSE_COV](header=header, pose=with_cov)
    vector = ts.types["geometry_msgs/msg/Vector3"]
    twist = ts.types["geometry_msgs/msg/TwistWithCovariance"](
        twist=ts.types["geometry_msgs/msg/Twist"](
            linear=vector(x=rng.standard_normal(), y=0.0, z=0.0),
            angular=vector(x=0.0, y=0.0, z=rng.standard_normal()),
        ),
        covariance=rng.standard_normal(36),
    )
    return ts.types[ODOM](header=header, child_frame_id=shape.child, pose=with_cov, twist=twist)


def number_values(typ: str) -> st.SearchStrategy[Any]:
    if typ in INTS:
        low, high = INTS[typ]
        return st.integers(low, high)
    return st.floats(width=FLOATS[typ], allow_nan=True, allow_infinity=True)


def shuffled_text(draw: st.DrawFn, text: str) -> str:
    """Another text of the same UTF-8 length: ``text``'s characters in another order."""
    return "".join(draw(st.permutations(list(text))))


@st.composite
def batch(draw: st.DrawFn, typ: str, ros2: bool, joints: tuple[str, str]) -> list[Message]:
    """A template, its siblings, variants and others, the template first.

    Joint states may start with messages without the wheel joints: they are deserialized
    and skipped, and no layout is derived from them.
    """
    order = draw(st.sampled_from(["le", "be"])) if ros2 else "ros1"
    other_order = {"le": "be", "be": "le"}.get(order)
    any_order = st.sampled_from(["le", "be"]) if ros2 else st.just("ros1")
    siblings = draw(st.integers(1, 6))
    out: list[Message] = []

    def add(msg: object, role: str, encoding: str = order) -> None:
        out.append(Message(serialize(msg, typ, encoding), role))

    skipped = 0
    if typ == JS:
        skipped = draw(st.integers(0, 2))
        for _ in range(skipped):
            other = draw(joint_shape(joints, template=False, wheels="missing"))
            add(draw(joint_state(other, ros2)), "skipped", draw(any_order))
        shape = draw(joint_shape(joints, template=True))
        add(draw(joint_state(shape, ros2)), "template")
        for _ in range(siblings):
            sibling = JointShape(shuffled_text(draw, shape.frame), shape.names, shape.lengths)
            add(draw(joint_state(sibling, ros2)), "sibling")
        swapped = tuple(
            joints[1] if n == joints[0] else joints[0] if n == joints[1] else n for n in shape.names
        )
        variants = [
            JointShape(shape.frame, swapped, shape.lengths),
            JointShape(shape.frame + "x", shape.names, shape.lengths),
        ]
        for variant in variants:
            add(draw(joint_state(variant, ros2)), "variant")
        if other_order is not None:
            add(draw(joint_state(shape, ros2)), "variant", other_order)
        for _ in range(draw(st.integers(0, 4))):
            other = draw(joint_shape(joints, template=False))
            add(draw(joint_state(other, ros2)), "other", draw(any_order))
    elif typ in (*POSE_TYPES, IMU):
        shape = PoseShape(draw(TEXT), draw(TEXT) if typ == ODOM else "")
        add(draw(pose_message(typ, shape, ros2)), "template")
        for _ in range(siblings):
            texts = PoseShape(shuffled_text(draw, shape.frame), shuffled_text(draw, shape.child))
            add(draw(pose_message(typ, texts, ros2)), "sibling")
        variants = [PoseShape(shape.frame + "x", shape.child)]
        if typ == ODOM:  # one byte moved from child_frame_id to frame_id: same length
            variants.append(PoseShape(shape.frame + "x", shape.child[1:]))
        for variant in variants:
            add(draw(pose_message(typ, variant, ros2)), "variant")
        if other_order is not None:
            add(draw(pose_message(typ, shape, ros2)), "variant", other_order)
        for _ in range(draw(st.integers(0, 4))):
            other = PoseShape(draw(TEXT), draw(TEXT) if typ == ODOM else "")
            add(draw(pose_message(typ, other, ros2)), "other", draw(any_order))
    else:
        cls = store(ros2).types[typ]
        values = number_values(typ)
        add(cls(data=draw(values)), "template")
        for _ in range(siblings):
            add(cls(data=draw(values)), "sibling")
        if other_order is not None:
            add(cls(data=draw(values)), "variant", other_order)
    rest = draw(st.permutations(out[skipped + 1 :]))
    return [*out[: skipped + 1], *rest]


# --- comparing ---------------------------------------------------------------------------


def assert_same_floats(got: np.ndarray, want: np.ndarray) -> None:
    """Equal bit for bit, except that any NaN equals any NaN."""
    assert got.shape == want.shape
    nan = np.isnan(want)
    np.testing.assert_array_equal(np.isnan(got), nan)
    np.testing.assert_array_equal(got[~nan].view(np.uint64), want[~nan].view(np.uint64))


def check_batch(
    messages: list[Message], typ: str, ros2: bool, joints: tuple[str, str], batch_size: int
) -> None:
    deserialized: list[bytes] = []

    def decode(raw: bytes) -> list[Sample]:
        deserialized.append(raw)
        return reference(deserialize(raw, typ, ros2), typ, joints)

    layout_of = fastpath.fast_layout(typ, joints if typ == JS else None)
    bag_ns = [1_000 * k + 7 for k in range(len(messages))]
    with mock.patch.object(fastpath, "_BATCH", batch_size):
        got = fastpath.decode_messages(
            list(zip(bag_ns, [m.raw for m in messages], strict=True)),
            ros2=ros2,
            width=width_of(typ),
            decode=decode,
            layout_of=layout_of,
        )

    want: list[tuple[int, Sample]] = [
        (ns, sample)
        for ns, m in zip(bag_ns, messages, strict=True)
        for sample in reference(deserialize(m.raw, typ, ros2), typ, joints)
    ]
    assert got.messages == len(messages)
    assert got.deserialized == len(deserialized)
    np.testing.assert_array_equal(got.bag_ns, [ns for ns, _ in want])
    np.testing.assert_array_equal(got.sec, [s[0] for _, s in want])
    np.testing.assert_array_equal(got.nsec, [s[1] for _, s in want])
    np.testing.assert_array_equal(got.kind, [s[3] for _, s in want])
    want_values = np.array([s[2] for _, s in want], np.float64).reshape(-1, width_of(typ))
    assert_same_floats(got.values, want_values)

    # the fast path read what it should: the template's siblings were never deserialized,
    # the template once (to check its layout), the variants one by one
    ids = [id(raw) for raw in deserialized]
    roles = [m.role for m in messages]
    for m, role in zip(messages, roles, strict=True):
        if role == "sibling":
            assert id(m.raw) not in ids, "a message of the template's layout was deserialized"
        elif role in ("skipped", "template", "variant"):
            assert ids.count(id(m.raw)) == 1, f"the {role} was not deserialized once"


# --- the properties ----------------------------------------------------------------------

joint_names = st.lists(st.text(min_size=1, max_size=10), min_size=2, max_size=2, unique=True)


@pytest.mark.parametrize("ros2", [False, True], ids=["ros1", "cdr"])
@pytest.mark.parametrize("typ", TYPES)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_decoder_equals_rosbags_deserializer(typ: str, ros2: bool, data: st.DataObject):
    joints = tuple(data.draw(joint_names, label="joints"))
    assert len(joints) == 2
    messages = data.draw(batch(typ, ros2, (joints[0], joints[1])), label="messages")
    batch_size = data.draw(st.sampled_from([1, 2, 3, 1 << 16]), label="batch size")
    check_batch(messages, typ, ros2, (joints[0], joints[1]), batch_size)


# --- a few cases worth pinning down explicitly --------------------------------------------


def _number_raws(typ: str, values: list[Any], encoding: str) -> list[bytes]:
    cls = store(encoding != "ros1").types[typ]
    return [serialize(cls(data=v), typ, encoding) for v in values]


@pytest.mark.parametrize("encoding", ["ros1", "le", "be"])
@pytest.mark.parametrize("typ", list(INTS))
def test_integer_extremes(typ: str, encoding: str):
    low, high = INTS[typ]
    values = [0, low, high, low + 1, high - 1, 2**53 + 1 if high > 2**53 else high]
    raws = _number_raws(typ, values, encoding)
    ros2 = encoding != "ros1"
    messages = [Message(raw, "template" if k == 0 else "sibling") for k, raw in enumerate(raws)]
    check_batch(messages, typ, ros2, ("l", "r"), 1 << 16)


@pytest.mark.parametrize("encoding", ["ros1", "le", "be"])
def test_ros1_seconds_past_2038_read_as_rosbags_reads_them(encoding: str):
    # a ROS 1 stamp after 2038-01-19 has sec >= 2^31 on the wire; rosbags reads the
    # int32 bits (negative): so must the decoder, or fast and deserialized samples differ
    ros2 = encoding != "ros1"
    joints = ("l", "r")
    raws = []
    for sec in (2**31 - 1, -(2**31), -1, 5):
        msg = store(ros2).types[JS](
            header=make_header(ros2, 0, sec, 999_999_999, ""),
            name=list(joints),
            position=np.array([1.0, math.inf]),
            velocity=np.zeros(0),
            effort=np.zeros(0),
        )
        raws.append(serialize(msg, JS, encoding))
    messages = [Message(raw, "template" if k == 0 else "sibling") for k, raw in enumerate(raws)]
    check_batch(messages, JS, ros2, joints, 1 << 16)


def test_types_without_a_layout_are_deserialized():
    assert fastpath.fast_layout("tf2_msgs/msg/TFMessage") is None
    with pytest.raises(ValueError, match="joint names"):
        fastpath.fast_layout(JS)
    typ = "std_msgs/msg/Int32"
    raws = _number_raws(typ, [1, 2, 3], "le")
    calls: list[bytes] = []

    def decode(raw: bytes) -> list[Sample]:
        calls.append(raw)
        return reference(deserialize(raw, typ, True), typ, ("l", "r"))

    got = fastpath.decode_messages(
        list(enumerate(raws)), ros2=True, width=1, decode=decode, layout_of=None
    )
    assert got.deserialized == len(calls) == 3
    np.testing.assert_array_equal(got.values[:, 0], [1.0, 2.0, 3.0])

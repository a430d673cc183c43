"""The inputs of the hostile-input corpus: the valid ones every case starts from, and the
bags a case's recipe asks for.

:func:`build_base` writes the valid inputs (a runs table as CSV, TSV, ``;`` and decimal
comma, a run log, the OptiOdom sessions, results, parameter YAML, ROS 1 / ROS 2 sqlite3 /
MCAP bags written with rosbags, a bag with a custom message type); :func:`bag_step`
writes a bag as a case file's recipe says (``tests/corpus_cases.py`` runs the steps).
"""

from __future__ import annotations

import math
import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

TABLE_ARGS = ("-b", "0.34", "-L", "4", "--unit", "mm")
BAG_FORMATS = ("ros1", "sqlite3", "mcap")
T0 = 1_750_000_000
WHEELS_MSG = "std_msgs/Header header\nfloat64 left\nfloat64 right\n"
ROS2_PARAMS = """\
diff_drive_controller:
  ros__parameters:
    left_wheel_names: ["left_wheel_joint"]
    right_wheel_names: ["right_wheel_joint"]
    wheel_separation: 0.34
    wheel_radius: 0.075
    wheel_separation_multiplier: 1.0
    left_wheel_radius_multiplier: 1.0
    right_wheel_radius_multiplier: 1.0
"""
ROS1_PARAMS = """\
diff_drive_controller:
  type: diff_drive_controller/DiffDriveController
  left_wheel: left_wheel_joint
  right_wheel: right_wheel_joint
  wheel_separation: 0.34
  wheel_radius: 0.075
  wheel_separation_multiplier: 1.0
  wheel_radius_multiplier: 1.0
"""

#: ``time (n,)``, wheel angles ``(n, 2)`` [rad] (left, right), true pose ``(n, 3)``.
Session = tuple[np.ndarray, np.ndarray, np.ndarray]


def umbmark(*args: str, cwd: Path) -> None:
    """Run ``python -m umbmark ARGS`` in ``cwd``; it must succeed."""
    cmd = [sys.executable, "-m", "umbmark", *args]
    subprocess.run(cmd, cwd=cwd, check=True, capture_output=True)


# --- valid inputs -----------------------------------------------------------------------


def build_base(base: Path) -> None:
    """Write the valid inputs every case starts from into ``base``."""
    base.mkdir(parents=True, exist_ok=True)
    umbmark("example", "runs.csv", cwd=base)
    data = [ln for ln in (base / "runs.csv").read_text().splitlines() if not ln.startswith("#")]
    for name, old, new in (
        ("runs.tsv", ",", "\t"),
        ("runs_semicolon.csv", ",", ";"),
        ("runs_decimal_comma.csv", ",", ";"),
    ):
        rows = [ln.replace(old, new) for ln in data]
        if name == "runs_decimal_comma.csv":
            rows = [ln.replace(".", ",") for ln in rows]
        (base / name).write_text("\n".join(rows) + "\n")
    umbmark("simulate", "-L", "1", "-n", "3", "-o", "sim.csv", "--logs", "logs", cwd=base)
    umbmark("example", "--real", "real", cwd=base)
    outputs = ("-o", "result.json", "--yaml", "overlay.yaml", "--ros1-yaml", "ros1.yaml")
    umbmark("calibrate", "runs.csv", *TABLE_ARGS, *outputs, cwd=base)
    other = ("-b", "0.5", "-L", "4", "--unit", "mm", "-o", "result_other.json")
    umbmark("calibrate", "runs.csv", *other, cwd=base)
    (base / "ros2_controllers.yaml").write_text(ROS2_PARAMS)
    (base / "ros1_params.yaml").write_text(ROS1_PARAMS)
    session = simulated_session()
    np.savez(base / "session.npz", *session)
    for fmt in BAG_FORMATS:
        write_session_bag(base / f"bag_{fmt}", fmt, session)
        write_custom_bag(base / f"custom_{fmt}", fmt, session)


def simulated_session(directions: Sequence[str] = ("cw", "cw", "ccw", "ccw")) -> Session:
    """Runs around a 1 m square with 3 s rests, every 2nd simulator step (50 Hz)."""
    from umbmark.core.conventions import Direction
    from umbmark.model.kinematics import WheelParams
    from umbmark.sim.engine import simulate
    from umbmark.sim.paths import square
    from umbmark.sim.robot import SimRobot

    odo = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
    robot = SimRobot.with_errors(odo, E_d=1.002, E_b=1.01)
    dirs = [Direction(d) for d in directions]
    result = simulate(robot, square(1.0), dirs, None, np.random.default_rng(0), record=True)
    trace = result.trace
    assert trace is not None
    dt = float(trace.time[1] - trace.time[0])
    still = round(3.0 / dt)
    counts: list[np.ndarray] = []
    poses: list[tuple[float, float, float]] = []
    base_counts = np.zeros(2, dtype=np.int64)
    x0 = y0 = th0 = 0.0

    def hold() -> None:
        for _ in range(still):
            counts.append(base_counts.copy())
            poses.append((x0, y0, th0))

    hold()
    for i in range(len(dirs)):
        n = int(result.samples_used[i]) + 1
        c, s = math.cos(th0), math.sin(th0)
        for k in range(n - 1):
            lx, ly, lth = trace.true_pose[i, k + 1]
            counts.append(base_counts + trace.counts[i, k + 1])
            poses.append((x0 + c * lx - s * ly, y0 + s * lx + c * ly, th0 + lth))
        base_counts = base_counts + trace.counts[i, n - 1]
        x0, y0, th0 = poses[-1]
        hold()
    times = np.arange(len(counts)) * dt
    angles = np.array(counts, dtype=np.float64) * odo.radians_per_pulse
    return times[::2], angles[::2], np.array(poses)[::2]


# --- bags -------------------------------------------------------------------------------


class _Bag:
    """A bag being written in ``fmt`` (``ros1``, ``sqlite3``, ``mcap``) and its messages."""

    def __init__(self, path: Path, fmt: str) -> None:
        from rosbags.rosbag1 import Writer as Writer1
        from rosbags.rosbag2 import Writer as Writer2
        from rosbags.rosbag2.enums import StoragePlugin
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
        ts.register(get_types_from_msg(WHEELS_MSG, "my_robot/msg/Wheels"))
        if fmt == "ros1":  # Noetic's store has no tf2_msgs; ROS 1 bags carry the definition
            tf = "geometry_msgs/TransformStamped[] transforms"
            ts.register(get_types_from_msg(tf, "tf2_msgs/msg/TFMessage"))
        self.fmt, self.ts, self.types = fmt, ts, ts.types
        self.serialize = ts.serialize_ros1 if fmt == "ros1" else ts.serialize_cdr
        if fmt == "ros1":
            self.path = path.with_suffix(".bag")
            self.writer = Writer1(self.path)
        else:
            plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
            self.path, self.writer = path, Writer2(path, version=9, storage_plugin=plugin)

    def topic(self, name: str, typ: str) -> Any:
        return self.writer.add_connection(name, typ, typestore=self.ts)

    def write(self, conn: Any, t: float, msg: Any, typ: str) -> None:
        self.writer.write(conn, round((T0 + float(t)) * 1e9), self.serialize(msg, typ))

    def msg(self, typ: str, **fields: Any) -> Any:
        return self.types[typ](**fields)

    def header(self, t: float, frame: str = "base") -> Any:
        sec, nsec = divmod(round((T0 + float(t)) * 1e9), 1_000_000_000)
        stamp = self.msg("builtin_interfaces/msg/Time", sec=sec, nanosec=nsec)
        seq = {"seq": 0} if self.fmt == "ros1" else {}
        return self.msg("std_msgs/msg/Header", **seq, stamp=stamp, frame_id=frame)

    def quaternion(self, th: float) -> Any:
        q = "geometry_msgs/msg/Quaternion"
        return self.msg(q, x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2))

    def pose_stamped(self, header: Any, x: float, y: float, th: float) -> Any:
        point = self.msg("geometry_msgs/msg/Point", x=x, y=y, z=0.0)
        pose = self.msg("geometry_msgs/msg/Pose", position=point, orientation=self.quaternion(th))
        return self.msg("geometry_msgs/msg/PoseStamped", header=header, pose=pose)

    def transform(self, t: float, parent: str, child: str, x: float, y: float, th: float) -> Any:
        shift = self.msg("geometry_msgs/msg/Vector3", x=x, y=y, z=0.0)
        move = self.msg(
            "geometry_msgs/msg/Transform", translation=shift, rotation=self.quaternion(th)
        )
        return self.msg(
            "geometry_msgs/msg/TransformStamped",
            header=self.header(t, parent),
            child_frame_id=child,
            transform=move,
        )


#: ``(sample index, joint names, wheel angles) -> (names, position, velocity)`` of a
#: JointState message: malformed ones, by the name a bag recipe gives (``joints``).
JOINTS: dict[str, Callable[[int, list[str], list[float]], tuple[list[Any], ...]]] = {
    "position-short": lambda k, n, a: (n, a[:1], []),
    "position-empty-some": lambda k, n, a: (n, a if k % 7 else [], []),
    "names-more": lambda k, n, a: ([*n, "caster"], a, []),
    "names-1000": lambda k, n, a: ([*n, *(f"j{i}" for i in range(1000))], a, []),
    "velocity-only": lambda k, n, a: (n, [], [1.0, 1.1]),
    "velocity-nan": lambda k, n, a: (n, [], [math.nan, 1.0]),
    "names-change": lambda k, n, a: (n if k < 500 else n[::-1], a, []),
}


def write_session_bag(
    path: Path,
    fmt: str,
    session: Session,
    *,
    wheel_type: str = "sensor_msgs/msg/JointState",
    truth_type: str = "geometry_msgs/msg/PoseStamped",
    names: Sequence[str] = ("left_wheel_joint", "right_wheel_joint"),
    truth: bool = True,
    wheels: bool = True,
    extra_topic: str | None = None,
    joints: str | None = None,
    imu: str | None = None,
) -> Path:
    """The session as JointState (wheel angles [rad]) on /joint_states and PoseStamped
    ground truth (every 2nd sample) on /mocap/pose; types may be swapped for wrong ones,
    ``joints`` names a malformation of :data:`JOINTS`; ``imu`` one of :data:`IMUS`, an IMU
    on /imu (``sensor_msgs/Imu`` in imu_link, level on base: ``/tf_static``)."""
    times, angles, poses = session
    bag = _Bag(path, fmt)

    def message(typ: str, t: float, k: int) -> Any:
        if typ == "sensor_msgs/msg/JointState":
            a = [float(angles[k, 0]), float(angles[k, 1])]
            name, position, velocity = (
                (list(names), [angles[k, 0], angles[k, 1]], [])
                if joints is None
                else JOINTS[joints](k, list(names), a)
            )
            return bag.msg(
                typ,
                header=bag.header(t),
                name=name,
                position=np.array(position, np.float64),
                velocity=np.array(velocity, np.float64),
                effort=np.array([], np.float64),
            )
        if typ == "geometry_msgs/msg/PoseStamped":
            return bag.pose_stamped(bag.header(t), *poses[k])
        if typ == "std_msgs/msg/String":
            return bag.msg(typ, data=f"sample {k}")
        if typ == "std_msgs/msg/Float64":
            return bag.msg(typ, data=float(angles[k, 0]))
        raise ValueError(typ)

    with bag.writer:
        if imu is not None:
            _write_imu(bag, imu, times, poses)
        js = bag.topic("/joint_states", wheel_type) if wheels else None
        gt = bag.topic("/mocap/pose", truth_type) if truth else None
        ex = bag.topic(extra_topic, "std_msgs/msg/String") if extra_topic else None
        for k, t in enumerate(times):
            if js is not None:
                bag.write(js, t, message(wheel_type, t, k), wheel_type)
            if gt is not None and k % 2 == 0:
                bag.write(gt, t, message(truth_type, t, k), truth_type)
            if ex is not None and k % 50 == 0:
                string = "std_msgs/msg/String"
                bag.write(ex, t, message(string, t, k), string)
    return bag.path


#: The IMUs a session bag may carry: a gyro that reads the true turn rate (its bias 0.3
#: deg/s, its noise 1e-3 rad/s a reading), and what goes wrong with one: a topic without
#: messages, every reading the same, a frame without a transform, accelerations only
#: (``angular_velocity_covariance[0] = -1``), the turns clipped at 0.6 rad/s (34 deg/s).
IMUS = ("ok", "empty", "frozen", "no-frame", "accel-only", "saturated")
IMU_MSG = "sensor_msgs/msg/Imu"


def _write_imu(bag: _Bag, kind: str, times: np.ndarray, poses: np.ndarray) -> None:
    """The IMU ``kind`` (:data:`IMUS`) of the session on /imu, and its mounting."""
    if kind not in IMUS:
        raise ValueError(kind)
    if kind != "no-frame":
        tf = bag.topic("/tf_static", "tf2_msgs/msg/TFMessage")
        move = bag.transform(0.0, "base_link", "imu_link", 0.0, 0.0, 0.0)
        bag.write(tf, 0.0, bag.msg("tf2_msgs/msg/TFMessage", transforms=[move]),
                  "tf2_msgs/msg/TFMessage")  # fmt: skip
    conn = bag.topic("/imu", IMU_MSG)
    if kind == "empty":
        return
    rng = np.random.default_rng(7)
    yaw = np.gradient(np.unwrap(poses[:, 2]), times) + math.radians(0.3)
    rates = np.column_stack([np.zeros_like(yaw), np.zeros_like(yaw), yaw])
    rates += rng.normal(0.0, 1e-3, rates.shape)
    if kind == "frozen":
        rates[:] = rates[0]
    if kind == "saturated":
        rates[:, 2] = np.clip(rates[:, 2], -0.6, 0.6)
    covariance = np.zeros(9)
    covariance[0] = -1.0 if kind == "accel-only" else 0.0
    none = np.zeros(9)
    none[0] = -1.0

    def vector(x: float, y: float, z: float) -> Any:
        return bag.msg("geometry_msgs/msg/Vector3", x=x, y=y, z=z)

    for k, t in enumerate(times):
        msg = bag.msg(
            IMU_MSG, header=bag.header(t, "imu_link"), orientation=bag.quaternion(0.0),
            orientation_covariance=none, angular_velocity=vector(*map(float, rates[k])),
            angular_velocity_covariance=covariance,
            linear_acceleration=vector(0.0, 0.0, 9.81), linear_acceleration_covariance=np.zeros(9),
        )  # fmt: skip
        bag.write(conn, t, msg, IMU_MSG)


def write_tf_ticks_bag(
    path: Path,
    fmt: str,
    session: Session,
    *,
    frames: Sequence[Sequence[str]] = (("map", "base"),),
    static: Sequence[Sequence[str]] = (),
    ticks_type: str = "std_msgs/msg/Int32",
    ticks: str | None = None,
) -> Path:
    """The session with ground truth on /tf (each ``(parent, child)`` of ``frames`` carries
    the true pose; each of ``static`` an identity on /tf_static) and the wheels as
    cumulative encoder counts (4096 a revolution) on /left_ticks and /right_ticks, made
    wrong as :data:`TICKS` ``[ticks]`` says."""
    times, angles, poses = session
    bag = _Bag(path, fmt)
    counts = np.round(angles / (2 * math.pi) * 4096.0)
    if ticks is not None:
        counts = TICKS[ticks](counts)
    tf_type = "tf2_msgs/msg/TFMessage"
    as_number = float if ticks_type.endswith("Float64") else int
    with bag.writer:
        tf = bag.topic("/tf", tf_type)
        tf_static = bag.topic("/tf_static", tf_type) if static else None
        left = bag.topic("/left_ticks", ticks_type)
        right = bag.topic("/right_ticks", ticks_type)
        if tf_static is not None:
            t0 = float(times[0])
            still = [bag.transform(t0, p, c, 0.0, 0.0, 0.0) for p, c in static]
            bag.write(tf_static, t0, bag.msg(tf_type, transforms=still), tf_type)
        for k, t in enumerate(times):
            bag.write(left, t, bag.msg(ticks_type, data=as_number(counts[k, 0])), ticks_type)
            bag.write(right, t, bag.msg(ticks_type, data=as_number(counts[k, 1])), ticks_type)
            if k % 2 == 0:
                moved = [bag.transform(float(t), p, c, *poses[k]) for p, c in frames]
                bag.write(tf, t, bag.msg(tf_type, transforms=moved), tf_type)
    return bag.path


def write_custom_bag(path: Path, fmt: str, session: Session) -> Path:
    """The session's wheels as a custom ``my_robot/msg/Wheels`` (left, right [rad])."""
    times, angles, poses = session
    bag = _Bag(path, fmt)
    typ, pose_type = "my_robot/msg/Wheels", "geometry_msgs/msg/PoseStamped"
    with bag.writer:
        conn = bag.topic("/wheels", typ)
        gt = bag.topic("/mocap/pose", pose_type)
        for k, t in enumerate(times):
            hdr = bag.header(t)
            wheels = bag.msg(typ, header=hdr, left=float(angles[k, 0]), right=float(angles[k, 1]))
            bag.write(conn, t, wheels, typ)
            if k % 2 == 0:
                bag.write(gt, t, bag.pose_stamped(hdr, *poses[k]), pose_type)
    return bag.path


def _half(s: Session) -> Session:
    n = s[0].size // 2
    return s[0][:n], s[1][:n], s[2][:n]


def _shifted(times: np.ndarray, start: int, count: int, by: float) -> np.ndarray:
    out = times.copy()
    out[start : start + count] += by
    return out


def _paired(times: np.ndarray) -> np.ndarray:
    out = times.copy()
    out[1::2] = out[::2][: out[1::2].size]
    return out


def _nan_rows(a: np.ndarray, start: int, stop: int) -> np.ndarray:
    out = a.copy()
    out[start:stop] = np.nan
    return out


def _left_jump(a: np.ndarray, by: float) -> np.ndarray:
    out = a.copy()
    out[out.shape[0] // 2 :, 0] += by
    return out


#: Encoder counts ``(n, 2)`` made wrong, by the name a bag recipe gives (``ticks``).
TICKS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "nan": lambda c: _nan_rows(c, 200, 205),
    "wrap-int16": lambda c: (c + 2**15) % 2**16 - 2**15,
    "wrap-uint8": lambda c: c % 256,
    "times-1e300": lambda c: c * 1e300,
    "still": lambda c: c * 0,
    "jump": lambda c: _left_jump(c, 4096 * 1e5),
}


#: The session made wrong before it is written, by the name a bag recipe gives (``edit``).
EDITS: dict[str, Callable[[Session], Session]] = {
    "no-messages": lambda s: (s[0][:0], s[1][:0], s[2][:0]),
    "one-message": lambda s: (s[0][:1], s[1][:1], s[2][:1]),
    "first-half": _half,
    "time-backwards": lambda s: (_shifted(s[0], s[0].size // 2, 200, -30.0), s[1], s[2]),
    "time-duplicated": lambda s: (_paired(s[0]), s[1], s[2]),
    "time-reversed": lambda s: (s[0][::-1].copy(), s[1], s[2]),
    "positions-1e300": lambda s: (s[0], s[1] * 1e300, s[2]),
    "positions-nan": lambda s: (s[0], _nan_rows(s[1], 100, 110), s[2]),
    "positions-inf": lambda s: (s[0], np.where(s[1] > 5, np.inf, s[1]), s[2]),
    "truth-1e300": lambda s: (s[0], s[1], s[2] * 1e300),
    "truth-still": lambda s: (s[0], s[1], s[2] * 0),
    "wheels-still": lambda s: (s[0], s[1] * 0, s[2]),
    "wheel-jump": lambda s: (s[0], _left_jump(s[1], 1e6), s[2]),
}


def bag_step(d: Path, b: Path, fmt: str, recipe: dict[str, Any], kind: str = "session") -> None:
    """Write ``d/bag`` in ``fmt``: ``kind`` ``session`` (JointState and PoseStamped,
    :func:`write_session_bag`) or ``tf`` (/tf and encoder ticks,
    :func:`write_tf_ticks_bag`), as ``recipe`` says: ``edit`` (:data:`EDITS`) and the
    writer's keywords (``truth``, ``wheels`` as ``"false"``; ``static_chain: N``: N + 2
    static frames in a row)."""
    opts = dict(recipe)
    data = np.load(b / "session.npz")
    session: Session = (data["arr_0"], data["arr_1"], data["arr_2"])
    if "edit" in opts:
        session = EDITS[opts.pop("edit")](session)
    for flag in ("truth", "wheels"):
        if flag in opts:
            opts[flag] = opts[flag] == "true"
    if "static_chain" in opts:
        n = int(opts.pop("static_chain"))
        links = [(f"f{i}", f"f{i + 1}") for i in range(n)]
        opts["static"] = [("map", "f0"), *links, (f"f{n}", "odom")]
    writer = write_tf_ticks_bag if kind == "tf" else write_session_bag
    writer(d / "bag", fmt, session, **opts)

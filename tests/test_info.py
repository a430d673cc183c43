"""``umbmark info``: what is in a bag, a run log or a session, and the options it suggests.

The bags are written here with rosbags' writers at known rates and with known motion;
every expected count, rate, duration, joint, transform and candidate comes from what the
test wrote, never from the code under test.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.core.errors import InputError

from helpers import OPTIODOM, api_error, cli_error, run_cli

pytest.importorskip("rosbags")

from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

TS2 = get_typestore(Stores.LATEST)
TS1 = get_typestore(Stores.ROS1_NOETIC)
# Noetic's store has no tf2_msgs; ROS 1 bags carry this definition.
TS1.register(
    get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
)
FORMATS = ["ros1", "sqlite3", "mcap"]
T0 = 1_760_000_000  # epoch seconds of the first stamp
RECEIVE_DELAY = 0.001  # bag time after the header stamp [s]

JS = "sensor_msgs/msg/JointState"
POSE = "geometry_msgs/msg/PoseStamped"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
ODOM = "nav_msgs/msg/Odometry"
TF = "tf2_msgs/msg/TFMessage"
INT32 = "std_msgs/msg/Int32"
STRING = "std_msgs/msg/String"


class Bag:
    """Messages to write: ``(topic, stamp [s from T0], message)``, and their types."""

    def __init__(self, fmt: str) -> None:
        self.fmt = fmt
        self.ts = TS1 if fmt == "ros1" else TS2
        self.types: dict[str, str] = {}
        self.messages: list[tuple[str, float, object]] = []

    def T(self, name: str):
        return self.ts.types[name]

    def header(self, t: float | None, frame: str = ""):
        if t is None:
            sec = nsec = 0
        else:
            sec, nsec = divmod(round((T0 + t) * 1e9), 1_000_000_000)
        stamp = self.T("builtin_interfaces/msg/Time")(sec=sec, nanosec=nsec)
        if self.fmt == "ros1":
            return self.T("std_msgs/msg/Header")(seq=0, stamp=stamp, frame_id=frame)
        return self.T("std_msgs/msg/Header")(stamp=stamp, frame_id=frame)

    def add(self, topic: str, msgtype: str, t: float, msg: object) -> None:
        self.types[topic] = msgtype
        self.messages.append((topic, t, msg))

    def pose(self, x: float, y: float, yaw: float):
        return self.T("geometry_msgs/msg/Pose")(
            position=self.T("geometry_msgs/msg/Point")(x=x, y=y, z=0.0),
            orientation=self.T("geometry_msgs/msg/Quaternion")(
                x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
            ),
        )

    def joint_state(self, t, names, position, stamp: float | None = -1.0):
        return self.T(JS)(
            header=self.header(t if stamp == -1.0 else stamp),
            name=list(names),
            position=np.array(position, np.float64),
            velocity=np.array([], np.float64),
            effort=np.array([], np.float64),
        )

    def pose_stamped(self, t, x, y, yaw, stamp: float | None = -1.0):
        return self.T(POSE)(
            header=self.header(t if stamp == -1.0 else stamp, "world"), pose=self.pose(x, y, yaw)
        )

    def pose_cov(self, t, x, y, yaw):
        with_cov = self.T("geometry_msgs/msg/PoseWithCovariance")(
            pose=self.pose(x, y, yaw), covariance=np.zeros(36)
        )
        return self.T(POSE_COV)(header=self.header(t, "map"), pose=with_cov)

    def odometry(self, t, x, y, yaw):
        with_cov = self.T("geometry_msgs/msg/PoseWithCovariance")(
            pose=self.pose(x, y, yaw), covariance=np.zeros(36)
        )
        vec = self.T("geometry_msgs/msg/Vector3")
        twist = self.T("geometry_msgs/msg/TwistWithCovariance")(
            twist=self.T("geometry_msgs/msg/Twist")(
                linear=vec(x=0.0, y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=0.0)
            ),
            covariance=np.zeros(36),
        )
        return self.T(ODOM)(
            header=self.header(t, "odom"), child_frame_id="base_link", pose=with_cov, twist=twist
        )

    def transform(self, t, parent, child, x, y, yaw, axis: str = "z"):
        vec = self.T("geometry_msgs/msg/Vector3")
        half = {"x": 0.0, "y": 0.0, "z": 0.0}
        half[axis] = math.sin(yaw / 2)
        return self.T("geometry_msgs/msg/TransformStamped")(
            header=self.header(t, parent),
            child_frame_id=child,
            transform=self.T("geometry_msgs/msg/Transform")(
                translation=vec(x=x, y=y, z=0.0),
                rotation=self.T("geometry_msgs/msg/Quaternion")(**half, w=math.cos(yaw / 2)),
            ),
        )

    def tf(self, transforms):
        return self.T(TF)(transforms=list(transforms))

    def write(self, path: Path) -> Path:
        if self.fmt == "ros1":
            path = path.with_suffix(".bag")
            writer: Writer1 | Writer2 = Writer1(path)
        else:
            plugin = StoragePlugin.MCAP if self.fmt == "mcap" else StoragePlugin.SQLITE3
            writer = Writer2(path, version=9, storage_plugin=plugin)
        serialize = self.ts.serialize_ros1 if self.fmt == "ros1" else self.ts.serialize_cdr
        with writer:
            conns = {
                topic: writer.add_connection(topic, typ, typestore=self.ts)
                for topic, typ in self.types.items()
            }
            for topic, t, msg in sorted(self.messages, key=lambda m: m[1]):
                bag_ns = round((T0 + t + RECEIVE_DELAY) * 1e9)
                writer.write(conns[topic], bag_ns, serialize(msg, self.types[topic]))
        return path


def still_then_moving(t: float, speed: float) -> float:
    """A wheel angle [rad]: still for the first 5 s, then turning at ``speed`` rad/s."""
    return 0.0 if t < 5 else speed * (t - 5)


def robot_bag(tmp_path: Path, fmt: str) -> Path:
    """20 s of a robot: joint states at 50 Hz, mocap at 100 Hz, AMCL at 2 Hz, odometry and
    /tf at 20 Hz, wheel counters at 10 Hz, a status topic at 5 Hz for 10 s only, and two
    static sensor mounts."""
    bag = Bag(fmt)
    for k in range(1001):  # 50 Hz
        t = 0.02 * k
        left, right = still_then_moving(t, 2.0), still_then_moving(t, 1.8)
        bag.add(
            "/joint_states",
            JS,
            t,
            bag.joint_state(t, ["wheel_left_joint", "wheel_right_joint", "caster_joint"],
                            [left, right, 0.3]),
        )  # fmt: skip
    for k in range(2001):  # 100 Hz
        t = 0.01 * k
        x = 0.1 * max(t - 5, 0.0)
        bag.add("/mocap/pose", POSE, t, bag.pose_stamped(t, x, 0.02 * x, 0.1 * x))
    for k in range(41):  # 2 Hz
        t = 0.5 * k
        x = 0.1 * max(t - 5, 0.0)
        bag.add("/amcl_pose", POSE_COV, t, bag.pose_cov(t, x, 0.0, 0.0))
    for k in range(401):  # 20 Hz
        t = 0.05 * k
        x = 0.1 * max(t - 5, 0.0)
        bag.add("/odom", ODOM, t, bag.odometry(t, x, 0.0, 0.1 * x))
        transforms = [
            bag.transform(t, "odom", "base_link", x, 0.0, 0.1 * x),
            bag.transform(t, "base_link", "wheel_left_link", 0.0, 0.17, 2 * x, axis="y"),
        ]
        if k % 2 == 0:  # 10 Hz
            transforms.append(bag.transform(t, "map", "odom", 0.5, 0.25, 0.0))
        bag.add("/tf", TF, t, bag.tf(transforms))
    for k in range(201):  # 10 Hz
        t = 0.1 * k
        counts = round(1000 * max(t - 5, 0.0))
        bag.add("/lwheel", INT32, t, bag.T(INT32)(data=counts))
        bag.add("/rwheel", INT32, t, bag.T(INT32)(data=counts + 7))
    for k in range(51):  # 5 Hz, for 10 s
        t = 0.2 * k
        bag.add("/status", STRING, t, bag.T(STRING)(data=f"ok {k}"))
    static = [
        bag.transform(0.0, "base_link", "laser_frame", 0.1, 0.0, 0.0),
        bag.transform(0.0, "base_link", "imu_link", 0.0, 0.0, 0.0),
    ]
    bag.add("/tf_static", TF, 0.0, bag.tf(static))
    return bag.write(tmp_path / f"robot_{fmt}")


# (topic, type, count, duration [s]) as written
TOPICS = [
    ("/amcl_pose", POSE_COV, 41, 20.0),
    ("/joint_states", JS, 1001, 20.0),
    ("/lwheel", INT32, 201, 20.0),
    ("/mocap/pose", POSE, 2001, 20.0),
    ("/odom", ODOM, 401, 20.0),
    ("/rwheel", INT32, 201, 20.0),
    ("/status", STRING, 51, 10.0),
    ("/tf", TF, 401, 20.0),
    ("/tf_static", TF, 1, 0.0),
]
SUGGESTED = (
    "--truth-topic /mocap/pose --left-joint wheel_left_joint --right-joint wheel_right_joint"
)


@pytest.fixture(scope="module", params=FORMATS)
def robot(request, tmp_path_factory) -> Path:
    return robot_bag(tmp_path_factory.mktemp("bag"), request.param)


def test_topics_counts_rates_and_durations(robot):
    report = umbmark.info(robot)
    data = report.to_dict()
    assert data["format"] == "bag"
    assert data["storage"] == {".bag": "ros1"}.get(robot.suffix, data["storage"])
    assert data["messages"] == sum(count for _, _, count, _ in TOPICS)
    assert data["start"] == pytest.approx(T0 + RECEIVE_DELAY, abs=1e-6)
    assert data["duration"] == pytest.approx(20.0, abs=1e-6)
    got = [(t["name"], t["type"], t["count"], t["duration"]) for t in data["topics"]]
    assert [g[:3] for g in got] == [w[:3] for w in TOPICS]
    for (_, _, count, duration), topic in zip(TOPICS, data["topics"], strict=True):
        assert topic["duration"] == pytest.approx(duration, abs=1e-6), topic["name"]
        if count > 1:
            assert topic["rate"] == pytest.approx((count - 1) / duration, rel=1e-6)
        else:
            assert topic["rate"] is None
    # the mocap topic has more messages than are looked into: sampled, not complete
    mocap = next(t for t in data["topics"] if t["name"] == "/mocap/pose")
    assert mocap["scanned"] == 2000
    assert data["complete"] is False
    status = next(t for t in data["topics"] if t["name"] == "/status")
    assert status["scanned"] == 0  # strings are not looked into
    assert json.loads(report.to_json()) == data


def test_joints_and_which_move(robot):
    (js,) = umbmark.info(robot).to_dict()["joint_states"]
    assert js["topic"] == "/joint_states"
    assert js["complete"] is True
    assert js["scanned"] == 1001
    joints = {j["name"]: j for j in js["joints"]}
    assert list(joints) == ["wheel_left_joint", "wheel_right_joint", "caster_joint"]
    assert joints["wheel_left_joint"]["position_range"] == pytest.approx(2.0 * 15, abs=1e-9)
    assert joints["wheel_right_joint"]["position_range"] == pytest.approx(1.8 * 15, abs=1e-9)
    assert joints["caster_joint"]["position_range"] == 0.0
    assert [j["moving"] for j in joints.values()] == [True, True, False]
    assert all(j["samples"] == 1001 for j in joints.values())
    # no velocities: the speed is the positions' change over the stamps, 2.0 and 1.8 rad/s
    # as written (the caster stands still)
    assert joints["wheel_left_joint"]["max_speed"] == pytest.approx(2.0, rel=1e-6)
    assert joints["wheel_right_joint"]["max_speed"] == pytest.approx(1.8, rel=1e-6)
    assert joints["caster_joint"]["max_speed"] == 0.0
    assert {j["speed_from"] for j in joints.values()} == {"positions"}


def test_a_bounded_scan_still_sees_wheels_that_start_moving_late(robot):
    data = umbmark.info(robot, max_messages=40).to_dict()
    (js,) = data["joint_states"]
    assert js["complete"] is False
    assert js["scanned"] == 40
    # The first 5 of the 40 messages are from the first 0.1 s, when nothing moves; the
    # stretches spread over the 20 s see the wheels turn.
    joints = {j["name"]: j for j in js["joints"]}
    assert joints["wheel_left_joint"]["moving"] is True
    assert joints["caster_joint"]["moving"] is False
    assert data["max_messages"] == 40
    # Counts and durations stay exact.
    topic = next(t for t in data["topics"] if t["name"] == "/joint_states")
    assert topic["count"] == 1001
    assert topic["duration"] == pytest.approx(20.0, abs=1e-6)


def test_transforms_and_chains(robot):
    data = umbmark.info(robot).to_dict()
    tfs = {(t["parent"], t["child"]): t for t in data["transforms"]}
    assert set(tfs) == {
        ("odom", "base_link"),
        ("base_link", "wheel_left_link"),
        ("map", "odom"),
        ("base_link", "laser_frame"),
        ("base_link", "imu_link"),
    }
    assert tfs["odom", "base_link"]["rate"] == pytest.approx(20.0, rel=1e-6)
    # 201 of 401 messages: the topic's 20 Hz times 201/401, within 0.3 % of 10 Hz
    assert tfs["map", "odom"]["rate"] == pytest.approx(10.0, rel=3e-3)
    assert tfs["base_link", "laser_frame"]["static"] is True
    assert tfs["base_link", "laser_frame"]["rate"] is None
    assert tfs["odom", "base_link"]["moving"] is True
    assert tfs["base_link", "wheel_left_link"]["moving"] is True  # it only turns
    assert tfs["map", "odom"]["moving"] is False
    # sensor mounts are left out of the chains
    assert data["chains"] == [["map", "odom", "base_link", "wheel_left_link"]]


def test_candidates_and_suggested_options(robot):
    report = umbmark.info(robot)
    data = report.to_dict()
    wheels = data["candidates"]["wheels"]
    assert wheels[0]["options"] == {
        "--wheel-topic": "/joint_states",
        "--left-joint": "wheel_left_joint",
        "--right-joint": "wheel_right_joint",
    }
    assert wheels[0]["moving"] is True
    assert wheels[1]["kind"] == "ticks"
    assert wheels[1]["options"]["--left-ticks-topic"] == "/lwheel"
    assert wheels[1]["options"]["--right-ticks-topic"] == "/rwheel"
    assert wheels[1]["moving"] is True
    truth = data["candidates"]["truth"]
    # The controller's /odom, and the chain map -> odom -> base_link whose map -> odom never
    # moves (so it is that odometry), are no ground truth and are not listed.
    assert [c["label"] for c in truth] == [f"/mocap/pose ({POSE})", f"/amcl_pose ({POSE_COV})"]
    # rates as written; --max-gap: 1.1 times the intervals (0.01 s, 0.5 s), two digits
    assert [c["rate"] for c in truth] == [pytest.approx(100.0), pytest.approx(2.0)]
    assert [c["max_gap"] for c in truth] == [pytest.approx(0.011), pytest.approx(0.55)]
    assert all(c["warning"] is None and c["headings"] for c in truth)
    odometry = data["candidates"]["odometry"]
    assert [c["options"] for c in odometry] == [
        {"--odom-topic": "/odom"},
        {"--odom-tf": "odom base_link"},
    ]
    assert data["suggested_options"] == SUGGESTED
    assert report.suggested_options == SUGGESTED
    assert SUGGESTED in repr(report)


def test_the_suggested_options_read_the_bag(robot):
    """What info suggests, calibrate accepts: the wheels and the truth are found."""
    argv = SUGGESTED.split()
    options = {argv[i].lstrip("-").replace("-", "_"): argv[i + 1] for i in range(0, len(argv), 2)}
    report = umbmark.replay(robot, wheelbase=0.3, wheel_diameter=0.1, split="none", **options)
    (run,) = report.runs
    assert run.log is not None
    assert run.log.time[-1] == pytest.approx(20.0, abs=1e-6)


def test_empty_header_stamps_suggest_the_bag_time(tmp_path):
    bag = Bag("sqlite3")
    for k in range(300):
        t = 0.01 * k
        angle = 2.0 * t
        bag.add("/joint_states", JS, t,
                bag.joint_state(t, ["l_wheel", "r_wheel"], [angle, angle], stamp=None))  # fmt: skip
        bag.add("/vicon/robot", POSE, t, bag.pose_stamped(t, 0.1 * t, 0.0, 0.0, stamp=None))
    path = bag.write(tmp_path / "nostamps")
    report = umbmark.info(path)
    assert report.suggested_options == (
        "--truth-topic /vicon/robot --left-joint l_wheel --right-joint r_wheel --time-source bag"
    )
    assert any("/joint_states" in w and "--time-source bag" in w for w in report.warnings)


def test_a_bag_without_candidates(tmp_path):
    bag = Bag("mcap")
    for k in range(10):
        bag.add("/status", STRING, 0.1 * k, bag.T(STRING)(data="ok"))
    report = umbmark.info(bag.write(tmp_path / "plain"))
    data = report.to_dict()
    assert data["candidates"] == {"wheels": [], "odometry": [], "truth": []}
    assert data["suggested_options"] is None
    assert data["topics"][0]["rate"] == pytest.approx(10.0, rel=1e-6)
    assert data["complete"] is True


@pytest.mark.slow
def test_the_command_prints_a_summary(robot):
    """(That ``--json`` is the library's dictionary: tests/cli/test_main.py, for every command.)"""
    proc = run_cli("info", str(robot))
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    for fragment in (
        "/mocap/pose",
        "wheel_left_joint",
        "map -> odom -> base_link -> wheel_left_link",
        f"Suggested options: {SUGGESTED}",
        "at most 2000 messages per topic",
    ):
        assert fragment in out, fragment


def test_left_and_right_names_are_paired():
    from umbmark.sources.bag.names import mirrored_pairs

    names = ["wheel_left_joint", "wheel_right_joint", "l_wheel", "r_wheel", "wheel_l", "wheel_r",
             "LeftWheel", "RightWheel", "fl_wheel", "fr_wheel", "/lwheel", "/rwheel",
             "caster_joint", "left_only", "lidar", "rlidar"]  # fmt: skip
    assert mirrored_pairs(names) == [
        ("wheel_left_joint", "wheel_right_joint"),
        ("l_wheel", "r_wheel"),
        ("wheel_l", "wheel_r"),
        ("LeftWheel", "RightWheel"),
        ("fl_wheel", "fr_wheel"),
        ("/lwheel", "/rwheel"),
    ]


def test_chains_leave_sensor_mounts_out():
    from umbmark.sources.bag.info.frames import TransformInfo, tf_chains

    def tf(parent, child, static):
        return TransformInfo(parent, child, "/tf_static" if static else "/tf", 1, None)

    transforms = [
        tf("map", "odom", True),  # a static link above a moving one is kept
        tf("odom", "base_footprint", False),
        tf("base_footprint", "base_link", True),
        tf("base_link", "left_wheel", False),
        tf("base_link", "right_wheel", False),
        tf("base_link", "laser", True),
        tf("world", "mocap_robot", False),
    ]
    assert tf_chains(transforms) == [
        ("map", "odom", "base_footprint", "base_link", "left_wheel"),
        ("map", "odom", "base_footprint", "base_link", "right_wheel"),
        ("world", "mocap_robot"),
    ]
    # only static transforms: followed to their leaves
    assert tf_chains([tf("base_link", "laser", True), tf("base_link", "imu", True)]) == [
        ("base_link", "laser"),
        ("base_link", "imu"),
    ]


# --- missing ground truth ----------------------------------------------------------------


@pytest.mark.slow
def test_calibrating_a_bag_without_ground_truth_names_the_candidates(robot):
    err = api_error(umbmark.calibrate, robot, wheelbase=0.3, wheel_diameter=0.1, side_length=1)
    assert err.startswith(f"{robot}: no ground truth given (truth_topic or tf_parent/tf_child)")
    assert err.endswith(f"candidates: /mocap/pose ({POSE}), /amcl_pose ({POSE_COV})")
    line = cli_error("calibrate", str(robot), "-b", "0.3", "--wheel-diameter", "0.1", "-L", "1")
    assert "no ground truth given" in line
    line = cli_error("replay", str(robot), "-b", "0.3", "--wheel-diameter", "0.1")
    assert "candidates: /mocap/pose" in line


def test_without_any_candidate(tmp_path):
    bag = Bag("ros1")
    for k in range(10):
        t = 0.1 * k
        bag.add(
            "/joint_states",
            JS,
            t,
            bag.joint_state(t, ["left_wheel_joint", "right_wheel_joint"], [t, t]),
        )
    path = bag.write(tmp_path / "wheels_only")
    err = api_error(umbmark.calibrate, path, wheelbase=0.3, wheel_diameter=0.1, side_length=1)
    assert "no ground truth given" in err
    assert err.endswith("the bag has no pose, odometry or TF topics")


# --- other sources -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    umbmark.simulate(runs=2, side_length=2, seed=3, logs=folder / "log", output=folder / "runs.csv")
    return folder


@pytest.mark.slow
def test_a_run_log(logs):
    report = umbmark.info(logs / "log")
    data = report.to_dict()
    assert data["format"] == "log"
    assert data["runs"] == 4  # 2 cw + 2 ccw, one file each
    assert [f["name"] for f in data["files"]] == [f"run-{i:02d}.csv" for i in range(1, 5)]
    for f in data["files"]:
        lines = (logs / "log" / f["name"]).read_text().splitlines()
        data_lines = [line for line in lines if not line.startswith("#")][1:]
        rows = np.array([[float(c) for c in line.split(",")] for line in data_lines])
        assert f["wheel_samples"] == rows.shape[0]
        assert f["duration"] == pytest.approx(rows[-1, 0] - rows[0, 0])
    assert data["duration"] == pytest.approx(sum(f["duration"] for f in data["files"]))
    assert data["wheel_parameters"]["wheelbase"] == 0.34
    assert data["wheel_parameters"]["wheel_diameter"] == 0.15
    assert data["side_length"] == 2.0
    assert data["suggested_options"] is None
    assert "runs=4" in repr(report)
    proc = run_cli("info", str(logs / "log"))
    assert proc.returncode == 0, proc.stderr
    assert "run log, 4 runs" in proc.stdout
    assert "b = 340.00 mm" in proc.stdout


@pytest.mark.skipif(not (OPTIODOM / "square" / "230620202042").is_dir(), reason="no data")
def test_an_optiodom_session():
    data = umbmark.info(OPTIODOM / "square" / "230620202042").to_dict()
    assert data["format"] == "optiodom"
    assert data["runs"] == 6
    assert len(data["files"]) == 6
    assert data["wheel_parameters"]["wheelbase"] == 0.2
    assert data["side_length"] == 0.75


@pytest.mark.slow
def test_other_sources_are_refused_with_one_line(logs, tmp_path):
    err = api_error(umbmark.info, logs / "runs.csv")
    assert err.startswith(f"{logs / 'runs.csv'}: is read as a runs table")
    assert "nothing to look into" in err
    assert "no such file" in api_error(umbmark.info, tmp_path / "missing.bag")
    empty = tmp_path / "empty"
    empty.mkdir()
    assert "no known layout" in cli_error("info", str(empty))
    fake = tmp_path / "fake.bag"
    fake.write_text("hello")
    assert cli_error("info", str(fake)).startswith(f"umbmark: error: {fake}: cannot read the bag")
    assert "--max-messages" in cli_error("info", str(fake), "--max-messages", "0")
    with pytest.raises(InputError, match="max_messages=0"):
        umbmark.info(fake, max_messages=0)


def test_every_option_is_a_keyword_of_the_library_function():
    import inspect

    from umbmark.cli.main import cli

    keywords = set(inspect.signature(umbmark.info).parameters)
    for param in cli.commands["info"].params:
        if param.name != "json_out":
            assert param.name in keywords, param.name


def test_a_ros1_bag_whose_index_is_damaged_is_one_line(tmp_path: Path) -> None:
    # a real bag whose index record counts one message more than it holds: rosbags stops
    # on an internal assertion with no text, which alone would tell the user nothing
    store = get_typestore(Stores.ROS1_NOETIC)
    path = tmp_path / "damaged.bag"
    with Writer1(path) as writer:
        conn = writer.add_connection("/n", "std_msgs/msg/Int32", typestore=store)
        for k in range(3):
            message = store.types["std_msgs/msg/Int32"](data=k)
            writer.write(conn, 10**9 * (k + 1), store.serialize_ros1(message, conn.msgtype))
    data = bytearray(path.read_bytes())
    op = data.find(b"op=\x04")  # the index data record's header
    count = data.find(b"count=", op - 60, op + 60) + len(b"count=")
    assert op > 0
    assert data[count] == 3
    data[count] = 4
    path.write_bytes(bytes(data))
    line = cli_error("info", str(path))
    assert line.startswith(f"umbmark: error: {path}: cannot read the bag: AssertionError: its")
    assert "a damaged index" in line
    assert "rosbag reindex" in line

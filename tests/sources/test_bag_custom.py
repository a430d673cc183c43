"""Wheel data in custom message types, and the progress of reading bags.

Real bags written with rosbags' writers (ROS 1, ROS 2 sqlite3 and MCAP) hold a vendor's
wheel message, ``my_robot_msgs/msg/WheelEncoders``, registered in the writer's typestore
from its ``.msg`` text. Every expected value is what the test wrote: angles, counts,
stamps and poses computed here, never by the code under test.
"""

from __future__ import annotations

import io
import json
import math
import sqlite3
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pytest

import umbmark
from umbmark.model.kinematics import WheelParams
from umbmark.sim.robot import SimRobot

from helpers import api_error, run_cli, simulated_session

pytest.importorskip("rosbags")

from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from umbmark.sources import progress
from umbmark.sources.bag.bag_options import BagOptions
from umbmark.sources.bag.recording import read_bag

FORMATS = ["ros1", "sqlite3", "mcap"]
ENCODERS = "my_robot_msgs/msg/WheelEncoders"
PAIR = "my_robot_msgs/msg/WheelPair"
STATE = "my_robot_msgs/msg/WheelState"
POSE = "geometry_msgs/msg/PoseStamped"
#: The .msg files of the vendor's package.
MSG = {
    ENCODERS: (
        "# Wheel encoders of my robot\n"
        "std_msgs/Header header\n"
        "int32 left_ticks\n"
        "int32 right_ticks\n"
        "float64[] positions\n"
        "WheelState[2] wheels\n"
        "string note\n"
        "uint32 from  # a Python keyword: rosbags names the attribute from_\n"
    ),
    STATE: "float64 position\nint16 counter\n",
    PAIR: "WheelState left\nWheelState right\n",  # no header: bag time
}
TPR = 4096  # encoder counts per wheel revolution
WRAP_OFFSET = 32_000  # the int16 counters start here, so they wrap soon
T0 = 1_700_000_000  # epoch seconds of the first stamp
N = 120  # messages per topic
DT = 0.02  # [s] between messages
BAG_DELAY_NS = 3_000_000  # the recorder receives each message 3 ms after its stamp


def typestore(fmt: str):
    ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
    for name in (STATE, ENCODERS, PAIR):
        ts.register(get_types_from_msg(MSG[name], name))
    return ts


def truth_angles(t: np.ndarray) -> np.ndarray:
    """The wheel angles [rad] the bags hold, shape (n, 2): left, right."""
    return np.column_stack([0.8 * t + 0.3 * np.sin(t), 1.1 * t])


def counts_of(angles: np.ndarray) -> np.ndarray:
    return np.round(angles * TPR / (2 * math.pi)).astype(np.int64)


def int16(value: int) -> int:
    """``value`` as a 16-bit counter shows it (wrapped into -32768 .. 32767)."""
    return (value + 32768) % 65536 - 32768


def stamp_ns(k: int) -> int:
    return T0 * 1_000_000_000 + round(k * DT * 1e9)


def write_bag(
    path: Path,
    fmt: str,
    n: int = N,
    *,
    pair: bool = False,
    strip_definitions: bool = False,
) -> Path:
    """A bag with ``/wheels`` (WheelEncoders, or WheelPair) and ``/mocap/pose``.

    ``strip_definitions``: a sqlite3 bag without message definitions, as rosbag2 wrote
    them before Iron.
    """
    ts = typestore(fmt)
    types = ts.types
    if fmt == "ros1":
        path = path.with_suffix(".bag")
        writer: Writer1 | Writer2 = Writer1(path)
    else:
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    serialize = ts.serialize_ros1 if fmt == "ros1" else ts.serialize_cdr
    t = np.arange(n) * DT
    angles = truth_angles(t)
    counts = counts_of(angles)

    def header(k: int, frame: str):
        sec, nsec = divmod(stamp_ns(k), 1_000_000_000)
        stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        if fmt == "ros1":
            return types["std_msgs/msg/Header"](seq=k, stamp=stamp, frame_id=frame)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def state(k: int, side: int):
        counter = int16(int(counts[k, side]) + WRAP_OFFSET)
        return types[STATE](position=float(angles[k, side]), counter=counter)

    wheel_type = PAIR if pair else ENCODERS
    with writer:
        wheels = writer.add_connection("/wheels", wheel_type, typestore=ts)
        mocap = writer.add_connection("/mocap/pose", POSE, typestore=ts)
        for k in range(n):
            if pair:
                msg = types[PAIR](left=state(k, 0), right=state(k, 1))
            else:
                msg = types[ENCODERS](
                    header=header(k, "base_link"),
                    left_ticks=int(counts[k, 0]),
                    right_ticks=int(counts[k, 1]),
                    positions=np.array(angles[k], np.float64),
                    wheels=[state(k, 0), state(k, 1)],
                    note="ok",
                    from_=int(counts[k, 0]),
                )
            writer.write(wheels, stamp_ns(k) + BAG_DELAY_NS, serialize(msg, wheel_type))
            yaw = 0.5 * t[k]
            pose = types[POSE](
                header=header(k, "world"),
                pose=types["geometry_msgs/msg/Pose"](
                    position=types["geometry_msgs/msg/Point"](x=t[k], y=-2 * t[k], z=0.0),
                    orientation=types["geometry_msgs/msg/Quaternion"](
                        x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
                    ),
                ),
            )
            writer.write(mocap, stamp_ns(k) + BAG_DELAY_NS, serialize(pose, POSE))
    if strip_definitions:
        assert fmt == "sqlite3"
        (db,) = path.glob("*.db3")
        with sqlite3.connect(db) as con:
            con.execute("DELETE FROM message_definitions")
        con.close()
    return path


def write_msg_files(root: Path, names: Iterable[str], *, flat: bool = False) -> Path:
    """The package's ``.msg`` files: ``<pkg>/msg/<Name>.msg``, or ``<pkg>/<Name>.msg``."""
    for name in names:
        package, _, short = name.partition("/msg/")
        folder = root / package if flat else root / package / "msg"
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"{short}.msg").write_text(MSG[name], encoding="utf-8")
    return root


def expected_time(n: int = N, *, bag: bool = False) -> np.ndarray:
    """Seconds of the stamps (or bag times) written, as ``sec + nanosec * 1e-9``."""
    ns = np.array([stamp_ns(k) + (BAG_DELAY_NS if bag else 0) for k in range(n)])
    sec, nsec = np.divmod(ns, 1_000_000_000)
    return sec + nsec * 1e-9


def fields(left: str, right: str, **more: object) -> BagOptions:
    return BagOptions(wheel_topic="/wheels", left_field=left, right_field=right, **more)  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def bags(tmp_path_factory) -> dict[str, Path]:
    """One bag of each format; ROS 1 bags and these ROS 2 bags carry the definitions."""
    root = tmp_path_factory.mktemp("custom")
    return {fmt: write_bag(root / fmt, fmt) for fmt in FORMATS}


@pytest.fixture(scope="module")
def bare(tmp_path_factory) -> Path:
    """A sqlite3 bag that carries no message definitions (rosbag2 before Iron)."""
    return write_bag(tmp_path_factory.mktemp("bare") / "bare", "sqlite3", strip_definitions=True)


# --- reading custom messages -----------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
def test_counts_and_angles_of_a_custom_message(bags, fmt):
    angles = truth_angles(np.arange(N) * DT)
    counts = counts_of(angles)
    wheels, truth = read_bag(bags[fmt], fields("left_ticks", "right_ticks", ticks_per_rev=TPR))
    np.testing.assert_allclose(wheels.time, expected_time(), rtol=0, atol=1e-9)
    np.testing.assert_allclose(wheels.angles, counts * (2 * math.pi / TPR), rtol=0, atol=1e-12)
    assert truth is None

    wheels, _ = read_bag(bags[fmt], fields("from", "right_ticks", ticks_per_rev=TPR))
    np.testing.assert_allclose(wheels.angles, counts * (2 * math.pi / TPR), rtol=0, atol=1e-12)

    wheels, _ = read_bag(bags[fmt], fields("positions[0]", "positions[1]"))
    np.testing.assert_array_equal(wheels.angles, angles)  # float64 stored and read exactly

    # nested: an array of messages, and a field of each; the ground truth alongside
    wheels, truth = read_bag(
        bags[fmt], fields("wheels[0].position", "wheels[1].position", truth_topic="/mocap/pose")
    )
    np.testing.assert_array_equal(wheels.angles, angles)
    assert truth is not None
    t = np.arange(N) * DT
    np.testing.assert_allclose(truth.poses[:, 0], t, atol=1e-12)
    np.testing.assert_allclose(truth.poses[:, 1], -2 * t, atol=1e-12)
    np.testing.assert_allclose(truth.poses[:, 2], 0.5 * t, atol=1e-12)


def test_16_bit_counters_are_unwrapped(bags):
    counts = counts_of(truth_angles(np.arange(N) * DT)) + WRAP_OFFSET
    written = [int16(int(c)) for c in counts[:, 1]]
    assert min(written) < 0 < max(written)  # the right counter did wrap
    wheels, _ = read_bag(
        bags["mcap"],
        fields("wheels[0].counter", "wheels[1].counter", ticks_per_rev=TPR),
    )
    np.testing.assert_allclose(wheels.angles, counts * (2 * math.pi / TPR), rtol=0, atol=1e-9)


def test_time_is_the_bag_time_without_a_header_or_when_asked(tmp_path, bags):
    pair = write_bag(tmp_path / "pair", "sqlite3", pair=True)
    wheels, _ = read_bag(pair, fields("left.position", "right.position"))
    np.testing.assert_allclose(wheels.time, expected_time(bag=True), rtol=0, atol=1e-9)
    np.testing.assert_array_equal(wheels.angles, truth_angles(np.arange(N) * DT))
    wheels, _ = read_bag(bags["ros1"], fields("positions[0]", "positions[1]", time_source="bag"))
    np.testing.assert_allclose(wheels.time, expected_time(bag=True), rtol=0, atol=1e-9)


# --- definitions from .msg files -------------------------------------------------------


@pytest.mark.slow
def test_a_bag_without_definitions_needs_msg_dir(tmp_path, bare):
    options = fields("left_ticks", "right_ticks", ticks_per_rev=TPR)
    err = api_error(read_bag, bare, options)
    assert err == (
        f"{bare}: topic /wheels has type {ENCODERS}, whose definition the bag does not "
        "carry: give --msg-dir with its .msg files"
    )
    expected = counts_of(truth_angles(np.arange(N) * DT)) * (2 * math.pi / TPR)
    for root, flat, given in [
        (tmp_path / "ws", False, tmp_path / "ws"),  # a workspace: <pkg>/msg/<Name>.msg
        (tmp_path / "pkg", False, tmp_path / "pkg" / "my_robot_msgs" / "msg"),  # msg/ itself
        (tmp_path / "flat", True, tmp_path / "flat"),  # <pkg>/<Name>.msg
    ]:
        write_msg_files(root, [ENCODERS, STATE], flat=flat)
        wheels, _ = read_bag(
            bare, fields("left_ticks", "right_ticks", ticks_per_rev=TPR, msg_dir=given)
        )
        np.testing.assert_allclose(wheels.angles, expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(wheels.time, expected_time(), rtol=0, atol=1e-9)


@pytest.mark.slow
def test_msg_dir_errors_name_the_type_or_the_file(tmp_path, bare):
    def error(msg_dir: Path) -> str:
        options = fields("left_ticks", "right_ticks", ticks_per_rev=TPR, msg_dir=msg_dir)
        return api_error(read_bag, bare, options)

    only_top = write_msg_files(tmp_path / "only_top", [ENCODERS])
    err = error(only_top)
    assert f"the definition of {STATE} (used by {ENCODERS}) is neither in the bag" in err
    assert "my_robot_msgs/msg/WheelState.msg" in err

    broken = write_msg_files(tmp_path / "broken", [ENCODERS, STATE])
    bad_file = broken / "my_robot_msgs" / "msg" / "WheelState.msg"
    bad_file.write_text("float64 position\nint16[ counter\n", encoding="utf-8")
    err = error(broken)
    assert err.startswith(f"{bad_file.resolve()}: not a valid definition of {STATE}")

    assert error(tmp_path / "nowhere") == f"{tmp_path / 'nowhere'}: no such folder of .msg files"


def test_definitions_in_the_bag_win_over_msg_dir(tmp_path, bags):
    wrong = tmp_path / "wrong" / "my_robot_msgs" / "msg"
    wrong.mkdir(parents=True)
    (wrong / "WheelEncoders.msg").write_text("int8 left_ticks\nint8 right_ticks\n")
    options = fields("left_ticks", "right_ticks", ticks_per_rev=TPR, msg_dir=wrong)
    wheels, _ = read_bag(bags["sqlite3"], options)
    expected = counts_of(truth_angles(np.arange(N) * DT)) * (2 * math.pi / TPR)
    np.testing.assert_allclose(wheels.angles, expected, rtol=0, atol=1e-12)


# --- field paths -----------------------------------------------------------------------


def test_field_path_errors_list_what_is_there(bags):
    bag = bags["ros1"]

    def error(left: str, right: str = "positions[1]", **more: object) -> str:
        return api_error(read_bag, bag, fields(left, right, **more))

    err = error("left_tick")
    assert err.startswith(f"{bag}: left field 'left_tick' of /wheels: {ENCODERS} has no field")
    assert "its fields: header (std_msgs/msg/Header), left_ticks (int32), right_ticks" in err
    assert "positions (float64[]), wheels (my_robot_msgs/msg/WheelState[2]), note (string)" in err
    err = error("wheels[0].angle")
    assert f"{STATE} has no field 'angle'; its fields: position (float64), counter (int16)" in err
    assert "note is string, not a number" in error("note")
    assert "header is a message (std_msgs/msg/Header), not a number" in error("header")
    assert "positions is an array (float64[]): give an index, e.g. positions[0]" in error(
        "positions"
    )
    assert "wheels (my_robot_msgs/msg/WheelState[2]) has 2 entries" in error("wheels[2].position")
    assert "left_ticks is int32, not an array" in error("left_ticks[0]")
    assert "left_ticks is int32, which has no field 'x'" in error("left_ticks.x")
    # an integer read as an angle is a mistake: counts need counts per revolution
    assert "is an integer (int32): encoder counts need --ticks-per-rev" in error(
        "left_ticks", "right_ticks"
    )
    # a sequence shorter than the index, found while reading
    assert "has too few entries for the field positions[7]" in error("positions[7]")


def test_malformed_field_options_are_refused_before_reading(tmp_path):
    missing = tmp_path / "missing.bag"  # never opened: the options are refused first
    for left, right, problem in [
        ("left ticks", "right_ticks", "is not a field path"),
        ("a.b.c.d.e.f.g.h.i", "right_ticks", "is deeper than 8 fields"),
        ("positions[70000]", "right_ticks", "index 70000 is larger than 65535"),
        ("positions[0][1]", "right_ticks", "is not a field path"),
        ("left_ticks", "left_ticks", "the left and right fields are the same"),
    ]:
        assert problem in api_error(read_bag, missing, fields(left, right))
    err = api_error(read_bag, missing, BagOptions(left_field="left_ticks"))
    assert "give both or neither" in err
    err = api_error(read_bag, missing, BagOptions(msg_dir=tmp_path))
    assert "--msg-dir is for wheel data in a custom message type" in err
    both = fields("a", "b", left_ticks_topic="/l", right_ticks_topic="/r", ticks_per_rev=1)
    err = api_error(read_bag, missing, both)
    assert "--left-field/--right-field read the wheels from --wheel-topic: leave out" in err


# --- through the job and the command ---------------------------------------------------

ODO = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
ROBOT_E_D, ROBOT_E_B = 1.002, 1.01
ROBOT = SimRobot.with_errors(ODO, E_d=ROBOT_E_D, E_b=ROBOT_E_B)
COUNTS_PER_REV = 2000 * 20


def write_session(path: Path, session) -> Path:
    """A simulated session as an old sqlite3 bag of WheelEncoders (no definitions), every
    other sample of it (50 Hz), wheels and ground truth alike."""
    times, counts, poses, _ = session
    ts = typestore("sqlite3")
    types = ts.types
    writer = Writer2(path, version=9, storage_plugin=StoragePlugin.SQLITE3)

    def header(t: float):
        sec, nsec = divmod(round((T0 + t) * 1e9), 1_000_000_000)
        stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id="base")

    zero = types[STATE](position=0.0, counter=0)
    with writer:
        wheels = writer.add_connection("/wheels", ENCODERS, typestore=ts)
        mocap = writer.add_connection("/mocap/pose", POSE, typestore=ts)
        for k in range(0, times.size, 2):
            t = float(times[k])
            bag_ns = round((T0 + t) * 1e9)
            msg = types[ENCODERS](
                header=header(t),
                left_ticks=int(counts[k, 0]),
                right_ticks=int(counts[k, 1]),
                positions=np.array([], np.float64),
                wheels=[zero, zero],
                note="",
                from_=0,
            )
            writer.write(wheels, bag_ns, ts.serialize_cdr(msg, ENCODERS))
            x, y, th = poses[k]
            pose = types[POSE](
                header=header(t),
                pose=types["geometry_msgs/msg/Pose"](
                    position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                    orientation=types["geometry_msgs/msg/Quaternion"](
                        x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2)
                    ),
                ),
            )
            writer.write(mocap, bag_ns, ts.serialize_cdr(pose, POSE))
    (db,) = path.glob("*.db3")
    with sqlite3.connect(db) as con:
        con.execute("DELETE FROM message_definitions")
    con.close()
    return path


@pytest.mark.slow
def test_the_command_calibrates_from_a_custom_message(tmp_path):
    session = simulated_session(ROBOT, ["cw", "cw", "ccw", "ccw"], side=1.0, rest=1.5)
    bag = write_session(tmp_path / "session", session)
    msg_dir = write_msg_files(tmp_path / "msgs", [ENCODERS, STATE])
    args = ["-b", "0.34", "--wheel-diameter", "0.15", "-L", "1", "--truth-topic", "/mocap/pose"]
    args += ["--wheel-topic", "/wheels", "--left-field", "left_ticks", "--right-field"]
    args += ["right_ticks", "--ticks-per-rev", str(COUNTS_PER_REV)]
    proc = run_cli("calibrate", str(bag), *args, "--msg-dir", str(msg_dir), "--json")
    assert proc.returncode == 0, proc.stderr
    # no progress bar in captured output: stderr is no terminal
    assert "reading bag" not in proc.stderr
    assert "\x1b[" not in proc.stdout + proc.stderr
    data = json.loads(proc.stdout)
    assert [r["direction"] for r in data["runs"]] == ["cw", "cw", "ccw", "ccw"]
    # the simulated robot's errors: without slip, the runs show them to 1e-4
    assert data["E_d"] == pytest.approx(ROBOT_E_D, abs=1e-4)
    assert data["E_b"] == pytest.approx(ROBOT_E_B, abs=1e-4)
    options = {"wheelbase": 0.34, "wheel_diameter": 0.15, "side_length": 1.0}
    options |= {"truth_topic": "/mocap/pose", "wheel_topic": "/wheels"}
    options |= {"left_field": "left_ticks", "right_field": "right_ticks"}
    err = api_error(umbmark.calibrate, bag, **options, ticks_per_rev=COUNTS_PER_REV)
    assert err == (
        f"{bag}: topic /wheels has type {ENCODERS}, whose definition the bag does not carry: "
        "give msg_dir with its .msg files"
    )


def test_the_job_checks_the_field_options(tmp_path):
    def error(**options: object) -> str:
        return api_error(umbmark.calibrate, tmp_path / "never.bag", wheelbase=0.34, **options)

    assert "left_field and right_field go together" in error(left_field="left_ticks")
    assert "left_field='left ticks' is not a field path" in error(
        left_field="left ticks", right_field="right_ticks"
    )
    err = error(left_field="a", right_field="b", odom_topic="/odom")
    assert "left_field/right_field read the wheels from wheel_topic: leave out odom_topic" in err
    err = error(msg_dir=tmp_path)
    assert "msg_dir is for wheel data in a custom message type" in err


# --- progress --------------------------------------------------------------------------


def test_progress_counts_up_to_every_message_read(bags, monkeypatch):
    monkeypatch.setattr(progress, "REPORT_EVERY", 7)
    calls: list[tuple[int, int]] = []
    options = fields("positions[0]", "positions[1]", truth_topic="/mocap/pose")
    read_bag(bags["mcap"], options, progress=lambda read, total: calls.append((read, total)))
    total = 2 * N  # the wheel and the truth topics, every message once
    assert calls[0] == (0, total)
    assert calls[-1] == (total, total)
    assert all(t == total for _, t in calls)
    reads = [r for r, _ in calls]
    assert reads == sorted(reads)
    assert len(set(reads)) == len(reads)
    assert len(calls) >= total // 7  # reported as it goes, not only at the end

    # the same through a reading_progress block, from a job that reads the bag deep inside
    seen: list[tuple[int, int]] = []
    with progress.reading_progress(lambda read, total: seen.append((read, total))):
        read_bag(bags["ros1"], options)
    assert seen[0] == (0, total)
    assert seen[-1] == (total, total)
    calls.clear()
    read_bag(bags["ros1"], options)  # outside the block: no one is told
    assert calls == []


def test_the_bar_shows_only_long_reads_on_a_terminal(monkeypatch):
    from rich.console import Console

    from umbmark.cli import common

    def feed(console: Console, total: int) -> str:
        bar = common._ReadingBar(console)
        for read in range(0, total + 1, 50):
            bar(read, total)
        bar.close()
        file = console.file
        assert isinstance(file, io.StringIO)
        return file.getvalue()

    def terminal() -> Console:
        return Console(file=io.StringIO(), force_terminal=True, width=100)

    assert feed(terminal(), 1000) == ""  # short: done before the bar is worth showing
    monkeypatch.setattr(common, "BAR_MESSAGES", 500)
    assert "reading bag" in feed(terminal(), 1000)
    piped = Console(file=io.StringIO(), force_terminal=False)
    assert feed(piped, 1000) == ""

    # inside another command's bar (validate): one more line of that display, then gone
    from rich.progress import Progress

    outer = Progress(console=terminal())
    monkeypatch.setattr(common, "_LIVE", [outer])
    bar = common._ReadingBar(terminal())
    bar(0, 1000)
    assert [task.description for task in outer.tasks] == ["reading bag"]
    bar(1000, 1000)
    assert outer.tasks == []

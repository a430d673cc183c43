"""Hostile-input corpus: bad, odd and hostile inputs for every reader and every option.

Issue 10 reported a corpus of 832 hostile inputs this project did not have; this script
is ours. It writes valid inputs of every kind into a temporary folder (a runs table as
CSV, TSV and ``;``, a run log, an OptiOdom session, ROS 1 / ROS 2 sqlite3 / MCAP bags
written with rosbags, ros2_control and ROS 1 parameter YAML, a result JSON, a bag with a
custom message type), mutates them (truncation, byte flips, encodings, columns, numbers,
empty files, folders, symlink loops, permissions, long paths, huge cells, deep YAML and
JSON, alias bombs, device files, bags with wrong types or times) and hands each case to
``python -m umbmark ...`` in a subprocess under a wall-time limit and a 1 GB
address-space limit. Each outcome is classified (:func:`classify`):

* ``ok-result``: exit 0 (stderr holds only ``umbmark: warning:`` / ``umbmark: wrote``
  lines, ``--json`` output is strict JSON);
* ``clean-error``: exit 2 or 3 with exactly one ``umbmark: error:`` line (warnings
  before it allowed);
* ``traceback``: a Python traceback, exit 1 or 70 (an internal error), or a crash;
* ``hang``: the wall-time limit ran out;
* ``memory``: a ``MemoryError`` / "out of memory" under the 1 GB limit, or killed;
* ``wrong-result``: a case with a known-wrong outcome ended with exit 0 without the
  warning that names its cause (or an output check failed);
* ``unclean``: any other stderr text (click's usage block, numpy warnings, ...);
* ``refused-valid``: a valid input that was refused.

Permission cases need a process that file modes apply to: run as root, each case drops
``CAP_DAC_OVERRIDE`` and ``CAP_DAC_READ_SEARCH`` from its bounding set before it starts
(so root obeys modes like any owner); where that is impossible those cases are skipped
and the summary says so.

Usage::

    python tools/hostile_corpus.py               # build, run every case, print the summary
    python tools/hostile_corpus.py --list        # the cases
    python tools/hostile_corpus.py --filter bag  # only cases whose name contains 'bag'
    python tools/hostile_corpus.py --jobs 2 --timeout 60 --keep DIR
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: Address-space limit of every case [bytes]: the issue's "runs over 1 GB".
MEMORY_LIMIT = 1 << 30
#: Default wall-time limit of a case [s]: longer is a hang.
TIMEOUT = 60.0

FAILURES = ("traceback", "hang", "memory", "wrong-result", "unclean", "refused-valid")
CLASSES = ("ok-result", "clean-error", *FAILURES)

TABLE_ARGS = ("-b", "0.34", "-L", "4", "--unit", "mm")
BAG_ARGS = ("-b", "0.34", "--wheel-diameter", "0.15", "-L", "1", "--truth-topic", "/mocap/pose")
BAG_FORMATS = ("ros1", "sqlite3", "mcap")


# --- cases ----------------------------------------------------------------------------

Setup = Callable[[Path, Path], None]
Check = Callable[[Path, "Outcome"], "str | None"]


@dataclass
class Case:
    """One hostile input: files made by ``setup(case_dir, base_dir)``, then the command.

    ``argv`` follows ``python -m umbmark``; ``{d}`` is the case's folder, ``{b}`` the
    folder of the valid inputs. ``expect``: ``any`` (a result or one clean error),
    ``error`` (must be refused), ``warn`` (refused, or exit 0 with a warning holding one
    of ``warn``, any warning when empty), ``ok`` (a valid input: must succeed).
    ``stdout``: ``pipe``, ``full`` (/dev/full) or ``head`` (closed after 10 bytes).
    """

    name: str
    reader: str
    argv: list[str]
    setup: Setup | None = None
    expect: str = "any"
    warn: tuple[str, ...] = ()
    env: dict[str, str] = field(default_factory=dict)
    stdout: str = "pipe"
    needs_modes: bool = False
    check: Check | None = None
    timeout: float | None = None


@dataclass
class Outcome:
    """What one case did: exit status (None: timed out), output, time [s]."""

    returncode: int | None
    stdout: str
    stderr: str
    seconds: float
    peak_mib: float | None = None


@dataclass
class Verdict:
    """A case's class and, for failures, why."""

    case: Case
    klass: str
    detail: str
    outcome: Outcome
    command: str


def _lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if line.strip()]


def classify(case: Case, out: Outcome, case_dir: Path | None = None) -> tuple[str, str]:
    """The class of an outcome (see the module docstring) and a short reason."""
    text = out.stdout + out.stderr
    err = _lines(out.stderr)
    if out.returncode is None:
        return "hang", f"no end within {out.seconds:.0f} s"
    if "MemoryError" in text or any("out of memory" in line for line in err):
        return "memory", "ran out of the 1 GB address space"
    if out.returncode in (-signal.SIGKILL, 137):
        return "memory", "killed"
    if "Traceback" in text:
        return "traceback", "a Python traceback"
    if out.returncode == 70 or any("internal error" in line for line in err):
        return "traceback", "internal error (exit 70)"
    broken_pipe = case.stdout == "head"
    if out.returncode == 1 and not broken_pipe:
        return "traceback", "exit 1"
    if out.returncode not in (0, 1, 2, 3):
        return "traceback", f"exit {out.returncode}"
    # ours: errors, warnings, files written and notes of what was done (``umbmark: ...``)
    stray = [line for line in err if not line.startswith("umbmark: ")]
    if stray:
        return "unclean", f"stderr not ours: {stray[0][:120]}"
    errors = [line for line in err if line.startswith("umbmark: error: ")]
    if out.returncode in (2, 3):
        if len(errors) != 1 or err[-1] != errors[0]:
            return "unclean", f"{len(errors)} error line(s) on exit {out.returncode}"
        if case.expect == "ok":
            return "refused-valid", errors[0][:160]
        return "clean-error", errors[0][:160]
    if errors:
        return "unclean", "an error line on exit 0"
    if broken_pipe:
        return "ok-result", "quiet on a broken pipe"
    if "--json" in case.argv and case.stdout == "pipe":
        problem = _strict_json(out.stdout)
        if problem:
            return "wrong-result", f"--json output: {problem}"
    if case.expect == "error":
        return "wrong-result", "accepted (exit 0); it must be refused"
    if case.expect == "warn":
        warnings = [line.lower() for line in err if line.startswith("umbmark: warning: ")]
        wanted = [w.lower() for w in case.warn]
        if not any(not wanted or any(w in line for w in wanted) for line in warnings):
            return "wrong-result", f"exit 0 without a warning about {' / '.join(case.warn)}"
    if case.check is not None and case_dir is not None:
        problem = case.check(case_dir, out)
        if problem:
            return "wrong-result", problem
    return "ok-result", "exit 0"


def _strict_json(text: str) -> str | None:
    def refuse(name: str) -> float:
        raise ValueError(f"{name} is not JSON")

    try:
        json.loads(text, parse_constant=refuse)
    except ValueError as exc:
        return str(exc).splitlines()[0][:100]
    return None


# --- running --------------------------------------------------------------------------

#: Runs in the child before umbmark: the 1 GB address-space limit and, for root, the
#: capabilities that let it ignore file modes dropped from the bounding set (so the exec
#: that follows starts without them); then it runs ``python ARGS`` as its own child,
#: writes that child's peak resident memory [KiB] to ``$UMBMARK_CORPUS_RSS`` and ends as
#: the child ended (its exit status, or the same signal). A launcher rather than
#: ``preexec_fn``, which is unsafe with the threads of ``--jobs``.
LAUNCHER = f"""
import ctypes, os, resource, signal, sys
resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_LIMIT}, {MEMORY_LIMIT}))
if os.geteuid() == 0:
    libc = ctypes.CDLL(None, use_errno=True)
    for cap in (1, 2):  # CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH
        libc.prctl(24, cap, 0, 0, 0)  # PR_CAPBSET_DROP
pid = os.fork()
if pid == 0:
    os.execv(sys.executable, [sys.executable, *sys.argv[1:]])
for fd in (0, 1):
    os.close(fd)
_, status, usage = os.wait4(pid, 0)
report = os.environ.get("UMBMARK_CORPUS_RSS")
if report:
    with open(report, "w") as file:
        file.write(str(usage.ru_maxrss))
if os.WIFSIGNALED(status):
    signal.signal(os.WTERMSIG(status), signal.SIG_DFL)
    os.kill(os.getpid(), os.WTERMSIG(status))
os._exit(os.waitstatus_to_exitcode(status))
"""


def limited(*args: str) -> list[str]:
    """The command line that runs ``python ARGS`` under :data:`LAUNCHER`'s limits."""
    return [sys.executable, "-c", LAUNCHER, *args]


def modes_apply(folder: Path) -> bool:
    """Do file modes stop a case's process here (a user, or root without DAC caps)?"""
    probe = folder / "mode-probe"
    probe.write_text("x")
    probe.chmod(0)
    try:
        proc = subprocess.run(
            limited("-c", f"open({str(probe)!r}).read()"),
            capture_output=True,
            check=False,
        )
        return proc.returncode != 0
    finally:
        probe.chmod(0o600)
        probe.unlink()


def _expand(arg: str, case_dir: Path, base: Path) -> str:
    return arg.replace("{d}", str(case_dir)).replace("{b}", str(base))


def run_case(case: Case, root: Path, base: Path, timeout: float) -> Verdict:
    """Set up the case's files in its own folder under ``root``, run it, classify it."""
    case_dir = root / "".join(c if c.isalnum() or c in "-_.=" else "_" for c in case.name)
    if case_dir.exists() or case_dir.is_symlink():  # a rerun into a kept corpus
        _restore_modes(case_dir)
        shutil.rmtree(case_dir)
    case_dir.mkdir(parents=True)
    argv = [_expand(a, case_dir, base) for a in case.argv]
    command = "python -m umbmark " + " ".join(_quote(a) for a in argv)
    try:
        if case.setup is not None:
            case.setup(case_dir, base)
    except Exception as exc:  # a broken case, not a finding
        out = Outcome(0, "", "", 0.0)
        return Verdict(case, "setup-failed", f"{type(exc).__name__}: {exc}", out, command)
    env = {**os.environ, "COLUMNS": "80", "OPENBLAS_NUM_THREADS": "1", **case.env}
    env.pop("UMBMARK_HISTORY", None)
    env.setdefault("UMBMARK_HISTORY", str(case_dir / "history.sqlite3"))
    env.update(case.env)
    rss_file = root / f".{case_dir.name}.rss"
    env["UMBMARK_CORPUS_RSS"] = str(rss_file)
    limit = case.timeout or timeout
    start = time.perf_counter()
    stdout_target: int | object = subprocess.PIPE
    devfull = None
    if case.stdout == "full":
        devfull = open("/dev/full", "wb")  # noqa: SIM115
        stdout_target = devfull
    try:
        proc = subprocess.Popen(
            limited("-m", "umbmark", *argv),
            cwd=case_dir,
            stdin=subprocess.DEVNULL,
            stdout=stdout_target,  # type: ignore[arg-type]
            stderr=subprocess.PIPE,
            env=env,
            start_new_session=True,
        )
    except OSError as exc:  # an argument longer than the kernel takes: a broken case
        if devfull is not None:
            devfull.close()
        out = Outcome(0, "", "", 0.0)
        return Verdict(case, "setup-failed", f"cannot start: {exc}", out, command)
    try:
        if case.stdout == "head":
            assert proc.stdout is not None
            head = proc.stdout.read(10)
            proc.stdout.close()
            _, err = proc.communicate(timeout=limit)
            stdout = head
        else:
            stdout, err = proc.communicate(timeout=limit)
        code: int | None = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        stdout, err = b"", b""
        proc.wait()
        code = None
    finally:
        if devfull is not None:
            devfull.close()
    seconds = time.perf_counter() - start
    peak: float | None = None
    if rss_file.exists():
        text = rss_file.read_text().strip()
        peak = int(text) / 1024 if text.isdigit() else None
        rss_file.unlink()
    out = Outcome(
        code,
        (stdout or b"").decode("utf-8", "replace"),
        (err or b"").decode("utf-8", "replace"),
        seconds,
        peak,
    )
    klass, detail = classify(case, out, case_dir)
    _restore_modes(case_dir)
    return Verdict(case, klass, detail, out, command)


def _restore_modes(folder: Path) -> None:
    for path in [folder, *folder.rglob("*")] if folder.exists() else []:
        try:
            if not path.is_symlink():
                path.chmod(0o700 if path.is_dir() else 0o600)
        except OSError:
            pass


def _quote(arg: str) -> str:
    if len(arg) > 120:
        return f"'{arg[:40]}...({len(arg)} chars)'"
    if not arg or any(c in arg for c in " '\"$;|&<>*?()\\\t\n"):
        return "'" + arg.replace("'", "'\\''") + "'"
    return arg


# --- valid inputs ---------------------------------------------------------------------


def _umbmark(*args: str, cwd: Path) -> None:
    subprocess.run(
        [sys.executable, "-m", "umbmark", *args], cwd=cwd, check=True, capture_output=True
    )


def build_base(base: Path) -> None:
    """Write the valid inputs every case starts from into ``base``."""
    base.mkdir(parents=True, exist_ok=True)
    _umbmark("example", "runs.csv", cwd=base)
    lines = (base / "runs.csv").read_text().splitlines()
    data = [line for line in lines if not line.startswith("#")]
    (base / "runs.tsv").write_text("\n".join(line.replace(",", "\t") for line in data) + "\n")
    (base / "runs_semicolon.csv").write_text(
        "\n".join(line.replace(",", ";") for line in data) + "\n"
    )
    (base / "runs_decimal_comma.csv").write_text(
        "\n".join(line.replace(",", ";").replace(".", ",") for line in data) + "\n"
    )
    _umbmark("simulate", "-L", "1", "-n", "3", "-o", "sim.csv", "--logs", "logs", cwd=base)
    _umbmark("example", "--real", "real", cwd=base)
    _umbmark(
        "calibrate",
        "runs.csv",
        *TABLE_ARGS,
        "-o",
        "result.json",
        "--yaml",
        "overlay.yaml",
        "--ros1-yaml",
        "ros1.yaml",
        cwd=base,
    )
    _umbmark(
        "calibrate",
        "runs.csv",
        "-b",
        "0.5",
        "-L",
        "4",
        "--unit",
        "mm",
        "-o",
        "result_other.json",
        cwd=base,
    )
    (base / "ros2_controllers.yaml").write_text(ROS2_PARAMS)
    (base / "ros1_params.yaml").write_text(ROS1_PARAMS)
    session = simulated_session()
    np.savez(base / "session.npz", *session)
    for fmt in BAG_FORMATS:
        write_session_bag(base / f"bag_{fmt}", fmt, *session)
        write_custom_bag(base / f"custom_{fmt}", fmt, *session)


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

SessionArrays = tuple[np.ndarray, np.ndarray, np.ndarray]
#: ``(sample index, joint names, wheel angles) -> (names, position, velocity)`` of a
#: JointState message, to write malformed ones.
JointFn = Callable[[int, list[str], list[float]], tuple[list[str], list[float], list[float]]]


def simulated_session(directions: Sequence[str] = ("cw", "cw", "ccw", "ccw")) -> SessionArrays:
    """Runs around a 1 m square with 3 s rests: ``time (n,)``, wheel angles ``(n, 2)``
    [rad] (left, right), true pose ``(n, 3)``; every 2nd simulator step (50 Hz)."""
    from umbmark.core.conventions import Direction
    from umbmark.model.kinematics import WheelParams
    from umbmark.sim.engine import simulate
    from umbmark.sim.paths import square
    from umbmark.sim.robot import VirtualRobot

    odo = WheelParams(wheelbase=0.34, wheel_diameter=0.15, encoder_resolution=2000, gear_ratio=20)
    robot = VirtualRobot.with_errors(odo, E_d=1.002, E_b=1.01)
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


T0 = 1_750_000_000


def _typestore(fmt: str):  # type: ignore[no-untyped-def]  # noqa: ANN202
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.LATEST)
    ts.register(get_types_from_msg(WHEELS_MSG, "my_robot/msg/Wheels"))
    if fmt == "ros1":  # Noetic's store has no tf2_msgs; ROS 1 bags carry the definition
        ts.register(
            get_types_from_msg(
                "geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"
            )
        )
    return ts


WHEELS_MSG = "std_msgs/Header header\nfloat64 left\nfloat64 right\n"


def _writer(path: Path, fmt: str):  # type: ignore[no-untyped-def]  # noqa: ANN202
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.rosbag2.enums import StoragePlugin

    if fmt == "ros1":
        return path.with_suffix(".bag"), Writer1(path.with_suffix(".bag"))
    plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
    return path, Writer2(path, version=9, storage_plugin=plugin)


def write_session_bag(
    path: Path,
    fmt: str,
    times: np.ndarray,
    angles: np.ndarray,
    poses: np.ndarray,
    *,
    wheel_type: str = "sensor_msgs/msg/JointState",
    truth_type: str = "geometry_msgs/msg/PoseStamped",
    names: tuple[str, str] = ("left_wheel_joint", "right_wheel_joint"),
    truth: bool = True,
    wheels: bool = True,
    extra_topic: str | None = None,
    joints: JointFn | None = None,
) -> Path:
    """The session as JointState (wheel angles [rad]) and PoseStamped ground truth (every
    2nd sample) on /joint_states and /mocap/pose; types may be swapped for wrong ones."""
    ts = _typestore(fmt)
    types = ts.types
    path, writer = _writer(path, fmt)
    serialize = ts.serialize_ros1 if fmt == "ros1" else ts.serialize_cdr

    def header(t: float):  # type: ignore[no-untyped-def]  # noqa: ANN202
        sec, nsec = divmod(round((T0 + t) * 1e9), 1_000_000_000)
        stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        if fmt == "ros1":
            return types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="base")
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id="base")

    def message(typ: str, t: float, k: int):  # type: ignore[no-untyped-def]  # noqa: ANN202
        if typ == "sensor_msgs/msg/JointState":
            name, position, velocity = (
                (list(names), [angles[k, 0], angles[k, 1]], [])
                if joints is None
                else joints(k, list(names), [float(angles[k, 0]), float(angles[k, 1])])
            )
            return types[typ](
                header=header(t),
                name=name,
                position=np.array(position, np.float64),
                velocity=np.array(velocity, np.float64),
                effort=np.array([], np.float64),
            )
        if typ == "geometry_msgs/msg/PoseStamped":
            x, y, th = poses[k]
            return types[typ](
                header=header(t),
                pose=types["geometry_msgs/msg/Pose"](
                    position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                    orientation=types["geometry_msgs/msg/Quaternion"](
                        x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2)
                    ),
                ),
            )
        if typ == "std_msgs/msg/String":
            return types[typ](data=f"sample {k}")
        if typ == "std_msgs/msg/Float64":
            return types[typ](data=float(angles[k, 0]))
        raise ValueError(typ)

    with writer:
        js = writer.add_connection("/joint_states", wheel_type, typestore=ts) if wheels else None
        gt = writer.add_connection("/mocap/pose", truth_type, typestore=ts) if truth else None
        ex = (
            writer.add_connection(extra_topic, "std_msgs/msg/String", typestore=ts)
            if extra_topic
            else None
        )
        for k, t in enumerate(times):
            stamp = round((T0 + float(t)) * 1e9)
            if js is not None:
                writer.write(js, stamp, serialize(message(wheel_type, t, k), wheel_type))
            if gt is not None and k % 2 == 0:
                writer.write(gt, stamp, serialize(message(truth_type, t, k), truth_type))
            if ex is not None and k % 50 == 0:
                msg = message("std_msgs/msg/String", t, k)
                writer.write(ex, stamp, serialize(msg, "std_msgs/msg/String"))
    return path


def write_tf_ticks_bag(
    path: Path,
    fmt: str,
    times: np.ndarray,
    angles: np.ndarray,
    poses: np.ndarray,
    *,
    frames: Sequence[tuple[str, str]] = (("map", "base"),),
    static: Sequence[tuple[str, str]] = (),
    ticks_type: str = "std_msgs/msg/Int32",
    ticks_per_rev: float = 4096.0,
    tick_fn: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Path:
    """The session with ground truth on /tf (each ``(parent, child)`` of ``frames`` carries
    the true pose; each of ``static`` an identity on /tf_static) and the wheels as
    cumulative encoder counts on /left_ticks and /right_ticks (``ticks_per_rev`` counts per
    revolution, passed through ``tick_fn``)."""
    ts = _typestore(fmt)
    types = ts.types
    path, writer = _writer(path, fmt)
    serialize = ts.serialize_ros1 if fmt == "ros1" else ts.serialize_cdr
    counts = np.round(angles / (2 * math.pi) * ticks_per_rev)
    if tick_fn is not None:
        counts = tick_fn(counts)
    tf_type = "tf2_msgs/msg/TFMessage"

    def header(t: float, frame: str):  # type: ignore[no-untyped-def]  # noqa: ANN202
        sec, nsec = divmod(round((T0 + t) * 1e9), 1_000_000_000)
        stamp = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        if fmt == "ros1":
            return types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def transform(t: float, parent: str, child: str, x: float, y: float, th: float):  # type: ignore[no-untyped-def]  # noqa: ANN202
        return types["geometry_msgs/msg/TransformStamped"](
            header=header(t, parent),
            child_frame_id=child,
            transform=types["geometry_msgs/msg/Transform"](
                translation=types["geometry_msgs/msg/Vector3"](x=x, y=y, z=0.0),
                rotation=types["geometry_msgs/msg/Quaternion"](
                    x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2)
                ),
            ),
        )

    def number(value: float):  # type: ignore[no-untyped-def]  # noqa: ANN202
        if ticks_type.endswith("Float64"):
            return types[ticks_type](data=float(value))
        return types[ticks_type](data=int(value))

    with writer:
        tf = writer.add_connection("/tf", tf_type, typestore=ts)
        tf_static = writer.add_connection("/tf_static", tf_type, typestore=ts) if static else None
        left = writer.add_connection("/left_ticks", ticks_type, typestore=ts)
        right = writer.add_connection("/right_ticks", ticks_type, typestore=ts)
        if tf_static is not None:
            msg = types[tf_type](
                transforms=[transform(float(times[0]), p, c, 0.0, 0.0, 0.0) for p, c in static]
            )
            writer.write(tf_static, round((T0 + float(times[0])) * 1e9), serialize(msg, tf_type))
        for k, t in enumerate(times):
            stamp = round((T0 + float(t)) * 1e9)
            writer.write(left, stamp, serialize(number(counts[k, 0]), ticks_type))
            writer.write(right, stamp, serialize(number(counts[k, 1]), ticks_type))
            if k % 2 == 0:
                x, y, th = poses[k]
                msg = types[tf_type](
                    transforms=[transform(float(t), p, c, x, y, th) for p, c in frames]
                )
                writer.write(tf, stamp, serialize(msg, tf_type))
    return path


def write_custom_bag(
    path: Path, fmt: str, times: np.ndarray, angles: np.ndarray, poses: np.ndarray
) -> Path:
    """The session's wheels as a custom ``my_robot/msg/Wheels`` (left, right [rad])."""
    ts = _typestore(fmt)
    types = ts.types
    path, writer = _writer(path, fmt)
    serialize = ts.serialize_ros1 if fmt == "ros1" else ts.serialize_cdr
    typ = "my_robot/msg/Wheels"
    with writer:
        conn = writer.add_connection("/wheels", typ, typestore=ts)
        gt = writer.add_connection("/mocap/pose", "geometry_msgs/msg/PoseStamped", typestore=ts)
        for k, t in enumerate(times):
            sec, nsec = divmod(round((T0 + float(t)) * 1e9), 1_000_000_000)
            stamp_msg = types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
            hdr = (
                types["std_msgs/msg/Header"](seq=0, stamp=stamp_msg, frame_id="base")
                if fmt == "ros1"
                else types["std_msgs/msg/Header"](stamp=stamp_msg, frame_id="base")
            )
            stamp = round((T0 + float(t)) * 1e9)
            msg = types[typ](header=hdr, left=float(angles[k, 0]), right=float(angles[k, 1]))
            writer.write(conn, stamp, serialize(msg, typ))
            if k % 2 == 0:
                x, y, th = poses[k]
                pose = types["geometry_msgs/msg/PoseStamped"](
                    header=hdr,
                    pose=types["geometry_msgs/msg/Pose"](
                        position=types["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                        orientation=types["geometry_msgs/msg/Quaternion"](
                            x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2)
                        ),
                    ),
                )
                writer.write(gt, stamp, serialize(pose, "geometry_msgs/msg/PoseStamped"))
    return path


def _session(base: Path) -> SessionArrays:
    data = np.load(base / "session.npz")
    return data["arr_0"], data["arr_1"], data["arr_2"]


def _bag_path(fmt: str, name: str = "bag") -> str:
    return f"{{d}}/{name}.bag" if fmt == "ros1" else f"{{d}}/{name}"


def _base_bag(fmt: str, name: str = "bag") -> str:
    return f"{{b}}/{name}_{fmt}.bag" if fmt == "ros1" else f"{{b}}/{name}_{fmt}"


# --- mutations ------------------------------------------------------------------------


def _copy(src: str, dst: str = "") -> Setup:
    """Copy ``base/src`` (a file or folder) into the case folder (as ``dst``)."""

    def setup(d: Path, b: Path) -> None:
        source = b / src
        target = d / (dst or Path(src).name)
        if source.is_dir():
            shutil.copytree(source, target)
        else:
            shutil.copy(source, target)

    return setup


def _write(name: str, content: bytes | str | Callable[[Path], bytes | str]) -> Setup:
    def setup(d: Path, b: Path) -> None:
        data = content(b) if callable(content) else content
        target = d / name
        target.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(data, str):
            target.write_text(data, encoding="utf-8")
        else:
            target.write_bytes(data)

    return setup


def _chain(*steps: Setup) -> Setup:
    def setup(d: Path, b: Path) -> None:
        for step in steps:
            step(d, b)

    return setup


def _mutate_file(rel: str, fn: Callable[[bytes], bytes]) -> Setup:
    """Rewrite ``case_dir/rel`` (already copied) through ``fn``."""

    def setup(d: Path, b: Path) -> None:
        target = d / rel
        target.chmod(0o600)
        target.write_bytes(fn(target.read_bytes()))

    return setup


def truncate(fraction: float) -> Callable[[bytes], bytes]:
    return lambda data: data[: int(len(data) * fraction)]


def flips(seed: int, count: int) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        rng = random.Random(seed)
        out = bytearray(data)
        for _ in range(count):
            i = rng.randrange(len(out))
            out[i] = rng.randrange(256)
        return bytes(out)

    return fn


def reencode(codec: str) -> Callable[[bytes], bytes]:
    return lambda data: data.decode("utf-8").encode(codec)


def replace(old: str, new: str, count: int = 1) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        text = data.decode("utf-8")
        assert old in text, old
        return text.replace(old, new, count).encode("utf-8")

    return fn


def _chmod(rel: str, mode: int) -> Setup:
    def setup(d: Path, b: Path) -> None:
        (d / rel).chmod(mode)

    return setup


def deep_yaml(depth: int) -> str:
    return "a: " + "[" * depth + "]" * depth + "\n"


def deep_yaml_block(depth: int) -> str:
    return "".join(" " * i + f"k{i}:\n" for i in range(depth)) + " " * depth + "v: 1\n"


ALIAS_BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(8)
)
MAPPING_BOMB = "a: &a {x: 1, y: 1, z: 1}\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} {{"
    + ", ".join(f"k{j}: *{chr(97 + i)}" for j in range(9))
    + "}\n"
    for i in range(8)
)
RECURSIVE_ALIAS = "a: &a\n  b: *a\n"

NUMBERS = {
    "nan": "nan",
    "inf": "inf",
    "neg-inf": "-inf",
    "huge": "1e308",
    "overflow": "1.0e+400",
    "tiny": "1e-300",
    "negative": "-1",
    "zero": "0",
    "digits401": "9" * 401,
    "underscore": "1_000",
    "arabic-indic": "\u0661\u0662\u0663",
    "fullwidth": "\uff11\uff12\uff13",
    "hex": "0x10",
    "empty": "",
    "space": "   ",
    "word": "abc",
}
YAML_NUMBERS = {
    "nan": ".nan",
    "inf": ".inf",
    "overflow": "1.0e+400",
    "digits401": "9" * 401,
    "tiny": "1e-300",
    "negative": "-0.34",
    "zero": "0",
    "string": "'abc'",
    "list": "[1, 2]",
    "null": "null",
    "bool": "true",
}


# --- the corpus -----------------------------------------------------------------------


def corpus() -> list[Case]:
    """Every case, in a stable order with unique names."""
    cases: list[Case] = []

    def add(name: str, reader: str, argv: Iterable[str], **kw: object) -> None:
        cases.append(Case(name, reader, list(argv), **kw))  # type: ignore[arg-type]

    cal = ["calibrate"]
    t = ["{d}/runs.csv", *TABLE_ARGS]

    # -- runs tables ------------------------------------------------------------------
    add("table-valid-csv", "table", [*cal, *t], setup=_copy("runs.csv"), expect="ok")
    add(
        "table-valid-tsv",
        "table",
        [*cal, "{d}/runs.tsv", *TABLE_ARGS],
        setup=_copy("runs.tsv"),
        expect="ok",
    )
    add(
        "table-valid-semicolon",
        "table",
        [*cal, "{d}/runs.csv", *TABLE_ARGS],
        setup=_copy("runs_semicolon.csv", "runs.csv"),
        expect="ok",
    )
    add(
        "table-valid-decimal-comma",
        "table",
        [*cal, "{d}/runs.csv", *TABLE_ARGS],
        setup=_copy("runs_decimal_comma.csv", "runs.csv"),
        expect="ok",
    )
    add(
        "table-valid-theta",
        "table",
        [*cal, "{d}/sim.csv", "-b", "0.34", "-L", "1"],
        setup=_copy("sim.csv"),
        expect="ok",
    )
    for frac in (0.0, 0.05, 0.2, 0.35, 0.5, 0.75, 0.9, 0.99):
        add(
            f"table-truncated-{frac}",
            "table",
            [*cal, *t],
            setup=_chain(_copy("runs.csv"), _mutate_file("runs.csv", truncate(frac))),
        )
    for seed in range(24):
        add(
            f"table-flip-{seed}",
            "table",
            [*cal, *t],
            setup=_chain(_copy("runs.csv"), _mutate_file("runs.csv", flips(seed, 1 + seed % 6))),
        )
    for codec in ("utf-16", "utf-16-le", "utf-32", "utf-8-sig", "latin-1", "cp1252"):
        add(
            f"table-encoding-{codec}",
            "table",
            [*cal, *t],
            setup=_chain(_copy("runs.csv"), _mutate_file("runs.csv", reencode(codec))),
        )
    add(
        "table-latin1-comment",
        "table",
        [*cal, *t],
        setup=_write(
            "runs.csv",
            lambda b: (
                (b / "runs.csv")
                .read_text()
                .replace("# UMBmark", "# Messung \xe9\xe8 UMBmark")
                .encode("latin-1")
            ),
        ),
    )
    header = "direction,x_abs,y_abs,x_odo,y_odo"
    columns = header.split(",")
    for i, col in enumerate(columns):
        add(
            f"table-missing-column-{col}",
            "table",
            [*cal, *t],
            expect="error",
            setup=_write("runs.csv", _drop_column(i)),
        )
        add(
            f"table-misspelt-column-{col}",
            "table",
            [*cal, *t],
            expect="error",
            setup=_chain(
                _copy("runs.csv"),
                _mutate_file("runs.csv", replace(header, header.replace(col, col[:-1] + "X"))),
            ),
        )
        add(
            f"table-duplicated-column-{col}",
            "table",
            [*cal, *t],
            setup=_chain(
                _copy("runs.csv"), _mutate_file("runs.csv", replace(header, header + "," + col))
            ),
        )
    for key, value in NUMBERS.items():
        expect = (
            "error"
            if key
            in (
                "nan",
                "inf",
                "neg-inf",
                "overflow",
                "digits401",
                "underscore",
                "arabic-indic",
                "fullwidth",
                "hex",
                "word",
            )
            else "any"
        )
        add(
            f"table-cell-{key}",
            "table",
            [*cal, *t],
            expect=expect,
            setup=_chain(_copy("runs.csv"), _mutate_file("runs.csv", replace("69.3", value))),
        )
        add(
            f"table-direction-{key}",
            "table",
            [*cal, *t],
            expect="error" if value else "any",
            setup=_chain(
                _copy("runs.csv"), _mutate_file("runs.csv", replace("cw,69.3", value + ",69.3"))
            ),
        )
    add("table-empty", "table", [*cal, *t], expect="error", setup=_write("runs.csv", ""))
    add(
        "table-header-only",
        "table",
        [*cal, *t],
        expect="error",
        setup=_write("runs.csv", header + "\n"),
    )
    add(
        "table-whitespace",
        "table",
        [*cal, *t],
        expect="error",
        setup=_write("runs.csv", "  \n\n\t\n"),
    )
    add(
        "table-nul-bytes",
        "table",
        [*cal, *t],
        expect="error",
        setup=_write("runs.csv", b"\0" * 4096),
    )
    add(
        "table-binary",
        "table",
        [*cal, *t],
        expect="error",
        setup=_write("runs.csv", bytes(random.Random(5).randrange(256) for _ in range(20000))),
    )
    add(
        "table-crlf",
        "table",
        [*cal, *t],
        expect="ok",
        setup=_write("runs.csv", lambda b: (b / "runs.csv").read_text().replace("\n", "\r\n")),
    )
    add(
        "table-cr-only",
        "table",
        [*cal, *t],
        setup=_write("runs.csv", lambda b: (b / "runs.csv").read_text().replace("\n", "\r")),
    )
    add(
        "table-one-run-each",
        "table",
        [*cal, *t],
        expect="warn",
        setup=_write("runs.csv", f"{header}\ncw,69.3,36.4,0,0\nccw,227.8,-206.1,0,0\n"),
    )
    add(
        "table-cw-only",
        "table",
        [*cal, *t],
        expect="error",
        setup=_write(
            "runs.csv",
            lambda b: "\n".join(
                ln for ln in (b / "runs.csv").read_text().splitlines() if not ln.startswith("ccw")
            ),
        ),
    )
    add(
        "table-cell-130kb",
        "table",
        [*cal, *t],
        expect="error",
        setup=_chain(_copy("runs.csv"), _mutate_file("runs.csv", replace("69.3", "1" * 130_000))),
    )
    add(
        "table-line-130kb-quoted",
        "table",
        [*cal, *t],
        setup=_chain(
            _copy("runs.csv"), _mutate_file("runs.csv", replace("# UMBmark", '"' + "x" * 130_000))
        ),
    )
    add(
        "table-unterminated-quote",
        "table",
        [*cal, *t],
        setup=_chain(_copy("runs.csv"), _mutate_file("runs.csv", replace("cw,69.3", '"cw,69.3'))),
    )
    add(
        "table-rows-300k",
        "table",
        [*cal, *t],
        timeout=120.0,
        setup=_write("runs.csv", _many_rows(300_000)),
    )
    add(
        "table-rows-2M",
        "table",
        [*cal, *t],
        timeout=180.0,
        setup=_write("runs.csv", _many_rows(2_000_000)),
    )
    add(
        "table-many-columns",
        "table",
        [*cal, *t],
        setup=_write(
            "runs.csv",
            lambda b: (
                (b / "runs.csv")
                .read_text()
                .replace(header, header + "," + ",".join(f"c{i}" for i in range(20000)))
            ),
        ),
    )
    add(
        "table-mixed-units",
        "table",
        [*cal, *t],
        expect="warn",
        setup=_chain(
            _copy("runs.csv"), _mutate_file("runs.csv", replace("69.3,36.4", "0.0693,0.0364"))
        ),
    )
    add(
        "table-mm-read-as-m",
        "table",
        [*cal, "{d}/runs.csv", "-b", "0.34", "-L", "4"],
        setup=_copy("runs.csv"),
        expect="warn",
        warn=("unit", "mm", "m"),
    )
    add(
        "table-mm-read-as-cm",
        "table",
        [*cal, "{d}/runs.csv", "-b", "0.34", "-L", "4", "--unit", "cm"],
        setup=_copy("runs.csv"),
        expect="warn",
        warn=("unit",),
    )
    add(
        "table-heading-deg-as-rad",
        "table",
        [*cal, "{d}/sim.csv", "-b", "0.34", "-L", "1", "-m", "heading"],
        expect="warn",
        warn=("degree", "heading", "unit"),
        setup=_write("sim.csv", _theta_to_degrees),
    )
    add(
        "table-heading-rad-as-deg",
        "table",
        [*cal, "{d}/sim.csv", "-b", "0.34", "-L", "1", "-m", "heading", "--angle-unit", "deg"],
        expect="warn",
        warn=("degree", "heading", "unit"),
        setup=_copy("sim.csv"),
    )
    add(
        "table-label-swapped",
        "table",
        [*cal, *t],
        expect="warn",
        warn=("row", "label", "cluster"),
        setup=_chain(_copy("runs.csv"), _mutate_file("runs.csv", replace("ccw,219.6", "cw,219.6"))),
    )
    add(
        "table-comment-only",
        "table",
        [*cal, *t],
        expect="error",
        setup=_write("runs.csv", "# nothing\n# here\n"),
    )
    add(
        "table-bom-header",
        "table",
        [*cal, *t],
        expect="ok",
        setup=_write("runs.csv", lambda b: "\ufeff" + (b / "runs.csv").read_text()),
    )

    # paths and files of every kind, as table sources
    add(
        "path-folder-as-table",
        "table",
        [*cal, "{d}/runs.csv", *TABLE_ARGS, "-f", "table"],
        setup=lambda d, b: (d / "runs.csv").mkdir(),
        expect="error",
    )
    add(
        "path-empty-folder",
        "table",
        [*cal, "{d}/empty", *TABLE_ARGS],
        setup=lambda d, b: (d / "empty").mkdir(),
        expect="error",
    )
    add("path-missing", "table", [*cal, "{d}/nope.csv", *TABLE_ARGS], expect="error")
    add(
        "path-symlink-loop",
        "table",
        [*cal, "{d}/loop.csv", *TABLE_ARGS],
        expect="error",
        setup=_symlink_loop("loop.csv"),
    )
    add(
        "path-dangling-symlink",
        "table",
        [*cal, "{d}/dangling.csv", *TABLE_ARGS],
        expect="error",
        setup=lambda d, b: (d / "dangling.csv").symlink_to(d / "gone.csv"),
    )
    add(
        "path-unreadable-file",
        "table",
        [*cal, *t],
        expect="error",
        needs_modes=True,
        setup=_chain(_copy("runs.csv"), _chmod("runs.csv", 0)),
    )
    add(
        "path-unsearchable-folder",
        "table",
        [*cal, "{d}/locked/runs.csv", *TABLE_ARGS],
        expect="error",
        needs_modes=True,
        setup=_in_locked("runs.csv", 0o600),
    )
    long_name = "r" * 300 + ".csv"
    add("path-name-300-bytes", "table", [*cal, "{d}/" + long_name, *TABLE_ARGS], expect="error")
    add(
        "path-4200-bytes",
        "table",
        [*cal, "{d}/" + "/".join(["d" * 200] * 21) + "/runs.csv", *TABLE_ARGS],
        expect="error",
    )
    add("path-dev-zero", "table", [*cal, "/dev/zero", *TABLE_ARGS], expect="error", timeout=60.0)
    add(
        "path-dev-zero-forced-table",
        "table",
        [*cal, "/dev/zero", *TABLE_ARGS, "-f", "table"],
        expect="error",
    )
    add("path-dev-null", "table", [*cal, "/dev/null", *TABLE_ARGS], expect="error")
    add(
        "path-dev-urandom",
        "table",
        [*cal, "/dev/urandom", *TABLE_ARGS, "-f", "table"],
        expect="error",
    )
    add(
        "path-fifo",
        "table",
        [*cal, "{d}/fifo.csv", *TABLE_ARGS],
        expect="error",
        timeout=20.0,
        setup=lambda d, b: os.mkfifo(d / "fifo.csv"),
    )
    add(
        "path-newline-in-name",
        "table",
        [*cal, "{d}/a\nb.csv", *TABLE_ARGS],
        expect="ok",
        setup=_copy("runs.csv", "a\nb.csv"),
    )
    add(
        "path-non-utf8-name",
        "table",
        [*cal, "{d}/caf\udce9.csv", *TABLE_ARGS],
        setup=lambda d, b: shutil.copy(b / "runs.csv", os.fsencode(str(d)) + b"/caf\xe9.csv"),
    )
    add("path-same-file-twice", "table", [*cal, *t, "{d}/runs.csv"], setup=_copy("runs.csv"))
    add("path-stdin-dash", "table", [*cal, "-", *TABLE_ARGS], expect="error")

    # -- calibrate options ------------------------------------------------------------
    bad_floats = ["nan", "inf", "-inf", "1e308", "1e-300", "-1", "0", "abc", "", "1e400"]
    for opt in (
        "-L",
        "-b",
        "--current-c-l",
        "--current-c-r",
        "--current-separation-multiplier",
        "--wheel-diameter",
        "--max-gap",
        "--min-rest",
    ):
        for value in bad_floats:
            argv = [*cal, "{d}/runs.csv", "--unit", "mm", "-b", "0.34", "-L", "4", opt, value]
            add(f"opt-calibrate{opt}={value or 'empty'}", "options", argv, setup=_copy("runs.csv"))
    add(
        "opt-current-c-l-1e300",
        "options",
        [*cal, *t, "--current-c-l", "1e300"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    add(
        "opt-wheelbase-1e-300",
        "options",
        [*cal, "{d}/runs.csv", "--unit", "mm", "-L", "4", "-b", "1e-300"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    add(
        "opt-L0.5-b3",
        "options",
        [*cal, "{d}/runs.csv", "--unit", "mm", "-L", "0.5", "-b", "3"],
        expect="warn",
        setup=_copy("runs.csv"),
    )
    add(
        "opt-separation-1e308",
        "options",
        [*cal, *t, "--current-separation-multiplier", "1e308"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    for opt, value in (
        ("-m", "nope"),
        ("--unit", "km"),
        ("--angle-unit", "grad"),
        ("-f", "xml"),
        ("--split", "x"),
        ("--controller", ""),
        ("--controller", "x" * 130_000),
        ("--robot", ""),
        ("--robot", "r" * 130_000),
        ("--robot", "a\nb"),
        ("--history", "{d}"),
        ("--history", "/dev/zero"),
        ("--history", "{d}/garbage.sqlite3"),
    ):
        add(
            f"opt-calibrate{opt}={value[:20].replace('/', '_') or 'empty'}",
            "options",
            [*cal, *t, opt, value],
            setup=_chain(_copy("runs.csv"), _write("garbage.sqlite3", "not a db" * 100)),
        )
    add("opt-unknown-option", "options", [*cal, *t, "--nope"], setup=_copy("runs.csv"))
    add("opt-no-sources", "options", [*cal])
    add(
        "opt-calibrate-windows-on-table",
        "options",
        [*cal, *t, "--windows", "0:5"],
        setup=_copy("runs.csv"),
    )

    # -- outputs ----------------------------------------------------------------------
    add(
        "out-onto-input",
        "outputs",
        [*cal, *t, "-o", "{d}/runs.csv"],
        expect="error",
        setup=_copy("runs.csv"),
        check=_unchanged("runs.csv"),
    )
    add(
        "out-same-twice",
        "outputs",
        [*cal, *t, "-o", "{d}/x.png", "--plot", "{d}/x.png"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    add(
        "out-symlink-kept",
        "outputs",
        [*cal, *t, "-o", "{d}/link.json"],
        expect="ok",
        setup=_chain(
            _copy("runs.csv"),
            _write("real.json", "{}"),
            lambda d, b: (d / "link.json").symlink_to("real.json"),
        ),
        check=_still_link("link.json"),
    )
    add(
        "out-mode-kept",
        "outputs",
        [*cal, *t, "-o", "{d}/r.json"],
        expect="ok",
        setup=_chain(_copy("runs.csv"), _write("r.json", "{}"), _chmod("r.json", 0o600)),
        check=_mode_is("r.json", 0o600),
    )
    add(
        "out-all-or-nothing",
        "outputs",
        [*cal, *t, "-o", "{d}/r.json", "--yaml", "{d}/no/o.yaml"],
        expect="error",
        setup=_copy("runs.csv"),
        check=_absent("r.json"),
    )
    add(
        "out-wrote-lines",
        "outputs",
        [
            *cal,
            *t,
            "-o",
            "{d}/r.json",
            "--yaml",
            "{d}/o.yaml",
            "--ros1-yaml",
            "{d}/r1.yaml",
            "--plot",
            "{d}/p.png",
            "--report",
            "{d}/r.html",
        ],
        expect="ok",
        setup=_copy("runs.csv"),
        check=_wrote(5),
        timeout=120.0,
    )
    add(
        "out-into-folder",
        "outputs",
        [*cal, *t, "-o", "{d}"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    add(
        "out-readonly-folder",
        "outputs",
        [*cal, *t, "-o", "{d}/ro/r.json"],
        expect="error",
        needs_modes=True,
        setup=_chain(_copy("runs.csv"), lambda d, b: (d / "ro").mkdir(0o500)),
    )
    add(
        "out-name-300-bytes",
        "outputs",
        [*cal, *t, "-o", "{d}/" + "o" * 300 + ".json"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    add(
        "out-plot-bad-suffix",
        "outputs",
        [*cal, *t, "--plot", "{d}/p.txt"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    add(
        "out-report-bad-suffix",
        "outputs",
        [*cal, *t, "--report", "{d}/p.txt"],
        setup=_copy("runs.csv"),
    )
    add("out-tum-for-table", "outputs", [*cal, *t, "--tum", "{d}/tum"], setup=_copy("runs.csv"))
    add(
        "out-dev-full-json", "outputs", [*cal, *t, "--json"], stdout="full", setup=_copy("runs.csv")
    )
    add("out-dev-full-text", "outputs", [*cal, *t], stdout="full", setup=_copy("runs.csv"))
    add(
        "out-ascii-terminal",
        "outputs",
        [*cal, *t],
        env={"PYTHONIOENCODING": "ascii"},
        expect="ok",
        setup=_copy("runs.csv"),
    )
    add(
        "out-ascii-locale",
        "outputs",
        [*cal, *t],
        env={"LC_ALL": "C", "LANG": "C", "PYTHONUTF8": "0"},
        expect="ok",
        setup=_copy("runs.csv"),
    )
    add("out-broken-pipe", "outputs", [*cal, *t], stdout="head", setup=_copy("runs.csv"))
    add(
        "out-broken-pipe-json",
        "outputs",
        [*cal, *t, "--json"],
        stdout="head",
        setup=_copy("runs.csv"),
    )
    for command in (
        ["demo", "--out", "{d}/demo"],
        ["simulate", "--json"],
        ["plan", "--json"],
        ["info", _base_bag("mcap")],
        ["reproduce", "table1"],
        ["history"],
    ):
        add(f"out-broken-pipe-{command[0]}", "outputs", command, stdout="head", timeout=120.0)
        add(f"out-dev-full-{command[0]}", "outputs", command, stdout="full", timeout=120.0)
        add(
            f"out-ascii-{command[0]}",
            "outputs",
            command,
            env={"PYTHONIOENCODING": "ascii"},
            timeout=120.0,
        )

    # -- run logs ---------------------------------------------------------------------
    log = ["{d}/logs"]
    add("log-valid", "runlog", [*cal, *log], setup=_copy("logs"), expect="ok")
    meta = "logs/metadata.yaml"
    run3 = "logs/run-03.csv"
    for key, value in YAML_NUMBERS.items():
        for field_name in (
            "wheelbase",
            "wheel_diameter",
            "encoder_resolution",
            "side_length",
            "c_left",
        ):
            add(
                f"log-meta-{field_name}-{key}",
                "runlog",
                [*cal, *log],
                expect="any" if key in ("tiny",) and field_name == "c_left" else "error",
                setup=_chain(_copy("logs"), _mutate_file(meta, _yaml_set(field_name, value))),
            )
    add(
        "log-meta-wheelbase-mm",
        "runlog",
        [*cal, *log],
        expect="error",
        setup=_chain(_copy("logs"), _mutate_file(meta, _yaml_set("wheelbase", "340.0"))),
    )
    for name, text in (
        ("deep-flow", deep_yaml(5000)),
        ("deep-block", deep_yaml_block(3000)),
        ("alias-bomb", ALIAS_BOMB),
        ("mapping-bomb", MAPPING_BOMB),
        ("recursive-alias", RECURSIVE_ALIAS),
        ("empty", ""),
        ("list", "- 1\n- 2\n"),
        ("scalar", "hello\n"),
        ("tabs", "\tformat: x\n"),
        ("binary", "\x00\x01\x02"),
        ("huge-string", "format: " + "x" * 2_000_000),
    ):
        add(
            f"log-meta-{name}",
            "runlog",
            [*cal, *log],
            expect="error",
            setup=_chain(_copy("logs"), _write(meta, text)),
        )
    for frac in (0.0, 0.3, 0.7, 0.95):
        add(
            f"log-meta-truncated-{frac}",
            "runlog",
            [*cal, *log],
            setup=_chain(_copy("logs"), _mutate_file(meta, truncate(frac))),
        )
    for codec in ("utf-16", "utf-8-sig", "latin-1"):
        add(
            f"log-meta-{codec}",
            "runlog",
            [*cal, *log],
            setup=_chain(_copy("logs"), _mutate_file(meta, reencode(codec))),
        )
    add(
        "log-meta-missing",
        "runlog",
        [*cal, *log],
        expect="error",
        setup=_chain(_copy("logs"), lambda d, b: (d / meta).unlink()),
    )
    add(
        "log-meta-folder",
        "runlog",
        [*cal, *log],
        expect="error",
        setup=_chain(_copy("logs"), lambda d, b: ((d / meta).unlink(), (d / meta).mkdir())),
    )
    add(
        "log-meta-duplicate-key",
        "runlog",
        [*cal, *log],
        setup=_chain(_copy("logs"), _mutate_file(meta, lambda t: t + b"wheelbase: 0.5\n")),
    )
    add(
        "log-meta-misspelt-key",
        "runlog",
        [*cal, *log],
        expect="error",
        setup=_chain(_copy("logs"), _mutate_file(meta, replace("wheelbase:", "wheelbsae:"))),
    )
    add(
        "log-meta-unreadable",
        "runlog",
        [*cal, *log],
        expect="error",
        needs_modes=True,
        setup=_chain(_copy("logs"), _chmod(meta, 0)),
    )
    add(
        "log-folder-unsearchable",
        "runlog",
        [*cal, *log],
        expect="error",
        needs_modes=True,
        setup=_chain(_copy("logs"), _chmod("logs", 0o600)),
    )
    add(
        "log-folder-unreadable",
        "runlog",
        [*cal, *log],
        expect="error",
        needs_modes=True,
        setup=_chain(_copy("logs"), _chmod("logs", 0o300)),
    )
    # a run file that cannot be read must not be skipped silently
    for name, fn in (
        ("utf-16", reencode("utf-16")),
        ("misspelt-header", replace("theta", "thetta")),
        ("semicolons", lambda data: data.replace(b",", b";")),
        ("latin-1-comment", lambda data: b"# \xe9\n" + data),
        ("empty", lambda data: b""),
        (
            "header-only",
            lambda data: b"\n".join(line for line in data.splitlines() if not line[:1].isdigit()),
        ),
        ("truncated-mid-row", truncate(0.5)),
        ("nul", lambda data: b"\0" * 1000),
        ("binary", lambda data: bytes(random.Random(1).randrange(256) for _ in range(5000))),
    ):
        add(
            f"log-run-{name}",
            "runlog",
            [*cal, *log],
            expect="warn",
            warn=("run-03",),
            setup=_chain(_copy("logs"), _mutate_file(run3, fn)),
        )
    add(
        "log-run-unreadable",
        "runlog",
        [*cal, *log],
        expect="warn",
        warn=("run-03",),
        needs_modes=True,
        setup=_chain(_copy("logs"), _chmod(run3, 0)),
    )
    add(
        "log-run-folder",
        "runlog",
        [*cal, *log],
        expect="warn",
        warn=("run-11",),
        setup=_chain(_copy("logs"), lambda d, b: (d / "logs/run-11.csv").mkdir()),
    )
    add(
        "log-run-symlink-loop",
        "runlog",
        [*cal, *log],
        expect="warn",
        warn=("run-11",),
        setup=_chain(_copy("logs"), _symlink_loop("logs/run-11.csv")),
    )
    for seed in range(10):
        add(
            f"log-run-flip-{seed}",
            "runlog",
            [*cal, *log],
            setup=_chain(_copy("logs"), _mutate_file(run3, flips(seed, 1 + seed))),
        )
    for key, value in NUMBERS.items():
        add(
            f"log-run-cell-{key}",
            "runlog",
            [*cal, *log],
            expect="any" if key in ("negative", "zero", "tiny", "empty", "space") else "warn",
            setup=_chain(_copy("logs"), _mutate_file(run3, _set_cell(200, 1, value))),
        )
    add(
        "log-run-counts-1e300",
        "runlog",
        [*cal, *log],
        expect="error",
        setup=_chain(
            _copy("logs"),
            _mutate_file(run3, _scale_column(4, 1e300)),
            _mutate_file(run3, _scale_column(5, 1e300)),
        ),
    )
    add(
        "log-run-counts-zero",
        "runlog",
        [*cal, *log],
        expect="warn",
        setup=_chain(
            _copy("logs"),
            _mutate_file(run3, _scale_column(4, 0)),
            _mutate_file(run3, _scale_column(5, 0)),
        ),
    )
    add(
        "log-run-truth-still",
        "runlog",
        [*cal, *log],
        expect="warn",
        setup=_chain(_copy("logs"), *(_mutate_file(run3, _scale_column(c, 0)) for c in (1, 2, 3))),
    )
    add(
        "log-run-jump",
        "runlog",
        [*cal, *log],
        expect="warn",
        setup=_chain(_copy("logs"), _mutate_file(run3, _jump_column(4, 1e6))),
    )
    add(
        "log-run-time-backwards",
        "runlog",
        [*cal, *log],
        expect="warn",
        setup=_chain(_copy("logs"), _mutate_file(run3, _reverse_rows(500, 900))),
    )
    add(
        "log-run-time-duplicated",
        "runlog",
        [*cal, *log],
        setup=_chain(_copy("logs"), _mutate_file(run3, _duplicate_times(10))),
    )
    add(
        "log-run-130kb-cell",
        "runlog",
        [*cal, *log],
        expect="warn",
        warn=("run-03",),
        setup=_chain(_copy("logs"), _mutate_file(run3, _set_cell(100, 1, "1" * 130_000))),
    )
    add(
        "log-one-direction",
        "runlog",
        [*cal, *log],
        expect="error",
        setup=_chain(_copy("logs"), *(_remove(f"logs/run-0{i}.csv") for i in (4, 5, 6))),
    )
    add(
        "log-too-few-runs",
        "runlog",
        [*cal, *log],
        expect="warn",
        setup=_chain(_copy("logs"), *(_remove(f"logs/run-0{i}.csv") for i in (2, 3, 5, 6))),
    )
    add(
        "log-no-runs",
        "runlog",
        [*cal, *log],
        expect="error",
        setup=_chain(_copy("logs"), *(_remove(f"logs/run-0{i}.csv") for i in range(1, 7))),
    )
    add(
        "log-big-run-file",
        "runlog",
        [*cal, *log],
        timeout=180.0,
        setup=_chain(_copy("logs"), _mutate_file(run3, _repeat_rows(300))),
    )
    add(
        "log-windows-bad",
        "runlog",
        [*cal, *log, "--split", "windows", "--windows", "5:1"],
        expect="error",
        setup=_copy("logs"),
    )
    add(
        "log-replay-valid",
        "runlog",
        ["replay", *log, "-p", "{b}/result.json", "--force"],
        setup=_copy("logs"),
    )
    add("log-info", "runlog", ["info", *log], setup=_copy("logs"), expect="ok")
    add(
        "log-info-deep-meta",
        "runlog",
        ["info", *log],
        expect="error",
        setup=_chain(_copy("logs"), _write(meta, deep_yaml(5000))),
    )
    add(
        "log-tum-valid",
        "runlog",
        [*cal, *log, "--tum", "{d}/tum"],
        setup=_copy("logs"),
        expect="ok",
    )
    add(
        "log-tum-onto-file",
        "runlog",
        [*cal, *log, "--tum", "{d}/logs/metadata.yaml"],
        expect="error",
        setup=_copy("logs"),
    )
    add(
        "log-tum-readonly",
        "runlog",
        [*cal, *log, "--tum", "{d}/ro/tum"],
        expect="error",
        needs_modes=True,
        setup=_chain(_copy("logs"), lambda d, b: (d / "ro").mkdir(0o500)),
    )

    # -- OptiOdom sessions ------------------------------------------------------------
    opt = ["{d}/s"]
    sid = "230620202042"
    ometa = f"s/{sid}_metadata.csv"
    orun = f"s/{sid}_run-02.csv"
    copy_s = _copy(f"real/square/{sid}", "s")
    add("optiodom-valid", "optiodom", [*cal, *opt], setup=copy_s, expect="ok")
    for key, value in (
        ("encres-1e-300", "1e-300"),
        ("encres-0", "0"),
        ("encres-neg", "-64"),
        ("encres-nan", "nan"),
        ("encres-inf", "inf"),
        ("encres-word", "abc"),
        ("encres-1e400", "1e400"),
        ("encres-digits", "9" * 401),
    ):
        add(
            f"optiodom-meta-{key}",
            "optiodom",
            [*cal, *opt],
            expect="error",
            setup=_chain(copy_s, _mutate_file(ometa, replace("encRes,64", f"encRes,{value}"))),
        )
    for key, value in (
        ("ngear-0", "ngear,0"),
        ("ngear-nan", "ngear,nan"),
        ("li-0", "Li,0"),
        ("li-neg", "Li,-0.2"),
        ("di-0", "Di,0,0"),
        ("di-huge", "Di,1e300,1e300"),
    ):
        old = {"ngear": "ngear,43.7", "li": "Li,0.2", "di": "Di,0.084,0.084"}[key.split("-")[0]]
        add(
            f"optiodom-meta-{key}",
            "optiodom",
            [*cal, *opt],
            expect="error",
            setup=_chain(copy_s, _mutate_file(ometa, replace(old, value))),
        )
    add(
        "optiodom-meta-missing",
        "optiodom",
        [*cal, *opt, "-f", "optiodom"],
        expect="error",
        setup=_chain(copy_s, _remove(ometa)),
    )
    add(
        "optiodom-meta-empty",
        "optiodom",
        [*cal, *opt],
        expect="error",
        setup=_chain(copy_s, _write(ometa, "")),
    )
    for codec in ("utf-16", "utf-8-sig"):
        add(
            f"optiodom-meta-{codec}",
            "optiodom",
            [*cal, *opt],
            setup=_chain(copy_s, _mutate_file(ometa, reencode(codec))),
        )
    add(
        "optiodom-ticks-zero",
        "optiodom",
        [*cal, *opt],
        expect="warn",
        setup=_chain(
            copy_s,
            *(
                _mutate_file(f"s/{sid}_run-0{i}.csv", _scale_column(c, 0))
                for i in range(1, 7)
                for c in (4, 5)
            ),
        ),
    )
    add(
        "optiodom-ticks-1e300",
        "optiodom",
        [*cal, *opt],
        expect="error",
        setup=_chain(copy_s, _mutate_file(orun, _scale_column(4, 1e300))),
    )
    add(
        "optiodom-truth-still",
        "optiodom",
        [*cal, *opt],
        expect="warn",
        setup=_chain(
            copy_s,
            *(
                _mutate_file(f"s/{sid}_run-0{i}.csv", _scale_column(c, 0))
                for i in range(1, 7)
                for c in (1, 2, 3)
            ),
        ),
    )
    add(
        "optiodom-wheel-jump",
        "optiodom",
        [*cal, *opt],
        expect="warn",
        setup=_chain(copy_s, _mutate_file(orun, _set_cell(300, 4, "1000000"))),
    )
    for frac in (0.0, 0.4, 0.97):
        add(
            f"optiodom-run-truncated-{frac}",
            "optiodom",
            [*cal, *opt],
            setup=_chain(copy_s, _mutate_file(orun, truncate(frac))),
        )
    for seed in range(8):
        add(
            f"optiodom-run-flip-{seed}",
            "optiodom",
            [*cal, *opt],
            setup=_chain(copy_s, _mutate_file(orun, flips(seed, 1 + seed))),
        )
    for key, value in NUMBERS.items():
        add(
            f"optiodom-run-cell-{key}",
            "optiodom",
            [*cal, *opt],
            expect="any" if key in ("negative", "zero", "tiny", "empty", "space") else "warn",
            setup=_chain(copy_s, _mutate_file(orun, _set_cell(100, 1, value))),
        )
    add(
        "optiodom-run-utf16",
        "optiodom",
        [*cal, *opt],
        expect="warn",
        warn=("run-02",),
        setup=_chain(copy_s, _mutate_file(orun, reencode("utf-16"))),
    )
    add("optiodom-run-missing", "optiodom", [*cal, *opt], setup=_chain(copy_s, _remove(orun)))
    add(
        "optiodom-run-unreadable",
        "optiodom",
        [*cal, *opt],
        expect="warn",
        warn=("run-02",),
        needs_modes=True,
        setup=_chain(copy_s, _chmod(orun, 0)),
    )
    add(
        "optiodom-run-time-backwards",
        "optiodom",
        [*cal, *opt],
        expect="warn",
        setup=_chain(copy_s, _mutate_file(orun, _reverse_rows(100, 200))),
    )
    add("optiodom-info", "optiodom", ["info", *opt], setup=copy_s, expect="ok")
    add(
        "optiodom-replay-circle",
        "optiodom",
        ["replay", "{b}/real/circular/250620202104", "-p", "{d}/r.json"],
        setup=_chain(
            lambda d, b: _umbmark(
                "calibrate", str(b / "real/square" / sid), "-o", str(d / "r.json"), cwd=d
            )
        ),
    )

    # -- parameter YAML ---------------------------------------------------------------
    cp = ["--current-params", "{d}/p.yaml"]
    for kind, valid in (("ros2", "ros2_controllers.yaml"), ("ros1", "ros1_params.yaml")):
        add(
            f"params-{kind}-valid",
            "params",
            [*cal, *t, *cp],
            expect="ok",
            setup=_chain(_copy("runs.csv"), _copy(valid, "p.yaml")),
        )
        for key, value in YAML_NUMBERS.items():
            for field_name in ("wheel_separation", "wheel_radius", "wheel_separation_multiplier"):
                add(
                    f"params-{kind}-{field_name}-{key}",
                    "params",
                    [*cal, *t, *cp],
                    expect="error",
                    setup=_chain(
                        _copy("runs.csv"),
                        _copy(valid, "p.yaml"),
                        _mutate_file("p.yaml", _yaml_set(field_name, value)),
                    ),
                )
        add(
            f"params-{kind}-separation-mm",
            "params",
            [*cal, *t, *cp],
            expect="error",
            setup=_chain(
                _copy("runs.csv"),
                _copy(valid, "p.yaml"),
                _mutate_file("p.yaml", _yaml_set("wheel_separation", "340.0")),
            ),
        )
        add(
            f"params-{kind}-multiplier-1e300",
            "params",
            [*cal, *t, *cp],
            expect="error",
            setup=_chain(
                _copy("runs.csv"),
                _copy(valid, "p.yaml"),
                _mutate_file("p.yaml", _yaml_set("wheel_separation_multiplier", "1e300")),
            ),
        )
    for name, text in (
        ("deep-flow", deep_yaml(5000)),
        ("deep-block", deep_yaml_block(3000)),
        ("alias-bomb", ALIAS_BOMB),
        ("mapping-bomb", MAPPING_BOMB),
        ("recursive-alias", RECURSIVE_ALIAS),
        ("empty", ""),
        ("list", "- 1\n"),
        ("scalar", "3\n"),
        ("no-controller", "other:\n  x: 1\n"),
        ("binary", "\x00\xff"),
        ("130kb-key", "k" * 130_000 + ": 1\n"),
        ("huge", "a: " + "x" * 3_000_000 + "\n"),
        ("python-tag", "a: !!python/object/apply:os.system ['echo hi']\n"),
        ("tab-indent", "diff_drive_controller:\n\twheel_separation: 0.3\n"),
    ):
        add(
            f"params-{name}",
            "params",
            [*cal, *t, *cp],
            expect="error",
            setup=_chain(_copy("runs.csv"), _write("p.yaml", text)),
        )
    for codec in ("utf-16", "utf-8-sig", "latin-1"):
        add(
            f"params-{codec}",
            "params",
            [*cal, *t, *cp],
            setup=_chain(
                _copy("runs.csv"),
                _copy("ros2_controllers.yaml", "p.yaml"),
                _mutate_file("p.yaml", reencode(codec)),
            ),
        )
    for frac in (0.1, 0.5, 0.9):
        add(
            f"params-truncated-{frac}",
            "params",
            [*cal, *t, *cp],
            setup=_chain(
                _copy("runs.csv"),
                _copy("ros2_controllers.yaml", "p.yaml"),
                _mutate_file("p.yaml", truncate(frac)),
            ),
        )
    for seed in range(8):
        add(
            f"params-flip-{seed}",
            "params",
            [*cal, *t, *cp],
            setup=_chain(
                _copy("runs.csv"),
                _copy("ros2_controllers.yaml", "p.yaml"),
                _mutate_file("p.yaml", flips(seed, 1 + seed)),
            ),
        )
    add(
        "params-folder",
        "params",
        [*cal, *t, "--current-params", "{d}"],
        expect="error",
        setup=_copy("runs.csv"),
    )
    add("params-dev-zero", "params", [*cal, *t, "--current-params", "/dev/zero"], expect="error")
    add(
        "params-unreadable",
        "params",
        [*cal, *t, *cp],
        expect="error",
        needs_modes=True,
        setup=_chain(
            _copy("runs.csv"), _copy("ros2_controllers.yaml", "p.yaml"), _chmod("p.yaml", 0)
        ),
    )
    add(
        "params-controller-missing",
        "params",
        [*cal, *t, *cp, "--controller", "nope"],
        expect="error",
        setup=_chain(_copy("runs.csv"), _copy("ros2_controllers.yaml", "p.yaml")),
    )
    add(
        "params-overlay-valid",
        "params",
        [*cal, *t, "--current-params", "{b}/overlay.yaml"],
        expect="ok",
        setup=_copy("runs.csv"),
    )
    add(
        "params-ros1-output-valid",
        "params",
        [*cal, *t, "--current-params", "{b}/ros1.yaml"],
        expect="ok",
        setup=_copy("runs.csv"),
    )

    # -- result JSON ------------------------------------------------------------------
    rp = ["-p", "{d}/r.json"]
    replay_log = ["replay", "{b}/logs"]
    for name, fn in (
        ("c_L-1e300", _json_set_new("c_L", 1e300)),
        ("c_L-neg", _json_set_new("c_L", -1.0)),
        ("c_L-zero", _json_set_new("c_L", 0)),
        ("c_L-string", _json_set_new("c_L", "x")),
        ("c_L-null", _json_set_new("c_L", None)),
        ("c_L-true", _json_set_new("c_L", True)),
        ("new-missing", _json_del("new")),
        ("wheelbase-missing", _json_del_new("wheelbase")),
        ("new-list", _json_set("new", [1, 2])),
        ("new-c_L-1e300", _json_set_new("c_L", 1e300)),
        ("new-wheelbase-neg", _json_set_new("wheelbase", -0.3)),
    ):
        add(
            f"result-{name}",
            "result",
            [*replay_log, *rp, "--force"],
            expect="error",
            setup=_write("r.json", lambda b, fn=fn: fn((b / "result.json").read_text())),
        )
        add(
            f"result-current-{name}",
            "result",
            [*cal, *t, "--current-params", "{d}/r.json"],
            expect="error",
            setup=_chain(
                _copy("runs.csv"),
                _write("r.json", lambda b, fn=fn: fn((b / "result.json").read_text())),
            ),
        )
    for name, text in (
        ("NaN", lambda s: s.replace('"c_L": 0.9995', '"c_L": NaN, "x": 0.9995')),
        ("Infinity", lambda s: s.replace('"c_L": 0.9995', '"c_L": Infinity, "x": 0.9995')),
        ("1e400", lambda s: s.replace('"c_L": 0.9995', '"c_L": 1e400, "x": 0.9995')),
        (
            "digits5000",
            lambda s: s.replace('"c_L": 0.9995', '"c_L": ' + "9" * 5000 + ', "x": 0.9995'),
        ),
        ("deep", lambda s: "[" * 100_000 + "]" * 100_000),
        ("deep-object", lambda s: '{"a":' * 100_000 + "1" + "}" * 100_000),
        ("empty", lambda s: ""),
        ("list", lambda s: "[1, 2]"),
        ("truncated", lambda s: s[: len(s) // 2]),
        ("utf16", None),
        ("huge-string", lambda s: '{"a": "' + "x" * 5_000_000 + '"}'),
        ("duplicate-keys", lambda s: s.replace('"new": {', '"new": {"c_L": 5.0,', 1)),
    ):
        if text is None:
            setup = _write("r.json", lambda b: (b / "result.json").read_text().encode("utf-16"))
        else:
            setup = _write("r.json", lambda b, text=text: text((b / "result.json").read_text()))
        expect = "any" if name == "duplicate-keys" else "error"
        add(f"result-{name}", "result", [*replay_log, *rp, "--force"], expect=expect, setup=setup)
    add(
        "result-other-robot",
        "result",
        [*replay_log, "-p", "{b}/result_other.json"],
        expect="error",
        warn=("force",),
    )
    add(
        "result-other-robot-current",
        "result",
        ["calibrate", "{b}/logs", "--current-params", "{b}/result_other.json"],
        expect="error",
    )
    add(
        "result-other-robot-forced",
        "result",
        [*replay_log, "-p", "{b}/result_other.json", "--force"],
    )
    add("result-folder", "result", [*replay_log, "-p", "{d}"], expect="error")
    add("result-dev-zero", "result", [*replay_log, "-p", "/dev/zero"], expect="error")
    add(
        "result-second-pass",
        "result",
        [*cal, "{d}/t2.csv", "-b", "0.34", "-L", "1", "--json"],
        setup=lambda d, b: _umbmark(
            "simulate",
            "-L",
            "1",
            "--params",
            str(b / "result.json"),
            "--E-d",
            "1.0008",
            "--E-b",
            "0.99",
            "-o",
            "t2.csv",
            cwd=d,
        ),
        check=_second_pass_used,
    )
    add(
        "result-second-pass-log",
        "result",
        [*cal, "{d}/logs2", "--json"],
        setup=lambda d, b: _umbmark(
            "simulate",
            "-L",
            "1",
            "-n",
            "3",
            "--params",
            str(b / "result.json"),
            "--E-d",
            "1.0008",
            "--logs",
            "logs2",
            cwd=d,
        ),
        check=_second_pass_used,
    )
    add(
        "params-other-robot",
        "params",
        [*cal, "{b}/logs", "--current-params", "{d}/p.yaml"],
        expect="warn",
        warn=("wheel", "separation", "wheelbase"),
        setup=_chain(
            _copy("ros2_controllers.yaml", "p.yaml"),
            _mutate_file("p.yaml", _yaml_set("wheel_separation", "0.45")),
        ),
    )
    add(
        "out-piped-not-wrapped",
        "outputs",
        [*cal, *t],
        expect="ok",
        setup=_copy("runs.csv"),
        check=_not_wrapped,
    )
    add(
        "cmd-simulate-logs-readonly",
        "commands",
        ["simulate", "-n", "2", "-L", "1", "--logs", "{d}/ro/logs"],
        expect="error",
        needs_modes=True,
        setup=lambda d, b: (d / "ro").mkdir(0o500),
    )
    add(
        "cmd-simulate-logs-forced",
        "commands",
        ["simulate", "-n", "2", "-L", "1", "--logs", "{d}/logs", "--force"],
        setup=_copy("logs"),
    )

    # -- ROS bags ---------------------------------------------------------------------
    for fmt in BAG_FORMATS:
        bag = _bag_path(fmt)
        base_bag = _base_bag(fmt)
        copy_bag = _copy(Path(_base_bag(fmt)).name, Path(bag).name)
        pre = f"bag-{fmt}"
        add(f"{pre}-valid", "bag", [*cal, base_bag, *BAG_ARGS], expect="ok")
        add(f"{pre}-info", "bag", ["info", base_bag], expect="ok")
        add(f"{pre}-info-json", "bag", ["info", base_bag, "--json"], expect="ok")
        add(
            f"{pre}-replay",
            "bag",
            ["replay", base_bag, *BAG_ARGS, "-p", "{b}/result.json", "--force"],
        )
        add(
            f"{pre}-custom",
            "bag",
            [
                *cal,
                _base_bag(fmt, "custom"),
                *BAG_ARGS,
                "--wheel-topic",
                "/wheels",
                "--left-field",
                "left",
                "--right-field",
                "right",
            ],
        )
        for field_path in (
            "nope",
            "left.x",
            "header",
            "header.stamp",
            "left[0]",
            "positions[99999999999999999999]",
            "a..b",
            "",
            "x" * 130_000,
        ):
            add(
                f"{pre}-custom-field-{field_path[:20] or 'empty'}",
                "bag",
                [
                    *cal,
                    _base_bag(fmt, "custom"),
                    *BAG_ARGS,
                    "--wheel-topic",
                    "/wheels",
                    "--left-field",
                    field_path,
                    "--right-field",
                    "right",
                ],
                expect="error",
            )
        add(
            f"{pre}-msg-dir-garbage",
            "bag",
            [
                *cal,
                _base_bag(fmt, "custom"),
                *BAG_ARGS,
                "--wheel-topic",
                "/wheels",
                "--left-field",
                "left",
                "--right-field",
                "right",
                "--msg-dir",
                "{d}/msgs",
            ],
            setup=_msg_dir("garbage"),
        )
        add(
            f"{pre}-msg-dir-recursive",
            "bag",
            [
                *cal,
                _base_bag(fmt, "custom"),
                *BAG_ARGS,
                "--wheel-topic",
                "/wheels",
                "--left-field",
                "left",
                "--right-field",
                "right",
                "--msg-dir",
                "{d}/msgs",
            ],
            setup=_msg_dir("recursive"),
        )
        add(
            f"{pre}-msg-dir-missing",
            "bag",
            [
                *cal,
                _base_bag(fmt, "custom"),
                *BAG_ARGS,
                "--wheel-topic",
                "/wheels",
                "--left-field",
                "left",
                "--right-field",
                "right",
                "--msg-dir",
                "{d}/none",
            ],
        )
        # options that name what is not there
        for opt, value in (
            ("--truth-topic", "/vicon"),
            ("--wheel-topic", "/nope"),
            ("--wheel-topic", "/mocap/pose"),
            ("--truth-topic", "/joint_states"),
            ("--left-joint", "wheel_l"),
            ("--left-joint", ",,,"),
            ("--odom-topic", "/joint_states"),
            ("--odom-topic", "/nope"),
            ("--left-ticks-topic", "/nope"),
            ("--left-ticks-topic", "/joint_states"),
            ("--tf-parent", "map"),
            ("--time-source", "bag"),
            ("--ticks-per-rev", "0"),
            ("--ticks-per-rev", "nan"),
            ("--ticks-per-rev", "1e308"),
        ):
            expect = "any" if opt in ("--time-source", "--ticks-per-rev") else "error"
            add(
                f"{pre}-opt{opt}={value.replace('/', '_')}",
                "bag",
                [*cal, base_bag, *BAG_ARGS, opt, value],
                expect=expect,
            )
        add(
            f"{pre}-opt-odom-tf",
            "bag",
            [*cal, base_bag, *BAG_ARGS, "--odom-tf", "odom", "base"],
            expect="error",
        )
        for value in (
            "5:1",
            "a:b",
            "nan:inf",
            "0:1e308",
            "-5:3",
            ",".join(f"{i}:{i + 1}" for i in range(10_000)),
            "0:3",
            ":",
            "1e400:1e401",
        ):
            add(
                f"{pre}-windows-{value[:12]}",
                "bag",
                [*cal, base_bag, *BAG_ARGS, "--split", "windows", "--windows", value],
                expect="error",
            )
        for opt, value in (
            ("--max-gap", "nan"),
            ("--max-gap", "-1"),
            ("--max-gap", "1e308"),
            ("--min-rest", "nan"),
            ("--min-rest", "1e308"),
            ("--min-rest", "0"),
            ("--truth-offset", "nan 0"),
            ("--truth-offset", "1e308 0"),
        ):
            add(f"{pre}-opt{opt}={value}", "bag", [*cal, base_bag, *BAG_ARGS, opt, *value.split()])
        add(
            f"{pre}-split-none",
            "bag",
            [*cal, base_bag, *BAG_ARGS, "--split", "none"],
            expect="error",
        )
        add(
            f"{pre}-no-params",
            "bag",
            [*cal, base_bag, "--truth-topic", "/mocap/pose"],
            expect="error",
        )
        for frac in (0.01, 0.1, 0.5, 0.9, 0.999):
            target = _storage_file(fmt)
            add(
                f"{pre}-truncated-{frac}",
                "bag",
                [*cal, bag, *BAG_ARGS],
                setup=_chain(copy_bag, _mutate_file(target, truncate(frac))),
            )
        for seed in range(20):
            add(
                f"{pre}-flip-{seed}",
                "bag",
                [*cal, bag, *BAG_ARGS],
                setup=_chain(copy_bag, _mutate_file(_storage_file(fmt), flips(seed, 1 + 3 * seed))),
            )
        # bags written wrong
        variants: dict[
            str, tuple[dict[str, object], Callable[[SessionArrays], SessionArrays] | None, str]
        ] = {
            "wheel-type-string": ({"wheel_type": "std_msgs/msg/String"}, None, "error"),
            "wheel-type-float": ({"wheel_type": "std_msgs/msg/Float64"}, None, "error"),
            "truth-type-string": ({"truth_type": "std_msgs/msg/String"}, None, "error"),
            "truth-type-jointstate": ({"truth_type": "sensor_msgs/msg/JointState"}, None, "error"),
            "no-truth": ({"truth": False}, None, "error"),
            "no-wheels": ({"wheels": False}, None, "error"),
            "no-topics": ({"wheels": False, "truth": False}, None, "error"),
            "no-messages": ({}, lambda s: (s[0][:0], s[1][:0], s[2][:0]), "error"),
            "one-message": ({}, lambda s: (s[0][:1], s[1][:1], s[2][:1]), "error"),
            "unknown-topic-extra": ({"extra_topic": "/chatter"}, None, "ok"),
            "unnamed-joints": ({"names": ("a", "b")}, None, "error"),
            "same-joint-names": (
                {"names": ("left_wheel_joint", "left_wheel_joint")},
                None,
                "error",
            ),
            "time-backwards": ({}, _times_backwards, "any"),
            "time-duplicated": ({}, _times_duplicated, "any"),
            "time-reversed": ({}, lambda s: (s[0][::-1].copy(), s[1], s[2]), "any"),
            "positions-1e300": ({}, lambda s: (s[0], s[1] * 1e300, s[2]), "error"),
            "positions-nan": ({}, _angles_nan, "any"),
            "positions-inf": (
                {},
                lambda s: (s[0], np.where(s[1] > 5, np.inf, s[1]), s[2]),
                "error",
            ),
            "truth-1e300": ({}, lambda s: (s[0], s[1], s[2] * 1e300), "error"),
            "truth-still": ({}, lambda s: (s[0], s[1], s[2] * 0), "warn"),
            "wheels-still": ({}, lambda s: (s[0], s[1] * 0, s[2]), "warn"),
            "wheel-jump": ({}, _wheel_jump, "warn"),
            "one-direction": ({}, _first_half, "error"),
            "position-short": ({"joints": lambda k, n, a: (n, a[:1], [])}, None, "error"),
            "position-empty-some": (
                {"joints": lambda k, n, a: (n, a if k % 7 else [], [])},
                None,
                "any",
            ),
            "names-more": ({"joints": lambda k, n, a: ([*n, "caster"], a, [])}, None, "any"),
            "names-1000": (
                {"joints": lambda k, n, a: ([*n, *(f"j{i}" for i in range(1000))], a, [])},
                None,
                "any",
            ),
            "velocity-only": ({"joints": lambda k, n, a: (n, [], [1.0, 1.1])}, None, "any"),
            "velocity-nan": ({"joints": lambda k, n, a: (n, [], [math.nan, 1.0])}, None, "any"),
            "names-change": (
                {"joints": lambda k, n, a: (n if k < 500 else n[::-1], a, [])},
                None,
                "any",
            ),
        }
        for vname, (kwargs, transform, expect) in variants.items():
            add(
                f"{pre}-{vname}",
                "bag",
                [*cal, bag, *BAG_ARGS],
                expect=expect,
                setup=_bag_variant(fmt, kwargs, transform),
                timeout=120.0,
            )
        add(
            f"{pre}-info-wrong-types",
            "bag",
            ["info", bag],
            setup=_bag_variant(fmt, {"wheel_type": "std_msgs/msg/String"}, None),
        )
        add(f"{pre}-info-max-messages-0", "bag", ["info", base_bag, "--max-messages", "0"])
        add(
            f"{pre}-info-max-messages-huge",
            "bag",
            ["info", base_bag, "--max-messages", "9223372036854775808"],
        )
        if fmt != "ros1":
            for name, text in (
                ("deep", deep_yaml(5000)),
                ("alias-bomb", ALIAS_BOMB),
                ("mapping-bomb", MAPPING_BOMB),
                ("empty", ""),
                ("garbage", "rosbag2_bagfile_information: 3\n"),
            ):
                add(
                    f"{pre}-metadata-{name}",
                    "bag",
                    [*cal, bag, *BAG_ARGS],
                    expect="error",
                    setup=_chain(copy_bag, _write("bag/metadata.yaml", text)),
                )
            add(
                f"{pre}-metadata-missing",
                "bag",
                [*cal, bag, *BAG_ARGS],
                setup=_chain(copy_bag, _remove("bag/metadata.yaml")),
            )
            add(
                f"{pre}-storage-missing",
                "bag",
                [*cal, bag, *BAG_ARGS],
                expect="error",
                setup=_chain(copy_bag, _remove(_storage_file(fmt))),
            )
            add(
                f"{pre}-storage-unreadable",
                "bag",
                [*cal, bag, *BAG_ARGS],
                expect="error",
                needs_modes=True,
                setup=_chain(copy_bag, _chmod(_storage_file(fmt), 0)),
            )
        add(f"{pre}-tum", "bag", [*cal, base_bag, *BAG_ARGS, "--tum", "{d}/tum"], expect="ok")
        # ground truth on /tf, wheels as encoder counts
        tf_args = [
            *BAG_ARGS[:6],
            "--tf-parent",
            "map",
            "--tf-child",
            "base",
            "--left-ticks-topic",
            "/left_ticks",
            "--right-ticks-topic",
            "/right_ticks",
            "--ticks-per-rev",
            "4096",
        ]
        deep = [("map", "f0"), *((f"f{i}", f"f{i + 1}") for i in range(300)), ("f300", "odom")]
        tf_variants: dict[str, tuple[dict[str, object], str]] = {
            "valid": ({}, "ok"),
            "cycle": ({"frames": (("map", "base"), ("base", "map"))}, "any"),
            "two-parents": ({"frames": (("map", "base"), ("odom", "base"))}, "any"),
            "deep-static-chain": ({"frames": (("odom", "base"),), "static": deep}, "any"),
            "static-cycle": (
                {"frames": (("map", "base"),), "static": (("a", "b"), ("b", "a"))},
                "any",
            ),
            "no-such-child": ({"frames": (("map", "base_link"),)}, "error"),
            "ticks-float-nan": (
                {"ticks_type": "std_msgs/msg/Float64", "tick_fn": _ticks_nan},
                "any",
            ),
            "ticks-int16-wrap": (
                {"ticks_type": "std_msgs/msg/Int16", "tick_fn": _wrap_int16},
                "ok",
            ),
            "ticks-uint8": ({"ticks_type": "std_msgs/msg/UInt8", "tick_fn": _wrap_uint8}, "any"),
            "ticks-float-1e300": (
                {"ticks_type": "std_msgs/msg/Float64", "tick_fn": lambda c: c * 1e300},
                "error",
            ),
            "ticks-still": ({"tick_fn": lambda c: c * 0}, "error"),
            "ticks-jump": ({"tick_fn": _ticks_jump}, "error"),
        }
        for vname, (kwargs, expect) in tf_variants.items():
            add(
                f"{pre}-tf-ticks-{vname}",
                "bag",
                [*cal, bag, *tf_args],
                expect=expect,
                setup=_tf_variant(fmt, kwargs),
                timeout=120.0,
            )
        add(
            f"{pre}-tf-ticks-per-rev-wrong",
            "bag",
            [*cal, bag, *tf_args[:-1], "4.096"],
            expect="error",
            setup=_tf_variant(fmt, {}),
        )
        add(
            f"{pre}-tf-ticks-one-topic",
            "bag",
            [*cal, bag, *tf_args[:12], "--ticks-per-rev", "4096"],
            expect="error",
            setup=_tf_variant(fmt, {}),
        )
        add(
            f"{pre}-tf-ticks-same-topic",
            "bag",
            [*cal, bag, *tf_args[:13], "/left_ticks", "--ticks-per-rev", "4096"],
            expect="error",
            setup=_tf_variant(fmt, {}),
        )
        add(f"{pre}-tf-info", "bag", ["info", bag], expect="ok", setup=_tf_variant(fmt, {}))
    add(
        "bag-fake-bag-text",
        "bag",
        [*cal, "{d}/x.bag", *BAG_ARGS],
        expect="error",
        setup=_write("x.bag", "hello"),
    )
    add(
        "bag-fake-mcap",
        "bag",
        [*cal, "{d}/x.mcap", *BAG_ARGS],
        expect="error",
        setup=_write("x.mcap", b"\x89MCAP0\r\n" + b"\0" * 100),
    )
    add(
        "bag-fake-db3",
        "bag",
        [*cal, "{d}/x.db3", *BAG_ARGS],
        expect="error",
        setup=_write("x.db3", b"SQLite format 3\0" + b"\0" * 100),
    )
    add("bag-dev-zero-forced", "bag", [*cal, "/dev/zero", *BAG_ARGS, "-f", "bag"], expect="error")
    add("bag-info-dev-zero", "bag", ["info", "/dev/zero"], expect="error")
    add(
        "bag-sqlite-other-db",
        "bag",
        [*cal, "{d}/b", *BAG_ARGS],
        expect="error",
        setup=_other_sqlite,
    )
    add("bag-validate", "bag", ["validate", _base_bag("mcap"), *BAG_ARGS], timeout=120.0)
    add(
        "bag-validate-methods-bad",
        "bag",
        ["validate", _base_bag("mcap"), *BAG_ARGS, "--methods", "nope"],
        expect="error",
    )
    add(
        "bag-validate-methods-empty",
        "bag",
        ["validate", _base_bag("mcap"), *BAG_ARGS, "--methods", ",,,"],
    )

    # -- the other commands' options --------------------------------------------------
    for value in ("-1", "0", "1000000", "9223372036854775808", "abc", "1e3"):
        add(f"cmd-demo-runs={value}", "commands", ["demo", "--out", "{d}/o", "-n", value])
    for value in ("-1", "9223372036854775808", "abc"):
        add(f"cmd-demo-seed={value}", "commands", ["demo", "--out", "{d}/o", "--seed", value])
    add(
        "cmd-demo-out-file",
        "commands",
        ["demo", "--out", "{d}/f"],
        expect="error",
        setup=_write("f", "x"),
    )
    add(
        "cmd-demo-out-readonly",
        "commands",
        ["demo", "--out", "{d}/ro/o"],
        expect="error",
        needs_modes=True,
        setup=lambda d, b: (d / "ro").mkdir(0o500),
    )
    sim = ["simulate", "--json"]
    for opt, values in (
        ("--turn-angle", ("nan", "inf", "1e308", "1000000", "0", "-720")),
        ("--dt", ("1e-9", "0", "-1", "1e308", "nan")),
        ("--speed", ("1e-6", "0", "-1", "1e308", "nan")),
        ("--bump-size", ("1e308", "-1", "nan")),
        ("--bump-rate", ("1e308", "-1", "nan")),
        ("--encoder-resolution", ("1e308", "0", "0.5", "nan")),
        ("--gear-ratio", ("1e308", "0", "nan")),
        ("--E-d", ("0", "-1", "nan", "1e308", "1e-300")),
        ("--E-b", ("0", "-1", "nan", "1e308")),
        ("--E-s", ("0", "nan")),
        ("-b", ("0", "nan", "1e308", "1e-300")),
        ("--wheel-diameter", ("0", "1e308")),
        ("-L", ("0", "nan", "1e308", "1e-9")),
        ("-n", ("0", "-1", "1000000", "9223372036854775808")),
        ("--slip", ("nan", "-1", "1e308")),
        ("--seed", ("-1", "9223372036854775808")),
    ):
        for value in values:
            extra = ["--path", "turn"] if opt == "--turn-angle" else []
            add(f"cmd-simulate{opt}={value}", "commands", [*sim, *extra, opt, value])
    add("cmd-simulate-turn-0-json", "commands", [*sim, "--path", "turn", "--turn-angle", "0"])
    add(
        "cmd-simulate-logs-existing",
        "commands",
        ["simulate", "-n", "2", "-L", "1", "--logs", "{d}/logs"],
        expect="error",
        setup=_copy("logs"),
    )
    add(
        "cmd-simulate-logs-file",
        "commands",
        ["simulate", "--logs", "{d}/f"],
        expect="error",
        setup=_write("f", "x"),
    )
    add(
        "cmd-simulate-o-input",
        "commands",
        ["simulate", "-o", "{d}/runs.csv"],
        setup=_copy("runs.csv"),
    )
    add(
        "cmd-simulate-params-bad",
        "commands",
        ["simulate", "--params", "{d}/p.json"],
        expect="error",
        setup=_write("p.json", "[" * 100_000),
    )
    add(
        "cmd-simulate-params-yaml",
        "commands",
        ["simulate", "--params", "{b}/ros2_controllers.yaml"],
    )
    for opt, value in (
        ("--trials", "0"),
        ("--trials", "1000000000"),
        ("--workers", "0"),
        ("--workers", "100000"),
        ("--slip", "a,b"),
        ("-L", "1,,2"),
        ("-L", "nan"),
        ("-n", "0"),
        ("-n", "1" + ",1" * 10000),
        ("-b", "-1"),
        ("--methods", "x"),
        ("--E-d-spread", "nan"),
        ("--E-b-spread", "1e308"),
        ("--seed", "-1"),
    ):
        add(
            f"cmd-study{opt}={value[:20]}",
            "commands",
            ["study", "--trials", "3", "--workers", "1", opt, value],
            timeout=120.0,
        )
    for args in (
        ["table1", "--seeds", "1000000"],
        ["nope"],
        ["table1", "--seeds", "-1"],
        ["table1", "--seeds", "0"],
        [],
    ):
        add(f"cmd-reproduce-{'_'.join(args) or 'none'}", "commands", ["reproduce", *args])
    for opt in (
        "--scatter",
        "-b",
        "-L",
        "--floor",
        "--margin",
        "--target-E-d",
        "--target-E-b",
        "--target-e-max",
    ):
        for value in ("nan", "inf", "-1", "0", "1e308", "1e-300"):
            add(f"cmd-plan{opt}={value}", "commands", ["plan", opt, value])
    for value in ("0", "-1", "1000000000", "9223372036854775808"):
        add(f"cmd-plan--runs={value}", "commands", ["plan", "--runs", value, "-L", "4"])
    add(
        "cmd-example-existing",
        "commands",
        ["example", "{d}/runs.csv"],
        expect="error",
        setup=_copy("runs.csv"),
        check=_unchanged("runs.csv"),
    )
    add("cmd-example-folder", "commands", ["example", "{d}"])
    add(
        "cmd-example-real-into-file",
        "commands",
        ["example", "--real", "{d}/f"],
        expect="error",
        setup=_write("f", "x"),
    )
    add(
        "cmd-example-readonly",
        "commands",
        ["example", "{d}/ro/x.csv"],
        expect="error",
        needs_modes=True,
        setup=lambda d, b: (d / "ro").mkdir(0o500),
    )
    add(
        "cmd-example-long-name",
        "commands",
        ["example", "{d}/" + "e" * 300 + ".csv"],
        expect="error",
    )
    hist = ["history", "--history", "{d}/h.sqlite3"]
    for name, setup in (
        ("garbage", _write("h.sqlite3", "not a database" * 50)),
        ("empty", _write("h.sqlite3", "")),
        ("other-db", _other_sqlite_file("h.sqlite3")),
        ("folder", lambda d, b: (d / "h.sqlite3").mkdir()),
    ):
        add(f"cmd-history-{name}", "commands", hist, setup=setup)
        add(f"cmd-history-{name}-robot", "commands", [*hist, "r1"], setup=setup)
    add("cmd-history-dev-zero", "commands", ["history", "--history", "/dev/zero"])
    add(
        "cmd-history-unreadable",
        "commands",
        hist,
        expect="error",
        needs_modes=True,
        setup=_chain(_other_sqlite_file("h.sqlite3"), _chmod("h.sqlite3", 0)),
    )
    add("cmd-history-applied-bad", "commands", [*hist, "r1", "--applied", "-1"])
    add("cmd-history-applied-huge", "commands", [*hist, "r1", "--applied", "9223372036854775808"])
    add("cmd-history-robot-130kb", "commands", [*hist, "r" * 130_000])
    add(
        "cmd-calibrate-robot-record",
        "commands",
        [*cal, *t, "--robot", "r1", "--history", "{d}/h.sqlite3"],
        setup=_copy("runs.csv"),
        expect="ok",
    )
    add(
        "cmd-calibrate-robot-other",
        "commands",
        [
            *cal,
            "{d}/runs.csv",
            "--unit",
            "mm",
            "-L",
            "4",
            "-b",
            "0.5",
            "--robot",
            "r1",
            "--history",
            "{d}/h.sqlite3",
        ],
        expect="error",
        setup=_chain(
            _copy("runs.csv"),
            lambda d, b: _umbmark(
                "calibrate",
                "runs.csv",
                *TABLE_ARGS,
                "--robot",
                "r1",
                "--history",
                "h.sqlite3",
                cwd=d,
            ),
        ),
    )
    add("cmd-info-table", "commands", ["info", "{b}/runs.csv"])
    add(
        "cmd-info-folder-empty",
        "commands",
        ["info", "{d}/e"],
        expect="error",
        setup=lambda d, b: (d / "e").mkdir(),
    )
    add("cmd-info-missing", "commands", ["info", "{d}/nope"], expect="error")
    add("cmd-validate-one-log", "commands", ["validate", "{b}/logs"], timeout=120.0)
    add("cmd-validate-table", "commands", ["validate", "{b}/runs.csv", *TABLE_ARGS])
    add("cmd-unknown", "commands", ["nope"], expect="error")
    # umbmark report: one page from several passes
    rep = ["report", "-o", "{d}/r.html"]
    add("cmd-report-table", "commands", [*rep, "{b}/runs.csv", *TABLE_ARGS], expect="ok")
    add("cmd-report-two-passes", "commands", [*rep, "{b}/runs.csv", "{b}/runs.csv", *TABLE_ARGS])
    add("cmd-report-log-bag", "commands", [*rep, "{b}/logs"], timeout=120.0)
    add(
        "cmd-report-bad-suffix",
        "commands",
        ["report", "-o", "{d}/r.txt", "{b}/runs.csv", *TABLE_ARGS],
        expect="error",
    )
    add(
        "cmd-report-onto-input",
        "commands",
        ["report", "-o", "{d}/runs.csv", "{d}/runs.csv", *TABLE_ARGS],
        expect="error",
        setup=_copy("runs.csv"),
        check=_unchanged("runs.csv"),
    )
    add("cmd-report-no-output", "commands", ["report", "{b}/runs.csv", *TABLE_ARGS], expect="error")
    add("cmd-report-dev-zero", "commands", [*rep, "/dev/zero", *TABLE_ARGS], expect="error")
    add(
        "cmd-report-deep-params",
        "commands",
        [*rep, "{b}/runs.csv", *TABLE_ARGS, "--current-params", "{d}/p.yaml"],
        expect="error",
        setup=_write("p.yaml", deep_yaml(5000)),
    )
    add(
        "cmd-report-many-sources",
        "commands",
        [*rep, *(["{b}/runs.csv"] * 200), *TABLE_ARGS],
        timeout=120.0,
    )
    add(
        "cmd-report-json-full",
        "commands",
        [*rep, "{b}/runs.csv", *TABLE_ARGS, "--json"],
        stdout="full",
    )
    # replay's own options
    rl = ["replay", "{b}/logs"]
    add("cmd-replay-valid", "commands", rl, expect="ok")
    add("cmd-replay-table", "commands", ["replay", "{b}/runs.csv", *TABLE_ARGS], expect="error")
    add("cmd-replay-plot-bad", "commands", [*rl, "--plot", "{d}/p.txt"], expect="error")
    add(
        "cmd-replay-tum-onto-file",
        "commands",
        [*rl, "--tum", "{d}/f"],
        expect="error",
        setup=_write("f", "x"),
    )
    add(
        "cmd-replay-params-yaml",
        "commands",
        [*rl, "-p", "{b}/ros2_controllers.yaml"],
        expect="error",
    )
    add("cmd-replay-two-sources", "commands", [*rl, "{b}/logs"], expect="error")
    # info's options
    for value in ("-1", "0", "1", "1e3", "abc"):
        add(
            f"cmd-info-max-messages={value}",
            "commands",
            ["info", "{b}/logs", "--max-messages", value],
        )
    add("cmd-info-format-wrong", "commands", ["info", "{b}/logs", "-f", "bag"], expect="error")
    add(
        "cmd-info-optiodom-as-log",
        "commands",
        ["info", "{b}/real/square/230620202042", "-f", "log"],
        expect="error",
    )

    names = Counter(case.name for case in cases)
    dupes = [n for n, k in names.items() if k > 1]
    assert not dupes, dupes
    return cases


def _drop_column(index: int) -> Callable[[Path], str]:
    def make(b: Path) -> str:
        out = []
        for line in (b / "runs.csv").read_text().splitlines():
            if line.startswith("#"):
                out.append(line)
                continue
            cells = line.split(",")
            out.append(",".join(cells[:index] + cells[index + 1 :]))
        return "\n".join(out) + "\n"

    return make


def _many_rows(n: int) -> Callable[[Path], str]:
    def make(b: Path) -> str:
        rows = [line for line in (b / "runs.csv").read_text().splitlines()[6:] if line]
        body = "\n".join(rows[i % len(rows)] for i in range(n))
        return "direction,x_abs,y_abs,x_odo,y_odo\n" + body + "\n"

    return make


def _theta_to_degrees(b: Path) -> str:
    out = []
    for line in (b / "sim.csv").read_text().splitlines():
        cells = line.split(",")
        if len(cells) == 7 and cells[0] in ("cw", "ccw"):
            cells[3] = f"{math.degrees(float(cells[3])):.6f}"
            cells[6] = f"{math.degrees(float(cells[6])):.6f}"
        out.append(",".join(cells))
    return "\n".join(out) + "\n"


def _symlink_loop(name: str) -> Setup:
    def setup(d: Path, b: Path) -> None:
        target = d / name
        other = target.with_name(target.name + ".other")
        target.symlink_to(other.name)
        other.symlink_to(target.name)

    return setup


def _in_locked(name: str, mode: int) -> Setup:
    def setup(d: Path, b: Path) -> None:
        (d / "locked").mkdir()
        shutil.copy(b / "runs.csv", d / "locked" / name)
        (d / "locked").chmod(0o600)

    return setup


def _remove(rel: str) -> Setup:
    def setup(d: Path, b: Path) -> None:
        (d / rel).unlink()

    return setup


def _yaml_set(key: str, value: str) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        lines = data.decode("utf-8").splitlines()
        found = False
        for i, line in enumerate(lines):
            stripped = line.lstrip()
            if stripped.startswith(key + ":"):
                indent = line[: len(line) - len(stripped)]
                lines[i] = f"{indent}{key}: {value}"
                found = True
                break
        assert found, key
        return ("\n".join(lines) + "\n").encode("utf-8")

    return fn


def _data_rows(data: bytes) -> tuple[list[bytes], list[int]]:
    """Lines, and the indices of the data rows (first cell a number)."""
    lines = data.split(b"\n")
    rows = [
        i
        for i, line in enumerate(lines)
        if line[:1].isdigit() or (line[:1] == b"-" and line[1:2].isdigit())
    ]
    return lines, rows


def _set_cell(row: int, col: int, value: str) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        lines, rows = _data_rows(data)
        i = rows[min(row, len(rows) - 1)]
        cells = lines[i].split(b",")
        cells[col] = value.encode("utf-8")
        lines[i] = b",".join(cells)
        return b"\n".join(lines)

    return fn


def _scale_column(col: int, factor: float) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        lines, rows = _data_rows(data)
        for i in rows:
            cells = lines[i].split(b",")
            if col < len(cells):
                cells[col] = repr(float(cells[col]) * factor).encode()
            lines[i] = b",".join(cells)
        return b"\n".join(lines)

    return fn


def _jump_column(col: int, jump: float) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        lines, rows = _data_rows(data)
        for i in rows[len(rows) // 2 :]:
            cells = lines[i].split(b",")
            cells[col] = repr(float(cells[col]) + jump).encode()
            lines[i] = b",".join(cells)
        return b"\n".join(lines)

    return fn


def _reverse_rows(start: int, stop: int) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        lines, rows = _data_rows(data)
        chosen = rows[start:stop]
        values = [lines[i] for i in chosen][::-1]
        for i, v in zip(chosen, values, strict=True):
            lines[i] = v
        return b"\n".join(lines)

    return fn


def _duplicate_times(every: int) -> Callable[[bytes], bytes]:
    def fn(data: bytes) -> bytes:
        lines, rows = _data_rows(data)
        for a, b in zip(rows[::every], rows[1::every], strict=False):
            cells_a, cells_b = lines[a].split(b","), lines[b].split(b",")
            cells_b[0] = cells_a[0]
            lines[b] = b",".join(cells_b)
        return b"\n".join(lines)

    return fn


def _repeat_rows(times: int) -> Callable[[bytes], bytes]:
    """A run-log CSV driven ``times`` over, as one long recording: time goes on, the
    counts (columns 4, 5) keep adding up, the truth starts each lap where the last ended
    (closed laps: within the scatter)."""

    def fn(data: bytes) -> bytes:
        lines, rows = _data_rows(data)
        kept = set(rows)
        head = [line for i, line in enumerate(lines) if i not in kept and line]
        parsed = [[float(c) for c in lines[i].split(b",")] for i in rows]
        step = parsed[1][0] - parsed[0][0]
        last_left, last_right = parsed[-1][4], parsed[-1][5]
        out = []
        n = 0
        for lap in range(times):
            for cells in parsed:
                left = cells[4] + lap * last_left
                right = cells[5] + lap * last_right
                values = [f"{n * step:.6f}", *(f"{c:.6f}" for c in cells[1:4])]
                out.append(",".join([*values, f"{left:.0f}", f"{right:.0f}"]).encode())
                n += 1
        return b"\n".join([*head, *out]) + b"\n"

    return fn


def _json_set(key: str, value: object) -> Callable[[str], str]:
    def fn(text: str) -> str:
        data = json.loads(text)
        data[key] = value
        return json.dumps(data)

    return fn


def _json_set_new(key: str, value: object) -> Callable[[str], str]:
    def fn(text: str) -> str:
        data = json.loads(text)
        data["new"][key] = value
        return json.dumps(data)

    return fn


def _json_del_new(key: str) -> Callable[[str], str]:
    def fn(text: str) -> str:
        data = json.loads(text)
        del data["new"][key]
        return json.dumps(data)

    return fn


def _json_del(key: str) -> Callable[[str], str]:
    def fn(text: str) -> str:
        data = json.loads(text)
        del data[key]
        return json.dumps(data)

    return fn


def _msg_dir(kind: str) -> Setup:
    def setup(d: Path, b: Path) -> None:
        folder = d / "msgs" / "my_robot" / "msg"
        folder.mkdir(parents=True)
        if kind == "garbage":
            (folder / "Wheels.msg").write_text("this is { not a ] message\nfloat64[[ x\n")
        else:
            (folder / "Wheels.msg").write_text("my_robot/Wheels inner\nfloat64 left\n")

    return setup


def _storage_file(fmt: str) -> str:
    """The file of the case's copy of the valid bag (rosbags names it after its folder)."""
    return {"ros1": "bag.bag", "sqlite3": "bag/bag_sqlite3.db3", "mcap": "bag/bag_mcap.mcap"}[fmt]


def _bag_variant(
    fmt: str,
    kwargs: dict[str, object],
    transform: Callable[[SessionArrays], SessionArrays] | None,
) -> Setup:
    def setup(d: Path, b: Path) -> None:
        session = _session(b)
        if transform is not None:
            session = transform(session)
        write_session_bag(d / "bag", fmt, *session, **kwargs)  # type: ignore[arg-type]

    return setup


def _tf_variant(fmt: str, kwargs: dict[str, object]) -> Setup:
    def setup(d: Path, b: Path) -> None:
        write_tf_ticks_bag(d / "bag", fmt, *_session(b), **kwargs)  # type: ignore[arg-type]

    return setup


def _ticks_nan(counts: np.ndarray) -> np.ndarray:
    out = counts.copy()
    out[200:205] = np.nan
    return out


def _wrap_int16(counts: np.ndarray) -> np.ndarray:
    return (counts + 2**15) % 2**16 - 2**15


def _wrap_uint8(counts: np.ndarray) -> np.ndarray:
    return counts % 256


def _ticks_jump(counts: np.ndarray) -> np.ndarray:
    out = counts.copy()
    out[out.shape[0] // 2 :, 0] += 4096 * 1e5
    return out


def _times_backwards(s: SessionArrays) -> SessionArrays:
    times = s[0].copy()
    n = times.size
    times[n // 2 : n // 2 + 200] -= 30.0
    return times, s[1], s[2]


def _times_duplicated(s: SessionArrays) -> SessionArrays:
    times = s[0].copy()
    times[1::2] = times[::2][: times[1::2].size]
    return times, s[1], s[2]


def _angles_nan(s: SessionArrays) -> SessionArrays:
    angles = s[1].copy()
    angles[100:110] = np.nan
    return s[0], angles, s[2]


def _wheel_jump(s: SessionArrays) -> SessionArrays:
    angles = s[1].copy()
    angles[angles.shape[0] // 2 :, 0] += 1e6
    return s[0], angles, s[2]


def _first_half(s: SessionArrays) -> SessionArrays:
    n = s[0].size // 2
    return s[0][:n], s[1][:n], s[2][:n]


def _other_sqlite(d: Path, b: Path) -> None:
    import sqlite3

    (d / "b").mkdir()
    with sqlite3.connect(d / "b" / "b.db3") as db:
        db.execute("create table people (name text)")
        db.execute("insert into people values ('x')")


def _other_sqlite_file(name: str) -> Setup:
    def setup(d: Path, b: Path) -> None:
        import sqlite3

        con = sqlite3.connect(d / name)
        with con:
            con.execute("create table calibrations (x text)")
            con.execute("insert into calibrations values ('x')")
        con.close()

    return setup


def _unchanged(rel: str) -> Check:
    def check(d: Path, out: Outcome) -> str | None:
        text = (d / rel).read_text(errors="replace")
        return None if text.lstrip().startswith("#") else f"{rel} was overwritten"

    return check


def _still_link(rel: str) -> Check:
    def check(d: Path, out: Outcome) -> str | None:
        return None if (d / rel).is_symlink() else f"{rel} is no longer a symlink"

    return check


def _mode_is(rel: str, mode: int) -> Check:
    def check(d: Path, out: Outcome) -> str | None:
        got = (d / rel).stat().st_mode & 0o777
        return None if got == mode else f"{rel} has mode {got:o}, was {mode:o}"

    return check


def _absent(rel: str) -> Check:
    def check(d: Path, out: Outcome) -> str | None:
        return f"{rel} was written although the command failed" if (d / rel).exists() else None

    return check


def _wrote(n: int) -> Check:
    def check(d: Path, out: Outcome) -> str | None:
        got = sum(line.startswith("umbmark: wrote ") for line in out.stderr.splitlines())
        return None if got >= n else f"{got} 'wrote' lines for {n} outputs"

    return check


def _not_wrapped(d: Path, out: Outcome) -> str | None:
    """Piped, the summary keeps each line whole: the overlay's header line ends with its
    method, not broken at 80 columns."""
    lines = [line for line in out.stdout.splitlines() if line.startswith("# Written by umbmark")]
    if not lines:
        return "no overlay header line in the summary"
    return None if lines[0].rstrip().endswith("(method exact).") else "a line wrapped at 80 columns"


def _second_pass_used(d: Path, out: Outcome) -> str | None:
    """The table's header records the parameters active while it was simulated: they are
    used (active c_L not 1) or a warning says they were not."""
    if "umbmark: warning:" in out.stderr:
        return None
    try:
        data = json.loads(out.stdout)
    except ValueError:
        return "no JSON"
    active = data.get("active", {})
    if abs(float(active.get("c_L", 1.0)) - 1.0) < 1e-12:
        return "the active parameters the table records were neither used nor warned about"
    return None


# --- main -----------------------------------------------------------------------------


def summarize(verdicts: Sequence[Verdict], skipped: Sequence[Case], note: str) -> str:
    """The summary table (counts per class, per reader) and the failing cases."""
    readers = sorted({v.case.reader for v in verdicts})
    counts: dict[str, Counter[str]] = defaultdict(Counter)
    for v in verdicts:
        counts[v.case.reader][v.klass] += 1
    shown = [c for c in (*CLASSES, "setup-failed") if any(counts[r][c] for r in readers)]
    width = max([10, *(len(c) for c in shown)])
    lines = [f"{'reader':<10} {'cases':>6} " + " ".join(f"{c:>{width}}" for c in shown)]
    total: Counter[str] = Counter()
    for r in readers:
        total.update(counts[r])
        n = sum(counts[r].values())
        lines.append(f"{r:<10} {n:>6} " + " ".join(f"{counts[r][c]:>{width}}" for c in shown))
    n = sum(total.values())
    lines.append(f"{'total':<10} {n:>6} " + " ".join(f"{total[c]:>{width}}" for c in shown))
    peaks = sorted(
        (v.outcome.peak_mib, v.case.name) for v in verdicts if v.outcome.peak_mib is not None
    )
    if peaks:
        top, name = peaks[-1]
        median = peaks[len(peaks) // 2][0]
        lines.append(
            f"peak resident memory of a case: median {median:.0f} MiB, largest {top:.0f} MiB "
            f"({name}); address space limited to {MEMORY_LIMIT >> 20} MiB"
        )
    if skipped:
        lines.append(f"skipped {len(skipped)} case(s): {note}")
    failing = [v for v in verdicts if v.klass in FAILURES or v.klass == "setup-failed"]
    if failing:
        lines.append("")
        lines.append(f"{len(failing)} failing case(s):")
    for v in failing:
        lines.append(f"- [{v.klass}] {v.case.name} ({v.case.reader}): {v.detail}")
        lines.append(f"    $ {v.command}" + _redirect(v.case))
        for line in _lines(v.outcome.stderr)[-4:]:
            lines.append(f"    ! {line[:200]}")
    return "\n".join(lines)


def _redirect(case: Case) -> str:
    env = " ".join(f"{k}={v}" for k, v in case.env.items())
    out = {"full": " > /dev/full", "head": " | head -c 10"}.get(case.stdout, "")
    return (f"   (env {env})" if env else "") + out


#: Why permission cases are skipped where file modes do not apply.
SKIP_NOTE = (
    "file modes do not apply to this process (root with CAP_DAC_OVERRIDE that could "
    "not be dropped): permission cases skipped"
)


def run_corpus(
    cases: Sequence[Case], root: Path, *, jobs: int = 1, timeout: float = TIMEOUT
) -> tuple[list[Verdict], list[Case]]:
    """Build the valid inputs in ``root/_base`` (unless there already) and run ``cases``
    in ``root/cases``, ``jobs`` at a time. Returns the verdicts and the skipped cases."""
    root.mkdir(parents=True, exist_ok=True)
    base = root / "_base"
    if not (base / "session.npz").exists():
        print(f"building the valid inputs in {base} ...", file=sys.stderr)
        build_base(base)
    modes = modes_apply(root)
    skipped = [c for c in cases if c.needs_modes and not modes]
    todo = [c for c in cases if c not in skipped]
    print(f"running {len(todo)} case(s) with {jobs} job(s) ...", file=sys.stderr)

    def one(case: Case) -> Verdict:
        try:
            verdict = run_case(case, root / "cases", base, timeout)
        except Exception as exc:  # a fault of this script: report it, go on
            out = Outcome(0, "", "", 0.0)
            verdict = Verdict(case, "setup-failed", f"{type(exc).__name__}: {exc}", out, "")
        mark = "." if verdict.klass in ("ok-result", "clean-error") else "F"
        print(mark, end="", file=sys.stderr, flush=True)
        return verdict

    try:
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            return list(pool.map(one, todo)), skipped
    finally:
        print(file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=1, help="cases run in parallel (default 1)")
    parser.add_argument("--filter", default="", help="only cases whose name holds this")
    parser.add_argument("--list", action="store_true", help="list the cases and stop")
    parser.add_argument("--timeout", type=float, default=TIMEOUT, help="wall time of a case [s]")
    parser.add_argument("--keep", type=Path, help="build and keep the corpus in this folder")
    parser.add_argument("--json", type=Path, help="also write every verdict to this JSON file")
    args = parser.parse_args(argv)
    cases = [c for c in corpus() if args.filter in c.name]
    if args.list:
        for c in cases:
            print(
                f"{c.name:<55} {c.reader:<9} {c.expect:<5} umbmark {' '.join(map(_quote, c.argv))}"
            )
        print(f"{len(cases)} case(s)")
        return 0
    root = args.keep or Path(tempfile.mkdtemp(prefix="umbmark-corpus-"))
    started = time.perf_counter()
    try:
        verdicts, skipped = run_corpus(cases, root, jobs=args.jobs, timeout=args.timeout)
    finally:
        if args.keep is None:
            _restore_modes(root)
            shutil.rmtree(root, ignore_errors=True)
    print(summarize(verdicts, skipped, SKIP_NOTE))
    print(f"\n{len(verdicts)} case(s) in {time.perf_counter() - started:.0f} s")
    if args.json:
        args.json.write_text(
            json.dumps(
                [
                    {
                        "name": v.case.name,
                        "reader": v.case.reader,
                        "class": v.klass,
                        "detail": v.detail,
                        "command": v.command + _redirect(v.case),
                        "returncode": v.outcome.returncode,
                        "seconds": round(v.outcome.seconds, 3),
                        "peak_mib": v.outcome.peak_mib,
                        "stderr": v.outcome.stderr[-2000:],
                    }
                    for v in verdicts
                ],
                indent=1,
            )
        )
    failing = [v for v in verdicts if v.klass in FAILURES]
    return 1 if failing else 0


if __name__ == "__main__":
    sys.exit(main())

"""Shared test helpers: inputs built from first principles.

Nothing here calls the code under test to make an expected value: the helpers build
inputs (files, run end points) from first principles.
"""

from __future__ import annotations

import ast
import functools
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The shared data beside the checkout, or where UMBMARK_SHARED says (a worktree elsewhere).
SHARED = Path(os.environ.get("UMBMARK_SHARED") or ROOT.parent / "shared")
#: The copy of two OptiOdom sessions the package ships (square 230620202042, circle
#: 250620202104): what tests of those two read when the shared data is not here.
BUNDLED_OPTIODOM = ROOT / "src" / "umbmark" / "data" / "optiodom"
#: The OptiOdom sessions: all of them beside the checkout, else the bundled two (tests of
#: other sessions skip then, saying so; under CI the shared data is there).
OPTIODOM = (
    SHARED / "data" / "optiodom" if (SHARED / "data" / "optiodom").is_dir() else BUNDLED_OPTIODOM
)


def parsed(path: Path) -> ast.Module:
    """The syntax tree of the Python file ``path``, parsed once for each text it has: the
    checks of the architecture and of the docs read every module of the package (one
    parse of them all costs about a second). Do not change the tree."""
    return _parse(path.read_text(encoding="utf-8"))


def walked(path: Path) -> tuple[ast.AST, ...]:
    """Every node of :func:`parsed` ``(path)``, in :func:`ast.walk`'s order (once each)."""
    return _walk(path.read_text(encoding="utf-8"))


@functools.cache
def _parse(text: str) -> ast.Module:
    return ast.parse(text)


@functools.cache
def _walk(text: str) -> tuple[ast.AST, ...]:
    return tuple(ast.walk(_parse(text)))


def turtle_square(
    turn_deg: float,
    leg_turn_deg: float,
    side: float,
    direction: str,
    steps: int = 20_000,
    turn_offset: float = 0.0,
) -> tuple[float, float, float]:
    """Walk a square the slow, obvious way: an independent reference for the geometry.

    Each leg is walked in ``steps`` tiny straight steps that together turn the heading by
    ``leg_turn_deg`` (a circular arc of length ``side``); each corner turns by
    ``turn_deg`` to the left (ccw) or right (cw), about a point ``turn_offset`` [m] to
    the robot's left. Returns the end ``x, y`` [m] and the total heading [rad].
    """
    sign = 1.0 if direction == "ccw" else -1.0
    x = y = heading = 0.0
    ds = side / steps
    dh = math.radians(leg_turn_deg) / steps
    for _ in range(4):
        for _ in range(steps):
            heading += dh / 2
            x += ds * math.cos(heading)
            y += ds * math.sin(heading)
            heading += dh / 2
        turn = sign * math.radians(turn_deg)
        cx = x - turn_offset * math.sin(heading)
        cy = y + turn_offset * math.cos(heading)
        rx, ry = x - cx, y - cy
        x = cx + rx * math.cos(turn) - ry * math.sin(turn)
        y = cy + rx * math.sin(turn) + ry * math.cos(turn)
        heading += turn
    return x, y, heading


def write_table(path: Path, rows: Sequence[Sequence[object]], header: str) -> Path:
    """Write a CSV with ``header`` and ``rows`` (cells formatted with ``str``)."""
    lines = [header, *(",".join(str(c) for c in row) for row in rows)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def linear_cgs(alpha: float, beta: float, side: float) -> dict[str, tuple[float, float]]:
    """Centres of gravity by the paper's first-order results (paper-notes.md).

    ``x_cw = -2L(a + b)``, ``y_cw = -2L(a + b)``, ``x_ccw = -2L(a - b)``, ``y_ccw = +2L(a - b)``.
    """
    return {
        "cw": (-2 * side * (alpha + beta), -2 * side * (alpha + beta)),
        "ccw": (-2 * side * (alpha - beta), 2 * side * (alpha - beta)),
    }


def runs_around(
    cgs: dict[str, tuple[float, float]], spread: float = 0.0, n: int = 5
) -> list[tuple[str, float, float, float, float]]:
    """Rows ``(direction, x_abs, y_abs, x_odo, y_odo)`` whose errors average to ``cgs``.

    Around each centre the runs sit symmetrically (a regular polygon of radius
    ``spread``, whose points average to its centre), with odometry ends of (0, 0).
    """
    rows = []
    for direction, (cx, cy) in cgs.items():
        for k in range(n):
            angle = 2 * math.pi * k / n
            rows.append(
                (direction, cx + spread * math.cos(angle), cy + spread * math.sin(angle), 0.0, 0.0)
            )
    return rows


def simulated_session(
    robot: object,
    directions: Sequence[str],
    side: float = 2.0,
    rest: float = 3.0,
    seed: int = 0,
    control: object = None,
):
    """One continuous recording of several simulated runs, with rests between them.

    Each run starts where the previous one ended (the robot is not carried back), and the
    robot stands still for ``rest`` seconds before, between and after the runs. Returns
    ``(time (n,), counts (n, 2), true_pose (n, 3), ends)`` where ``ends`` lists each run's
    true end pose in its own start frame, from the simulator.
    """
    import numpy as np

    from umbmark.core.conventions import Direction
    from umbmark.sim.engine import simulate
    from umbmark.sim.paths import square

    dirs = [Direction(d) for d in directions]
    result = simulate(robot, square(side), dirs, control, np.random.default_rng(seed), record=True)
    trace = result.trace
    dt = float(trace.time[1] - trace.time[0])
    still = round(rest / dt)
    times, counts, poses = [], [], []
    step = 0
    base_counts = np.zeros(2, dtype=np.int64)
    x0 = y0 = th0 = 0.0

    def hold(n: int) -> None:
        nonlocal step
        for _ in range(n):
            times.append(step * dt)
            counts.append(base_counts.copy())
            poses.append((x0, y0, th0))
            step += 1

    hold(still)
    for i in range(len(dirs)):
        n = int(result.samples_used[i]) + 1
        c, s = math.cos(th0), math.sin(th0)
        local = trace.true_pose[i, 1:n]
        for k in range(local.shape[0]):
            lx, ly, lth = local[k]
            times.append(step * dt)
            counts.append(base_counts + trace.counts[i, k + 1])
            poses.append((x0 + c * lx - s * ly, y0 + s * lx + c * ly, th0 + lth))
            step += 1
        base_counts = base_counts + trace.counts[i, n - 1]
        x0, y0, th0 = poses[-1]
        hold(still)
    ends = [tuple(result.true_end[i]) for i in range(len(dirs))]
    return np.array(times), np.array(counts), np.array(poses), ends


def session_log(folder: Path, session, truth, wheelbase: float = 0.34, side: float = 1.0):  # type: ignore[no-untyped-def]
    """Write a :func:`simulated_session` as a run-log folder, with ``truth`` (n, 3) as its
    ground truth (D_n 0.15 m, 2000 counts per motor turn, gear 20)."""
    from umbmark.sources.runlog.reader import LogMetadata
    from umbmark.sources.runlog.writer import write_log_csv, write_metadata

    times, counts, _, _ = session
    folder.mkdir()
    write_metadata(
        folder,
        LogMetadata(
            wheel_diameter=0.15,
            wheelbase=wheelbase,
            encoder_resolution=2000,
            gear_ratio=20,
            side_length=side,
        ),
    )
    write_log_csv(folder / "session.csv", times, truth, counts)
    return folder


def umbmark_command() -> str:
    """The installed ``umbmark`` console script of this Python environment."""
    import shutil
    import sys

    beside = Path(sys.executable).with_name("umbmark")
    found = str(beside) if beside.exists() else shutil.which("umbmark")
    assert found, "the umbmark command is not installed: pip install -e ."
    return found


def run_cli(
    *args: str,
    env: dict[str, str] | None = None,
    timeout: float = 300,
    cwd: Path | None = None,
):
    """Run the installed ``umbmark ARGS`` as a user would (in ``cwd``, if given); returns the
    finished process."""
    import subprocess

    return subprocess.run(
        [umbmark_command(), *args],
        capture_output=True,
        text=True,
        check=False,
        env=env,
        timeout=timeout,
        cwd=cwd,
    )


def cli_json(*args: str) -> dict:  # type: ignore[type-arg]
    """Run ``umbmark ARGS --json``; it must succeed. Returns the JSON object."""
    import json

    proc = run_cli(*args, "--json")
    assert proc.returncode == 0, proc.stderr
    return dict(json.loads(proc.stdout))


def cli_error(*args: str) -> str:
    """Run ``umbmark ARGS``; it must fail on bad input: exit status 2 and one line on
    stderr, no traceback. Returns that line."""
    proc = run_cli(*args)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stderr.startswith("umbmark: error: "), proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert "Traceback" not in proc.stdout + proc.stderr
    return str(proc.stderr)


def api_error(fn, *args, **kwargs) -> str:  # type: ignore[no-untyped-def]
    """Call ``fn``; it must raise :class:`umbmark.InputError`. Returns its message, which
    is the line the command prints."""
    import pytest

    from umbmark.core.errors import InputError

    with pytest.raises(InputError) as caught:
        fn(*args, **kwargs)
    message = str(caught.value)
    assert "\n" not in message
    return message


def in_ci() -> bool:
    """CI runs (``CI`` set, as ``.ci/run`` and the usual CI services do), where every piece
    is installed, so that a missing one fails rather than skips."""
    return bool(os.environ.get("CI"))


def unavailable(reason: str) -> None:
    """Skip the calling test module for ``reason`` (a piece that cannot be had here), or fail
    it under CI, which installs everything."""
    import pytest

    if in_ci():
        pytest.fail(f"{reason} (CI installs it: .ci/run)", pytrace=False)
    pytest.skip(reason, allow_module_level=True)


def dom_text(page: Path, tmp_path: Path) -> str:
    """The page's DOM as headless chromium builds it (its own text where chromium is
    missing, outside CI, which installs it)."""
    import shutil
    import subprocess

    import pytest

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        if in_ci():
            pytest.fail("chromium is missing on CI (apt-get install chromium)")
        return page.read_text()
    argv = [chromium, "--headless", "--disable-gpu", "--no-sandbox", "--dump-dom"]
    argv += [f"--user-data-dir={tmp_path / 'profile'}", page.resolve().as_uri()]
    done = subprocess.run(argv, check=True, capture_output=True, text=True, timeout=60)
    return done.stdout


#: What the ROS 1 tests' robot node and probe (tests/ros1_robot_node.py, ros1_probe.py)
#: import besides the adapter's own modules (umbmark.robot.ros1.ROS1_MODULES).
ROS1_TEST_MODULES = (
    "std_msgs.msg",
    "diagnostic_msgs.msg",
    "rosgraph_msgs.msg",
    "tf2_msgs.msg",
    "dynamic_reconfigure.server",
    "dynamic_reconfigure.encoding",
)


@dataclass(frozen=True)
class DemoCommand:
    """What ``umbmark demo --out FOLDER`` printed and wrote (the ``demo_command`` fixture)."""

    folder: Path
    stdout: str
    stderr: str


def assert_click_options_are_specs(  # type: ignore[no-untyped-def]
    command, specs, *, same_help: bool = True, besides: set[str] | None = None
) -> None:
    """``command``'s click options are ``specs`` (:class:`umbmark.options.spec.Spec`):
    the same flags, default (a list's as typed, comma-separated), type and choices, and
    with ``same_help`` the same help; with ``besides``, the command has no options but
    these and the specs'."""
    import click

    params = {p.name: p for p in command.params if isinstance(p, click.Option) and p.name}
    for spec in specs:
        param = params[spec.name]
        assert set(param.opts) == set(spec.flags), spec.name
        if same_help:
            assert param.help == spec.help, spec.name
        if spec.most:  # comma-separated: the default as typed
            assert param.default == ",".join(format(v, "g") for v in spec.default), spec.name
        elif spec.kind == "flag":
            pass
        elif spec.default is None:  # not given: click's default is no value
            assert not isinstance(param.default, (bool, int, float, str)), spec.name
        else:
            assert param.default == spec.default, spec.name
        expected = {"integer": click.INT, "number": click.FLOAT}.get(spec.kind)
        if expected is not None and not spec.most:
            assert param.type is expected, spec.name
        if spec.kind == "file":
            assert isinstance(param.type, click.Path), spec.name
            assert not param.type.dir_okay, spec.name
        if spec.kind == "choice":
            assert isinstance(param.type, click.Choice), spec.name
            assert tuple(param.type.choices) == spec.choices, spec.name
    if besides is not None:
        assert set(params) - {spec.name for spec in specs} <= besides


#: How many of its standard errors one random draw of an estimate may miss its truth by: a
#: run over a ROS graph is a new draw each time (which messages arrive when is the
#: machine's), so a test that asked its 95 % interval to hold the truth would fail one run
#: in twenty for each figure; 4 fails one in 16,000. Coverage at the stated rate is
#: proven by Monte Carlo (tools/gyro_coverage.py, tests/estimators/test_gyro_fit.py).
DRAW_SIGMAS = 4.0


def assert_drawn_near(name: str, interval_95: Sequence[float], truth: float) -> None:
    """Assert that the estimate whose 95 % interval is ``interval_95`` (low, high) is within
    :data:`DRAW_SIGMAS` of its standard errors of ``truth``."""
    low, high = interval_95
    value, se = (low + high) / 2.0, (high - low) / (2.0 * 1.959964)
    assert se > 0.0, (name, low, high)
    assert abs(value - truth) < DRAW_SIGMAS * se, (
        f"{name} {value:.6g} +- {se:.2g} is {(value - truth) / se:+.2f} standard errors off "
        f"its truth {truth:.6g}"
    )

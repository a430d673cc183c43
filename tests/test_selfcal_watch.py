"""A self-calibration a person can watch and trust (issue 22, item 4), on the virtual
robot: what is said as it happens, the runs left, the one line after a stop (Ctrl-C as a
real SIGINT to ``umbmark selfcal``), the obstacle stop's distance by its formula, and the
faults that stop the robot (a zero velocity is the last command)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from dataclasses import replace

import numpy as np
import pytest

from umbmark.core.conventions import Direction
from umbmark.core.errors import SafetyError
from umbmark.jobs.selfcal import selfcal
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import World, corner_world
from umbmark.routines.corner import CornerNotFoundError
from umbmark.routines.drive import DriveLimits, drive_square
from umbmark.routines.watch import RunsLeft, stopped

from helpers import run_cli, umbmark_command


def _last_command_is_a_stop(robot: VirtualRobot) -> None:
    assert robot.commands, "no command was sent"
    _, linear, angular = robot.commands[-1]
    assert (linear, angular) == (0.0, 0.0)


# --- said as it happens ---------------------------------------------------------------------


@pytest.mark.slow
def test_checks_runs_and_passes_are_said_as_they_happen_with_the_runs_left(tmp_path, monkeypatch):
    """One pass of 2 + 2 runs and the verification: 8 runs planned from the start. Each
    line is said while the routine runs (the robot's clock is read at each), in order:
    the checks before the robot moved, the coarse check, the four runs of pass 1, its
    result, the four of the verification, its result. The time left is the mean time of
    the runs so far times the runs left (the clock here: the robot's)."""
    robot = VirtualRobot(E_d=1.004, E_b=0.97, slip=0.0004, seed=4)
    monkeypatch.setattr("umbmark.routines.watch._wall", robot.now)
    said: list[tuple[float, str]] = []
    counts: list[tuple[float, RunsLeft]] = []
    report = selfcal(
        robot, side_length=1.0, runs=2, max_passes=1, out=tmp_path / "out",
        notify=lambda line: said.append((robot.now(), line)),
        runs_left=lambda left: counts.append((robot.now(), left)),
    )  # fmt: skip
    lines = [line for _, line in said]
    assert lines[:2] == list(report.checks[:2])  # the odometry, the controller
    assert lines[0].startswith("odometry alive")
    assert lines[1].startswith("controller answers")
    assert any("laser watches for obstacles" in line for line in lines[:4])
    coarse = next(k for k, line in enumerate(lines) if line.startswith("Coarse turning check"))
    assert coarse == len(report.checks)
    runs = [
        k
        for k, line in enumerate(lines)
        if re.match(r"(pass 1|verification), run [1-4] of 4 \(c?cw [12] of 2\): return error", line)
    ]
    assert len(runs) == 8
    assert runs[0] == coarse + 1
    pass_1 = lines.index(next(line for line in lines if line.startswith("pass 1: E_max,syst")))
    assert runs[:4] == list(range(coarse + 1, pass_1))
    assert runs[4] == pass_1 + 1
    # the last: the verification, and then what the overlay is keyed by (no controller
    # was named: the default)
    assert lines[-2].startswith("verification: E_max,syst")
    assert lines[-1].startswith("no controller named: keyed diff_drive_controller")
    # said while driving: the robot's clock went on between the lines
    times = [t for t, _ in said]
    assert times[runs[0]] > times[coarse]
    assert times[runs[-1]] > times[runs[0]]
    assert times[-1] < robot.now() + 1e-9
    # the runs left: 8 planned, counted one by one
    assert [left.done for _, left in counts] == [0, 1, 2, 3, 4, 4, 5, 6, 7, 8]
    assert {left.planned for _, left in counts} == {8}
    begun = counts[0][0]
    for now, left in counts[1:]:
        assert left.seconds_left == pytest.approx((now - begun) / left.done * (8 - left.done))
    assert counts[0][1].seconds_left is None


def test_the_progress_line_says_about_how_long():
    assert RunsLeft(3, 30, 725.0).text() == "3 of 30 runs, about 12 min left"
    assert RunsLeft(0, 30, None).text() == "0 of 30 runs"
    assert RunsLeft(29, 30, 40.0).text() == "29 of 30 runs, about 40 s left"
    assert RunsLeft(1, 90, 3.0 * 3600).text() == "1 of 90 runs, about 3.0 h left"


# --- a stop mid-way -----------------------------------------------------------------------------


@pytest.mark.slow
def test_ctrl_c_in_the_verification_leaves_what_the_controller_holds(tmp_path):
    robot = VirtualRobot(E_d=1.004, E_b=0.97, seed=4)

    def interrupt(label: str, k: int, direction: object, what: str) -> None:
        if label == "verification" and k == 2 and what.startswith("driving, leg 2"):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as caught:
        selfcal(robot, side_length=1.0, runs=2, max_passes=1, out=tmp_path, progress=interrupt)
    _last_command_is_a_stop(robot)
    stop = stopped(caught.value)
    assert stop is not None
    assert stop.passes == ("pass 1",)
    assert stop.folder == tmp_path
    held = robot.drive_params()
    assert held.wheel_separation_multiplier == pytest.approx(0.97, abs=0.01)  # E_b's truth
    assert stop.holds.startswith("The controller holds the correction of pass 1")
    assert f"wheel_separation_multiplier {held.wheel_separation_multiplier:.6f}" in stop.holds
    assert stop.text().endswith(f"on disk: pass 1 in {tmp_path}")


def test_a_refusal_before_moving_is_no_stop(tmp_path):
    """The checks before moving refuse as before: the exception carries no stop."""
    robot = VirtualRobot(seed=1, world=World.build([[6.0, -5.5, 6.0, 5.5]]))
    with pytest.raises(CornerNotFoundError, match="no L-shaped corner") as caught:
        selfcal(robot, side_length=1.0, runs=2, out=tmp_path)
    assert stopped(caught.value) is None


@pytest.mark.slow
def test_sigint_to_the_command_stops_the_robot_and_says_how_to_go_on(tmp_path):
    """A real SIGINT to ``umbmark selfcal --sim`` once pass 1 is applied (its line is
    read as the command runs): exit 130, and the last line says what the controller
    holds (pass 1's correction: the virtual robot's E_b of 0.97 in the separation
    multiplier), the pass on disk, and the command again into a new folder."""
    out = tmp_path / "out"
    env = {**os.environ, "COLUMNS": "200"}
    command = [
        umbmark_command(), "selfcal", "--sim", "-L", "2", "--runs", "4", "--max-passes", "1",
        "--out", str(out),
    ]  # fmt: skip
    with subprocess.Popen(
        command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, env=env
    ) as proc:
        assert proc.stderr is not None
        lines = []
        deadline = time.monotonic() + 120.0
        for line in proc.stderr:
            lines.append(line)
            if line.startswith("umbmark: pass 1: E_max,syst") or time.monotonic() > deadline:
                break
        assert lines, "no line from the command"
        assert lines[-1].startswith("umbmark: pass 1: E_max,syst"), "".join(lines)
        assert "applied by reconfigure" in lines[-1]
        proc.send_signal(signal.SIGINT)
        rest = proc.stderr.read()
        assert proc.wait(timeout=60) == 130, rest
    last = rest.strip().splitlines()[-1]
    assert last.startswith("umbmark: error: interrupted, the robot stopped (zero velocity sent); ")
    found = re.search(r"wheel_separation_multiplier (\d\.\d{6})", last)
    assert found is not None, last
    assert float(found.group(1)) == pytest.approx(0.97, abs=0.01), last
    assert "the controller holds the correction of pass 1" in last
    assert f"on disk: pass 1 in {out};" in last
    again = f"umbmark selfcal --sim -L 2 --runs 4 --max-passes 1 --out {out}-2"
    assert last.endswith(f"to run it again from what the controller holds: {again}"), last
    assert (out / "pass-1").is_dir()
    assert not (out.parent / "out-2").exists()
    assert sum(line.startswith("umbmark: error:") for line in rest.splitlines()) == 1


# --- the obstacle stop --------------------------------------------------------------------------


def _wall_ahead(at: float) -> World:
    """The standard corner, without the clutter, and a wall across the first leg at
    ``x = at`` [m] (2 m wide)."""
    base = corner_world(clutter=False)
    return World.build(np.array([[at, -1.0, at, 1.0]]), (), base.corner)


def test_the_obstacle_stop_scales_with_speed():
    """Cruising at v towards a wall 3 m ahead, the robot is stopped where the laser sees
    it nearer than d = v^2/(2 a) + v t + margin (a = 0.3 m/s^2, t = 0.4 s, margin 0.3 m:
    0.447 m at 0.2 m/s, 0.917 m at 0.5 m/s), the figure the stop names. Braking at a, as
    the virtual robot does, it comes to rest at least the margin from the wall (less the
    laser's 1 cm noise) and at most margin + v t + 3 cm (the noise on the nearest of
    many beams): the braking distance v^2/(2 a) is used up, not left over."""
    wall = 3.0
    for speed in (0.2, 0.5):
        limits = DriveLimits(speed=speed, acceleration=0.3)
        robot = VirtualRobot(world=_wall_ahead(wall), seed=1, acceleration=0.3)
        with pytest.raises(SafetyError, match=r"obstacle .* ahead on the robot's path") as caught:
            drive_square(robot, 4.0, Direction.CCW, limits)
        _last_command_is_a_stop(robot)
        found = re.search(r"stop distance (\d\.\d\d) m at (\d\.\d\d) m/s", str(caught.value))
        assert found is not None
        v = float(found[2])
        assert v == pytest.approx(speed, abs=0.005)
        assert float(found[1]) == pytest.approx(v**2 / 0.6 + 0.4 * v + 0.3, abs=0.006)
        robot.wait(5.0)
        left = wall - robot.true_pose.x
        assert 0.3 - 0.01 <= left <= 0.3 + speed * 0.4 + 0.03, (speed, left)


def test_the_margin_is_an_option_within_bounds():
    limits = DriveLimits(obstacle_margin=1.0)
    assert limits.stop_distance(0.2) == pytest.approx(0.04 / 0.6 + 0.08 + 1.0)
    assert limits.stop_distance(-0.2) == limits.stop_distance(0.2)
    proc = run_cli("selfcal", "--sim", "--obstacle-margin", "3")
    assert proc.returncode == 2
    assert proc.stderr.strip() == "umbmark: error: --obstacle-margin must be 0.05 to 2, got 3"


def test_without_a_laser_the_routine_says_nothing_watches_for_obstacles(tmp_path):
    class Blind(VirtualRobot):
        def scan(self):  # type: ignore[no-untyped-def]
            return None

    said: list[str] = []
    robot = Blind(E_d=1.001, E_b=0.995, seed=1)
    with pytest.raises(KeyboardInterrupt):
        selfcal(
            robot, measure="truth", side_length=1.0, runs=2, out=tmp_path, notify=said.append,
            progress=lambda *a: (_ for _ in ()).throw(KeyboardInterrupt),
        )  # fmt: skip
    assert sum("nothing watches for obstacles" in line for line in said) == 1
    assert said[-1].startswith("no laser: nothing watches for obstacles")
    _last_command_is_a_stop(robot)


# --- faults -------------------------------------------------------------------------------------


class _ClockJump(VirtualRobot):
    """The robot's clock steps by ``step`` seconds at 5 s (a restarted simulation goes
    back; a stalled one, forward)."""

    step = 0.0

    def now(self) -> float:
        t = super().now()
        return t + self.step if t >= 5.0 else t

    def odometry(self):  # type: ignore[no-untyped-def]
        odom = super().odometry()
        return replace(odom, time=odom.time + self.step) if odom.time >= 5.0 else odom

    def scan(self):  # type: ignore[no-untyped-def]
        scan = super().scan()
        return replace(scan, time=scan.time + self.step) if scan.time >= 5.0 else scan


@pytest.mark.parametrize(
    ("step", "message"),
    [
        (-3.0, r"clock went back 2\.980 s .*simulation restarted"),
        (10.0, r"clock jumped 10\.02 s forward in one control step \(limit 5 s\)"),
    ],
)
def test_a_clock_jump_stops_the_robot(step, message):
    robot = _ClockJump(seed=1)
    robot.step = step
    with pytest.raises(SafetyError, match=message):
        drive_square(robot, 4.0, Direction.CCW)
    _last_command_is_a_stop(robot)
    assert VirtualRobot.now(robot) < 5.0 + 0.05  # stopped at the jump


def test_a_small_forward_step_of_the_clock_is_no_fault():
    robot = _ClockJump(seed=1)
    robot.step = 2.0  # within the 5 s bound: a busy machine's stall, not a jump
    run = drive_square(robot, 1.0, Direction.CCW)
    assert run.end_error[0] <= 0.005


def test_a_safety_stop_mid_routine_leaves_what_the_controller_holds(tmp_path):
    """The clock jumps 10 s at 5 s of the robot's time (the checks and the first fix are
    done by then, the coarse check turning): a SafetyError after a zero velocity, with the
    parameters it started with and no pass on disk."""
    robot = _ClockJump(seed=1)
    robot.step = 10.0
    with pytest.raises(SafetyError, match="clock jumped") as caught:
        selfcal(robot, side_length=1.0, runs=2, out=tmp_path)
    _last_command_is_a_stop(robot)
    stop = stopped(caught.value)
    assert stop is not None
    assert stop.passes == ()
    assert stop.text() == (
        "the controller holds no correction of these passes: wheel_separation_multiplier "
        "1.000000, left_wheel_radius_multiplier 1.000000, right_wheel_radius_multiplier "
        f"1.000000; on disk: no pass finished, nothing in {tmp_path}"
    )


@pytest.mark.slow
def test_on_a_terminal_the_progress_is_one_live_line(tmp_path):
    """``umbmark selfcal`` with its stderr on a pseudo-terminal: rich's live line shows
    the runs done out of planned and the time left; the routine's lines scroll above it;
    no plain ``progress:`` line."""
    import pty

    primary, secondary = pty.openpty()
    env = {**os.environ, "COLUMNS": "160", "TERM": "xterm"}
    command = [
        umbmark_command(), "selfcal", "--sim", "-L", "1", "--runs", "2", "--max-passes", "1",
        "--out", str(tmp_path / "out"),
    ]  # fmt: skip
    with subprocess.Popen(
        command, stderr=secondary, stdout=subprocess.DEVNULL, env=env
    ) as proc:  # fmt: skip
        os.close(secondary)
        chunks = []
        while True:
            try:
                chunk = os.read(primary, 65536)
            except OSError:  # the terminal closed with the process
                break
            if not chunk:
                break
            chunks.append(chunk)
        assert proc.wait(timeout=120) == 0
    os.close(primary)
    text = b"".join(chunks).decode("utf-8", "replace")
    assert re.search(r"[1-8] of 8 runs, about \d+ s left", text), text[-3000:]
    assert "umbmark: pass 1, run 1 of 4 (cw 1 of 2): return error" in text
    assert "umbmark: progress:" not in text


@pytest.mark.slow
def test_a_fix_lost_mid_routine_is_one_line_with_what_the_controller_holds(tmp_path):
    """Range sensors lose the corner at the end of the first ccw run of the virtual
    LabMate's 4 m squares (tests/test_selfcal.py): exit 2, the cause and the stop in one
    line, the same folder offered again (nothing in it)."""
    out = tmp_path / "out"
    proc = run_cli("selfcal", "--sim", "--measure", "ranges", "--runs", "2", "--out", str(out))
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert sum(line.startswith("umbmark: error: ") for line in lines) == 1
    last = lines[-1]
    assert last.startswith("umbmark: error: missing echo: ")
    assert "(at the end of ccw run 1)" in last
    assert "; the robot stopped; the controller holds no correction of these passes" in last
    assert f"on disk: no pass finished, nothing in {out};" in last
    again = f"umbmark selfcal --sim --measure ranges --runs 2 --out {out}"
    assert last.endswith(f"to run it again from what the controller holds: {again}")

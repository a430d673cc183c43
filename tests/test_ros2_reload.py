"""``umbmark selfcal --ros2 --reload`` against a real ROS 2 graph: the node of
``tests/ros2_robot_node.py`` with its controller manager (``/controller_manager``'s
list/switch/configure/load/unload services, controller_manager.cpp's state rules), on a
private domain at 8x sim time.

The controller manager's interfaces are the real ``controller_manager_msgs``, generated
and compiled into ``.venv-ros2`` by ``tools/build_ros2_interfaces.py`` (the README's test
command runs it): the same messages a robot's controller manager answers with.

Expected values come from the node's truth (E_d 1.004, E_b 0.97: the multipliers that
correct it are E_b for the separation and a right/left radius ratio of E_d), and from
what the node reports at its end (the parameters its controller runs on, every call its
manager took), never from the code under test.
"""

from __future__ import annotations

import json
import os
import subprocess
import threading
from pathlib import Path
from typing import Any

import pytest
import yaml

from test_ros2 import (
    E_B,
    E_D,
    PROBE,
    PYTHON,
    STAMPED_TOPIC,
    UNSTAMPED_TOPIC,
    Robot2,
    _probe,
    _umbmark,
    humble_unstamped,
    ros2_env,
)  # fmt: skip

#: The controller (ros2_robot_node's default).
NAME = "diff_drive_controller"
#: What the node's manager is asked for one reconfigure (Jazzy, Kilted) and one reload
#: with the overlay (Rolling).
CONFIGURE = [f"switch + -{NAME}", f"configure {NAME}", f"switch +{NAME} -"]
LOAD = [f"switch + -{NAME}", f"unload {NAME}", f"load {NAME}", f"configure {NAME}",
        f"switch +{NAME} -"]  # fmt: skip
MULTIPLIERS = (
    "wheel_separation_multiplier",
    "left_wheel_radius_multiplier",
    "right_wheel_radius_multiplier",
)

if not any((PYTHON.parents[1] / "lib").glob("python3*/site-packages/controller_manager_msgs/srv")):
    why = "no controller_manager_msgs in .venv-ros2: python tools/build_ros2_interfaces.py"
    if os.environ.get("CI") == "true":
        pytest.fail(f"{why} (the test command runs it)", pytrace=False)
    pytest.skip(why, allow_module_level=True)


class Node(Robot2):
    """The robot node, keeping what it prints at its end."""

    final: dict[str, Any] | None = None

    def _watch(self, ready: threading.Event) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.strip() == "ready":
                ready.set()
            elif line.startswith("final "):
                self.final = json.loads(line[len("final ") :])

    def ended(self) -> dict[str, Any]:
        self.close()
        assert self.final is not None, "the node printed no final line"
        return self.final


def _overlay(path: Path) -> dict[str, float]:
    data = yaml.safe_load(path.read_text())
    block = data[NAME]["ros__parameters"]
    return {k: float(block[k]) for k in MULTIPLIERS}


def _truth_held(held: dict[str, float]) -> None:
    """The multipliers correct the node's true robot."""
    assert held["wheel_separation_multiplier"] == pytest.approx(E_B, abs=0.005)
    ratio = held["right_wheel_radius_multiplier"] / held["left_wheel_radius_multiplier"]
    assert ratio == pytest.approx(E_D, abs=0.001)


@pytest.mark.slow
def test_kilted_reload_through_the_controller_manager(tmp_path: Path) -> None:
    """Kilted (multipliers settable, read on configure): before moving it says it will
    set them and deactivate, configure, activate; every applied pass went exactly that
    way through the manager; the odometry restarted at each (reset, then jumped by the
    wheels' rotation times the radius change) and the routine took that as a new
    origin, not as motion or a fault; the verification ran on the applied parameters;
    at the end the controller runs on (not only declares) the overlay's values, which
    correct the truth, and E_max,syst fell at least tenfold."""
    env = ros2_env(tmp_path)
    out = tmp_path / "out"
    node = Node(env, "--upside-down")
    try:
        done = _umbmark(env, "selfcal", "--ros2", "--reload", "--runs", "2", "-L", "1",
                        "--max-passes", "2", "--out", str(out), "--json")  # fmt: skip
    finally:
        final = node.ended()
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout)
    # among the checks before moving
    assert any("applying: set_parameters on /diff_drive_controller" in c for c in report["checks"])
    labels = [p["label"] for p in report["passes"]]
    assert labels[-1] == "verification"
    applied = [p for p in report["passes"] if p["label"] != "verification"]
    assert all(p["applied"] for p in applied)
    assert all("configured and activated" in p["apply_message"] for p in applied)
    coarse = report["coarse"]  # a turning check whose correction was applied: one more
    reloads = len(applied) + (1 if coarse is not None and coarse["needed"] else 0)
    assert final["calls"] == CONFIGURE * reloads
    assert final["state"] == "active"
    # the odometry restarted where the wheels had turned: not at zero
    assert len(final["restarts"]) == reloads
    assert all(abs(x) + abs(y) + abs(t) > 1e-4 for x, y, t in final["restarts"])
    configured = {k: final["configured"][k] for k in MULTIPLIERS}
    assert report["passes"][-1]["active"] == pytest.approx(configured, rel=1e-12)
    assert report["applied"] == pytest.approx(configured, rel=1e-12)
    assert _overlay(out / "overlay.yaml") == pytest.approx(configured, rel=1e-9)
    _truth_held(configured)
    assert report["e_max_syst_after"] < report["e_max_syst_before"] / 10.0


@pytest.mark.slow
def test_rolling_reload_unloads_and_loads_with_the_overlay(tmp_path: Path) -> None:
    """Rolling (multipliers read-only: set_parameters refused): before moving it says it
    will append the overlay to the manager's parameter files and unload, load, configure,
    activate; the manager's NAME.params_file ends as the robot's file then the overlay;
    the controller loaded on them runs on the overlay's values (its first update after
    the load integrates the wheels' whole travel: a restart far from zero, taken as the
    new origin), and the verification pass ran on them."""
    env = ros2_env(tmp_path)
    out, base, overlay = tmp_path / "out", tmp_path / "robot.yaml", tmp_path / "overlay.yaml"
    base.write_text(
        f"{NAME}:\n  ros__parameters:\n    wheel_separation: 0.34\n    wheel_radius: 0.075\n"
    )
    node = Node(env, "--upside-down", "--distro", "rolling", "--params-file", str(base))
    try:
        done = _umbmark(env, "selfcal", "--ros2", "--reload", "--params-file", str(overlay),
                        "--runs", "2", "-L", "1", "--max-passes", "1", "--out", str(out),
                        "--json")  # fmt: skip
    finally:
        final = node.ended()
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout)
    (plan,) = [c for c in report["checks"] if c.startswith("applying:")]  # before moving
    assert "multipliers are read-only" in plan
    assert "unloads, loads, configures and activates" in plan
    assert [p["label"] for p in report["passes"]] == ["pass 1", "verification"]
    assert report["passes"][0]["applied"] is True
    coarse = report["coarse"]  # a turning check whose correction was applied: one more
    assert final["calls"] == LOAD * (2 if coarse is not None and coarse["needed"] else 1)
    assert final["params_file"] == [str(base), str(overlay)]
    assert final["state"] == "active"
    configured = {k: final["configured"][k] for k in MULTIPLIERS}
    assert final["configured"]["wheel_separation"] == 0.34  # the robot's file still read
    assert _overlay(overlay) == pytest.approx(configured, rel=1e-9)
    assert report["passes"][-1]["active"] == pytest.approx(configured, rel=1e-12)
    _truth_held(configured)
    # four 1 m squares and the moves home: the wheels turned more than 16 m, and the
    # controller just loaded integrates all of it at once
    x, y, _t = final["restarts"][-1]
    assert (x * x + y * y) ** 0.5 > 1.0


@pytest.mark.slow
def test_a_failed_configure_stops_the_robot_and_drives_no_further_pass(
    tmp_path: Path,
) -> None:
    """The manager fails to configure the controller on the new multipliers: one line
    (exit 3) saying so and what the controller is now, the robot stands, and no further
    pass (nor the verification) is driven on parameters that were not applied."""
    env = ros2_env(tmp_path)
    out = tmp_path / "out"
    node = Node(env, "--fail-configure")
    try:
        done = _umbmark(env, "selfcal", "--ros2", "--reload", "--runs", "2", "-L", "1",
                        "--max-passes", "3", "--out", str(out))  # fmt: skip
    finally:
        final = node.ended()
    assert done.returncode == 3, done.stderr[-3000:]
    errors = [line for line in done.stderr.splitlines() if line.startswith("umbmark: error:")]
    assert len(errors) == 1, done.stderr
    assert "failed to configure diff_drive_controller" in errors[0]
    assert "is unconfigured now" in errors[0]
    assert "no further pass" in errors[0]
    assert "Traceback" not in done.stderr
    assert final["calls"] == CONFIGURE[:2]  # deactivated, the configure failed: no activate
    assert final["state"] == "unconfigured"
    assert (out / "pass-1").is_dir()
    assert not (out / "pass-2").exists()
    assert not (out / "verification").exists()


@pytest.mark.slow
def test_the_plan_is_said_before_moving(tmp_path: Path) -> None:
    """Which way applying goes, found on the graph before anything moves: Kilted
    configures; Rolling without --params-file cannot (read-only multipliers), so the
    routine will stop for a restart; without --reload it will too."""
    env = ros2_env(tmp_path)
    node = Node(env, "--distro", "rolling")
    try:
        rolling = _plan(env, "--reload")
        without = _plan(env)
    finally:
        node.close()
    assert rolling["can_apply"] is not None
    assert rolling["note"] is None
    assert "read-only" in rolling["can_apply"]
    assert "--params-file" in rolling["can_apply"]
    assert "stops after the first pass" in rolling["can_apply"]
    assert without["can_apply"] is not None
    assert "--reload" in without["can_apply"]
    node = Node(env)
    try:
        kilted = _plan(env, "--reload")
    finally:
        node.close()
    assert kilted["can_apply"] is None
    assert "deactivates, configures and activates" in kilted["note"]


@pytest.mark.slow
@pytest.mark.parametrize("distro", ["humble-unstamped", "kilted"])
def test_the_velocity_subscription_lives_from_configure_to_cleanup(
    tmp_path: Path, distro: str
) -> None:
    """The controller creates its velocity subscription on configure and drops it on
    cleanup (diff_drive_controller.cpp: on_configure, reset()), as the graph shows through
    the controller manager: there while active and inactive, gone once cleaned up, back
    after configure. Humble with ``use_stamped_vel: false``: Twist on
    ``~/cmd_vel_unstamped`` only; Kilted: TwistStamped on ``~/cmd_vel`` only."""
    env = ros2_env(tmp_path)
    args = humble_unstamped(tmp_path) if distro == "humble-unstamped" else ()
    node = Node(env, *args)
    try:
        seen = _probe(env, "lifecycle")
    finally:
        final = node.ended()
    if distro == "humble-unstamped":
        there = {UNSTAMPED_TOPIC: [f"/{NAME} geometry_msgs/msg/Twist"], STAMPED_TOPIC: []}
    else:
        there = {UNSTAMPED_TOPIC: [], STAMPED_TOPIC: [f"/{NAME} geometry_msgs/msg/TwistStamped"]}
    gone = {UNSTAMPED_TOPIC: [], STAMPED_TOPIC: []}
    assert seen["active"] == there
    assert seen["deactivate"] == [True, there]
    assert seen["cleanup"] == [True, gone]
    assert seen["configure"] == [True, there]
    assert seen["activate"] == [True, there]
    assert final["state"] == "active"
    assert final["calls"] == [f"switch + -{NAME}", f"cleanup {NAME}", f"configure {NAME}",
                              f"switch +{NAME} -"]  # fmt: skip


def _plan(env: dict[str, str], *args: str) -> dict[str, Any]:
    done = subprocess.run(
        [str(PYTHON), str(PROBE), "plan", *args],
        env=env, capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    out: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return out


#: A user's controller file, as a person writes and tunes it.
USER_FILE = """\
# my_controllers.yaml: hand-tuned, do not lose these comments!
controller_manager:
  ros__parameters:
    update_rate: 100  # Hz

diff_cont:
  ros__parameters:
    left_wheel_names: ["left_wheel_joint"]
    right_wheel_names: [ 'right_wheel_joint' ]

    wheel_separation: 0.34   # m, measured with a tape
    wheel_radius: 0.075      # m
    wheel_separation_multiplier: 1.0   # calibrated by hand, 2024
    left_wheel_radius_multiplier: 1.0
    right_wheel_radius_multiplier: 1.0 # same tyres
    publish_rate: 50.0  # Hz
"""


@pytest.mark.slow
def test_a_controller_named_diff_cont_and_its_commented_file(tmp_path: Path) -> None:
    """Kilted through ``--reload``, the controller ``/diff_cont``, ``--params-file`` the
    user's commented file: the pass's correction went by set_parameters and the JSON's
    ``apply_method`` says so (not ``yaml``); the file holds the values the controller
    runs on, every other byte as it was (the three value substrings masked, byte for
    byte), its previous copy beside it, and a line on the terminal named it; the overlay
    and the page's overlay are keyed ``diff_cont``."""
    import html
    import re

    env = ros2_env(tmp_path)
    out, mine = tmp_path / "out", tmp_path / "my_controllers.yaml"
    mine.write_text(USER_FILE)
    node = Node(env, "--upside-down", "--controller", "/diff_cont", "--params-file", str(mine))
    try:
        done = _umbmark(env, "selfcal", "--ros2", "--reload", "--controller", "/diff_cont",
                        "--params-file", str(mine), "--runs", "2", "-L", "1", "--max-passes",
                        "1", "--no-coarse", "--out", str(out), "--json")  # fmt: skip
    finally:
        final = node.ended()
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout)
    first = report["passes"][0]
    assert first["applied"] is True
    assert first["apply_method"] == "set_parameters"
    assert final["calls"] == [c.replace(NAME, "diff_cont") for c in CONFIGURE]
    configured = {k: final["configured"][k] for k in MULTIPLIERS}
    _truth_held(configured)
    value = r"(?<=_multiplier: )[0-9.e+-]+"
    assert re.sub(value, "V", mine.read_text()) == re.sub(value, "V", USER_FILE)
    written = yaml.safe_load(mine.read_text())["diff_cont"]["ros__parameters"]
    assert {k: written[k] for k in MULTIPLIERS} == pytest.approx(configured, rel=1e-9)
    assert (tmp_path / "my_controllers.yaml.bak").read_text() == USER_FILE
    assert f"umbmark: changed {mine}: diff_cont's wheel_separation_multiplier 1.0 -> " in (
        done.stderr
    )
    assert list(yaml.safe_load((out / "overlay.yaml").read_text())) == ["diff_cont"]
    page = (out / "report.html").read_text()
    shown = re.search(r'<pre id="overlay-yaml">(.*?)</pre>', page, re.S)
    assert shown is not None
    assert list(yaml.safe_load(html.unescape(shown[1]))) == ["diff_cont"]

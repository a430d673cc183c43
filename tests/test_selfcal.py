"""The self-calibration on the virtual robot: the paper's Sec. 6 routine, its proof figures
(the robot's truth is known: it is what the virtual robot was built with), its refusals and
its safety stops (a zero velocity is the last command sent)."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from html.parser import HTMLParser

import numpy as np
import pytest

import umbmark
from umbmark.core.conventions import Direction
from umbmark.core.errors import InputError, SafetyError
from umbmark.jobs.selfcal import selfcal
from umbmark.robot.base import Pose2D
from umbmark.robot.virtual import VirtualRobot
from umbmark.robot.world import World, box, corner_world, legs
from umbmark.routines.drive import DriveLimits, drive_square

from helpers import run_cli

#: The paper's kind of errors (Sec. 5, Fig. 11): unequal wheels and a wrong wheelbase.
E_D, E_B = 1.004, 0.97


def _last_command_is_a_stop(robot: VirtualRobot) -> None:
    assert robot.commands, "no command was sent"
    _, linear, angular = robot.commands[-1]
    assert (linear, angular) == (0.0, 0.0)


@pytest.fixture(scope="module")
def paper_robot(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    robot = VirtualRobot(E_d=E_D, E_b=E_B, slip=0.0004, seed=3)
    out = tmp_path_factory.mktemp("selfcal") / "out"
    history = out.parent / "history.sqlite"
    return robot, selfcal(robot, out=out, robot_name="labmate", history=history), history


@pytest.mark.slow
def test_the_papers_errors_are_reduced_at_least_tenfold(paper_robot):
    _, report, _ = paper_robot
    before, after = report.e_max_syst_before, report.e_max_syst_after
    assert before is not None
    assert after is not None
    assert before > 0.3  # the paper's LabMate: 317 mm (larger errors here: E_b 0.97)
    assert before / after >= 10.0
    assert report.passes[-1].label == "verification"
    assert report.passes[-1].applied is None


@pytest.mark.slow
def test_the_applied_multipliers_are_the_robots_truth(paper_robot):
    robot, report, _ = paper_robot
    final = report.final
    assert final == robot.drive_params()  # what the controller holds at the end
    # E_b: the true wheelbase over the nominal one; the odometry needs exactly that
    assert final.wheel_separation_multiplier == pytest.approx(E_B, abs=0.002)
    # c_R / c_L = D_R / D_L (Eqs. 4.31, 4.32), and the mean diameter unchanged (E_s = 1)
    ratio = final.right_wheel_radius_multiplier / final.left_wheel_radius_multiplier
    assert ratio == pytest.approx(E_D, abs=5e-4)
    mean = 0.5 * (final.right_wheel_radius_multiplier + final.left_wheel_radius_multiplier)
    assert mean == pytest.approx(1.0, abs=1e-3)


class _Page(HTMLParser):
    """The page's statement of what the controller holds and its overlay's text."""

    def __init__(self) -> None:
        super().__init__()
        self.holds_pass: str | None = None
        self.holds_text = ""
        self.overlay = ""
        self._in: str | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        named = dict(attrs)
        if named.get("id") == "holds":
            self.holds_pass, self._in = named.get("data-pass"), "holds"
        elif named.get("id") == "overlay-yaml":
            self._in = "overlay"

    def handle_endtag(self, tag: str) -> None:
        if tag in ("p", "pre"):
            self._in = None

    def handle_data(self, data: str) -> None:
        if self._in == "holds":
            self.holds_text += data
        elif self._in == "overlay":
            self.overlay += data


@pytest.mark.slow
def test_every_output_names_what_the_controller_holds(paper_robot):
    # the verification pass is driven on the held parameters and not applied: the page,
    # the terminal, overlay.yaml and the JSON all name the pass the robot holds and its
    # multipliers, and those are what the virtual robot runs with (its own truth)
    import io

    import yaml
    from rich.console import Console

    from umbmark.cli.render import render_selfcal

    robot, report, _ = paper_robot
    truth = robot.drive_params()
    names = (
        "wheel_separation_multiplier",
        "left_wheel_radius_multiplier",
        "right_wheel_radius_multiplier",
    )
    held = [truth.wheel_separation_multiplier, truth.left_wheel_radius_multiplier]
    held.append(truth.right_wheel_radius_multiplier)
    applied = [k for k, p in enumerate(report.passes, 1) if p.applied and p.applied.active]
    verification = report.passes[-1]
    assert verification.label == "verification"
    assert verification.applied is None
    k = applied[-1]
    label = report.passes[k - 1].label
    assert k == len(report.passes) - 1
    # the verification's own correction is not what the robot holds (a page showing it
    # would be told apart)
    new = verification.report.calibration.new_separation_multiplier
    assert abs(new - truth.wheel_separation_multiplier) > 1e-5

    folder = report.passes[0].folder.parent
    page = _Page()
    page.feed((folder / "report.html").read_text(encoding="utf-8"))
    assert page.holds_pass == str(k)
    assert f"correction of {label}:" in page.holds_text
    shown = yaml.safe_load(page.overlay)["diff_drive_controller"]["ros__parameters"]
    overlay = yaml.safe_load((folder / "overlay.yaml").read_text(encoding="utf-8"))
    overlay = overlay["diff_drive_controller"]["ros__parameters"]
    data = json.loads(report.to_json())
    assert data["holds"]["pass"] == label
    screen = Console(file=io.StringIO(), width=400)
    render_selfcal(report, screen)
    text = " ".join(screen.file.getvalue().split())  # type: ignore[attr-defined]
    assert f"The controller holds the correction of {label}:" in text
    for name, value in zip(names, held, strict=True):
        assert shown[name] == pytest.approx(value, abs=1e-9)
        assert overlay[name] == pytest.approx(value, abs=1e-9)
        assert data["holds"][name] == pytest.approx(value, abs=1e-12)
        assert data["applied"][name] == pytest.approx(value, abs=1e-12)
        assert f"{name} {value:.6f}" in text
        assert f"{name} {value:.6f}" in page.holds_text


def test_with_nothing_applied_the_page_offers_the_last_pass_by_hand(tmp_path):
    # --apply none: the controller holds none of the passes' corrections; the page says so
    # and offers the last pass's correction to apply by hand (its verdict is apply)
    from umbmark.calibration.passes import Holds

    table = tmp_path / "runs.csv"
    umbmark.example(str(table))
    page = umbmark.report(table, side_length=4, wheelbase=0.34, unit="mm")
    held = Holds(("pass 1",), None, 1.0, 1.0, 1.0)
    parsed = _Page()
    parsed.feed(replace(page, holds=held).html())
    assert parsed.holds_pass == ""
    assert parsed.holds_text.startswith("The controller holds no correction of these passes")
    assert parsed.overlay == page.last.overlay_yaml()


@pytest.mark.slow
def test_the_corner_is_measured_within_the_target(paper_robot):
    _, report, _ = paper_robot
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.002  # m rms (the paper's calibrator: 2 mm)
    assert math.degrees(errors[1]) <= 0.2  # deg rms (the paper's: 0.4 deg)
    assert report.fix_errors is not None
    assert report.fix_errors.shape[0] >= 40


@pytest.mark.slow
def test_the_json_holds_what_the_issue_names(paper_robot):
    _, report, _ = paper_robot
    data = json.loads(report.to_json())
    assert {"passes", "e_max_syst_before", "e_max_syst_after", "applied", "measurement"} <= set(
        data
    )
    for p in data["passes"]:
        assert {"e_max_syst", "E_d", "E_b", "applied"} <= set(p)
    assert set(data["applied"]) == {
        "wheel_separation_multiplier",
        "left_wheel_radius_multiplier",
        "right_wheel_radius_multiplier",
    }
    assert data["measurement"]["method"] == "lidar"
    assert data["measurement"]["rms_position_error"] <= 0.002


@pytest.mark.slow
def test_every_pass_is_a_run_log_that_calibrate_reads(paper_robot, tmp_path):
    import umbmark

    _, report, _ = paper_robot
    first = report.passes[0]
    again = umbmark.calibrate(first.folder)
    assert len(again.runs) == 10
    assert again.e_max_syst == pytest.approx(first.report.e_max_syst)
    # the metadata records the parameters active during the pass: pass 2 ran on pass 1's
    second = report.passes[1]
    assert second.params.wheel_separation_multiplier == pytest.approx(
        first.report.calibration.new_separation_multiplier
    )
    # replay reads it too: pass 1's runs integrated with its correction end nearer the
    # true end (the truth at the stops is what replay compares with)
    result = tmp_path / "pass-1.json"
    first.report.write(output=result)
    replayed = umbmark.replay(first.folder, params=result)
    errors = {name: float(np.mean(e)) for name, e in replayed.end_errors.items()}
    assert len(errors) == 2
    before, after = sorted(errors.values(), reverse=True)
    assert after < before / 5


@pytest.mark.slow
def test_the_history_has_every_pass_and_marks_the_applied(paper_robot):
    import umbmark

    _, report, history = paper_robot
    found = umbmark.history("labmate", history=history)
    assert len(found.calibrations) == len(report.passes)
    applied = [c.applied for c in found.calibrations]
    assert applied == [p.applied is not None and p.applied.active for p in report.passes]
    assert found.drift is not None
    assert "no drift" in found.drift


@pytest.mark.slow
def test_a_skid_steer_like_robot_is_calibrated_through_the_coarse_pass(tmp_path):
    # E_b 1.6: the robot turns 1/1.6 of what its odometry believes; no square is possible
    # until the coarse turning check multiplies the separation by about 1.6
    robot = VirtualRobot(E_d=1.002, E_b=1.6, slip=0.0004, seed=5)
    report = selfcal(robot, out=tmp_path / "out", side_length=2.0, runs=3, max_passes=2)
    assert report.coarse is not None
    assert report.coarse.needed
    assert report.coarse.ratio == pytest.approx(1.6, rel=0.01)
    assert report.coarse_applied is not None
    assert report.coarse_applied.active
    assert report.final.wheel_separation_multiplier == pytest.approx(1.6, abs=0.005)
    assert report.e_max_syst_after is not None
    assert report.e_max_syst_after < 0.03


# --- refusals before anything moves ---------------------------------------------------


def test_no_corner_in_view_is_refused_before_moving(tmp_path):
    world = World.build([[6.0, -5.5, 6.0, 5.5]])  # only a far wall
    robot = VirtualRobot(E_d=E_D, E_b=E_B, world=world, seed=1)
    with pytest.raises(InputError, match=r"no L-shaped corner|too few"):
        selfcal(robot, out=tmp_path / "out")
    assert robot.true_pose == world.start  # nothing moved
    _last_command_is_a_stop(robot)


def test_something_on_the_squares_path_is_refused_naming_where(tmp_path):
    base = corner_world()
    world = World.build(
        np.vstack([base.segments[2:], box(2.0, 0.0, 0.4, 0.4)]), base.circles, base.corner
    )
    robot = VirtualRobot(world=world, seed=1)
    where = r"something stands on the squares' path at x = 1\.(7[5-9]|8[0-5]) m"
    with pytest.raises(InputError, match=where):
        selfcal(robot, out=tmp_path / "out")
    assert robot.true_pose == world.start
    _last_command_is_a_stop(robot)


def test_a_folder_with_files_is_refused(tmp_path):
    (tmp_path / "keep.txt").write_text("mine")
    robot = VirtualRobot(seed=1)
    for force in (False, True):  # not a self-calibration's: refused even with force
        with pytest.raises(InputError, match=r"holds keep\.txt, which a self-calibration did not"):
            selfcal(robot, out=tmp_path, force=force)
    assert [p.name for p in tmp_path.iterdir()] == ["keep.txt"]
    assert robot.true_pose == robot.world.start  # refused before it moved


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"side_length": 0.1}, "side_length"),
        ({"runs": 1}, "runs"),
        ({"max_passes": 9}, "max_passes"),
    ],
)
def test_bad_options_are_refused(tmp_path, options, message):
    """Called from Python (the facade), the message names the keyword as Python spells it."""
    robot = VirtualRobot(seed=1)
    with pytest.raises(InputError, match=rf"^{message} must be "):
        umbmark.selfcal(robot, out=tmp_path / "out", **options)
    assert robot.commands == []  # refused before anything moved


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"E_d": 5.0}, "E_d=5.0: give 0.5 to 2"),
        ({"E_b": math.nan}, "E_b=nan: give 0.5 to 2"),
        ({"slip": -1.0}, "slip=-1.0 m^0.5: give 0 to 0.01"),
        ({"wheelbase": 0.0}, "wheelbase=0.0 m: give more than 0 and at most 5 m"),
    ],
)
def test_a_virtual_robot_the_simulation_cannot_stand_for_is_refused(options, message):
    with pytest.raises(InputError) as caught:
        umbmark.VirtualRobot(**options)
    assert str(caught.value) == message


# --- safety stops -------------------------------------------------------------------------


class _FrozenOdometry(VirtualRobot):
    """The controller stops publishing odometry after ``freeze`` seconds."""

    freeze = 5.0

    def odometry(self):  # type: ignore[no-untyped-def]
        odom = super().odometry()
        return odom if odom.time <= self.freeze else replace(odom, time=self.freeze)


def test_stale_odometry_stops_the_robot():
    robot = _FrozenOdometry(seed=1)
    with pytest.raises(SafetyError, match="odometry stale"):
        drive_square(robot, 4.0, Direction.CCW)
    _last_command_is_a_stop(robot)


class _SilentLaser(VirtualRobot):
    """The laser stops after ``after`` seconds (its last scan stays the latest)."""

    after = 5.0

    def scan(self):  # type: ignore[no-untyped-def]
        scan = super().scan()
        if scan is not None and scan.time > self.after:
            scan = replace(scan, time=self.after)
        return scan


def test_a_silent_laser_stops_the_robot():
    """On the first leg (4 m at 0.2 m/s takes 20 s) the laser goes silent at 5 s: the
    robot stops within the 1 s limit plus one look ahead (0.25 s)."""
    robot = _SilentLaser(seed=1)
    with pytest.raises(SafetyError, match="scan stale"):
        drive_square(robot, 4.0, Direction.CCW)
    _last_command_is_a_stop(robot)
    assert robot.now() < 5.0 + 1.0 + 0.25 + 0.05


class _ResetOdometry(VirtualRobot):
    """The controller restarts at ``at`` seconds: its odometry starts again from zero."""

    at = 8.0

    def odometry(self):  # type: ignore[no-untyped-def]
        odom = super().odometry()
        if odom.time < self.at:
            return odom
        if not hasattr(self, "_zero"):
            self._zero = odom.pose
        return replace(odom, pose=odom.pose.relative_to(self._zero))


def test_a_controller_restart_mid_leg_stops_the_robot():
    """At 8 s the robot is about 1.3 m along its first leg (0.2 m/s after its 0.67 s
    ramp): the odometry jumps back to zero, far more than 20 ms of driving allows."""
    robot = _ResetOdometry(seed=1)
    with pytest.raises(SafetyError, match=r"odometry jumped 1\.[0-9]+ m .*restarted"):
        drive_square(robot, 4.0, Direction.CCW)
    _last_command_is_a_stop(robot)
    assert robot.now() < 8.0 + 0.05


def test_a_person_stepping_in_stops_the_robot():
    base = corner_world()
    # someone stands on the first leg, 2 m ahead
    world = World.build(base.segments[2:], np.vstack([base.circles, legs(2.0, 0.0)]), base.corner)
    robot = VirtualRobot(world=world, seed=1)
    with pytest.raises(SafetyError, match="obstacle"):
        drive_square(robot, 4.0, Direction.CCW)
    _last_command_is_a_stop(robot)
    assert robot.true_pose.x < 2.0 - 0.3 + 0.05  # it stopped in front of the legs


class _Pushed(VirtualRobot):
    """Something pushes the robot's odometry sideways (a slipping wheel), from ``after``
    seconds on."""

    after = 1.0

    def odometry(self):  # type: ignore[no-untyped-def]
        odom = super().odometry()
        push = 0.2 * max(0.0, odom.time - self.after)
        return replace(odom, pose=Pose2D(odom.pose.x, odom.pose.y - push, odom.pose.theta))


def test_leaving_the_square_stops_the_robot():
    robot = _Pushed(seed=1)
    with pytest.raises(SafetyError, match="left the square"):
        drive_square(robot, 4.0, Direction.CCW, DriveLimits(heading_gain=0.0, cross_track_gain=0.0))
    _last_command_is_a_stop(robot)
    # 0.5 m sideways at 0.2 m/s, from 1 s on: stopped about 3.5 s in
    assert 3.3 <= robot.now() <= 3.8


def test_odometry_that_never_comes_to_rest_stops_the_robot():
    robot = _Pushed(seed=1)
    robot.after = 0.0  # moving from the start: the first settling never ends
    limits = DriveLimits(settle_limit=5.0)
    with pytest.raises(SafetyError, match="does not come to rest"):
        drive_square(robot, 4.0, Direction.CCW, limits)
    _last_command_is_a_stop(robot)
    assert 5.0 <= robot.now() <= 5.5


class _Weak(VirtualRobot):
    """The wheels turn at a third of the commanded speed (a motor that cannot keep up)."""

    def send_velocity(self, linear: float, angular: float) -> None:
        super().send_velocity(linear / 3.0, angular / 3.0)


def test_a_run_taking_too_long_stops_the_robot():
    robot = _Weak(seed=1)
    with pytest.raises(SafetyError, match="expected time"):
        drive_square(robot, 4.0, Direction.CCW)
    _last_command_is_a_stop(robot)


def test_ctrl_c_stops_the_robot(tmp_path):
    robot = VirtualRobot(seed=1)

    def interrupt(label: str, k: int, direction: object, what: str) -> None:
        if what == "driving" and k == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        selfcal(robot, out=tmp_path / "out", progress=interrupt)
    _last_command_is_a_stop(robot)


def test_the_odometry_ends_where_it_was_sent():
    # the benchmark assumes the robot follows the square by its odometry: the odometry's
    # own end pose within a few mm and 0.1 deg of the commanded one
    robot = VirtualRobot(E_d=E_D, E_b=E_B, slip=0.0004, seed=2)
    for direction in (Direction.CW, Direction.CCW):
        run = drive_square(robot, 4.0, direction)
        distance, heading = run.end_error
        assert distance <= 0.005
        assert math.degrees(heading) <= 0.1


# --- the command ------------------------------------------------------------------------------


@pytest.mark.slow
def test_the_command_on_the_virtual_robot(tmp_path):
    proc = run_cli(
        "selfcal", "--sim", "--side-length", "2", "--runs", "3", "--max-passes", "1",
        "--out", str(tmp_path / "out"), "--json",
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    assert data["e_max_syst_before"] / data["e_max_syst_after"] >= 5.0
    assert "umbmark: odometry alive" in proc.stderr
    assert (tmp_path / "out" / "report.html").is_file()


def test_the_command_needs_a_robot():
    proc = run_cli("selfcal")
    assert proc.returncode == 2
    assert proc.stderr.strip() == "umbmark: error: choose the robot: --sim, --ros1 or --ros2"


@pytest.mark.slow
def test_one_pass_without_verification_says_so(tmp_path):
    """With one pass and no verification nothing measured the corrected robot: no 'after'
    figure is shown, and the reason is."""
    proc = run_cli(
        "selfcal", "--sim", "-L", "1", "-n", "2", "--max-passes", "1", "--no-verify",
        "--no-coarse", "--out", str(tmp_path / "out"),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "-fold" not in proc.stdout
    assert "the correction was applied but not verified (--no-verify)" in proc.stdout
    report = umbmark.selfcal(
        VirtualRobot(E_d=E_D, E_b=E_B, seed=2), side_length=1.0, runs=2, max_passes=1,
        verify=False, coarse=False, out=tmp_path / "api",
    )  # fmt: skip
    assert len(report.passes) == 1
    assert report.e_max_syst_after is None
    assert json.loads(report.to_json())["e_max_syst_after"] is None


@pytest.mark.slow
def test_range_sensors_that_lose_the_corner_say_which_run_and_what_to_do(tmp_path):
    """Three single beams see both walls only near the start: the paper's LabMate errors
    on 4 m squares end the ccw runs about a metre away (its E_max,syst is 1.04 m)."""
    robot = VirtualRobot(E_d=E_D, E_b=E_B, slip=0.0004, seed=1)
    with pytest.raises(InputError, match=r"at the end of (cw|ccw) run [1-5]\): the robot stopped"):
        selfcal(robot, measure="ranges", out=tmp_path / "out")
    _last_command_is_a_stop(robot)


@pytest.mark.slow
def test_range_sensors_calibrate_a_robot_with_moderate_errors(tmp_path):
    """The paper's sonar calibrator: fixes within its 2 mm and 0.4 deg where the robot
    returns near its start."""
    robot = VirtualRobot(E_d=1.001, E_b=0.995, slip=0.0004, seed=1)
    report = selfcal(robot, measure="ranges", side_length=2.0, out=tmp_path / "out")
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.003  # m rms
    assert math.degrees(errors[1]) <= 0.4  # deg rms
    before, after = report.e_max_syst_before, report.e_max_syst_after
    assert before is not None
    assert after is not None
    assert before / after >= 5.0
    final = report.final
    assert final.wheel_separation_multiplier == pytest.approx(0.995, abs=0.001)
    ratio = final.right_wheel_radius_multiplier / final.left_wheel_radius_multiplier
    assert ratio == pytest.approx(1.001, abs=0.0002)


@pytest.mark.slow
def test_fixes_by_motion_capture_are_compared_in_its_own_frame(tmp_path):
    """Motion capture's fixes are in the world frame; the virtual robot's truth there is its
    true pose: the errors are the capture's noise (0.5 mm, 0.05 deg per reading, five
    readings averaged), not the distance between two frames."""
    robot = VirtualRobot(E_d=1.001, E_b=0.995, slip=0.0004, seed=1)
    report = selfcal(
        robot, measure="truth", side_length=1.0, runs=2, max_passes=1, out=tmp_path / "o"
    )
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.001  # m rms
    assert math.degrees(errors[1]) <= 0.05  # deg rms


@pytest.mark.slow
@pytest.mark.parametrize(
    "marks", [None, [-0.3, 0.15, -0.3, -0.15, -0.2, -0.2]], ids=["the robot's", "given"]
)
def test_a_person_with_a_tape_measure_is_asked_at_each_stop(tmp_path, marks):
    """The person is simulated by geometry: at each prompt, the distance from the named mark
    on the robot to the named wall, square to it, read off the virtual robot's true pose in
    the corner frame (walls along x = 0, the "y wall", and y = 0, the "x wall") and rounded
    to the millimetre as a tape is read."""
    import re

    robot = VirtualRobot(E_d=1.001, E_b=0.995, slip=0.0004, seed=3)
    asked: list[str] = []

    def person(prompt: str) -> str:
        asked.append(prompt)
        found = re.search(
            r"mark \d \(x (-?\d+) mm, y (-?\d+) mm on the robot\) to the (x|y) wall", prompt
        )
        assert found, prompt
        mark = Pose2D(float(found[1]) / 1000, float(found[2]) / 1000, 0.0)
        where = robot.corner_truth()
        assert where is not None
        at = where.compose(mark)
        distance = at.x if found[3] == "y" else at.y
        return f"{round(distance * 1000)}"

    report = selfcal(
        robot, measure="tape", ask=person, tape_marks=marks, side_length=1.0, runs=2, max_passes=1,
        verify=False, out=tmp_path / "out",
    )  # fmt: skip
    fixes = report.fix_errors
    assert fixes is not None
    assert len(asked) == 3 * fixes.shape[0]  # three distances a fix
    errors = report.measurement_errors()
    assert errors is not None
    assert errors[0] <= 0.002  # m rms: millimetre readings
    assert math.degrees(errors[1]) <= 0.4  # deg rms (marks 0.5 m apart)


@pytest.mark.slow
def test_progress_names_the_pass_the_run_and_the_leg(tmp_path):
    seen: list[tuple[str, int, object, str]] = []
    selfcal(
        VirtualRobot(E_d=1.001, E_b=0.995, seed=4), side_length=1.0, runs=2, max_passes=1,
        verify=False, coarse=False, out=tmp_path / "out",
        progress=lambda label, k, direction, what: seen.append((label, k, direction, what)),
    )  # fmt: skip
    assert ("pass 1", 1, Direction.CW, "driving, leg 1") in seen
    assert ("pass 1", 4, Direction.CCW, "driving, turn 4") in seen
    assert ("pass 1", 4, Direction.CCW, "measuring") in seen


@pytest.mark.slow
def test_a_run_whose_odometry_does_not_end_where_it_was_sent_is_warned_of(tmp_path):
    """The benchmark assumes the robot follows the square by its odometry: an end pose
    far from the commanded one is said, naming the pass and the run."""
    limits = DriveLimits(end_position=1e-6, end_heading=1e-9)  # nothing is that close
    report = selfcal(
        VirtualRobot(E_d=1.001, E_b=0.995, seed=4), side_length=1.0, runs=2, max_passes=1,
        verify=False, coarse=False, out=tmp_path / "out", limits=limits,
    )  # fmt: skip
    (only,) = report.passes
    assert len(only.warnings) == 4  # every run
    assert only.warnings[0].startswith("cw run 1: the odometry ended ")
    assert only.warnings[3].startswith("ccw run 2: ")
    assert json.loads(report.to_json())["passes"][0]["warnings"] == list(only.warnings)
    ordinary = selfcal(
        VirtualRobot(E_d=1.001, E_b=0.995, seed=4), side_length=1.0, runs=2, max_passes=1,
        verify=False, coarse=False, out=tmp_path / "out2",
    )  # fmt: skip
    assert ordinary.passes[0].warnings == ()


def test_a_tape_measurement_needs_the_marks_of_a_robot_that_has_none(tmp_path):
    class Unmarked(VirtualRobot):
        tape_marks = None  # a real robot: nobody knows where on it a person measures from

    robot = Unmarked(seed=1)
    with pytest.raises(InputError, match=r'^measure="tape" needs tape_marks: the three points'):
        umbmark.selfcal(robot, measure="tape", ask=input, out=tmp_path / "out")
    assert robot.commands == []
    with pytest.raises(InputError, match="at least 50 mm apart"):
        umbmark.selfcal(
            robot, measure="tape", tape_marks=[-0.3, 0.1, -0.3, 0.11, 0.0, -0.2], out=tmp_path
        )

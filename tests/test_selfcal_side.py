"""The squares' side a robot can self-calibrate on (issue 35, item 5): refused before
moving where the calibration would refuse the pass, and what a pass driven but not
calibrated leaves on disk.

The calibration refuses a wheelbase that is not below half the side
(``core/bounds.check_square_geometry``), so a robot whose odometry's wheelbase is b needs
squares of more than 2 b: for the virtual robot's 0.34 m, more than 0.68 m. Before this,
``selfcal --side-length 0.6`` drove a whole pass (ten runs) and was then refused.
"""

from __future__ import annotations

import pytest

import umbmark
from umbmark.core.errors import InputError
from umbmark.robot.base import DriveParams
from umbmark.robot.virtual import VirtualRobot
from umbmark.routines.preflight import check_side
from umbmark.routines.watch import stopped

from helpers import run_cli


def _moved(robot: VirtualRobot) -> bool:
    return any((linear, angular) != (0.0, 0.0) for _, linear, angular in robot.commands)


@pytest.mark.parametrize(
    ("side", "params", "refused", "enough"),
    [
        (0.6, DriveParams(0.34, 0.075), True, "0.7"),  # 2 x 0.34 = 0.68
        (0.68, DriveParams(0.34, 0.075), True, "0.7"),  # not more than 0.68
        (0.69, DriveParams(0.34, 0.075), False, None),
        # 0.34 x 1.1 = 0.374 m: more than 0.748 m, so 0.8
        (0.7, DriveParams(0.34, 0.075, wheel_separation_multiplier=1.1), True, "0.8"),
        (0.7, DriveParams(0.34, 0.075, wheel_separation_multiplier=0.97), False, None),
    ],
)
def test_the_side_must_be_more_than_twice_the_odometrys_wheelbase(side, params, refused, enough):
    if not refused:
        check_side(side, params)
        return
    with pytest.raises(InputError) as caught:
        check_side(side, params)
    message = str(caught.value)  # outside the facade: named as the command names it
    assert message.startswith(f"--side-length {side:g} m is too short for this robot")
    assert f"more than {2 * params.wheelbase:g} m" in message
    assert message.endswith(f"the smallest side that works is --side-length {enough} m")


@pytest.mark.slow
def test_a_square_too_small_for_the_robot_is_refused_before_it_moves(tmp_path):
    robot = VirtualRobot(E_d=1.004, E_b=0.97, seed=1)
    out = tmp_path / "out"
    with pytest.raises(InputError) as caught:
        umbmark.selfcal(robot, side_length=0.6, out=out)
    assert "side_length=0.6 m is too short" in str(caught.value)
    assert stopped(caught.value) is None  # no stop: the robot never moved
    assert not _moved(robot)
    assert robot.true_pose == robot.world.start
    assert not out.exists()


@pytest.mark.slow
def test_the_command_refuses_it_in_one_line_naming_the_smallest_side(tmp_path):
    # The checks before it say what they found (the controller's wheelbase among them);
    # the refusal is the one error line, exit 2.
    out = tmp_path / "out"
    proc = run_cli("selfcal", "--sim", "--side-length", "0.6", "--out", str(out))
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert [k for k, line in enumerate(lines) if "error" in line] == [len(lines) - 1]
    assert "Traceback" not in proc.stderr
    line = lines[-1]
    assert line.startswith("umbmark: error: --side-length 0.6 m is too short for this robot")
    assert "twice the odometry's wheelbase, 0.34 m (the controller's wheel_separation" in line
    assert "so more than 0.68 m" in line
    assert line.rstrip().endswith("the smallest side that works is --side-length 0.7 m")
    assert "to run it again" not in line
    assert not out.exists()


@pytest.mark.slow
def test_a_later_pass_the_correction_makes_too_small_is_refused_before_it_is_driven(tmp_path):
    # E_b = 1.03: pass 1 sets the separation multiplier near 1.03, an odometry wheelbase
    # near 0.35 m, whose limit (0.70 m) the 0.7 m squares no longer exceed. Pass 2 is
    # refused before it drives: the stop keeps pass 1, the controller holds its correction.
    robot = VirtualRobot(E_d=1.004, E_b=1.03, seed=1)
    with pytest.raises(InputError) as caught:
        umbmark.selfcal(robot, side_length=0.7, runs=2, out=tmp_path, verify=False)
    multiplier = robot.drive_params().wheel_separation_multiplier
    assert multiplier == pytest.approx(1.03, abs=0.005)
    assert 2 * 0.34 * multiplier >= 0.7
    assert f"times wheel_separation_multiplier {multiplier:g}" in str(caught.value)
    stop = stopped(caught.value)
    assert stop is not None
    assert stop.passes == ("pass 1",)
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_dir()) == ["pass-1"]


@pytest.mark.slow
def test_a_pass_driven_but_not_calibrated_is_named_on_disk(tmp_path):
    # The history holds robot "bot" with a 0.5 m wheelbase: the pass of the virtual
    # robot (0.34 m) is refused for another robot once it is driven and recorded (2 runs
    # each way: four run files in out/pass-1). The line says where those four runs are,
    # not "nothing in", and offers a new folder (out holds them: out would be refused).
    history = tmp_path / "history.sqlite3"
    runs = tmp_path / "runs.csv"
    assert run_cli("example", str(runs)).returncode == 0
    made = run_cli(
        "calibrate", str(runs), "-L", "4", "-b", "0.5", "--unit", "mm", "--robot", "bot",
        "--history", str(history),
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    out = tmp_path / "out"
    proc = run_cli(
        "selfcal", "--sim", "-L", "1", "--runs", "2", "--max-passes", "1", "--robot", "bot",
        "--history", str(history), "--out", str(out),
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    last = proc.stderr.strip().splitlines()[-1]
    assert "this calibration is not robot bot" in last
    assert "nothing in" not in last
    where = out / "pass-1"
    assert sorted(p.name for p in where.glob("run-*.csv")) == [
        "run-01-cw.csv", "run-02-cw.csv", "run-03-ccw.csv", "run-04-ccw.csv",
    ]  # fmt: skip
    assert (
        f"on disk: no pass finished; 4 runs of a pass not calibrated in {where} "
        f"(umbmark calibrate {where} reads them)"
    ) in last
    assert last.endswith(f"--out {out}-2")

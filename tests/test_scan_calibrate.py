"""``umbmark calibrate BAG --scan-topic /scan`` and its Python API: a bag written with
rosbags of a simulated drive through the virtual robot's room, whose true wheel radii,
wheelbase and laser mounting are known (``scan_sim``), calibrated end to end; ``info``
proposing it; the refusals."""

from __future__ import annotations

import dataclasses
import html
import math
from pathlib import Path

import numpy as np
import pytest

import umbmark
from scan_sim import mirrored, simulate
from umbmark.calibration.scan import calibrate_scan_bags
from umbmark.core.errors import InputError
from umbmark.model.recording import PoseSeries
from umbmark.robot.base import Pose2D
from umbmark.robot.world import room_world
from umbmark.runs.read_options import ReadOptions
from umbmark.sources.bag.scans import scan_mounting
from umbmark.sources.bag.writer import bag_target, write_bag

from helpers import api_error, cli_error, cli_json, run_cli

#: What the odometry used: wheelbase and wheel diameter [m].
B_NOMINAL, D_NOMINAL = 0.34, 0.10
#: The truth against them: each many standard errors from the nominal (1), so that an
#: uncalibrated answer fails (``_far``).
E_D, E_B, E_S = 1.003, 1.02, 0.98
#: f_L, f_R: each wheel's diameter over the nominal; E_s = (f_L + f_R) / 2, E_d = f_R / f_L.
F_LEFT = 2 * E_S / (1 + E_D)
F_RIGHT = E_D * F_LEFT
TRUE_DIAMETERS = (F_LEFT * D_NOMINAL, F_RIGHT * D_NOMINAL)
TRUE_WHEELBASE = E_B * B_NOMINAL
#: The laser's true mounting, off the axle centre, and the one /tf_static states (the
#: matcher's first guess only: 2 cm and 3 degrees off).
LASER = Pose2D(0.1, 0.05, 0.2)
STATED = (0.08, 0.03, 0.15)
JOINTS = ("--left-joint", "left_wheel_joint", "--right-joint", "right_wheel_joint")
NOMINAL = ("--wheelbase", str(B_NOMINAL), "--wheel-diameter", str(D_NOMINAL))


def _bag(  # type: ignore[no-untyped-def]
    folder: Path, pattern=None, *, scans: bool = True, storage=None, upside_down=False
) -> Path:
    """The simulated drive as a bag: ROS 1, or ROS 2 of ``storage`` (sqlite3, mcap); with
    ``upside_down`` the scanner turned over about its x axis (its sweeps mirrored, and the
    mounting on /tf_static with a roll of pi)."""
    radii = (TRUE_DIAMETERS[0] / 2, TRUE_DIAMETERS[1] / 2)
    drive = simulate(pattern, radii=radii, wheelbase=TRUE_WHEELBASE, laser=LASER) if pattern \
        else simulate(radii=radii, wheelbase=TRUE_WHEELBASE, laser=LASER)  # fmt: skip
    poses = PoseSeries(time=drive.pose_times, poses=drive.poses)
    target = bag_target(folder / ("drive" if storage else "drive.bag"), storage)
    if not scans:
        return write_bag(target, drive.wheels, poses, poses)
    sweeps = drive.scans
    if upside_down:
        sweeps = dataclasses.replace(sweeps, ranges=mirrored(sweeps.ranges), upside_down=True)
    return write_bag(target, drive.wheels, poses, poses, scans=sweeps, laser_pose=STATED)


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _bag(tmp_path_factory.mktemp("scans"))


@pytest.fixture(scope="module")
def result(bag: Path) -> umbmark.CalibrationReport:
    return umbmark.calibrate(bag, scan_topic="/scan", wheelbase=B_NOMINAL, wheel_diameter=D_NOMINAL)


def _within(value: float, truth: float, error: float, what: str) -> None:
    # 4 standard errors: of 9 estimates none should be this far off by chance (6e-5 each)
    assert abs(value - truth) < 4 * error, f"{what}: {value} vs {truth} +- {error}"


def _far(data: dict, truth: dict, given: dict) -> None:  # type: ignore[type-arg]
    """Each true figure is more than 6 of its standard errors from what the code was given
    (the nominal geometry, the mounting the bag states): repeating it fails."""
    se = {**data["standard_errors"], "wheelbase": data["wheelbase_standard_error"]}
    for k, what in enumerate(("laser_x", "laser_y", "laser_yaw")):
        se[what] = data["laser_pose_standard_errors"][k]
    for key, value in truth.items():
        assert abs(value - given[key]) > 6 * se[key], (key, value, given[key], se[key])


def _check_truth(data: dict) -> None:  # type: ignore[type-arg]
    se = data["standard_errors"]
    assert data["method"] == "scan-matching"
    _far(
        data,
        {"E_d": E_D, "E_b": E_B, "E_s": E_S, "wheel_diameter_left": TRUE_DIAMETERS[0],
         "wheel_diameter_right": TRUE_DIAMETERS[1], "wheelbase": TRUE_WHEELBASE,
         "laser_x": LASER.x, "laser_y": LASER.y, "laser_yaw": LASER.theta},
        {"E_d": 1.0, "E_b": 1.0, "E_s": 1.0, "wheel_diameter_left": D_NOMINAL,
         "wheel_diameter_right": D_NOMINAL, "wheelbase": B_NOMINAL, "laser_x": STATED[0],
         "laser_y": STATED[1], "laser_yaw": STATED[2]},
    )  # fmt: skip
    for key, truth in (("E_d", E_D), ("E_b", E_B), ("E_s", E_S)):
        _within(data[key], truth, se[key], key)
    for side, truth in zip(("left", "right"), TRUE_DIAMETERS, strict=True):
        key = f"wheel_diameter_{side}"
        assert data[f"{key}_standard_error"] == se[key]
        _within(data[key], truth, se[key], key)
    _within(data["wheelbase"], TRUE_WHEELBASE, data["wheelbase_standard_error"], "wheelbase")
    truth = (LASER.x, LASER.y, LASER.theta)
    for k, what in enumerate(("laser x", "laser y", "laser yaw")):
        _within(data["laser_pose"][k], truth[k], data["laser_pose_standard_errors"][k], what)
    # and the errors are small enough to say something: the units are metres and radians
    assert se["E_d"] < 5e-4
    assert se["E_b"] < 5e-3
    assert se["E_s"] < 5e-3
    assert max(data["laser_pose_standard_errors"][:2]) < 0.003  # [m]
    assert data["laser_pose_standard_errors"][2] < math.radians(0.5)
    assert data["wheelbase_standard_error"] < 0.002  # [m]


def test_the_python_api_recovers_the_truth(result: umbmark.CalibrationReport) -> None:
    data = result.to_dict()
    _check_truth(data)
    assert data["verdict"]["level"] == "apply"
    assert result.warnings == ()
    said = " ".join(result.notes)
    assert "motion intervals matched" in said
    assert "from /tf_static in base_link: laser at x = 0.0800 m, y = 0.0300 m, yaw = 8.59" in said
    # the overlay composes the factors: new wheel multipliers are f_L, f_R (active 1)
    assert result.calibration.new_c_left == pytest.approx(data["wheel_diameter_left"] / 0.1)


def test_the_library_pipeline_is_the_jobs(bag: Path, result: umbmark.CalibrationReport) -> None:
    options = ReadOptions(scan_topic="/scan", wheel_diameter=D_NOMINAL)
    direct = calibrate_scan_bags([bag], options, wheelbase=B_NOMINAL)
    assert direct.estimate == result.estimate
    ours, theirs = direct.to_dict(), result.to_dict()
    for key in ("laser_pose", "laser_pose_standard_errors", "wheelbase", "motion_intervals"):
        assert ours[key] == theirs[key]


@pytest.mark.parametrize(
    ("storage", "upside_down"),
    [pytest.param("sqlite3", False, marks=pytest.mark.slow), ("mcap", True)],
)
def test_ros2_bags_recover_the_truth(tmp_path: Path, storage: str, upside_down: bool) -> None:
    # the same drive in a ROS 2 bag (sweeps at irregular rates, with NaN and inf ranges);
    # turned over, the scanner's sweeps are mirrored and /tf_static says so: the mounting
    # found is of the frame turned right side up, which has the same position and yaw
    bag = _bag(tmp_path, storage=storage, upside_down=upside_down)
    report = umbmark.calibrate(
        bag, scan_topic="/scan", wheelbase=B_NOMINAL, wheel_diameter=D_NOMINAL
    )
    _check_truth(report.to_dict())
    assert report.to_dict()["verdict"]["level"] == "apply"


def test_the_mounting_read_from_tf_static(bag: Path) -> None:
    base, pose, lift = scan_mounting(bag, "laser")  # type: ignore[misc]
    assert base == "base_link"
    assert pose == pytest.approx(STATED, abs=1e-9)
    assert lift == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)  # the writer's: on the floor, flat
    assert scan_mounting(bag, "no_such_frame") is None


def test_the_mounting_in_the_forms_a_user_applies(result: umbmark.CalibrationReport) -> None:
    """The fitted mounting as the URDF origin and the static transform publishers'
    arguments, and its difference from what /tf_static states: the truth's (2 cm and 3
    degrees), outside the fit's 95 % intervals (4 standard errors apart at least)."""
    data = result.to_dict()
    forms = data["laser_mounting"]
    x, y, yaw = data["laser_pose"]
    se = data["laser_pose_standard_errors"]
    assert forms["stated"]["source"] == "/tf_static in base_link"
    assert forms["stated"]["lift"] == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    truth = (LASER.x - STATED[0], LASER.y - STATED[1], LASER.theta - STATED[2])
    for k, what in enumerate(("dx", "dy", "dyaw")):
        _within(forms["difference"][k], truth[k], se[k], what)
    assert forms["outside_interval_95"] == [True, True, True]
    assert forms["urdf_origin"] == (
        f'<origin xyz="{x:.4f} {y:.4f} 0.0000" rpy="0.00000 0.00000 {yaw:.5f}"/>'
    )
    assert forms["ros1_static_transform_publisher"] == (
        f"rosrun tf2_ros static_transform_publisher {x:.4f} {y:.4f} 0.0000 {yaw:.5f} "
        "0.00000 0.00000 base_link laser"
    )
    assert forms["ros2_static_transform_publisher"].endswith(
        f"--yaw {yaw:.5f} --frame-id base_link --child-frame-id laser"
    )


def test_an_upside_down_mounting_keeps_its_position_and_heading(tmp_path: Path) -> None:
    drive = simulate(((1.0, 0.2, 0.0),))
    scans = dataclasses.replace(drive.scans, ranges=mirrored(drive.scans.ranges), upside_down=True)
    poses = PoseSeries(time=drive.pose_times, poses=drive.poses)
    bag = write_bag(
        bag_target(tmp_path / "flipped.bag"), drive.wheels, poses, poses, scans=scans,
        laser_pose=STATED,
    )  # fmt: skip
    # turned over about its x axis: the frame right side up has the same origin and x axis
    base, pose, (z, roll, pitch) = scan_mounting(bag, "laser")  # type: ignore[misc]
    assert base == "base_link"
    assert pose == pytest.approx(STATED, abs=1e-9)
    assert (z, abs(roll), pitch) == pytest.approx((0.0, math.pi, 0.0), abs=1e-9)


@pytest.mark.slow
def test_the_command_gives_the_same_in_metres_and_radians(
    bag: Path, result: umbmark.CalibrationReport
) -> None:
    data = cli_json("calibrate", str(bag), "--scan-topic", "/scan", *JOINTS, *NOMINAL)
    _check_truth(data)
    api = result.to_dict()
    for key in ("E_d", "E_b", "E_s", "wheel_diameter_left", "wheel_diameter_right", "wheelbase"):
        assert data[key] == pytest.approx(api[key], rel=1e-12)
    assert data["laser_pose"] == pytest.approx(api["laser_pose"], rel=1e-12)
    assert data["new"] == pytest.approx(api["new"], rel=1e-12)  # the overlay's values
    assert data["laser_mounting"] == api["laser_mounting"]
    # the terminal: the same forms, whole on their lines (to copy)
    text = run_cli("calibrate", str(bag), "--scan-topic", "/scan", *JOINTS, *NOMINAL)
    assert text.returncode == 0, text.stderr
    lines = text.stdout.splitlines()
    forms = api["laser_mounting"]
    assert f"  URDF joint origin of laser: {forms['urdf_origin']}" in lines
    assert f"  ROS 2: {forms['ros2_static_transform_publisher']}" in lines
    assert f"  ROS 1: {forms['ros1_static_transform_publisher']}" in lines
    said = next(line for line in lines if line.startswith("  stated (/tf_static in base_link)"))
    # and the page (--report): the same forms, escaped
    page = result.html()
    assert f'id="urdf-origin">{html.escape(forms["urdf_origin"])}</pre>' in page
    dx, dy, dyaw = forms["difference"]
    assert (
        f"x {dx * 1000:+.1f} mm, y {dy * 1000:+.1f} mm, yaw {math.degrees(dyaw):+.3f} deg" in said
    )


@pytest.mark.slow
def test_info_proposes_the_scan_topic(bag: Path, tmp_path: Path) -> None:
    proposed = "--scan-topic /scan --left-joint left_wheel_joint --right-joint right_wheel_joint"
    report = umbmark.info(bag)
    assert report.bag is not None
    assert report.bag.scan_options == proposed
    assert report.to_dict()["laser_scans"] == ["/scan"]
    proc = run_cli("info", str(bag))
    assert proc.returncode == 0, proc.stderr
    text = " ".join(proc.stdout.split())
    assert f"umbmark calibrate {bag} {proposed} --wheelbase ... --wheel-diameter ..." in text
    no_scans = umbmark.info(_bag(tmp_path, ((3.0, 0.2, 0.0),), scans=False)).to_dict()
    assert no_scans["scan_options"] is None
    assert no_scans["laser_scans"] == []


@pytest.mark.slow
def test_a_bag_driven_straight_only_is_refused_with_what_to_drive(tmp_path: Path) -> None:
    straight = ((4.0, 0.25, 0.0), (4.0, -0.25, 0.0), (4.0, 0.25, 0.0), (4.0, -0.25, 0.0))
    bag = _bag(tmp_path, straight)
    line = cli_error("calibrate", str(bag), "--scan-topic", "/scan", *NOMINAL)
    assert str(bag) in line
    assert "drive more turns on the spot" in line
    assert "0 turns on the spot" in line


def test_a_bag_turning_on_the_spot_only_is_refused(tmp_path: Path) -> None:
    bag = _bag(tmp_path, ((5.0, 0.0, 0.6), (5.0, 0.0, -0.6)))
    message = api_error(
        umbmark.calibrate, bag, scan_topic="/scan", wheelbase=B_NOMINAL, wheel_diameter=0.1
    )
    assert str(bag) in message
    assert "drive more straights" in message


@pytest.mark.slow
def test_bad_topics_and_methods_are_one_line(bag: Path) -> None:
    line = cli_error("calibrate", str(bag), "--scan-topic", "/laser", *NOMINAL)
    assert line.startswith(f"umbmark: error: {bag}: no topic /laser (laser scans)")
    kw = {"wheelbase": B_NOMINAL, "wheel_diameter": D_NOMINAL}
    message = api_error(umbmark.calibrate, bag, scan_topic="/odom", **kw)
    assert "/odom has messages of type nav_msgs/msg/Odometry" in message
    assert str(bag) in message
    message = api_error(umbmark.calibrate, bag, scan_topic="/scan", method="exact", **kw)
    assert "scan_topic calibrates by method='scan-matching'" in message
    message = api_error(umbmark.calibrate, bag, scan_topic="/scan", wheel_topic="/nope", **kw)
    assert str(bag) in message
    assert "no topic /nope" in message
    message = api_error(
        umbmark.calibrate, bag, scan_topic="/scan", left_joint="nope", right_joint="nix", **kw
    )
    assert message.startswith(f"{bag}: no joint 'nope' and 'nix' in /joint_states")
    with pytest.raises(InputError, match="scan_topic is read by calibrate only"):
        umbmark.replay(bag, scan_topic="/scan", **kw)


@pytest.mark.slow
def test_without_the_nominal_parameters_the_bag_gives_absolute_figures(bag: Path) -> None:
    # no --wheelbase, --wheel-diameter, no robot description: the matches start from the
    # scans alone and the radii, wheelbase and mounting come out absolute (each true
    # figure is many standard errors from the guess /tf_static states: 2 cm, 3 degrees)
    report = umbmark.calibrate(bag, scan_topic="/scan")
    data = report.to_dict()
    assert data["nominal"] is None
    assert data["E_b"] is None
    assert data["E_s"] is None
    for side, truth in zip(("left", "right"), TRUE_DIAMETERS, strict=True):
        key = f"wheel_diameter_{side}"
        _within(data[key], truth, data[f"{key}_standard_error"], key)
    _within(data["wheelbase"], TRUE_WHEELBASE, data["wheelbase_standard_error"], "wheelbase")
    _within(data["E_d"], E_D, data["standard_errors"]["E_d"], "E_d")
    assert 6 * data["standard_errors"]["E_d"] < E_D - 1
    for k, truth in enumerate((LASER.x, LASER.y, LASER.theta)):
        error = data["laser_pose_standard_errors"][k]
        _within(data["laser_pose"][k], truth, error, "laser")
        assert abs(STATED[k] - truth) > 6 * error
    summary = run_cli("calibrate", str(bag), "--scan-topic", "/scan").stdout
    assert "no nominal geometry was given" in summary
    assert "overlay (paste it" not in summary


def test_the_mounting_read_from_a_robot_description() -> None:
    from robot_bags import TB3_URDF
    from umbmark.sources.bag.urdf import parse_robot_description

    # a laser turned over (roll pi) and yawed by 0.2 rad, as a URDF mounts it
    laser = (
        '<joint name="scan_joint" type="fixed"><parent link="base_link"/>'
        '<child link="base_scan"/><origin xyz="-0.032 0.01 0.172" rpy="3.141592653589793 0 0.2"/>'
        '</joint><link name="base_scan"/></robot>'
    )
    described = parse_robot_description(TB3_URDF.replace("</robot>", laser))
    assert described.mountings["base_scan"] == pytest.approx((-0.032, 0.01, 0.2), abs=1e-12)
    assert described.mountings["base_link"] == pytest.approx((0.0, 0.0, 0.0))  # 1 cm up only
    assert "wheel_left_link" not in described.mountings  # on a turning joint: no mounting


@pytest.mark.slow
def test_a_turtlebot3_as_its_bags_are(tmp_path: Path) -> None:
    # TurtleBot3 Burger's published geometry (wheelbase 160 mm, wheels 66 mm, the LDS-01
    # at x = -32 mm in its URDF) with errors; its scanner as the LDS-01 reports: 360 beams
    # at 5 Hz from angle 0 round to 2 pi, each sweep measured over its 0.2 s period while
    # the robot moves, 0.12 to 3.5 m, 1.5 cm noise, 0.0 where a beam saw nothing; the
    # wheels at 30 Hz; a ROS 2 MCAP bag
    b_nominal, d_nominal = 0.160, 0.066
    e_d, e_b, e_s = 1.006, 1.04, 0.96  # each 6 of its (widened) errors off 1 at least
    f_left = 2 * e_s / (1 + e_d)
    radii = (f_left * d_nominal / 2, e_d * f_left * d_nominal / 2)
    world = room_world()
    assert world.lidar is not None
    lds = dataclasses.replace(
        world.lidar, angle_min=0.0, range_min=0.12, range_max=3.5, sigma=0.015
    )
    pattern = (
        (3.0, 0.0, 1.2), (3.0, 0.0, -1.2), (4.0, 0.2, 0.0), (4.0, -0.2, 0.0),
        (5.0, 0.15, 0.6), (5.0, -0.15, 0.6), (3.0, 0.0, -1.5),
    )  # fmt: skip
    # the LDS-01 truly sits 1 cm off and turned by 3 degrees from where the URDF puts it
    laser, stated = Pose2D(-0.042, 0.01, math.radians(3.0)), (-0.032, 0.0, 0.0)
    drive = simulate(
        pattern, world=dataclasses.replace(world, lidar=lds), beams=360, scan_rate=5.0, jitter=0.2,
        wheel_rate=30.0, sweep_time=0.2, radii=radii, wheelbase=e_b * b_nominal, laser=laser,
    )  # fmt: skip
    poses = PoseSeries(time=drive.pose_times, poses=drive.poses)
    ranges = drive.scans.ranges
    assert (~np.isfinite(ranges)).mean() > 0.05  # beyond 3.5 m, and dropouts
    zeros = dataclasses.replace(drive.scans, ranges=np.where(np.isfinite(ranges), ranges, 0.0))
    bag = write_bag(
        bag_target(tmp_path / "tb3", "mcap"), drive.wheels, poses, poses, scans=zeros,
        laser_pose=stated,
    )  # fmt: skip
    report = umbmark.calibrate(
        bag, scan_topic="/scan", wheelbase=b_nominal, wheel_diameter=d_nominal
    )
    data = report.to_dict()
    se = data["standard_errors"]
    for key, truth in (("E_d", e_d), ("E_b", e_b), ("E_s", e_s)):
        _within(data[key], truth, se[key], key)
    _within(data["wheelbase"], e_b * b_nominal, data["wheelbase_standard_error"], "wheelbase")
    for k, truth in enumerate((laser.x, laser.y, laser.theta)):
        _within(data["laser_pose"][k], truth, data["laser_pose_standard_errors"][k], "laser")
    f_right = e_d * f_left
    _far(
        data,
        {"E_d": e_d, "E_b": e_b, "E_s": e_s, "wheel_diameter_left": f_left * d_nominal,
         "wheel_diameter_right": f_right * d_nominal, "wheelbase": e_b * b_nominal,
         "laser_x": laser.x, "laser_y": laser.y, "laser_yaw": laser.theta},
        {"E_d": 1.0, "E_b": 1.0, "E_s": 1.0, "wheel_diameter_left": d_nominal,
         "wheel_diameter_right": d_nominal, "wheelbase": b_nominal, "laser_x": stated[0],
         "laser_y": stated[1], "laser_yaw": stated[2]},
    )  # fmt: skip
    for side, truth in zip(("left", "right"), (f_left, f_right), strict=True):
        key = f"wheel_diameter_{side}"
        _within(data[key], truth * d_nominal, se[key], key)
    assert se["E_d"] < 1e-3
    assert max(data["laser_pose_standard_errors"][:2]) < 0.003  # [m]
    assert any("44 motion intervals matched of 44" in note for note in report.notes)
